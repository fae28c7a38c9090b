#!/usr/bin/python3.11
"""The recombination engine's profile (issue 18): instructions per tet per phase, peak memory per
tet, wall time per phase and thread scaling, printed as the table the issue asks for.

- Instructions: callgrind (valgrind) on one thread, counted from the engine's entry
  (hexmerge::recombine) down, per phase by the inclusive cost of the phase's function:
  candidate search = find_candidates minus the quad pairs (QuadPairs' constructor); pruning =
  prune_unclosable; selection = select_candidates plus
  every other thread of the process (with threads=1 and OpenBLAS on one thread, the only other
  thread is the second selection strategy's, which select_candidates started on a std::thread
  up to commit 1ba8402); the rest of hexmerge::recombine = validation, adjacency, output.
  Instruction counts do not depend on the machine's load. The mesh is handed over as a .npz, so
  that callgrind runs neither meshio nor the mesh parsing; valgrind runs 50-100x slower than the
  program.
- Peak memory and wall time: run_bench.py's worker (a fresh process per run; peak = high-water
  mark of the resident set during the call minus the resident set before it), once per thread
  count. The wall times depend on the load of the machine: run on a quiet machine to compare.
- Heap peak (--heap): heaptrack on the same one-thread run as callgrind's (the .npz), the
  process's peak of heap memory as heaptrack_print reports it: the interpreter, numpy and the
  input arrays included (a few MB), only the heap (no stacks, no freed pages an allocator
  keeps), and the same on any load. Needs `heaptrack`; a 100k mesh takes about half a minute.
- The command line's files (--cli): the steps of `hexmerge recombine IN -o OUT.vtu` timed one
  by one in one process (hexmerge._io.read_tets, hexmerge.recombine, _io.to_meshio,
  _io.write_atomic), to see what reading and writing cost against the engine.

Usage (after building the module, see bench/README.md; meshes from make_meshes.py):
  PYTHONPATH=src/python /usr/bin/python3.11 bench/engine_profile.py
  ... engine_profile.py --callgrind box-delaunay-100k,box-tetgen-lattice-100k \\
        --timing box-delaunay-1m,box-tetgen-lattice-1m --threads 1,2 --output /tmp/p.json
  ... engine_profile.py --callgrind '' --timing '' --cli box-delaunay-1m --cli-threads 2
  ... engine_profile.py --callgrind '' --timing '' --heap box-tetgen-lattice-100k
  ... engine_profile.py --table /tmp/p.json
"""
import argparse
import json
import os
import re
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import benchlib  # noqa: E402
import run_bench  # noqa: E402  (load_tet_mesh, run_one, MESH_DIR)

# Phase -> functions whose inclusive costs add up to it (callgrind_annotate names, matched as
# the start of the name); "-" before a name subtracts it.
PHASES = [
    ("candidate search", ["hexmerge::find_candidates(", "-hexmerge::QuadPairs::QuadPairs("]),
    ("quad pairs", ["hexmerge::QuadPairs::QuadPairs("]),
    ("pruning of unclosable candidates", ["hexmerge::prune_unclosable("]),
    ("selection", ["hexmerge::select_candidates("]),
]
ENGINE = "hexmerge::recombine("


def callgrind_worker(npz, out_file):
    """Runs under valgrind: load the arrays, recombine on one thread."""
    import numpy as np
    src = os.path.join(benchlib.ROOT, "src", "python")
    if src not in sys.path:
        sys.path.append(src)
    import hexmerge
    data = np.load(npz)
    _, report = hexmerge.recombine(data["points"], data["cells"], threads=1)
    with open(out_file, "w") as f:
        json.dump(benchlib.jsonable(run_bench.as_dict(report)), f)


def inclusive_costs(callgrind_out):
    """{function name: inclusive instruction count} from callgrind_annotate."""
    text = subprocess.run(["callgrind_annotate", "--inclusive=yes", "--threshold=100",
                           callgrind_out], capture_output=True, text=True, check=True).stdout
    costs = {}
    for line in text.splitlines():
        m = re.match(r"\s*([\d,]+)\s+\([^)]*\)\s+(.*)$", line)
        if not m:
            continue
        # "file:function [object]", the file "???" without debugging information
        name = re.sub(r"^(?:\?\?\?|[^\s:(]+\.[A-Za-z+]+):(?!:)", "", m.group(2).strip())
        name = re.sub(r"\s*\[[^\]]*\]$", "", name)  # the object file
        costs[name] = costs.get(name, 0) + int(m.group(1).replace(",", ""))
    return costs


