#!/usr/bin/python3.11
"""Gmsh's own tet mesh of the real parts at the real-parts benchmark's sizes (issue 13).

Issue 13 asks for no worse a minimum than "Gmsh's own optimised tet mesh of the same part at the
same size". This script measures that reference: every part of bench/real_parts.py (its
find_parts: the shared CAD folder, bench/geometry's generated parts made into STEP by `gmsh -0`,
an --extra folder), at each target count (--targets, default 50k,250k), is meshed by the Gmsh
command line at the h of the real-parts sizes file (--sizes-from, default
bench/results/real-parts-sizes.json; the h is there even where hexmerge failed):

    gmsh FILE -3 -clmax H -format msh2 -o OUT [--gmsh-args ...]

Gmsh's defaults otherwise: Delaunay 3D and its default tet optimisation (Mesh.Optimize 1).
`-optimize_netgen` is not in it: Debian 12's gmsh 4.8.4 has no Netgen ("Netgen optimizer is not
compiled in this version of Gmsh"); --gmsh-args adds options to try. Each run is in a temporary
folder, in a session of its own with a timeout (--timeout, default 300 s) and an address-space
limit (--memory, default 8 GB): status ok, error (Gmsh's first `Error` line), crash (a signal)
or timeout.

Measures on the tets of the .msh (read with meshio), with bench/real_parts.py's functions (the
ones its benchmark uses on hexmerge's meshes): tets, the smallest scaled Jacobian
(tet_scaled_jacobians, Verdict's, the checker's measure) and the tets below 0.2, the smallest
corner angle of the boundary triangles (boundary_triangle_angles: faces of one tet only) and the
boundary triangles below 5 degrees.

Results: bench/results/gmsh-reference.json (--output; written after every run), a Markdown table
on stdout. bench/real_parts.py --table adds its "Gmsh min SJ" and "Gmsh min boundary angle"
columns from it.

Usage:
  /usr/bin/python3.11 bench/gmsh_reference.py                       # every part, 50k and 250k
  /usr/bin/python3.11 bench/gmsh_reference.py --parts Block,t20 --targets 50k
  /usr/bin/python3.11 bench/gmsh_reference.py --table bench/results/gmsh-reference.json
"""
import argparse
import concurrent.futures
import contextlib
import datetime
import io
import json
import os
import re
import shlex
import signal
import subprocess
import sys
import tempfile
import threading

import benchlib
import real_parts

OUTPUT = os.path.join(benchlib.RESULTS_DIR, "gmsh-reference.json")
GMSH_OPTIONS = ["-3", "-clmax", "{h}", "-format", "msh2"]  # then -o OUT; FILE comes first
ANGLE_FLOOR = 5.0  # issue 13: no boundary triangle angle below 5 degrees
# The lines of Gmsh's error summary box (after the messages themselves).
SUMMARY = re.compile(r"^(Warning|Error)\s*:\s*(-+|Mesh generation error summary|\d+ (warning|error)s?"
                     r"|Check the full log for details)$")


def gmsh_version() -> str:
    """What `gmsh --version` prints (4.8.4 on Debian 12)."""
    p = subprocess.run(["gmsh", "--version"], capture_output=True, text=True)
    return (p.stdout + p.stderr).strip()


def gmsh_lines(stderr: str, kind: str) -> list:
    """Gmsh's distinct lines of a kind ("Error", "Warning"), without its error summary box."""
    out = []
    for line in stderr.splitlines():
        line = " ".join(line.split())
        if line.startswith(kind) and not SUMMARY.match(line):
            line = re.sub(r"^(\w+) : ", r"\1: ", line)  # "Error   : x" -> "Error: x"
            if line not in out:
                out.append(line)
    return out


def gmsh_error(stderr: str) -> str:
    """Gmsh's first `Error` line, else its last non-empty line."""
    errors = gmsh_lines(stderr, "Error")
    lines = [line.strip() for line in stderr.splitlines() if line.strip()]
    return errors[0] if errors else (lines[-1] if lines else "")


