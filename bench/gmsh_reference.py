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

--hex-dominant runs Gmsh's own hex-dominant mesher instead (issue 13's comparison: Gmsh >= 4.12,
`-setnumber Mesh.Algorithm3D 9 -setnumber Mesh.Recombine3DAll 1`: frontal points along a frame
field, Delaunay, then its recombination into hexahedra) and measures its mixed mesh: the cells of
each type and their volume fractions (each cell split into tets), the zero-volume "trihedra" it
glues quads to triangles with, the quad faces against triangles (non-conforming: a quad face of a
cell that is no other cell's quad face while one of its triangles is another cell's face), the
smallest scaled Jacobian over the cells with volume (Verdict's, real_parts.CORNERS; Gmsh orders a
cell's vertices as hexmerge does) and those below 0.2, and the volume of its conforming hexahedra
(no quad face against triangles: the ones a conforming mesh made from Gmsh's keeps, every other
hexahedron split; `usable_hex_fraction`: of those, scaled Jacobian 0.2 or more). Results:
bench/results/gmsh-reference-hexdominant.json;
its table puts hexmerge's hex volume of the same part at the same h beside Gmsh's (--ours, default
bench/results/real-parts-latest.json). Debian 12's Gmsh 4.8.4 is too old: bench/fetch_gmsh.py
unpacks Debian 13's 4.13.1; --gmsh (or $HEXMERGE_GMSH) names the Gmsh to run.

Usage:
  /usr/bin/python3.11 bench/gmsh_reference.py                       # every part, 50k and 250k
  /usr/bin/python3.11 bench/gmsh_reference.py --parts Block,t20 --targets 50k
  /usr/bin/python3.11 bench/gmsh_reference.py --table bench/results/gmsh-reference.json
  /usr/bin/python3.11 bench/gmsh_reference.py --hex-dominant --gmsh ~/.cache/hexmerge/gmsh-trixie/gmsh
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
HEX_OUTPUT = os.path.join(benchlib.RESULTS_DIR, "gmsh-reference-hexdominant.json")
GMSH_OPTIONS = ["-3", "-clmax", "{h}", "-format", "msh2"]  # then -o OUT; FILE comes first
HEX_DOMINANT = ["-setnumber", "Mesh.Algorithm3D", "9", "-setnumber", "Mesh.Recombine3DAll", "1"]
# Gmsh's element types (its GmshDefines.h) of the volume cells: name, hexmerge's CellType index
# (real_parts.CORNERS), faces (Gmsh's vertex order), tets the cell's volume is summed over.
TRIHEDRON = 140  # MSH_TRIH_4: a quad glued to two triangles, no volume
CELLS = {
    4: ("tet", 0, [(1, 2, 3), (0, 2, 3), (0, 1, 3), (0, 1, 2)], [(0, 1, 2, 3)]),
    7: ("pyramid", 1, [(0, 1, 2, 3), (0, 1, 4), (1, 2, 4), (2, 3, 4), (3, 0, 4)], [(0, 1, 2, 4), (0, 2, 3, 4)]),
    6: ("prism", 2, [(0, 1, 4, 3), (1, 2, 5, 4), (2, 0, 3, 5), (0, 1, 2), (3, 4, 5)],
        [(0, 1, 2, 3), (1, 2, 3, 4), (2, 3, 4, 5)]),
    5: ("hex", 3, [(0, 1, 2, 3), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)],
        [(0, 1, 2, 6), (0, 2, 3, 6), (0, 3, 7, 6), (0, 7, 4, 6), (0, 4, 5, 6), (0, 5, 1, 6)]),
}
ANGLE_FLOOR = 5.0  # issue 13: no boundary triangle angle below 5 degrees
# The lines of Gmsh's error summary box (after the messages themselves).
SUMMARY = re.compile(r"^(Warning|Error)\s*:\s*(-+|Mesh generation error summary|\d+ (warning|error)s?"
                     r"|Check the full log for details)$")


def gmsh_version(gmsh: str = "gmsh") -> str:
    """What `gmsh --version` prints (4.8.4 on Debian 12)."""
    p = subprocess.run([gmsh, "--version"], capture_output=True, text=True)
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