def program_total(callgrind_out):
    text = subprocess.run(["callgrind_annotate", callgrind_out], capture_output=True, text=True,
                          check=True).stdout
    m = re.search(r"([\d,]+)\s+(?:\([^)]*\)\s+)?PROGRAM TOTALS", text)
    return int(m.group(1).replace(",", "")) if m else 0


def cost_of(costs, prefix):
    hits = [v for k, v in costs.items() if k.startswith(prefix)]
    return max(hits) if hits else 0


def worker_input(path, tmp):
    """The mesh saved for a worker run (--callgrind-worker) under a tool: (cells, the .npz, the
    report file it writes, its environment: this checkout's module, one BLAS thread)."""
    import numpy as np
    points, cells = run_bench.load_tet_mesh(path)
    npz = os.path.join(tmp, "mesh.npz")
    np.savez(npz, points=points, cells=cells)
    env = dict(os.environ)
    env["OPENBLAS_NUM_THREADS"] = "1"
    env["PYTHONPATH"] = os.pathsep.join(
        [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p] +
        [os.path.join(benchlib.ROOT, "src", "python")])
    return cells, npz, os.path.join(tmp, "report.json"), env


def stripped_module(env, tmp):
    """The module the worker would import, copied with its debugging information stripped:
    with it, callgrind_annotate lists a function once per source file its inlined code comes
    from, and the costs summed per function came out about twice the program's (issue 18)."""
    import glob
    import shutil
    package = subprocess.run([sys.executable, "-c", "import hexmerge, os; print(os.path.dirname(hexmerge.__file__))"],
                             env=env, capture_output=True, text=True, check=True).stdout.strip()
    copy = os.path.join(tmp, "module", "hexmerge")
    shutil.copytree(package, copy, ignore=shutil.ignore_patterns("__pycache__"))
    for so in glob.glob(os.path.join(copy, "*.so")):
        subprocess.run(["strip", "--strip-debug", so], check=True)
    return dict(env, PYTHONPATH=os.pathsep.join([os.path.dirname(copy), env.get("PYTHONPATH", "")]))


def profile_instructions(path, tmp):
    cells, npz, rep, env = worker_input(path, tmp)
    env = stripped_module(env, tmp)
    out = os.path.join(tmp, "callgrind.out")
    subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}",
                    "--separate-threads=yes",
                    sys.executable, os.path.abspath(__file__), "--callgrind-worker", npz, rep],
                   check=True, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    files = sorted(f for f in os.listdir(tmp) if f.startswith("callgrind.out-"))
    costs = inclusive_costs(os.path.join(tmp, files[0]))  # the main thread
    others = sum(program_total(os.path.join(tmp, f)) for f in files[1:])
    tets = int(cells.shape[0])
    engine = cost_of(costs, ENGINE) + others
    phases = {}
    for name, parts in PHASES:
        total = 0
        for p in parts:
            total += -cost_of(costs, p[1:]) if p.startswith("-") else cost_of(costs, p)
        phases[name] = total / tets
    phases["selection"] += others / tets
    phases["validation, adjacency, output"] = engine / tets - sum(phases.values())
    with open(rep) as f:
        report = json.load(f)
    return {"tets": tets, "engine": engine / tets, "phases": phases,
            "strategy": report.get("selection_strategy")}