def measure(msh: str) -> dict:
    """Tets, scaled Jacobians and boundary angles of the first-order tets of a .msh file."""
    import meshio
    import numpy as np

    with contextlib.redirect_stdout(io.StringIO()):  # meshio's msh reader prints an empty line
        mesh = meshio.read(msh)
    tets = [block.data for block in mesh.cells if block.type == "tetra"]
    if not tets:
        return {"tets": 0}
    tets = np.concatenate(tets).astype(np.int64)
    points = np.asarray(mesh.points, dtype=float)
    sj = real_parts.tet_scaled_jacobians(points, tets)
    angles = real_parts.boundary_triangle_angles(points, tets)
    volumes = [block_tags for block_tags, block in zip(mesh.cell_data.get("gmsh:geometrical", []), mesh.cells)
               if block.type == "tetra"]
    return {"tets": len(tets), "points": int(len(np.unique(tets))),
            "volumes": int(len(np.unique(np.concatenate(volumes)))) if volumes else None,
            "min_sj": float(sj.min()), "below_sj_floor": int((sj < real_parts.SJ_FLOOR).sum()),
            "nonpositive_sj": int((sj <= 0).sum()),
            "boundary_triangles": len(angles), "min_boundary_angle": float(angles.min()),
            "boundary_below_angle_floor": int((angles < ANGLE_FLOOR).sum())}


def run(name: str, path: str, target: str, h, args) -> dict:
    """Gmsh's tet mesh of one part at one size, measured: the result row."""
    row = {"part": name, "target": target, "h": h, "file": os.path.basename(path)}
    if h is None:
        row.update(status="error", error="no h for this part and target in the sizes file")
        return row
    with tempfile.TemporaryDirectory(prefix="gmsh-reference-") as work:
        out = os.path.join(work, "tets.msh")
        cmd = (["gmsh", os.path.abspath(path)] + [o.format(h=repr(h)) for o in GMSH_OPTIONS]
               + shlex.split(args.gmsh_args) + ["-o", out])
        kind, payload, err, seconds = benchlib.run_worker(cmd, args.timeout, None, int(args.memory * 2**30))
        row["gmsh_s"] = seconds
        row["warnings"] = gmsh_lines(err, "Warning")[:5]
        if kind == "timeout":
            row.update(status="timeout", error=f"timeout after {args.timeout:g} s")
        elif payload < 0:
            sig = signal.Signals(-payload).name if -payload in signal.valid_signals() else str(-payload)
            row.update(status="crash", error=f"signal {sig}: {gmsh_error(err)}".rstrip(": "))
        elif payload != 0 or not os.path.exists(out):
            row.update(status="error", error=f"exit {payload}: {gmsh_error(err)}".rstrip(": "))
        else:
            try:
                row.update(measure(out))
                row["status"] = "ok" if row["tets"] else "error"
                if not row["tets"]:
                    row["error"] = "no tets in Gmsh's mesh"
            except Exception as e:  # an unreadable mesh is the result
                row.update(status="error", error=real_parts.first_line(e))
    print(f"  {name} {target} h {h:.4g}: {row['status']}"
          + (f", {row['tets']:,} tets, min SJ {row['min_sj']:.3g}" if row.get("tets") else "")
          + (f", {row['error']}" if row.get("error") else "") + f" ({row['gmsh_s']:.1f} s)",
          file=sys.stderr, flush=True)
    return row


