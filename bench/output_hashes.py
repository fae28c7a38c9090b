#!/usr/bin/python3.11
"""Fingerprints of hexmerge.recombine's output, to check that a change leaves it identical.

For every mesh and thread count: a SHA-1 of the output mesh's arrays (types, offsets, cell
vertices, points, point map, regions, source tets) and the report without its timings. Writes
them as JSON; with --compare OLD.json, reports every difference (exit status 1 when any).

Usage (after building the module, see bench/README.md):
  PYTHONPATH=src/python /usr/bin/python3.11 bench/output_hashes.py --output /tmp/before.json
  ... output_hashes.py --output /tmp/after.json --compare /tmp/before.json
  ... output_hashes.py --sizes 10k --threads 1 --option conformity=allow
"""
import argparse
import hashlib
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import benchlib  # noqa: E402
import run_bench  # noqa: E402  (find_meshes, parse_value)

ARRAYS = ["types", "offsets", "cell_vertices", "points", "point_map", "regions",
          "source_offsets", "source_tets", "quadratic_offsets", "quadratic_nodes"]


def fingerprint(mesh, report):
    import numpy as np
    h = hashlib.sha1()
    for name in ARRAYS:
        a = getattr(mesh, name, None)
        h.update(name.encode())
        if a is not None:
            a = np.ascontiguousarray(a)
            h.update(str(a.dtype).encode() + str(a.shape).encode())
            h.update(a.tobytes())
    rep = {k: v for k, v in benchlib.jsonable(report).items() if k != "phase_seconds"}
    return h.hexdigest(), rep


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="*", help="mesh files instead of the benchmark set")
    ap.add_argument("--mesh-dir", default=run_bench.MESH_DIR)
    ap.add_argument("--sizes", default="10k,100k")
    ap.add_argument("--shapes", default=",".join(run_bench.SHAPES))
    ap.add_argument("--kinds", default="delaunay,tetgen-lattice")
    ap.add_argument("--threads", default="1,2", help="thread counts to run each mesh with")
    ap.add_argument("--option", action="append", default=[], metavar="NAME=VALUE")
    ap.add_argument("--output", required=True, help="JSON file to write")
    ap.add_argument("--compare", metavar="JSON", help="an earlier output to compare with")
    args = ap.parse_args()

    import hexmerge

    options = {}
    for o in args.option:
        k, v = o.split("=", 1)
        options[k.strip()] = run_bench.parse_value(v.strip())
    sizes = [s for s in args.sizes.split(",") if s]
    meshes = args.files or run_bench.find_meshes(args.shapes.split(","), args.kinds.split(","),
                                                 sizes, args.mesh_dir)
    results = {}
    for path in meshes:
        points, cells = run_bench.load_tet_mesh(path)
        for threads in [int(t) for t in args.threads.split(",")]:
            mesh, report = hexmerge.recombine(points, cells, threads=threads, **options)
            sha, rep = fingerprint(mesh, report)
            key = f"{os.path.basename(path)} threads={threads}"
            ps = report.get("phase_seconds")
            results[key] = {"sha1": sha, "report": rep,
                            "phase_seconds": benchlib.jsonable(ps)}
            print(f"{key}: {sha[:12]} {rep.get('output_counts')}", file=sys.stderr, flush=True)
    with open(args.output, "w") as f:
        json.dump(results, f, indent=1)

    if not args.compare:
        return 0
    return benchlib.compare_hashes(results, args.compare)

if __name__ == "__main__":
    sys.exit(main())
