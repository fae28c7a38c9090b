"""Helpers shared by the benchmark scripts in bench/ (one way of doing each thing).

- geo_to_cad: a Gmsh .geo (OpenCASCADE kernel) to a CAD file (BREP or STEP) with `gmsh -0`.
- rescaled_size: the size h that should give the wanted tet count, from one measured count.
- jsonable: numpy scalars and arrays, objects and odd values to plain JSON types.
- compare_hashes: output hashes against an earlier run's (mesher_hashes.py, output_hashes.py).
- run_worker: one run of a worker command in a fresh subprocess (a session of its own), with a
  timeout and an optional memory limit; the worker prints its result as one JSON line after
  RESULT_MARKER. kill_session, stop_workers_on_signals: leave no worker behind.
- git_commit, machine: what a results file is headed by.
"""
import json
import os
import platform
import resource
import signal
import subprocess
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
GEOMETRY_DIR = os.path.join(HERE, "geometry")
RESULTS_DIR = os.path.join(HERE, "results")
RESULT_MARKER = "@@RESULT@@"
LIVE_WORKERS = set()  # session ids of the workers running now (run_worker), for stop_workers


def geo_to_cad(geo: str, out: str) -> str:
    """Write the shape of a Gmsh .geo file (OpenCASCADE kernel) to `out` (.brep or .step, by its
    extension) with `gmsh -0`; returns `out`. Raises CalledProcessError when Gmsh fails."""
    subprocess.run(["gmsh", "-0", geo, "-o", out], check=True, capture_output=True)
    if not os.path.exists(out):
        raise RuntimeError(f"gmsh -0 {geo} wrote no {out}")
    return out


def rescaled_size(size: float, tets: int, wanted: int, exponent: float = 3.0) -> float:
    """The size giving about `wanted` tets when `size` gave `tets`: the count goes as
    h^-exponent (3 for a volume mesh; less while the boundary's share is large)."""
    return size * (tets / wanted) ** (1 / exponent)


def count_exponent(tries) -> float:
    """The exponent k of tets ~ h^-k through the last two (h, tets) of `tries` whose h differ,
    kept within [1.5, 3]; 3 when there are not two."""
    import math

    pts = [(h, n) for h, n in tries if n]
    for (h1, n1), (h2, n2) in zip(pts[-2::-1], pts[:0:-1]):
        if abs(math.log(h2 / h1)) > 1e-3:
            return min(3.0, max(1.5, math.log(n1 / n2) / math.log(h2 / h1)))
    return 3.0


def jsonable(x):
    """Convert numpy scalars/arrays and other odd values into plain JSON types."""
    try:
        import numpy as np
        if isinstance(x, np.generic):
            return x.item()
        if isinstance(x, np.ndarray):
            return x.tolist() if x.size <= 64 else f"<array {x.shape} {x.dtype}>"
    except ImportError:
        pass
    if isinstance(x, dict):
        return {str(k): jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    if isinstance(x, (str, int, float, bool)) or x is None:
        return x
    if hasattr(x, "__dict__"):
        return {k: jsonable(v) for k, v in vars(x).items() if not k.startswith("_")}
    return repr(x)


def compare_hashes(results: dict, path: str) -> int:
    """Compare {case: {"sha1", "report", ...}} with the same written earlier to `path`: print each
    case whose hash or report differs (with the report's changed fields, and whether the mesh
    alone is identical where both have "mesh_sha1"), then the count; 1 when any differs, else 0."""
    with open(path) as f:
        old = json.load(f)
    bad = 0
    for key, new in results.items():
        if key not in old:
            print(f"{key}: not in {path}")
            continue
        before, after = old[key].get("report", {}), new.get("report", {})
        if old[key]["sha1"] != new["sha1"] or before != after:
            bad += 1
            diff = {k: (before.get(k), after.get(k)) for k in sorted(set(before) | set(after))
                    if before.get(k) != after.get(k)}
            # (A report key removed changes the first hash with the same mesh: the second, of the
            # mesh alone, tells.)
            mesh = ""
            if "mesh_sha1" in old[key] and "mesh_sha1" in new:
                same = old[key]["mesh_sha1"] == new["mesh_sha1"]
                mesh = " (the mesh identical)" if same else " (the mesh differs)"
            print(f"{key}: DIFFERENT sha1 {old[key]['sha1'][:12]} -> {new['sha1'][:12]}{mesh} {diff}")
    print(f"{len(results) - bad} of {len(results)} identical to {path}")
    return 1 if bad else 0


def run_worker(cmd, timeout, env=None, memory_bytes=None, cwd=None):
    """Run `cmd` (a worker printing RESULT_MARKER + JSON on a line of its stdout) in a new
    session, so that a timeout ends the worker and every process it started (TetGen).

    memory_bytes: the address-space limit (RLIMIT_AS) of the worker and its children, or None;
    cwd: the folder it runs in (None: this process's).
    Returns (kind, payload, stderr, seconds): kind "result" with the decoded JSON, "timeout"
    (payload None), or "exit" with the return code (negative: the signal) when the worker
    printed no result."""
    import json

    def limit():
        if memory_bytes:
            resource.setrlimit(resource.RLIMIT_AS, (memory_bytes, memory_bytes))

    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env, cwd=cwd,
                            start_new_session=True, preexec_fn=limit if memory_bytes else None)
    LIVE_WORKERS.add(proc.pid)
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        kill_session(proc.pid)
        out, err = proc.communicate()
        return "timeout", None, err, time.perf_counter() - t0
    except BaseException:  # interrupted: leave no worker behind
        kill_session(proc.pid)
        raise
    finally:
        LIVE_WORKERS.discard(proc.pid)
    seconds = time.perf_counter() - t0
    for line in reversed(out.splitlines()):
        if line.startswith(RESULT_MARKER):
            return "result", json.loads(line[len(RESULT_MARKER):]), err, seconds
    return "exit", proc.returncode, err, seconds


def kill_session(sid: int) -> None:
    """SIGKILL every process of session `sid` (a worker started with start_new_session, and
    what it started, even in process groups of their own such as timeout(1)'s)."""
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[3]) == sid:  # fields after the name: state, ppid, pgrp, session
            try:
                os.kill(int(entry), signal.SIGKILL)
            except ProcessLookupError:
                pass


def stop_workers_on_signals() -> None:
    """On SIGINT or SIGTERM, end every running worker's session, then exit (128 + the signal):
    workers run in sessions of their own, which the terminal's Ctrl-C does not reach."""
    def stop(signum, _frame):
        for sid in list(LIVE_WORKERS):
            kill_session(sid)
        os._exit(128 + signum)

    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, stop)


def git_commit(root: str = ROOT) -> str:
    """The short hash of the checkout's HEAD ('' outside git)."""
    return subprocess.run(["git", "-C", root, "rev-parse", "--short", "HEAD"],
                          stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True).stdout.strip()


def machine() -> dict:
    """Host name, CPU count (nproc: the CPUs this process may use) and CPU model."""
    model = platform.processor()
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    model = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return {"host": platform.node(), "nproc": len(os.sched_getaffinity(0)), "cpu_model": model}