# --------------------------------------------------------------------------- table
def markdown(data) -> str:
    m = data["machine"]
    o = data["options"]
    lines = [f"Commit `{data['commit']}`, {m['nproc']} CPUs ({m['cpu_model']}), {data['date']}; "
             f"Gmsh {data['gmsh_version']}: `{data['command']}`; timeout {o['timeout']:g} s, "
             f"{o['jobs']} run(s) at a time; h from `{o['sizes_from']}`.", "",
             "| part | target | h | status | Gmsh s | Gmsh tets | min SJ | # SJ < 0.2 | min boundary angle ° "
             "| # boundary triangles < 5° |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    rows = sorted(data["rows"], key=lambda r: (o["targets"].index(r["target"]) if r["target"] in o["targets"]
                                               else len(o["targets"]), r["part"].lower()))
    for r in rows:
        status = r["status"] if r["status"] == "ok" else real_parts.short(f"{r['status']}: {r.get('error', '')}")
        lines.append(" | ".join([
            f"| {r['part']}", r["target"], real_parts.cell(r, "h", ".4g"), status, real_parts.cell(r, "gmsh_s", ".1f"),
            real_parts.cell(r, "tets", ","), real_parts.cell(r, "min_sj", ".3g"),
            real_parts.cell(r, "below_sj_floor", ","), real_parts.cell(r, "min_boundary_angle", ".3g"),
            real_parts.cell(r, "boundary_below_angle_floor", ",")]) + " |")
    lines.append("")
    for target in o["targets"]:
        ok = [r for r in rows if r["target"] == target and r["status"] == "ok"]
        total = sum(1 for r in rows if r["target"] == target)
        lines.append(f"- {target}: Gmsh meshed {len(ok)} of {total} parts; min SJ >= {real_parts.SJ_FLOOR} on "
                     f"{sum(1 for r in ok if r['min_sj'] >= real_parts.SJ_FLOOR)}, min boundary angle >= "
                     f"{ANGLE_FLOOR:g}° on {sum(1 for r in ok if r['min_boundary_angle'] >= ANGLE_FLOOR)}"
                     + (f"; worst min SJ {min(r['min_sj'] for r in ok):.3g}" if ok else ""))
    return "\n".join(lines)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cad", default=real_parts.DEFAULT_CAD, help="folder of the shared real parts (default: %(default)s)")
    ap.add_argument("--extra", help="another folder of parts (STEP, BREP, IGES or Gmsh .geo files)")
    ap.add_argument("--no-generated", action="store_true", help="leave out bench/geometry's generated parts")
    ap.add_argument("--parts", help="comma list; a part runs when its name holds one of them")
    ap.add_argument("--sizes-from", metavar="JSON", default=real_parts.SIZES_FILE,
                    help="the h per part and target (default: %(default)s)")
    ap.add_argument("--targets", default="50k,250k", help="target tet counts of the sizes file (default: %(default)s)")
    ap.add_argument("--gmsh-args", default="", help="more Gmsh options, appended (e.g. '-nt 1')")
    ap.add_argument("--timeout", type=float, default=300, help="seconds per Gmsh run (default: %(default)s)")
    ap.add_argument("--memory", type=float, default=8, help="GB of address space per run (default: %(default)s)")
    ap.add_argument("--jobs", type=int, default=1, help="Gmsh runs at a time (default: %(default)s)")
    ap.add_argument("--output", default=OUTPUT, help="results JSON (default: %(default)s)")
    ap.add_argument("--table", metavar="JSON", help="print the table of an earlier results file and exit")
    args = ap.parse_args()

    if args.table:
        with open(args.table) as f:
            print(markdown(json.load(f)))
        return 0

    benchlib.stop_workers_on_signals()
    with open(args.sizes_from) as f:
        sizes = json.load(f).get("parts", {})
    targets = [t.strip().lower() for t in args.targets.split(",") if t.strip()]
    targets.sort(key=real_parts.parse_count)
    command = " ".join(["gmsh FILE"] + [o.format(h="H") for o in GMSH_OPTIONS]
                       + shlex.split(args.gmsh_args) + ["-o OUT"])
    header = {"commit": benchlib.git_commit(), "machine": benchlib.machine(),
              "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
              "gmsh_version": gmsh_version(), "command": command,
              "options": {"timeout": args.timeout, "memory": args.memory, "jobs": args.jobs, "targets": targets,
                          "sizes_from": os.path.relpath(os.path.abspath(args.sizes_from), benchlib.ROOT),
                          "gmsh_args": args.gmsh_args}}
    rows = []
    lock = threading.Lock()

    def one(job):
        row = run(*job, args)
        with lock:
            rows.append(row)
            os.makedirs(os.path.dirname(os.path.abspath(args.output)), exist_ok=True)
            with open(args.output + ".tmp", "w") as f:
                json.dump(benchlib.jsonable(dict(header, rows=rows)), f, indent=1)
            os.replace(args.output + ".tmp", args.output)

    with tempfile.TemporaryDirectory() as work:
        parts = real_parts.find_parts(args, work)
        if not parts:
            print("gmsh_reference: no parts to run", file=sys.stderr)
            return 1
        missing = [n for n, _ in parts if n not in sizes]
        if missing:
            print(f"gmsh_reference: no sizes for {', '.join(missing)} in {args.sizes_from}", file=sys.stderr)
        jobs = [(name, path, target, sizes.get(name, {}).get(target, {}).get("h"))
                for target in targets for name, path in parts]
        print(f"gmsh_reference: {len(parts)} parts, targets {', '.join(targets)}: {command}", file=sys.stderr)
        with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
            list(pool.map(one, jobs))
    print(markdown(dict(header, rows=rows)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
