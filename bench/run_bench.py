#!/usr/bin/python3.11
"""Run hexmerge.recombine on the benchmark meshes and tabulate the results.

Every mesh runs in a fresh subprocess (this script with --worker), so that peak memory is the
engine's own: the worker loads the mesh with meshio, keeps only the point and tet arrays, resets
the kernel's resident-set high-water mark (/proc/self/clear_refs), records the resident memory
before the call, calls hexmerge.recombine, and reads the peak right after. The engine's peak is
(peak RSS after the call) - (RSS before the call); bytes per tet divide it by the tet count.
Then the worker runs the independent checker (hexmerge.check) on the output, outside the
measured window.

Results go to bench/results/bench-YYYYmmdd-HHMMSS.json (and bench/results/latest.json), and a
Markdown table is printed.

Usage (after building the module, see bench/README.md):
  PYTHONPATH=src/python /usr/bin/python3.11 bench/run_bench.py
  ... run_bench.py --sizes 10k,100k --shapes box,bracket --kinds delaunay
  ... run_bench.py --option conformity=conforming --option min_scaled_jacobian=0.2
  ... run_bench.py --table bench/results/latest.json     # re-print a table from a JSON
"""
import argparse
import datetime
import gc
import json
import os
import platform
import resource
import sys
import time

import benchlib
from benchlib import jsonable

HERE = benchlib.HERE
ROOT = benchlib.ROOT
MESH_DIR = os.path.join(HERE, "meshes")
RESULTS_DIR = benchlib.RESULTS_DIR
SHAPES = ["box", "cylinder", "bracket", "sphere", "torus"]
KINDS = ["delaunay", "lattice"]
SIZES = ["10k", "100k", "1m"]
TYPE_NAMES = ["tet", "pyramid", "prism", "hex"]  # CellType order in src/hexmerge/mesh/cell_type.h


# --------------------------------------------------------------------------- helpers
def rss_bytes(field="VmRSS"):
    """Current (VmRSS) or peak-since-reset (VmHWM) resident memory from /proc, in bytes."""
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(field + ":"):
                return int(line.split()[1]) * 1024
    return None


def reset_peak_rss():
    """Reset the kernel's RSS high-water mark (Linux >= 4.0); True when it worked."""
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
        return True
    except OSError:
        return False


def parse_value(text):
    low = text.lower()
    if low in ("true", "yes", "on"):
        return True
    if low in ("false", "no", "off"):
        return False
    for conv in (int, float):
        try:
            return conv(text)
        except ValueError:
            pass
    return text


def per_type(value):
    """Normalise a per-type report entry (dict by name or list in CellType order) to a dict."""
    if value is None:
        return {}
    if isinstance(value, dict):
        out = {}
        for k, v in value.items():
            key = TYPE_NAMES[k] if isinstance(k, int) and 0 <= k < len(TYPE_NAMES) else str(k).lower()
            key = {"tetra": "tet", "pyra": "pyramid", "wedge": "prism", "hexahedron": "hex",
                   "tetrahedron": "tet", "hexa": "hex", "penta": "prism"}.get(key, key)
            out[key] = v
        return out
    try:
        seq = list(value)
    except TypeError:
        return {}
    return {TYPE_NAMES[i]: seq[i] for i in range(min(len(seq), len(TYPE_NAMES)))}


def as_dict(obj):
    """A report/check result as a dict, whether the module returns a dict or an object."""
    if obj is None:
        return {}
    if isinstance(obj, dict):
        return obj
    if hasattr(obj, "_asdict"):
        return obj._asdict()
    out = {}
    for k in dir(obj):
        if k.startswith("_"):
            continue
        try:
            v = getattr(obj, k)
        except Exception:
            continue
        if callable(v):
            # zero-argument accessors such as valid()
            if k in ("valid",):
                try:
                    out[k] = v()
                except Exception:
                    pass
            continue
        out[k] = v
    return out


