#!/usr/bin/python3.11
"""Generate the benchmark tet meshes with the Gmsh command-line tool.

For every shape in bench/geometry/*.geo, every size (about 10k, 100k, 1M tets) and every kind
of tets, run

    gmsh -3 -clmax H -order 1 -format msh41 [kind options] geometry/SHAPE.geo -o meshes/NAME.msh

and write bench/meshes/SHAPE-KIND-SIZE.msh (msh 4.1, first-order tets). Existing files are
skipped, so the script can be re-run to fill in what is missing. A manifest
bench/meshes/manifest.json records, per mesh, the h used, the tet and node counts and the
generation time (wall seconds); meshes skipped because they exist keep their earlier entry.

Kinds:
  delaunay  Mesh.Algorithm3D = 1 (Delaunay).
  lattice   Mesh.Algorithm3D = 9 (Gmsh's R-tree / lattice-point mesher) with
            Mesh.Recombine3DAll = 0, i.e. its points tetrahedralised, no recombination.
            Debian's gmsh 4.8.4 is built without ANN and this algorithm crashes
            (SIGSEGV in Frame_field::search, called from Filler::get_metric) on every shape,
            at every size. The script still tries it and records the failure in the manifest.

Usage:
  /usr/bin/python3.11 bench/make_meshes.py                      # 10k and 100k, then 1M
  /usr/bin/python3.11 bench/make_meshes.py --sizes 10k,100k
  /usr/bin/python3.11 bench/make_meshes.py --shapes box,torus --kinds delaunay
  /usr/bin/python3.11 bench/make_meshes.py --find-h box:100000  # search the h of a target count
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
GEOMETRY_DIR = os.path.join(HERE, "geometry")
MESH_DIR = os.path.join(HERE, "meshes")
MANIFEST = os.path.join(MESH_DIR, "manifest.json")

SHAPES = ["box", "cylinder", "bracket", "sphere", "torus"]
SIZES = ["10k", "100k", "1m"]

# -clmax h (mm) per shape and size, found with --find-h on Delaunay meshes (gmsh 4.8.4,
# Mesh.Algorithm3D=1). The comment gives the tet count measured with that h.
# Shapes: box 100x40x30, cylinder r20 x 100, L-bracket 80x40x10 + 10x40x60 with a d16 hole,
# sphere r25, torus R40 r12 (all mm).
H = {
    "box":      {"10k": 3.94, "100k": 1.78, "1m": 0.82},    # 10,212 / 101,059 / 979,323
    "cylinder": {"10k": 4.04, "100k": 1.81, "1m": 0.835},   #  9,819 /  99,406 / 970,015
    "bracket":  {"10k": 3.07, "100k": 1.35, "1m": 0.613},   # 10,245 /  98,722 / 996,631
    "sphere":   {"10k": 3.2,  "100k": 1.44, "1m": None},    #  9,831 /  99,995 / ?
    "torus":    {"10k": 3.84, "100k": 1.74, "1m": None},    # 10,267 /  99,950 / ?
}

KINDS = {
    "delaunay": ["-setnumber", "Mesh.Algorithm3D", "1"],
    "lattice": ["-setnumber", "Mesh.Algorithm3D", "9", "-setnumber", "Mesh.Recombine3DAll", "0"],
}

TARGET = {"10k": 10_000, "100k": 100_000, "1m": 1_000_000}


def parse_size(s):
    s = s.strip().lower()
    if s in ("1m", "1000k"):
        return "1m"
    if s not in SIZES:
        raise argparse.ArgumentTypeError(f"unknown size {s!r} (choose from 10k, 100k, 1m)")
    return s


def count_msh41(path):
    """Count tets (type 4) and nodes in a Gmsh msh 4.1 ASCII file without loading it."""
    ntets = 0
    nnodes = 0
    with open(path, "r") as f:
        for line in f:
            if line.startswith("$Nodes"):
                nnodes = int(f.readline().split()[1])
            elif line.startswith("$Elements"):
                nblocks = int(f.readline().split()[0])
                for _ in range(nblocks):
                    _dim, _tag, etype, n = (int(x) for x in f.readline().split())
                    if etype == 4:
                        ntets += n
                    for _ in range(n):
                        f.readline()
                break
    return ntets, nnodes


def run_gmsh(shape, kind, h, out, timeout=3600):
    geo = os.path.join(GEOMETRY_DIR, shape + ".geo")
    cmd = ["gmsh", "-3", "-clmax", repr(h), "-order", "1", "-format", "msh41", "-nt", "1"]
    cmd += KINDS[kind] + [geo, "-o", out]
    t0 = time.perf_counter()
    try:
        p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                           timeout=timeout)
        rc = p.returncode
        log = p.stdout
    except subprocess.TimeoutExpired as e:
        rc = "timeout"
        log = e.stdout.decode() if isinstance(e.stdout, bytes) else (e.stdout or "")
    dt = time.perf_counter() - t0
    ok = rc == 0 and os.path.exists(out) and "Error" not in log
    return ok, rc, dt, log, cmd


def find_h(shape, target, kind="delaunay", h0=5.0, tol=0.03, maxit=8):
    """Secant search on log(count) = a - 3 log(h) for the h giving about `target` tets."""
    h = h0
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "m.msh")
        for _ in range(maxit):
            ok, rc, dt, log, _ = run_gmsh(shape, kind, h, out)
            if not ok:
                raise RuntimeError(f"gmsh failed for {shape} h={h}: rc={rc}\n{log[-2000:]}")
            n, _ = count_msh41(out)
            print(f"  {shape} h={h:.4g}: {n} tets ({dt:.1f} s)", flush=True)
            if abs(n / target - 1) < tol:
                return h, n
            h = h * (n / target) ** (1 / 3)
            h = float(f"{h:.3g}")
    return h, n


def load_manifest():
    if os.path.exists(MANIFEST):
        with open(MANIFEST) as f:
            return json.load(f)
    return {}


def save_manifest(m):
    tmp = MANIFEST + ".tmp"
    with open(tmp, "w") as f:
        json.dump(m, f, indent=1, sort_keys=True)
    os.replace(tmp, MANIFEST)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", default="10k,100k,1m", help="comma list of 10k, 100k, 1m")
    ap.add_argument("--shapes", default=",".join(SHAPES), help="comma list of " + ", ".join(SHAPES))
    ap.add_argument("--kinds", default=",".join(KINDS), help="comma list of " + ", ".join(KINDS))
    ap.add_argument("--force", action="store_true", help="regenerate meshes that exist")
    ap.add_argument("--retry-failed", action="store_true",
                    help="retry kinds recorded as failed in the manifest (by default skipped)")
    ap.add_argument("--find-h", metavar="SHAPE:COUNT[:H0]", action="append",
                    help="search the -clmax giving about COUNT Delaunay tets (first guess H0), print it and exit")
    args = ap.parse_args()

    if args.find_h:
        for spec in args.find_h:
            shape, count, *h0 = spec.split(":")
            count = int(float(count.lower().replace("k", "e3").replace("m", "e6")))
            h, n = find_h(shape, count, h0=float(h0[0]) if h0 else 5.0)
            print(f"{shape}: h={h:.4g} -> {n} tets")
        return 0

    sizes = [parse_size(s) for s in args.sizes.split(",") if s]
    shapes = [s for s in args.shapes.split(",") if s]
    kinds = [k for k in args.kinds.split(",") if k]
    for s in shapes:
        if s not in SHAPES:
            ap.error(f"unknown shape {s}")
    for k in kinds:
        if k not in KINDS:
            ap.error(f"unknown kind {k}")
    # Small sizes first: the 1M meshes take minutes each.
    sizes.sort(key=SIZES.index)

    os.makedirs(MESH_DIR, exist_ok=True)
    manifest = load_manifest()
    for size in sizes:
        for shape in shapes:
            for kind in kinds:
                name = f"{shape}-{kind}-{size}"
                out = os.path.join(MESH_DIR, name + ".msh")
                h = H[shape][size]
                if h is None:
                    print(f"{name}: no h chosen yet, skipped")
                    continue
                if os.path.exists(out) and not args.force:
                    print(f"{name}: exists, skipped")
                    continue
                prev = manifest.get(name, {})
                if prev.get("status") == "failed" and not args.retry_failed:
                    print(f"{name}: kind {kind} failed before ({prev.get('error', 'see manifest')}), skipped")
                    continue
                print(f"{name}: gmsh -clmax {h} ...", flush=True)
                tmp = out + ".part.msh"
                ok, rc, dt, log, cmd = run_gmsh(shape, kind, h, tmp)
                entry = {"shape": shape, "kind": kind, "size": size, "h": h,
                         "command": " ".join(cmd[:-1] + [os.path.relpath(out, HERE)]),
                         "seconds": round(dt, 2)}
                if ok:
                    os.replace(tmp, out)
                    ntets, nnodes = count_msh41(out)
                    entry.update(status="ok", tets=ntets, nodes=nnodes, file=os.path.basename(out))
                    print(f"{name}: {ntets} tets, {nnodes} nodes, {dt:.1f} s", flush=True)
                else:
                    if os.path.exists(tmp):
                        os.remove(tmp)
                    sig = ""
                    if isinstance(rc, int) and rc < 0:
                        sig = f" (signal {-rc})"
                    err = f"gmsh exit {rc}{sig}"
                    last = [l for l in log.splitlines() if l.strip()][-3:]
                    entry.update(status="failed", error=err, log_tail=last)
                    print(f"{name}: FAILED, {err}; last output: {' | '.join(last)}", flush=True)
                manifest[name] = entry
                save_manifest(manifest)
    return 0


if __name__ == "__main__":
    sys.exit(main())