def read_msh2(msh: str):
    """Points (n x 3) and the elements by Gmsh type (type -> m x k vertex indices) of an ASCII
    MSH 2.2 file (meshio knows no trihedra)."""
    import numpy as np

    with open(msh) as f:
        lines = iter(f.read().splitlines())
    points, index, cells = np.zeros((0, 3)), {}, {}
    for line in lines:
        if line == "$Nodes":
            n = int(next(lines))
            rows = [next(lines).split() for _ in range(n)]
            index = {int(r[0]): i for i, r in enumerate(rows)}
            points = np.array([[float(x) for x in r[1:4]] for r in rows])
        elif line == "$Elements":
            for _ in range(int(next(lines))):
                r = next(lines).split()
                kind, tags = int(r[1]), int(r[2])
                cells.setdefault(kind, []).append([index[int(v)] for v in r[3 + tags:]])
    return points, {k: np.array(v, dtype=np.int64) for k, v in cells.items()}


def measure_mixed(msh: str) -> dict:
    """Gmsh's hex-dominant mesh measured: cells, volume fractions, trihedra, quads against
    triangles, scaled Jacobians (see the module's docstring)."""
    import numpy as np

    points, cells = read_msh2(msh)
    row = {"cells": {}, "volume_fraction": {}, "trihedra": int(len(cells.get(TRIHEDRON, [])))}
    volume, sj, quads, triangles = {}, [], [], []
    hex_faces, hex_volume, hex_sj = [], None, None  # the hexahedra's sorted faces, volumes, scaled Jacobians
    for kind, (name, t, faces, split) in CELLS.items():
        c = cells.get(kind, np.zeros((0, 1 + max(max(f) for f in faces)), np.int64))
        row["cells"][name] = int(len(c))
        p = points[c]
        vol = np.zeros(len(c))
        for a, b, d, e in split:
            vol += np.abs(np.einsum("ij,ij->i", p[:, b] - p[:, a], np.cross(p[:, d] - p[:, a], p[:, e] - p[:, a]))) / 6
        volume[name] = float(vol.sum())
        if len(c):
            corners, scale = real_parts.CORNERS[t]
            sj.append(real_parts.corner_scaled_jacobians(p, corners, scale))
        if name == "hex":
            hex_volume = vol
            hex_sj = sj[-1] if len(c) else np.zeros(0)
        for f in faces:
            keys = np.sort(c[:, list(f)], axis=1)
            (quads if len(f) == 4 else triangles).append(keys)
            if name == "hex":
                hex_faces.append(keys)
    if not sj:  # no volume cells: the caller's row says so
        row["tets"] = 0
        return row
    total = sum(volume.values())
    row["volume_fraction"] = {k: v / total for k, v in volume.items()}
    row["volume"] = total
    sj = np.concatenate(sj)
    row.update(min_sj=float(sj.min()), below_sj_floor=int((sj < real_parts.SJ_FLOOR).sum()),
               nonpositive_sj=int((sj <= 0).sum()), tets=row["cells"]["tet"])
    # A quad face of one cell only, one of whose four triangles is a face of a cell: against triangles.
    quads = np.concatenate(quads)
    quads, counts = np.unique(quads, axis=0, return_counts=True)
    alone = quads[counts == 1]
    tri = {tuple(f) for f in np.concatenate(triangles).tolist()}
    against = {tuple(q) for q in alone.tolist()
               if any(tuple(sorted(q[i] for i in k)) in tri for k in ((0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3)))}
    row["nonconforming_quads"] = len(against)
    # The hexahedra a conforming mesh could keep as they are: no quad face against triangles (each
    # meets another cell's quad or the boundary); of those, the ones a solver can use (scaled
    # Jacobian at least the 0.2). Fractions of the whole volume, as the hex volume.
    if len(hex_volume):
        open_face = np.zeros(len(hex_volume), dtype=bool)
        for keys in hex_faces:
            open_face |= np.array([tuple(k) in against for k in keys.tolist()])
        conforming = ~open_face
        row["conforming_hexes"] = int(conforming.sum())
        row["conforming_hex_fraction"] = float(hex_volume[conforming].sum() / total)
        usable = conforming & (hex_sj >= real_parts.SJ_FLOOR)
        row["usable_hexes"] = int(usable.sum())
        row["usable_hex_fraction"] = float(hex_volume[usable].sum() / total)
    return row


