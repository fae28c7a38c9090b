#!/usr/bin/python3.11
"""Benchmark hexmerge.mesh_shape (issue #6): CAD shape -> lattice-seeded tets -> hex-dominant.

For each shape (BREP made by Gmsh's OpenCASCADE kernel from bench/geometry/*.geo, and the plate
with a hole of FreeCAD's FEM examples in resources/examples), at a target size giving about the
requested number of tets: meshing time and counts, then recombination with the defaults
(conforming), the independent checker, hex volume, element reduction, minimum scaled Jacobian
over every element (tets included), and the largest distance of a boundary node to the CAD.

Usage (after building the module, see bench/README.md):
  PYTHONPATH=src/python /usr/bin/python3.11 bench/mesh_shapes.py            # about 100k tets
  ... mesh_shapes.py --shapes box,bracket --tets 20000
Results: bench/results/mesh-shapes-latest.json and a Markdown table on stdout.
"""
import argparse
import json
import os
import sys
import tempfile
import time

import benchlib
import hexmerge
from hexmerge import _core

ROOT = benchlib.ROOT
SHAPES = {
    "box": os.path.join(ROOT, "bench", "geometry", "box.geo"),
    "cylinder": os.path.join(ROOT, "bench", "geometry", "cylinder.geo"),
    "bracket": os.path.join(ROOT, "bench", "geometry", "bracket.geo"),
    "fem-plate-with-hole": os.path.join(ROOT, "resources", "examples", "material_nl_platewithhole.brep"),
}


def shape_text(name: str, work: str) -> str:
    path = SHAPES[name]
    if path.endswith(".geo"):
        path = benchlib.geo_to_cad(path, os.path.join(work, name + ".brep"))
    return _core.read_shape_file(path)


# A first size per shape (about a tenth of its smallest side); the measured size is rescaled
# from the tet counts it and the next give.
PROBE_SIZE = {"box": 4.0, "cylinder": 3.0, "bracket": 3.0, "fem-plate-with-hole": 10.0}


def run(name: str, brep: str, tets_wanted: int) -> dict:
    size = PROBE_SIZE[name]
    for _ in range(2):  # the count goes about as h^-3; twice, to land near the wanted count
        _, probe, _, rep = _core.mesh_shape(brep, {"size": repr(float(size))})
        size = benchlib.rescaled_size(size, len(probe), tets_wanted)
    start = time.perf_counter()
    pts, tets, regions, rep = _core.mesh_shape(brep, {"size": repr(float(size))})
    mesh_s = time.perf_counter() - start
    start = time.perf_counter()
    mesh, report = hexmerge.recombine(pts, tets, regions=regions)
    recombine_s = time.perf_counter() - start
    check = hexmerge.check(mesh, pts, tets, regions)
    return {
        "shape": name,
        "size": size,
        "tets": int(len(tets)),
        "core_cells": rep["nb_core_cells"],
        "mesh_s": mesh_s,
        "tetgen_s": rep["phase_seconds"]["tetgen"],
        "recombine_s": recombine_s,
        "elements": int(sum(report["output_counts"].values())),
        "hex_volume": report["volume_fraction"]["hex"],
        "prism_volume": report["volume_fraction"]["prism"],
        "reduction": report["element_reduction_percent"],
        "nonconforming_quads": check["nonconforming_quads"],
        "cracks": check["cracks"],
        "min_sj": check["min_scaled_jacobian"],
        "valid": check["valid"],
        "boundary_distance_over_h": rep["max_boundary_distance"] / size,
        "strategy": report["selection_strategy"],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--shapes", default=",".join(SHAPES))
    parser.add_argument("--tets", type=int, default=100_000)
    args = parser.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as work:
        for name in args.shapes.split(","):
            row = run(name, shape_text(name, work), args.tets)
            rows.append(row)
            print(json.dumps(row), file=sys.stderr, flush=True)
    os.makedirs(os.path.join(ROOT, "bench", "results"), exist_ok=True)
    with open(os.path.join(ROOT, "bench", "results", "mesh-shapes-latest.json"), "w") as f:
        json.dump(rows, f, indent=1)
    print("| shape | h | tets | mesh s (TetGen s) | recombine s | elements | hex vol % | prism vol % "
          "| reduction % | non-conf. quads | cracks | min SJ | boundary dist / h |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['shape']} | {r['size']:.3g} | {r['tets']:,} | {r['mesh_s']:.2f} ({r['tetgen_s']:.2f}) "
              f"| {r['recombine_s']:.2f} | {r['elements']:,} | {100 * r['hex_volume']:.1f} "
              f"| {100 * r['prism_volume']:.1f} | {r['reduction']:.1f} | {r['nonconforming_quads']} "
              f"| {r['cracks']} | {r['min_sj']:.2g} | {r['boundary_distance_over_h']:.1e} |")


if __name__ == "__main__":
    main()