def phase_seconds(report):
    ps = report.get("phase_seconds")
    if ps is None:
        return {}
    if isinstance(ps, dict):
        return {str(k): float(v) for k, v in ps.items()}
    return {str(k): float(v) for k, v in ps}


# --------------------------------------------------------------------------- worker
def call_check(hexmerge, mesh, points, cells, regions):
    """hexmerge.check with the output mesh and the input arrays; tolerant to its exact form."""
    check = getattr(hexmerge, "check", None)
    if check is None:
        raise RuntimeError("hexmerge has no check()")
    attempts = [
        lambda: check(mesh, points, cells, regions),
        lambda: check(mesh, points, cells),
        lambda: check(mesh, input_points=points, input_cells=cells),
    ]
    errors = []
    for attempt in attempts:
        try:
            return attempt()
        except TypeError as e:
            errors.append(str(e))
    raise TypeError("could not call hexmerge.check: " + " / ".join(errors))


def load_tet_mesh(path, index_dtype="int32"):
    """The points (float64, N x 3) and tets (index_dtype, M x 4) of a mesh file, via meshio."""
    import numpy as np
    import meshio

    m = meshio.read(path)
    points = np.ascontiguousarray(m.points[:, :3], dtype=np.float64)
    cells = np.ascontiguousarray(np.concatenate([c.data for c in m.cells if c.type == "tetra"]),
                                 dtype=index_dtype)
    return points, cells


def worker(args):
    src = os.path.join(ROOT, "src", "python")
    if src not in sys.path:
        sys.path.append(src)  # after PYTHONPATH, so an installed or other build can take over
    import hexmerge

    options = dict(args.options)
    result = {"mesh": os.path.basename(args.worker), "options": options,
              "hexmerge_file": getattr(hexmerge, "__file__", None)}
    core = getattr(getattr(hexmerge, "_core", None), "__file__", None)
    if core:  # which build ran: other developers rebuild the module in place
        import hashlib
        with open(core, "rb") as f:
            result["core_sha1"] = hashlib.sha1(f.read()).hexdigest()[:12]
        result["core_mtime"] = datetime.datetime.fromtimestamp(os.path.getmtime(core)).isoformat(timespec="seconds")
    t0 = time.perf_counter()
    points, cells = load_tet_mesh(args.worker, "int64" if args.int64 else "int32")
    gc.collect()
    result["load_seconds"] = round(time.perf_counter() - t0, 3)
    result["tets"] = int(cells.shape[0])
    result["nodes"] = int(points.shape[0])
    regions = None

    hwm_reset = reset_peak_rss()
    rss_before = rss_bytes("VmRSS")
    maxrss_before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    t0 = time.perf_counter()
    try:
        mesh, report = hexmerge.recombine(points, cells, regions=regions, **options)
    except Exception as e:  # report the failure, keep the benchmark going
        result["error"] = f"recombine: {type(e).__name__}: {e}"
        return result
    wall = time.perf_counter() - t0
    maxrss_after = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    hwm_after = rss_bytes("VmHWM")

    # Peak: the high-water mark since the reset when the reset worked, else getrusage's maxrss
    # (which also covers loading the mesh: it is then an upper bound of the engine's peak only
    # when loading used less than the engine).
    peak = hwm_after if hwm_reset and hwm_after else maxrss_after
    result.update({
        "wall_seconds": wall,
        "rss_before_bytes": rss_before,
        "maxrss_before_bytes": maxrss_before,
        "maxrss_after_bytes": maxrss_after,
        "hwm_after_bytes": hwm_after,
        "hwm_reset": hwm_reset,
        "peak_bytes": peak - rss_before,
        "bytes_per_tet": (peak - rss_before) / max(1, cells.shape[0]),
    })
    report = as_dict(report)
    result["report"] = jsonable(report)
    result["phase_seconds"] = phase_seconds(report)
    result["output_counts"] = jsonable(per_type(report.get("output_counts")))
    result["volume_fraction"] = jsonable(per_type(report.get("volume_fraction")))
    result["min_scaled_jacobian_per_type"] = jsonable(per_type(report.get("min_scaled_jacobian")))

    if not args.no_check:
        t0 = time.perf_counter()
        try:
            chk = as_dict(call_check(hexmerge, mesh, points, cells, regions))
            result["check"] = jsonable(chk)
        except Exception as e:
            result["check_error"] = f"{type(e).__name__}: {e}"
        result["check_seconds"] = round(time.perf_counter() - t0, 3)
    return result


