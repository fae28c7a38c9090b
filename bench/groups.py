#!/usr/bin/env python3
"""Conforming groups (select/groups.cpp, issue 19 item 3): each tet mesh recombined in the
default conforming mode with group_size=0 (one hexahedron at a time, as before) and with the
given group sizes, every output checked by the independent checker (hexmerge.check).

Meshes: files given on the command line (Gmsh .msh, e.g. bench/meshes/*-delaunay-100k.msh),
--jittered SHAPE:SIZE:JITTER (tetgen-lattice points each moved by up to JITTER * h: hex-friendly
points that are no exact lattice; made once into bench/meshes/SHAPE-jittered-JITTER-SIZE.msh)
and --part NAME:H (hexmerge.mesh_shape(..., recombine=False) of ../shared/cad/NAME.st(e)p or of
bench/geometry/NAME.geo through gmsh -0, at size H: the mesher's own tets).

Prints one Markdown row per mesh and run: cells, fewer than group_size=0 (%), hex / prism /
pyramid / tet volume %, smallest scaled Jacobian of the new elements, the selection's seconds,
the groups (seeds tried / accepted / failed / given up at group_size, hexahedra in them), and
the checker (valid, non-conforming quads, cracks, relative volume difference). Writes JSON.

  PYTHONPATH=src/python /usr/bin/python3.11 bench/groups.py bench/meshes/*-delaunay-100k.msh
  PYTHONPATH=src/python /usr/bin/python3.11 bench/groups.py --option same_nodes=false bench/meshes/box-delaunay-100k.msh
  PYTHONPATH=src/python /usr/bin/python3.11 bench/groups.py --jittered box:100k:0.15 --part flanged_tee:7.911
"""
import argparse
import datetime
import json
import os
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import benchlib  # noqa: E402
import make_meshes  # noqa: E402
import run_bench  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
CAD_DIR = os.path.join(HERE, "..", "..", "..", "shared", "cad")
TYPES = ("hex", "prism", "pyramid", "tet")


def jittered_mesh(spec):
    shape, size, jitter = spec.split(":")
    out = os.path.join(make_meshes.MESH_DIR, f"{shape}-jittered-{jitter}-{size}.msh")
    if not os.path.exists(out):
        os.makedirs(make_meshes.MESH_DIR, exist_ok=True)
        h = make_meshes.H_TETGEN_LATTICE[shape][size]
        ok, rc, _, log, _ = make_meshes.make_tetgen_lattice(shape, h, out, jitter=float(jitter))
        if not ok:
            raise RuntimeError(f"{spec}: mesh failed ({rc}): {log[-300:]}")
    return out


def part_tets(hexmerge, spec):
    name, h = spec.split(":")
    geo = os.path.join(HERE, "geometry", name + ".geo")
    with tempfile.TemporaryDirectory() as tmp:
        if os.path.exists(geo):
            path = os.path.join(tmp, name + ".step")
            subprocess.run(["gmsh", "-0", geo, "-o", path], check=True, capture_output=True)
        else:
            path = next(os.path.join(CAD_DIR, name + ext) for ext in (".step", ".stp", ".STEP", ".STP")
                        if os.path.exists(os.path.join(CAD_DIR, name + ext)))
        tets, _ = hexmerge.mesh_shape(path, float(h), recombine=False)
    import numpy as np
    points = np.asarray(tets.points, dtype=np.float64).reshape(-1, 3)
    cells = np.asarray(tets.cell_vertices, dtype=np.int64).reshape(-1, 4)
    regions = getattr(tets, "regions", None)
    return points, cells, (np.asarray(regions) if regions is not None and len(regions) else None)


