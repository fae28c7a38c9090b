#!/usr/bin/python3.11
"""Benchmark hexmerge.regions_by_solid() (the OpenCASCADE layer) on 1M-tet meshes.

Cases (meshes and BREP files go to bench/meshes/, made once with the Gmsh command line):
  box-1solid   bench/meshes/box-delaunay-1m.msh and bench/geometry/box.geo: one solid
  box-2solids  the 100 x 40 x 30 box cut in two solids at x = 50 (Gmsh BooleanFragments)
  box-5+cyl    the box cut in five solids along x plus a cylinder through them all (ten solids,
               curved shared faces)
For each: the seconds of regions_by_solid() (default: pieces), its report, and whether every
tet's solid matches the Gmsh physical volume it was meshed in. --every-tet also times the
per-tet classification (the reference).

Usage: /usr/bin/python3.11 bench/regions_by_solid.py [--cases box-2solids,...] [--every-tet]
"""
import argparse
import os
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "src", "python"))
import hexmerge  # noqa: E402
import meshio  # noqa: E402

MESHES = os.path.join(HERE, "meshes")
H = 0.82  # bench/meshes/manifest.json: about 1M tets in the 100 x 40 x 30 box

GEO = {
    "box-2solids": """SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 50, 40, 30};
Box(2) = {50, 0, 0, 50, 40, 30};
BooleanFragments{ Volume{1}; Delete; }{ Volume{2}; Delete; }
""",
    "box-5+cyl": """SetFactory("OpenCASCADE");
For i In {0:4}
  Box(i + 1) = {20 * i, 0, 0, 20, 40, 30};
EndFor
Cylinder(6) = {0, 20, 15, 100, 0, 0, 8};
BooleanFragments{ Volume{1:5}; Delete; }{ Volume{6}; Delete; }
""",
}


def gmsh(args):
    subprocess.run(["gmsh", *args], check=True, capture_output=True)


def prepare(case):
    """(msh path, brep path); one physical volume per solid."""
    msh = os.path.join(MESHES, case + "-1m.msh")
    brep = os.path.join(MESHES, case + ".brep")
    if case == "box-1solid":
        msh = os.path.join(MESHES, "box-delaunay-1m.msh")
        if not os.path.exists(brep):
            gmsh(["-0", os.path.join(HERE, "geometry", "box.geo"), "-o", brep])
        return msh, brep
    geo = os.path.join(MESHES, case + ".geo")
    if not os.path.exists(msh):
        body = GEO[case] + "v[] = Volume{:};\nFor i In {0:#v[] - 1}\n  Physical Volume(i + 1) = {v[i]};\nEndFor\n"
        with open(geo, "w") as f:
            f.write(body)
        t = time.perf_counter()
        gmsh(["-3", "-clmax", str(H), "-order", "1", "-format", "msh41", "-nt", "1", geo, "-o", msh])
        print(f"  meshed {case} in {time.perf_counter() - t:.1f} s")
        gmsh(["-0", geo, "-o", brep])
    return msh, brep


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cases", default="box-1solid,box-2solids,box-5+cyl")
    ap.add_argument("--every-tet", action="store_true")
    ap.add_argument("--threads", type=int, default=0)
    args = ap.parse_args()
    for case in args.cases.split(","):
        msh, brep_path = prepare(case)
        m = meshio.read(msh)
        tets = m.cells_dict["tetra"]
        phys = np.concatenate([d for d, c in zip(m.cell_data["gmsh:physical"], m.cells) if c.type == "tetra"])
        with open(brep_path) as f:
            brep = f.read()
        modes = [("pieces", False)] + ([("every tet", True)] if args.every_tet else [])
        for label, every in modes:
            t = time.perf_counter()
            solids, report = hexmerge.regions_by_solid(brep, m.points, tets, classify_every_tet=every,
                                                       threads=args.threads)
            seconds = time.perf_counter() - t
            # One solid per physical volume and back (Gmsh numbers both the same way, but the
            # check need not rely on it).
            pairs = np.unique(np.stack([phys, solids]), axis=1)
            agree = (solids >= 0).all() and len(pairs[0]) == len(np.unique(phys)) == len(np.unique(pairs[1]))
            phases = ", ".join(f"{k} {v:.2f}" for k, v in report["phase_seconds"].items())
            print(f"{case}: {len(tets)} tets, {report['nb_solids']} solids, {label}: {seconds:.2f} s "
                  f"({phases}); pieces {report['nb_pieces']}, split {report['nb_split_pieces']}, "
                  f"interface nodes {report['nb_interface_nodes']}, queries {report['nb_classified_points']}, "
                  f"unassigned {report['nb_unassigned_tets']}; matches Gmsh volumes: {agree}")
            sys.stdout.flush()


if __name__ == "__main__":
    main()