# --------------------------------------------------------------------------- driver
def find_meshes(shapes, kinds, sizes, mesh_dir=MESH_DIR):
    found = []
    for size in sizes:
        for shape in shapes:
            for kind in kinds:
                p = os.path.join(mesh_dir, f"{shape}-{kind}-{size}.msh")
                if os.path.exists(p):
                    found.append(p)
    return found


def run_one(path, args):
    cmd = [sys.executable, os.path.abspath(__file__), "--worker", path]
    for k, v in args.options:
        cmd += ["--option", f"{k}={v}"]
    if args.no_check:
        cmd.append("--no-check")
    if args.int64:
        cmd.append("--int64")
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(
        [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p] + [os.path.join(ROOT, "src", "python")])
    kind, payload, err, seconds = benchlib.run_worker(cmd, args.timeout, env)
    if kind == "timeout":
        return {"mesh": os.path.basename(path), "error": f"timeout after {args.timeout} s"}
    if kind == "result":
        if err.strip():
            payload["stderr_tail"] = err.strip().splitlines()[-5:]
        return payload
    return {"mesh": os.path.basename(path),
            "error": f"worker exit {payload}" + (f" (signal {-payload})" if payload < 0 else ""),
            "stderr_tail": err.strip().splitlines()[-10:],
            "subprocess_seconds": round(seconds, 2)}


def fmt(x, spec):
    if x is None or x == "":
        return "–"
    try:
        return format(x, spec)
    except (TypeError, ValueError):
        return str(x)