def heap_peak(path, tmp):
    """The heap peak (bytes, and per tet) of a one-thread recombine of the mesh, by heaptrack."""
    cells, npz, rep, env = worker_input(path, tmp)
    out = os.path.join(tmp, "heaptrack")
    subprocess.run(["heaptrack", "-o", out, sys.executable, os.path.abspath(__file__),
                    "--callgrind-worker", npz, rep],
                   check=True, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    data = [f for f in os.listdir(tmp) if f.startswith("heaptrack")][0]
    text = subprocess.run(["heaptrack_print", "-f", os.path.join(tmp, data), "--print-peaks", "0",
                           "--print-allocators", "0", "--print-temporary", "0",
                           "--print-leaks", "0"], capture_output=True, text=True,
                          check=True).stdout
    m = re.search(r"peak heap memory consumption: ([\d.]+)([KMGT]?)", text)
    if not m:
        raise RuntimeError(f"no heap peak in heaptrack_print's output for {path}")
    scale = {"": 1, "K": 1e3, "M": 1e6, "G": 1e9, "T": 1e12}[m.group(2)]
    peak = float(m.group(1)) * scale
    tets = int(cells.shape[0])
    return {"tets": tets, "heap_peak_bytes": peak, "heap_bytes_per_tet": peak / tets}


def timing(path, threads, timeout):
    args = argparse.Namespace(options=[("threads", threads)], no_check=True, int64=False,
                              timeout=timeout)
    r = run_bench.run_one(path, args)
    return {k: r.get(k) for k in ("tets", "wall_seconds", "peak_bytes", "bytes_per_tet",
                                  "phase_seconds", "error")}


def cli_steps(path, threads):
    """Seconds of each step of `hexmerge recombine IN -o OUT.vtu`, and the .vtu's size."""
    import time
    src = os.path.join(benchlib.ROOT, "src", "python")
    if src not in sys.path:
        sys.path.append(src)
    from hexmerge import _api, _io
    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        target = os.path.join(tmp, "out.vtu")
        t = time.perf_counter()
        tets = _io.read_tets(path, None)
        out["read_seconds"] = time.perf_counter() - t
        t = time.perf_counter()
        mesh, _ = _api.recombine(tets.points, tets.cells, tets.regions, threads=threads)
        out["engine_seconds"] = time.perf_counter() - t
        t = time.perf_counter()
        m = _io.to_meshio(mesh, "vtu", region_key=tets.region_key, region_names=tets.region_names)
        _io.write_atomic(target, m, "vtu")
        out["write_seconds"] = time.perf_counter() - t
        out["vtu_bytes"] = os.path.getsize(target)
    out["tets"] = int(tets.cells.shape[0])
    out["threads"] = threads
    return out


def fmt(x, spec=",.0f"):
    return "–" if x is None else format(x, spec)


def table(data):
    lines = [f"commit {data['git']}, {data['machine'].get('cpu_model', '')} "
             f"({data['machine'].get('nproc')} CPUs), {data['date']}", ""]
    ins = data.get("instructions", {})
    if ins:
        names = list(ins)
        lines.append("| instructions per tet (callgrind, 1 thread) | " + " | ".join(names) + " |")
        lines.append("|---|" + "---|" * len(names))
        lines.append("| whole engine | " + " | ".join(fmt(ins[n]["engine"]) for n in names) + " |")
        for ph in list(ins[names[0]]["phases"]):
            lines.append(f"| – {ph} | " +
                         " | ".join(fmt(ins[n]["phases"].get(ph)) for n in names) + " |")
        lines.append("| selection strategy kept | " +
                     " | ".join(str(ins[n].get("strategy")) for n in names) + " |")
        lines.append("")
    tim = data.get("timing", {})
    if tim:
        threads = sorted({int(t) for runs in tim.values() for t in runs})
        phases = []
        for runs in tim.values():
            for r in runs.values():
                for p in (r.get("phase_seconds") or {}):
                    if p not in phases:
                        phases.append(p)
        head = ["mesh", "tets"] + [f"{t} thr. s" for t in threads]
        if len(threads) > 1:
            head.append(f"speed-up {threads[-1]}/{threads[0]}")
        head += [f"peak B/tet ({t} thr.)" for t in threads]
        head += [f"{p} s ({threads[0]} thr.)" for p in phases]
        lines.append("| " + " | ".join(head) + " |")
        lines.append("|" + "---|" * len(head))
        for name, runs in tim.items():
            rs = [runs.get(str(t), {}) for t in threads]
            walls = [r.get("wall_seconds") for r in rs]
            row = [name, fmt(rs[0].get("tets"))] + [fmt(w, ".2f") for w in walls]
            if len(threads) > 1:
                row.append(fmt(walls[0] / walls[-1], ".2f") if walls[0] and walls[-1] else "–")
            row += [fmt(r.get("bytes_per_tet")) for r in rs]
            ps = rs[0].get("phase_seconds") or {}
            row += [fmt(ps.get(p), ".3f") for p in phases]
            lines.append("| " + " | ".join(row) + " |")
    heap = data.get("heap", {})
    if heap:
        lines += ["", "| mesh | tets | heap peak MB (heaptrack, 1 thread) | B/tet |",
                  "|---|---|---|---|"]
        for name, r in heap.items():
            lines.append(f"| {name} | {fmt(r['tets'])} | {r['heap_peak_bytes'] / 1e6:.1f} | "
                         f"{fmt(r['heap_bytes_per_tet'])} |")
    cli = data.get("cli", {})
    if cli:
        lines += ["", "| mesh | tets | threads | read s | engine s | write .vtu s | .vtu MB | "
                      "read + write share |", "|---|---|---|---|---|---|---|---|"]
        for name, r in cli.items():
            io = r["read_seconds"] + r["write_seconds"]
            lines.append(f"| {name} | {fmt(r['tets'])} | {r['threads']} | {r['read_seconds']:.2f} | "
                         f"{r['engine_seconds']:.2f} | {r['write_seconds']:.2f} | "
                         f"{r['vtu_bytes'] / 1e6:.1f} | {io / (io + r['engine_seconds']):.0%} |")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--mesh-dir", default=run_bench.MESH_DIR)
    ap.add_argument("--callgrind", default="box-delaunay-100k,box-tetgen-lattice-100k",
                    help="meshes (SHAPE-KIND-SIZE) profiled with callgrind; '' for none")
    ap.add_argument("--timing", default="box-delaunay-100k,box-tetgen-lattice-100k,"
                                        "box-delaunay-1m,box-tetgen-lattice-1m",
                    help="meshes timed and measured for peak memory; '' for none")
    ap.add_argument("--heap", default="", help="meshes whose heap peak heaptrack measures (one "
                                               "thread); '' for none")
    ap.add_argument("--threads", default="1,2")
    ap.add_argument("--cli", default="", help="meshes whose `hexmerge recombine -o .vtu` steps are "
                                              "timed (read, engine, write); '' for none")
    ap.add_argument("--cli-threads", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=900, help="seconds per timed run")
    ap.add_argument("--output", help="JSON file to write")
    ap.add_argument("--commit", help="the commit of the module measured, when it is not the "
                                     "checkout's HEAD (a module on PYTHONPATH built elsewhere)")
    ap.add_argument("--table", metavar="JSON", help="print the table of an earlier output")
    ap.add_argument("--callgrind-worker", nargs=2, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.callgrind_worker:
        callgrind_worker(*args.callgrind_worker)
        return 0
    if args.table:
        with open(args.table) as f:
            print(table(json.load(f)))
        return 0

    import datetime
    data = {"git": args.commit or benchlib.git_commit(), "machine": benchlib.machine(),
            "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
            "instructions": {}, "timing": {}, "heap": {}, "cli": {}}

    def mesh_path(name):
        p = os.path.join(args.mesh_dir, name + ".msh")
        if not os.path.exists(p):
            print(f"{name}: no {p}; run bench/make_meshes.py", file=sys.stderr)
            return None
        return p

    def save():
        if args.output:
            with open(args.output, "w") as f:
                json.dump(data, f, indent=1)

    for names, key, tool, profile in ((args.callgrind, "instructions", "callgrind", profile_instructions),
                                      (args.heap, "heap", "heaptrack", heap_peak)):
        for name in [n for n in names.split(",") if n]:
            path = mesh_path(name)
            if path:
                with tempfile.TemporaryDirectory() as tmp:
                    print(f"{name}: {tool} ...", file=sys.stderr, flush=True)
                    data[key][name] = profile(path, tmp)
                save()
    for name in [n for n in args.timing.split(",") if n]:
        path = mesh_path(name)
        if not path:
            continue
        data["timing"][name] = {}
        for t in [int(x) for x in args.threads.split(",")]:
            print(f"{name}: {t} thread(s) ...", file=sys.stderr, flush=True)
            data["timing"][name][str(t)] = timing(path, t, args.timeout)
            save()
    for name in [n for n in args.cli.split(",") if n]:
        path = mesh_path(name)
        if path:
            print(f"{name}: command line steps ...", file=sys.stderr, flush=True)
            data["cli"][name] = cli_steps(path, args.cli_threads)
            save()
    print(table(data))
    return 0


if __name__ == "__main__":
    sys.exit(main())
