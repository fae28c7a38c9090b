#!/usr/bin/python3.11
"""How much hexahedron volume can a conforming selection reach at all on the benchmark meshes?

For each mesh, two conforming runs of hexmerge.recombine:
  1. the defaults: the hexahedron volume we make;
  2. the most permissive acceptance that still keeps every new element's scaled Jacobian at
     0.2 or more (issue #5's quality target): every subdivision (finder=exhaustive), any quad
     dihedral angle down to 90 degrees, on the boundary too, any face angle, scaled Jacobian
     0.2; with optimality_bound on, whose hex_volume_bound is the largest hexahedron volume of
     any conforming selection of those candidates (set packing over the hexahedra that
     prune_unclosable keeps; the closers' own needs are ignored, so it is an upper bound).
The bound holds for any selection strategy: no way of choosing among these merges of the given
tets, with every element at scaled Jacobian 0.2 or more and no quad face against two triangles,
fills more.

Usage (after building the module with GLPK, see bench/README.md):
  PYTHONPATH=src/python /usr/bin/python3.11 bench/hex_ceiling.py               # 10k and 100k
  ... hex_ceiling.py --sizes 10k --shapes box,sphere --time-limit 30
Results: bench/results/hex-ceiling-latest.json and a Markdown table on stdout.
"""
import argparse
import json
import os
import sys
import time

import hexmerge

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from run_bench import MESH_DIR, RESULTS_DIR, SHAPES, find_meshes, load_tet_mesh  # noqa: E402

PERMISSIVE = {
    "finder": "exhaustive",
    "min_dihedral_angle": 90,
    "min_boundary_dihedral_angle": 90,
    "max_face_angle": 180,
    "min_scaled_jacobian": 0.2,
}


def run(path, time_limit):
    points, tets = load_tet_mesh(path)
    _, default = hexmerge.recombine(points, tets)
    start = time.perf_counter()
    _, permissive = hexmerge.recombine(
        points, tets, optimality_bound=True, bound_time_limit=time_limit, **PERMISSIVE
    )
    return {
        "mesh": os.path.splitext(os.path.basename(path))[0],
        "tets": len(tets),
        "hex_volume_default": default["volume_fraction"]["hex"],
        "hex_volume_permissive": permissive["volume_fraction"]["hex"],
        "hex_volume_bound": permissive["hex_volume_bound"],
        "bound_proved": permissive["hex_volume_bound_proved"],
        "hex_candidates": permissive["candidates_per_template"].get("exhaustive_hex"),
        "candidates_unclosable": permissive["candidates_unclosable"],
        "seconds": time.perf_counter() - start,
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", default="10k,100k")
    ap.add_argument("--shapes", default=",".join(SHAPES))
    ap.add_argument("--mesh-dir", default=MESH_DIR)
    ap.add_argument("--time-limit", type=float, default=60.0, help="seconds per integer program")
    ap.add_argument("--output", default=os.path.join(RESULTS_DIR, "hex-ceiling-latest.json"))
    args = ap.parse_args()
    paths = find_meshes(args.shapes.split(","), ["delaunay"], args.sizes.split(","), args.mesh_dir)
    if not paths:
        sys.exit(f"no benchmark meshes in {args.mesh_dir} (bench/make_meshes.py makes them)")
    rows = []
    for path in paths:
        print(f"{os.path.basename(path)} ...", file=sys.stderr, flush=True)
        rows.append(run(path, args.time_limit))
        with open(args.output, "w") as f:
            json.dump(rows, f, indent=1)
    print("| mesh | tets | hex vol. % (defaults) | hex vol. % (SJ >= 0.2, any angle) | "
          "conforming ceiling % | proved | s |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['mesh']} | {r['tets']:,} | {100 * r['hex_volume_default']:.1f} | "
              f"{100 * r['hex_volume_permissive']:.1f} | {100 * r['hex_volume_bound']:.1f} | "
              f"{'yes' if r['bound_proved'] else 'no'} | {r['seconds']:.0f} |")


if __name__ == "__main__":
    main()
