#!/usr/bin/env python3
"""The post-merge stage (issue 19) against today's output: each mesh recombined with
same_nodes=true (the input's tets) and same_nodes=false (flips, edge contractions and node moves
close open quads, the selection runs again; with --flips-only also post_merge_contractions=false
and post_merge_moves=false, with --without-moves also post_merge_moves=false, with --with-splits
also post_merge_splits=true), each
checked by the independent checker (with the nodes the output declares changed: the boundary
and every region's volume verified).

Prints one Markdown row per mesh and run: cells, reduction, hexahedron volume, the census (hex
candidates whose every quad face is closed by the tets: on the input, after the stage), the
flips, contractions, node moves and vertex splits kept, the stage's time against the engine's, the checker's verdict, its volume differences
and the smallest scaled Jacobians (new elements; every element against the input's tets).
Writes the results as JSON.

  PYTHONPATH=src/python /usr/bin/python3.11 bench/postmerge.py                 # Delaunay 100k
  PYTHONPATH=src/python /usr/bin/python3.11 bench/postmerge.py --sizes 10k --option post_merge_rounds=1
"""
import argparse
import json
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import benchlib  # noqa: E402
import run_bench  # noqa: E402

# The stage's phases: census_before, census_after, post_merge_flips_<round>,
# post_merge_selection_<round>.
STAGE_PREFIXES = ("census", "post_merge")


def min_tet_scaled_jacobian(points, tets):
    """Verdict's scaled Jacobian of every tet (regular tet = 1), the smallest."""
    p = points[tets]
    worst = np.inf
    for v, (a, b, c) in enumerate(((1, 2, 3), (2, 0, 3), (0, 1, 3), (1, 0, 2))):
        e1, e2, e3 = p[:, a] - p[:, v], p[:, b] - p[:, v], p[:, c] - p[:, v]
        det = np.einsum("ij,ij->i", np.cross(e1, e2), e3)
        lengths = np.linalg.norm(e1, axis=1) * np.linalg.norm(e2, axis=1) * np.linalg.norm(e3, axis=1)
        worst = min(worst, float(np.min(np.sqrt(2.0) * np.abs(det) / lengths)))
    return worst


def run(hexmerge, points, tets, options):
    t0 = time.perf_counter()
    mesh, report = hexmerge.recombine(points, tets, **options)
    seconds = time.perf_counter() - t0
    check = hexmerge.check(mesh, points, tets)
    phases = report["phase_seconds"]
    stage = sum(v for k, v in phases.items() if k.startswith(STAGE_PREFIXES))
    flips = sum(v for k, v in phases.items() if k.startswith("post_merge_flips"))
    new_types = ("hex", "prism", "pyramid")
    return {
        "options": options,
        "seconds": seconds,
        "stage_seconds": stage,
        "flips_seconds": flips,
        "engine_seconds": sum(phases.values()) - stage,
        "report": report,
        "check": {k: check[k] for k in ("valid", "inverted_cells", "nonconforming_quads", "cracks",
                                       "moved_nodes", "unused_input_nodes",
                                       "declared_changed_nodes", "off_boundary_nodes",
                                       "volume_not_kept",
                                       "relative_volume_difference",
                                       "max_region_volume_difference", "min_scaled_jacobian")},
        "min_new_element_sj": min((report["min_scaled_jacobian"][t] for t in new_types
                                   if report["output_counts"][t]), default=None),
    }