def run(hexmerge, points, cells, regions, options):
    t0 = time.perf_counter()
    mesh, report = hexmerge.recombine(points, cells, regions=regions, **options)
    seconds = time.perf_counter() - t0
    check = run_bench.call_check(hexmerge, mesh, points, cells, regions)
    check = run_bench.as_dict(check)
    report = run_bench.as_dict(report)
    new = [report["min_scaled_jacobian"][t] for t in ("hex", "prism", "pyramid")
           if report["output_counts"][t]]
    return {"options": options, "seconds": seconds,
            "selection_seconds": report["phase_seconds"].get("selection"),
            "report": report,
            "check": {k: check.get(k) for k in ("valid", "nonconforming_quads", "cracks",
                                                "relative_volume_difference", "min_scaled_jacobian")},
            "min_new_element_sj": min(new) if new else None}


def row(name, r, base_cells):
    rep, chk = r["report"], r["check"]
    vf = rep["volume_fraction"]
    fewer = 100.0 * (1.0 - rep["output_cells"] / base_cells)
    groups = (f"{rep['group_seeds']} / {rep['groups']} / {rep['groups_failed']} / "
              f"{rep['groups_capped']} / {rep['group_hexahedra']}")
    sj = r["min_new_element_sj"]
    return (f"| {name} | {r['options'].get('group_size', 64)} | {rep['output_cells']:,} | {fewer:.1f} | "
            + " | ".join(f"{100 * vf[t]:.1f}" for t in TYPES)
            + f" | {'-' if sj is None else f'{sj:.3f}'} | {r['selection_seconds']:.2f} | {groups} | "
            f"{'yes' if chk['valid'] else 'NO'} / {chk['nonconforming_quads']} / {chk['cracks']} / "
            f"{chk['relative_volume_difference']:.1e} |")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="*")
    ap.add_argument("--jittered", action="append", default=[], metavar="SHAPE:SIZE:JITTER")
    ap.add_argument("--part", action="append", default=[], metavar="NAME:H")
    ap.add_argument("--group-sizes", default="64", help="comma list of group_size values besides 0")
    ap.add_argument("--option", action="append", default=[], metavar="NAME=VALUE",
                    help="another engine option for every run (repeatable), e.g. same_nodes=false")
    ap.add_argument("--output", help="JSON (default bench/results/groups-<time>.json)")
    args = ap.parse_args()
    import hexmerge

    options = dict((k.strip(), run_bench.parse_value(v.strip()))
                   for k, v in (o.split("=", 1) for o in args.option))
    sizes = [0] + [int(s) for s in args.group_sizes.split(",") if s]
    inputs = [(os.path.basename(f).rsplit(".", 1)[0], lambda f=f: run_bench.load_tet_mesh(f, "int64") + (None,))
              for f in args.files]
    inputs += [(os.path.basename(jittered_mesh(s)).rsplit(".", 1)[0],
                lambda s=s: run_bench.load_tet_mesh(jittered_mesh(s), "int64") + (None,))
               for s in args.jittered]
    inputs += [(s, lambda s=s: part_tets(hexmerge, s)) for s in args.part]
    started = datetime.datetime.now()
    out = args.output or os.path.join(run_bench.RESULTS_DIR, f"groups-{started:%Y%m%d-%H%M%S}.json")
    os.makedirs(os.path.dirname(out), exist_ok=True)
    results = []
    print("| mesh | group_size | cells | fewer % | hex % | prism % | pyramid % | tet % | min SJ new | "
          "selection s | groups: seeds / kept / failed / capped / hexes | valid / nonconf. / cracks / vol. diff |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name, load in inputs:
        points, cells, regions = load()
        base = None
        for size in sizes:
            r = run(hexmerge, points, cells, regions, {**options, "group_size": size})
            r.update({"mesh": name, "tets": int(cells.shape[0])})
            base = base or r["report"]["output_cells"]
            results.append(r)
            print(row(name, r, base), flush=True)
            with open(out, "w") as f:
                json.dump(benchlib.jsonable({"git": benchlib.git_commit(), "started": started.isoformat(),
                                             "results": results}), f, indent=1)
    print(f"\nresults: {os.path.relpath(out)}", file=sys.stderr)


if __name__ == "__main__":
    main()