def run(name: str, path: str, target: str, h, args) -> dict:
    """Gmsh's tet mesh of one part at one size, measured: the result row."""
    row = {"part": name, "target": target, "h": h, "file": os.path.basename(path)}
    if h is None:
        row.update(status="error", error="no h for this part and target in the sizes file")
        return row
    with tempfile.TemporaryDirectory(prefix="gmsh-reference-") as work:
        out = os.path.join(work, "tets.msh")
        cmd = ([args.gmsh, os.path.abspath(path)] + [o.format(h=repr(h)) for o in options(args)]
               + shlex.split(args.gmsh_args) + ["-o", out])
        # In the temporary folder: the hex-dominant mesher writes its points to new_points.pos there.
        kind, payload, err, seconds = benchlib.run_worker(cmd, args.timeout, None, int(args.memory * 2**30), work)
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
                row.update(measure_mixed(out) if args.hex_dominant else measure(out))
                row["status"] = "ok" if row["tets"] or row.get("cells", {}).get("hex") else "error"
                if row["status"] != "ok":
                    row["error"] = "no cells in Gmsh's mesh"
            except Exception as e:  # an unreadable mesh is the result
                row.update(status="error", error=real_parts.first_line(e))
    print(f"  {name} {target} h {h:.4g}: {row['status']}"
          + (f", {row['tets']:,} tets, min SJ {row['min_sj']:.3g}" if row.get("tets") else "")
          + (f", hex volume {100 * row['volume_fraction']['hex']:.1f} %" if row.get("volume_fraction") else "")
          + (f", {row['error']}" if row.get("error") else "") + f" ({row['gmsh_s']:.1f} s)",
          file=sys.stderr, flush=True)
    return row


def options(args) -> list:
    """Gmsh's options after FILE ({h} for the size), before --gmsh-args and -o OUT."""
    return GMSH_OPTIONS + (HEX_DOMINANT if args.hex_dominant else [])