def row(name, r, base_cells):
    rep, chk = r["report"], r["check"]
    hexv = 100.0 * rep["volume_fraction"]["hex"]
    fewer = 100.0 * (1.0 - rep["output_cells"] / base_cells)
    census = f"{rep['census_closable']} / {rep['census_hex_candidates']}"
    after = f"{rep['census_closable_after']} / {rep['census_hex_candidates_after']}"
    flips = (f"{rep['flips_23']} / {rep['flips_32']} / {rep['flips_44']} / {rep['contractions']}"
             f" / {rep['node_moves']} / {rep['vertex_splits']}")
    same = r["options"].get("same_nodes", True)
    if same:
        run = "true"
    elif r["options"].get("post_merge_splits", False):
        run = "false, splits"
    elif not r["options"].get("post_merge_contractions", True):
        run = "false, flips only"
    elif not r["options"].get("post_merge_moves", True):
        run = "false, no moves"
    else:
        run = "false"
    return (f"| {name} | {run} | {rep['output_cells']:,} | {fewer:.1f} | "
            f"{rep['element_reduction_percent']:.1f} | {hexv:.1f} | "
            f"{'' if same else census} | {'' if same else after} | {'' if same else flips} | "
            f"{rep['post_merge']} | {r['engine_seconds']:.2f} | {r['stage_seconds']:.2f} "
            f"({r['flips_seconds']:.2f}) | "
            f"{chk['valid']} | {chk['nonconforming_quads']} | {chk['cracks']} | "
            f"{chk['max_region_volume_difference']:.1e} | {r['min_new_element_sj']:.2f} | "
            f"{chk['min_scaled_jacobian']:.2f} |")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="*", help="mesh files instead of the benchmark set")
    ap.add_argument("--mesh-dir", default=run_bench.MESH_DIR)
    ap.add_argument("--sizes", default="100k")
    ap.add_argument("--shapes", default=",".join(run_bench.SHAPES))
    ap.add_argument("--kinds", default="delaunay")
    ap.add_argument("--option", action="append", default=[], metavar="NAME=VALUE",
                    help="extra option for both runs")
    ap.add_argument("--flips-only", action="store_true",
                    help="also run the stage with flips only (post_merge_contractions=false, "
                    "post_merge_moves=false)")
    ap.add_argument("--without-moves", action="store_true",
                    help="also run the stage without node moves (post_merge_moves=false)")
    ap.add_argument("--with-splits", action="store_true",
                    help="also run the stage with vertex splits (post_merge_splits=true)")
    ap.add_argument("--output", default=os.path.join(run_bench.RESULTS_DIR, "postmerge.json"))
    args = ap.parse_args()

    import hexmerge
    import meshio

    extra = {}
    for o in args.option:
        k, v = o.split("=", 1)
        extra[k.strip()] = run_bench.parse_value(v.strip())
    meshes = args.files or run_bench.find_meshes(args.shapes.split(","), args.kinds.split(","),
                                                 args.sizes.split(","), args.mesh_dir)
    print("| mesh | same_nodes | cells | fewer % | reduction % | hex vol. % | census before "
          "| census after | flips 2-3 / 3-2 / 4-4 / contractions / moves / splits | stage | engine s | stage s (flips) | valid "
          "| non-conf. | cracks | max region dV | min SJ new | min SJ all |")
    print("|" + "---|" * 18)
    results = {"commit": benchlib.git_commit(), "machine": benchlib.machine(), "meshes": {}}
    for path in meshes:
        m = meshio.read(path)
        points = np.asarray(m.points, dtype=float)
        tets = np.vstack([c.data for c in m.cells if c.type == "tetra"]).astype(np.int64)
        name = os.path.basename(path).rsplit(".", 1)[0]
        base = run(hexmerge, points, tets, dict(extra, same_nodes=True))
        cells = base["report"]["output_cells"]
        print(row(name, base, cells), flush=True)
        entry = {"input_min_tet_sj": min_tet_scaled_jacobian(points, tets), "same_nodes": base}
        for key, contract, moves, splits, wanted in (
                ("flips_only", False, False, False, args.flips_only),
                ("no_moves", True, False, False, args.without_moves),
                ("post_merge", True, True, False, True),
                ("splits", True, True, True, args.with_splits)):
            if not wanted:
                continue
            r = run(hexmerge, points, tets,
                    dict(extra, same_nodes=False, post_merge_contractions=contract,
                         post_merge_moves=moves, post_merge_splits=splits))
            print(row(name, r, cells), flush=True)
            entry[key] = r
        results["meshes"][name] = entry
    os.makedirs(os.path.dirname(args.output), exist_ok=True)
    with open(args.output, "w") as f:
        json.dump(benchlib.jsonable(results), f, indent=1)
    for name, r in results["meshes"].items():
        print(f"{name}: input min tet SJ {r['input_min_tet_sj']:.3f}")


if __name__ == "__main__":
    main()
