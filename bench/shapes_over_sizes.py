#!/usr/bin/python3.11
"""Shapes over sizes (issue 13): hexmerge.mesh_shape on generated shapes at many sizes.

The real-parts benchmark runs each part at two sizes; a mesher that works there can still fail,
or leave poor elements, at the size in between. This one meshes shapes the mesher was not tuned
on (bench/geometry: a filleted block, a stepped flange turned about an axis, a hollow box with a
rib, a drilled ball, a loft through ellipses, a gear, a filleted keyed shaft, four touching
solids, a plate turned off the axes, a quarter-torus tube; each .geo file says what it is) at
--steps sizes each, from a sixth of its largest extent down by a factor 1.3 each (defaults: 8
sizes, 300 to 200k tets), meshed and recombined with the defaults (conforming).

Each run: status (ok, or the error's first line), tets, hex volume, the smallest scaled Jacobian
of the output's elements and how many are under 0.2. Results as JSON (--output) and a table on
stdout; --compare FILE prints both side by side with the totals.

Usage (after building the module, see bench/README.md):
  PYTHONPATH=src/python /usr/bin/python3.11 bench/shapes_over_sizes.py --output /tmp/shapes.json
  ... shapes_over_sizes.py --shapes gear,hollow_box --steps 4
  ... shapes_over_sizes.py --compare /tmp/before.json --output /tmp/after.json
"""
import argparse
import json
import os
import statistics
import sys
import tempfile
import time

import benchlib
import real_parts

# The shapes (bench/geometry/NAME.geo) and their largest extent (mm), from which the sizes go.
SHAPES = {"fillet_block": 60, "revolved_flange": 100, "hollow_box": 80, "drilled_ball": 50,
          "loft_blade": 80, "gear": 60, "keyed_shaft": 130, "stacked_assembly": 60,
          "rotated_plate": 120, "elbow_pipe": 100}
SJ_FLOOR = real_parts.SJ_FLOOR


def run(brep: str, h: float) -> dict:
    import hexmerge
    start = time.perf_counter()
    try:
        mesh, report = hexmerge.mesh_shape(brep, h)
    except Exception as e:  # an InputError (or a crash of ours): the failure is the result
        return {"status": f"error: {str(e).splitlines()[0]}"}
    sj = real_parts.scaled_jacobians(mesh)
    return {"status": "ok", "seconds": time.perf_counter() - start,
            "tets": int(report["meshing"]["tets"]),
            "hex": float(report["volume_fraction"]["hex"]), "min_sj": float(sj.min()),
            "below": int((sj < SJ_FLOOR).sum())}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shapes", help="comma-separated names (default: all)")
    parser.add_argument("--steps", type=int, default=8, help="sizes per shape")
    parser.add_argument("--output", help="write the results here (JSON)")
    parser.add_argument("--compare", help="results of an earlier run (JSON) to print beside")
    args = parser.parse_args()
    names = args.shapes.split(",") if args.shapes else list(SHAPES)
    unknown = [n for n in names if n not in SHAPES]
    if unknown:
        print(f"unknown shapes: {', '.join(unknown)}", file=sys.stderr)
        return 2
    before = {}
    if args.compare:
        with open(args.compare) as f:
            before = {(r["shape"], round(r["h"], 6)): r for r in json.load(f)["rows"]}
    rows = []
    with tempfile.TemporaryDirectory(prefix="shapes-over-sizes-") as work:
        for name in names:
            brep = benchlib.geo_to_cad(os.path.join(benchlib.GEOMETRY_DIR, name + ".geo"),
                                       os.path.join(work, name + ".brep"))
            for k in range(args.steps):
                h = SHAPES[name] / (6 * 1.3 ** k)
                row = dict(shape=name, h=h, **run(brep, h))
                rows.append(row)
                old = before.get((name, round(h, 6)))
                line = f"{name:18s} h {h:7.3f} " + cell(row)
                if old:
                    line += "   before: " + cell(old)
                print(line, flush=True)
    ok = [r for r in rows if r["status"] == "ok"]
    print(f"\n{len(ok)} of {len(rows)} meshed; elements under {SJ_FLOOR}: "
          f"{sum(r['below'] for r in ok):,}; median hex volume "
          f"{100 * statistics.median(r['hex'] for r in ok) if ok else 0:.1f} %")
    if before:
        old = [r for r in before.values() if r["status"] == "ok"]
        print(f"before: {len(old)} of {len(before)} meshed; elements under {SJ_FLOOR}: "
              f"{sum(r['below'] for r in old):,}; median hex volume "
              f"{100 * statistics.median(r['hex'] for r in old) if old else 0:.1f} %")
    if args.output:
        with open(args.output, "w") as f:
            json.dump({"commit": benchlib.git_commit(), "machine": benchlib.machine(),
                       "rows": rows}, f, indent=1)
    return 0 if len(ok) == len(rows) else 1


def cell(row: dict) -> str:
    if row["status"] != "ok":
        return row["status"]
    return (f"{row['tets']:7d} tets  hex {100 * row['hex']:5.1f} %  min SJ {row['min_sj']:.3f}  "
            f"under {SJ_FLOOR}: {row['below']}")


if __name__ == "__main__":
    sys.exit(main())