# --------------------------------------------------------------------------- table
def median(values):
    values = sorted(values)
    n = len(values)
    return (values[(n - 1) // 2] + values[n // 2]) / 2 if n else float("nan")


def heading(data) -> str:
    """The line that heads a table: commit, machine, date, Gmsh and its command, run options."""
    m, o = data["machine"], data["options"]
    return (f"Commit `{data['commit']}`, {m['nproc']} CPUs ({m['cpu_model']}), {data['date']}; "
            f"Gmsh {data['gmsh_version']}: `{data['command']}`; timeout {o['timeout']:g} s, "
            f"{o['jobs']} run(s) at a time; h from `{o['sizes_from']}`")


def sorted_rows(data) -> list:
    """The rows by target (in the options' order), then part."""
    targets = data["options"]["targets"]
    return sorted(data["rows"], key=lambda r: (targets.index(r["target"]) if r["target"] in targets
                                               else len(targets), r["part"].lower()))


def markdown_hex(data, ours) -> str:
    """The hex-dominant table: Gmsh's cells beside hexmerge's hex volume at the same h."""
    o = data["options"]
    mine = {(r["part"], r["target"]): r for r in (ours or {}).get("rows", []) if r.get("status") == "ok"}
    lines = [heading(data) + f"; hexmerge: `{(ours or {}).get('commit', 'none')}`.", "",
             "| part | target | h | status | Gmsh s | hexahedra | prisms | pyramids | tets | trihedra "
             "| quads against triangles | min SJ | # SJ < 0.2 | Gmsh hex vol % | Gmsh conforming hex vol % "
             "| hexmerge hex vol % (same h) |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    rows = sorted_rows(data)

    def hexmerge_hex(r):
        h = mine.get((r["part"], r["target"]))
        return 100 * h["volume_fraction"]["hex"] if h and abs(h["h"] - r["h"]) <= 1e-9 * r["h"] else None

    for r in rows:
        status = r["status"] if r["status"] == "ok" else real_parts.short(f"{r['status']}: {r.get('error', '')}")
        c = r.get("cells", {})
        ok = r["status"] == "ok"
        ours_hex = hexmerge_hex(r)
        lines.append(" | ".join([
            f"| {r['part']}", r["target"], real_parts.cell(r, "h", ".4g"), status, real_parts.cell(r, "gmsh_s", ".1f")]
            + [f"{c[k]:,}" if ok else "–" for k in ("hex", "prism", "pyramid", "tet")]
            + [real_parts.cell(r, "trihedra", ","), real_parts.cell(r, "nonconforming_quads", ","),
               real_parts.cell(r, "min_sj", ".3g"), real_parts.cell(r, "below_sj_floor", ","),
               f"{100 * r['volume_fraction']['hex']:.1f}" if ok else "–",
               f"{100 * r['conforming_hex_fraction']:.1f}" if ok and "conforming_hex_fraction" in r else "–",
               f"{ours_hex:.1f}" if ours_hex is not None else "–"]) + " |")
    lines.append("")
    for target in o["targets"]:
        here = [r for r in rows if r["target"] == target]
        ok = [r for r in here if r["status"] == "ok"]
        both = [(100 * r["volume_fraction"]["hex"], hexmerge_hex(r)) for r in ok if hexmerge_hex(r) is not None]
        conforming = [(100 * r["conforming_hex_fraction"], hexmerge_hex(r)) for r in ok
                      if hexmerge_hex(r) is not None and "conforming_hex_fraction" in r]
        lines.append(
            f"- {target}: Gmsh meshed {len(ok)} of {len(here)} parts, median hex volume "
            f"{median([100 * r['volume_fraction']['hex'] for r in ok]):.1f} %, "
            f"{sum(r['nonconforming_quads'] for r in ok):,} quads against triangles and "
            f"{sum(r['trihedra'] for r in ok):,} trihedra in all; on the {len(both)} parts both meshed at the "
            f"same h: median hex volume Gmsh {median([g for g, _ in both]):.1f} %, hexmerge "
            f"{median([h for _, h in both]):.1f} %; hexmerge at least Gmsh's on {sum(1 for g, h in both if h >= g)}"
            + (f"; Gmsh's conforming hexahedra (no quad face against triangles) median "
               f"{median([g for g, _ in conforming]):.1f} % of the volume ({min(g for g, _ in conforming):.1f} to "
               f"{max(g for g, _ in conforming):.1f}), hexmerge at least that on "
               f"{sum(1 for g, h in conforming if h >= g)} of {len(conforming)}" if conforming else ""))
    return "\n".join(lines)


def markdown(data) -> str:
    o = data["options"]
    lines = [heading(data) + ".", "",
             "| part | target | h | status | Gmsh s | Gmsh tets | min SJ | # SJ < 0.2 | min boundary angle ° "
             "| # boundary triangles < 5° |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    rows = sorted_rows(data)
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
    ap.add_argument("--gmsh", default=os.environ.get("HEXMERGE_GMSH", "gmsh"),
                    help="the Gmsh to run (default: $HEXMERGE_GMSH, else gmsh; bench/fetch_gmsh.py for 4.13)")
    ap.add_argument("--hex-dominant", action="store_true",
                    help="Gmsh's hex-dominant mesher and its mixed mesh measured (default output "
                         "bench/results/gmsh-reference-hexdominant.json)")
    ap.add_argument("--ours", default=real_parts.RESULTS,
                    help="hexmerge's results beside Gmsh's in the hex-dominant table (default: %(default)s)")
    ap.add_argument("--timeout", type=float, default=300, help="seconds per Gmsh run (default: %(default)s)")
    ap.add_argument("--memory", type=float, default=8, help="GB of address space per run (default: %(default)s)")
    ap.add_argument("--jobs", type=int, default=1, help="Gmsh runs at a time (default: %(default)s)")
    ap.add_argument("--output", help=f"results JSON (default: {os.path.relpath(OUTPUT, benchlib.ROOT)}, "
                                     f"with --hex-dominant {os.path.relpath(HEX_OUTPUT, benchlib.ROOT)})")
    ap.add_argument("--table", metavar="JSON", help="print the table of an earlier results file and exit")
    args = ap.parse_args()

    args.output = args.output or (HEX_OUTPUT if args.hex_dominant else OUTPUT)

    def table(data) -> str:
        if "cells" not in next((r for r in data["rows"] if r["status"] == "ok"), {}):
            return markdown(data)
        ours = None
        if args.ours and os.path.exists(args.ours):
            with open(args.ours) as f:
                ours = json.load(f)
        return markdown_hex(data, ours)

    if args.table:
        with open(args.table) as f:
            print(table(json.load(f)))
        return 0

    benchlib.stop_workers_on_signals()
    with open(args.sizes_from) as f:
        sizes = json.load(f).get("parts", {})
    targets = [t.strip().lower() for t in args.targets.split(",") if t.strip()]
    targets.sort(key=real_parts.parse_count)
    command = " ".join(["gmsh FILE"] + [o.format(h="H") for o in options(args)]
                       + shlex.split(args.gmsh_args) + ["-o OUT"])
    header = {"commit": benchlib.git_commit(), "machine": benchlib.machine(),
              "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
              "gmsh_version": gmsh_version(args.gmsh), "command": command,
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
    print(table(dict(header, rows=rows)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