def table(results):
    # Phases in the order the engine reports them (union over all runs).
    phases = []
    for r in results:
        for ph in r.get("phase_seconds", {}):
            if ph not in phases:
                phases.append(ph)
    head = (["mesh", "tets"] + [f"{p} s" for p in phases] +
            ["total s", "peak MB", "B/tet", "hex", "prism", "pyramid", "tet",
             "hex vol %", "prism vol %", "reduction %", "nonconf. quads", "cracks",
             "min SJ", "min SJ new", "vol. diff", "valid"])
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in results:
        name = r["mesh"].removesuffix(".msh")
        if "error" in r:
            row = [name, fmt(r.get("tets"), ",")] + ["–"] * (len(head) - 3) + [r["error"][:60]]
            lines.append("| " + " | ".join(row) + " |")
            continue
        rep = r.get("report", {})
        chk = r.get("check", {})
        oc = r.get("output_counts", {})
        vf = r.get("volume_fraction", {})
        ps = r.get("phase_seconds", {})
        nonconf = chk.get("nonconforming_quads", rep.get("nonconforming_quads"))
        msj = chk.get("min_scaled_jacobian", rep.get("min_scaled_jacobian_overall"))
        if msj is None:
            vals = [v for k, v in per_type(rep.get("min_scaled_jacobian")).items()
                    if oc.get(k)]
            msj = min(vals) if vals else None
        vol = chk.get("relative_volume_difference")
        # Minimum over the merged elements only (the tets left are input tets, untouched).
        msj_types = per_type(rep.get("min_scaled_jacobian"))
        new = [v for k, v in msj_types.items() if k != "tet" and oc.get(k)]
        msj_new = min(new) if new else None
        row = ([name, fmt(r.get("tets"), ",")] + [fmt(ps.get(p), ".3f") for p in phases] +
               [fmt(r.get("wall_seconds"), ".3f"), fmt(r["peak_bytes"] / 2**20, ".0f"),
                fmt(r["bytes_per_tet"], ".0f"),
                fmt(oc.get("hex"), ","), fmt(oc.get("prism"), ","), fmt(oc.get("pyramid"), ","),
                fmt(oc.get("tet"), ","),
                fmt(100 * vf["hex"] if "hex" in vf else None, ".1f"),
                fmt(100 * vf["prism"] if "prism" in vf else None, ".1f"),
                fmt(rep.get("element_reduction_percent"), ".1f"),
                fmt(nonconf, ","), fmt(chk.get("cracks"), ","),
                fmt(msj, ".3f"), fmt(msj_new, ".3f"), fmt(vol, ".1e"),
                {True: "yes", False: "no"}.get(chk.get("valid"), "–")])
        lines.append("| " + " | ".join(row) + " |")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("files", nargs="*", help="mesh files to run instead of the benchmark set")
    ap.add_argument("--mesh-dir", default=MESH_DIR, help="where SHAPE-KIND-SIZE.msh are (bench/meshes)")
    ap.add_argument("--sizes", default="10k,100k,1m")
    ap.add_argument("--shapes", default=",".join(SHAPES))
    ap.add_argument("--kinds", default=",".join(KINDS))
    ap.add_argument("--option", action="append", default=[], metavar="NAME=VALUE",
                    help="engine option passed to hexmerge.recombine (repeatable)")
    ap.add_argument("--timeout", type=float, default=1800, help="seconds per mesh")
    ap.add_argument("--no-check", action="store_true", help="skip hexmerge.check")
    ap.add_argument("--int64", action="store_true", help="pass cells as int64 (default int32)")
    ap.add_argument("--output", help="JSON file (default bench/results/bench-<time>.json)")
    ap.add_argument("--table", metavar="JSON", help="print the table of an earlier results file")
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    args = ap.parse_args()
    args.options = []
    for o in args.option:
        if "=" not in o:
            ap.error(f"--option wants NAME=VALUE, got {o!r}")
        k, v = o.split("=", 1)
        args.options.append((k.strip().replace("-", "_"), parse_value(v.strip())))

    if args.worker:
        res = worker(args)
        print(benchlib.RESULT_MARKER + json.dumps(jsonable(res)), flush=True)
        return 0

    if args.table:
        with open(args.table) as f:
            data = json.load(f)
        print(table(data["results"]))
        return 0

    sizes = [s.strip().lower().replace("1000k", "1m") for s in args.sizes.split(",") if s]
    shapes = [s for s in args.shapes.split(",") if s]
    kinds = [k for k in args.kinds.split(",") if k]
    meshes = args.files or find_meshes(shapes, kinds, sizes, args.mesh_dir)
    if not meshes:
        print("no meshes found in bench/meshes; run bench/make_meshes.py first", file=sys.stderr)
        return 1

    results = []
    started = datetime.datetime.now()
    os.makedirs(RESULTS_DIR, exist_ok=True)
    out = args.output or os.path.join(RESULTS_DIR, f"bench-{started:%Y%m%d-%H%M%S}.json")
    git = benchlib.git_commit()
    for path in meshes:
        print(f"{os.path.basename(path)} ...", end=" ", flush=True, file=sys.stderr)
        res = run_one(path, args)
        results.append(res)
        if "error" in res:
            print("ERROR: " + res["error"], file=sys.stderr)
        else:
            print(f"{res.get('tets')} tets, {res['wall_seconds']:.3f} s, "
                  f"{res['peak_bytes'] / 2**20:.0f} MB", file=sys.stderr)
        data = {"started": started.isoformat(timespec="seconds"), "git": git,
                "host": platform.node(), "cpus": os.cpu_count(), "python": sys.version.split()[0],
                "options": dict(args.options), "results": results}
        with open(out, "w") as f:
            json.dump(data, f, indent=1)
    latest = os.path.join(RESULTS_DIR, "latest.json")
    if os.path.abspath(out) != latest:
        with open(latest, "w") as f:
            json.dump(data, f, indent=1)
    print(table(results))
    print(f"\nresults: {os.path.relpath(out, os.getcwd())}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
