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
  lattice   Mesh.Algorithm3D = 9 (Gmsh's R-tree / lattice-point mesher: points placed
            frontally along a frame field aligned with the boundary) with
            Mesh.Recombine3DAll = 0, i.e. its points tetrahedralised, no recombination.
            Needs Gmsh >= 4.12: Debian 12's gmsh 4.8.4 is built without ANN and this algorithm
            crashes there (SIGSEGV in Frame_field::search, called from Filler::get_metric) on
            every shape, at every size; bench/fetch_gmsh.py unpacks Debian 13's 4.13.1, and
            --gmsh (or $HEXMERGE_GMSH) runs it. A failure is recorded in the manifest (later
            runs skip a mesh recorded as failed unless --retry-failed). Its h per shape and
            size (H_LATTICE) were found with 4.13.1.
  tetgen-lattice
            A stand-in for the missing lattice kind: Gmsh's surface mesh (gmsh -2 -clmax h)
            plus the points of an axis-aligned cubic lattice of spacing h at least 0.6 h inside
            the shape, tetrahedralised by TetGen (Debian tetgen 1.5, tetgen -pY: the surface
            mesh is kept, no quality refinement). Regular tets inside, a Delaunay layer near
            the boundary. Not what Gmsh's algorithm 9 makes (its points follow a frame field
            aligned with the boundary), but the same idea: points on a lattice.

Usage:
  /usr/bin/python3.11 bench/make_meshes.py                      # 10k and 100k, then 1M
  /usr/bin/python3.11 bench/make_meshes.py --sizes 10k,100k
  /usr/bin/python3.11 bench/make_meshes.py --shapes box,torus --kinds delaunay
  /usr/bin/python3.11 bench/make_meshes.py --find-h box:100000  # search the h of a target count
  /usr/bin/python3.11 bench/make_meshes.py --kinds tetgen-lattice --find-h box:100000:1.9
  /usr/bin/python3.11 bench/make_meshes.py --kinds lattice --sizes 10k,100k \
      --gmsh ~/.cache/hexmerge/gmsh-trixie/gmsh                  # Gmsh >= 4.12: fetch_gmsh.py
"""
import argparse
import json
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
    "sphere":   {"10k": 3.2,  "100k": 1.44, "1m": 0.665},   #  9,831 /  99,995 / 1,001,791
    "torus":    {"10k": 3.84, "100k": 1.74, "1m": 0.8},     # 10,267 /  99,950 / 1,000,624
}

# -clmax h for the lattice kind (Gmsh 4.13.1's algorithm 9, -nt 1: the same h gives the same
# mesh), found with --kinds lattice --find-h; comments give the measured tet counts.
# The sphere and the torus have none: on them algorithm 9 does not follow -clmax (the sphere
# 330,881 tets at h 1.61 and 366,020 at every h from 13 to 16,000; the torus 644,167 at h 1.95 and
# a segmentation fault at h 17.2). At 1M two runs at h 0.93 gave 1,048,860 and 1,049,007 tets
# (at 100k two runs gave the same file).
H_LATTICE = {
    "box":      {"10k": 4.48, "100k": 2.0,  "1m": 0.93},   # 9,975 / 99,920 / 1,049,007 (80 s)
    "cylinder": {"10k": 4.25, "100k": 1.97, "1m": None},   # 9,705 / 102,292
    "bracket":  {"10k": 3.4,  "100k": 1.53, "1m": None},   # 9,936 / 97,130
    "sphere":   {"10k": None, "100k": None, "1m": None},
    "torus":    {"10k": None, "100k": None, "1m": None},
}
GMSH = os.environ.get("HEXMERGE_GMSH", "gmsh")  # the Gmsh every kind runs (--gmsh)

KINDS = {
    "delaunay": ["-setnumber", "Mesh.Algorithm3D", "1"],
    "lattice": ["-setnumber", "Mesh.Algorithm3D", "9", "-setnumber", "Mesh.Recombine3DAll", "0"],
    "tetgen-lattice": None,  # not a Gmsh 3D algorithm: see make_tetgen_lattice()
}

# h (surface -clmax and lattice spacing) for tetgen-lattice, found with
# --kinds tetgen-lattice --find-h SHAPE:COUNT; comments give the measured tet counts.
H_TETGEN_LATTICE = {
    "box":      {"10k": 4.16, "100k": 1.9,  "1m": 0.88},   # 10,210 / 98,629 / 1,027,223
    "cylinder": {"10k": 4.24, "100k": 1.97, "1m": 0.915},  # 10,051 / 98,450 / 985,764
    "bracket":  {"10k": 3.18, "100k": 1.41, "1m": 0.655},  # 10,232 / 96,929 / 1,058,986
    "sphere":   {"10k": 3.45, "100k": 1.6,  "1m": 0.74},   #  9,984 / 97,588 / 976,520
    "torus":    {"10k": 4.14, "100k": 1.92, "1m": 0.89},   #  9,747 / 98,512 / 973,221
}


def signed_distance(shape, p):
    """Approximate distance to the boundary of each shape (positive inside), p: (n, 3) in mm.
    Must match the .geo files."""
    import numpy as np
    x, y, z = p[:, 0], p[:, 1], p[:, 2]
    if shape == "box":
        return np.minimum.reduce([x, 100 - x, y, 40 - y, z, 30 - z])
    if shape == "cylinder":
        return np.minimum.reduce([20 - np.hypot(x, y), z, 100 - z])
    if shape == "bracket":
        base = np.minimum.reduce([x, 80 - x, y, 40 - y, z, 10 - z, np.hypot(x - 50, y - 20) - 8])
        flange = np.minimum.reduce([x, 10 - x, y, 40 - y, z, 60 - z])
        return np.maximum(base, flange)
    if shape == "sphere":
        return 25 - np.sqrt(x * x + y * y + z * z)
    if shape == "torus":
        return 12 - np.hypot(np.hypot(x, y) - 40, z)
    raise ValueError(shape)


BBOX = {"box": ((0, 0, 0), (100, 40, 30)), "cylinder": ((-20, -20, 0), (20, 20, 100)),
        "bracket": ((0, 0, 0), (80, 40, 60)), "sphere": ((-25, -25, -25), (25, 25, 25)),
        "torus": ((-52, -52, -12), (52, 52, 12))}


def make_tetgen_lattice(shape, h, out, timeout=3600, jitter=0.0, seed=1):
    """Substitute for Gmsh's lattice-point mesher (which crashes in Debian's build): Gmsh's
    surface mesh (-clmax h), plus the points of an axis-aligned cubic lattice of spacing h
    (cell centres of the bounding box grid) lying at least 0.6 h inside (each moved by up to
    jitter * h per coordinate, uniform, numpy seed `seed`: hex-friendly points that are no
    exact lattice, bench/groups.py), tetrahedralised by
    TetGen keeping the surface mesh (tetgen -pY), through the library's TetGen interface
    (hexmerge._core.tetrahedralize: the module must be importable, e.g. PYTHONPATH=src/python).
    Written as msh 4.1 through meshio."""
    import numpy as np
    import meshio
    log = []
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        surf = os.path.join(tmp, "s.mesh")
        cmd = [GMSH, "-2", "-clmax", repr(h), "-nt", "1", "-save_all", "-format", "mesh",
               os.path.join(GEOMETRY_DIR, shape + ".geo"), "-o", surf]
        p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                           timeout=timeout)
        log.append(p.stdout)
        if p.returncode != 0:
            return False, p.returncode, time.perf_counter() - t0, "\n".join(log), cmd
        surface = meshio.read(surf)
        tri = surface.get_cells_type("triangle")
        used, tri = np.unique(tri, return_inverse=True)
        tri = tri.reshape(-1, 3)
        lo, hi = (np.array(v, dtype=float) for v in BBOX[shape])
        axes = [np.arange(lo[i] + h / 2, hi[i], h) for i in range(3)]
        g = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
        g = g[signed_distance(shape, g) > 0.6 * h]
        if jitter > 0:
            g = g + np.random.default_rng(seed).uniform(-jitter * h, jitter * h, g.shape)
        # A PLC of the surface triangles whose point list also holds the lattice points: TetGen
        # keeps them as isolated interior vertices. (tetgen -i with an .a.node file crashes here.)
        from hexmerge import _core
        pts = np.vstack([surface.points[used], g])
        try:
            pts, tets, tcmd = _core.tetrahedralize(pts, tri, first_isolated=len(used),
                                                   time_limit=timeout, restarts=0)
        except ValueError as e:  # hexmerge.InputError: TetGen failed, in our words
            log.append(str(e))
            return False, 1, time.perf_counter() - t0, "\n".join(log), cmd
        cmd = cmd + ["&&", "(lattice points)", "&&", tcmd]
        tets = np.array(tets, dtype=np.int64)
        a, b, c, d = (pts[tets[:, i]] for i in range(4))
        neg = np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a) < 0
        tets[neg] = tets[neg][:, [0, 2, 1, 3]]
        meshio.write(out, meshio.Mesh(pts, [("tetra", tets)]), file_format="gmsh", binary=False)
    return True, 0, time.perf_counter() - t0, "\n".join(log), cmd

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
    if kind == "tetgen-lattice":
        return make_tetgen_lattice(shape, h, out, timeout)
    geo = os.path.join(GEOMETRY_DIR, shape + ".geo")
    cmd = [GMSH, "-3", "-clmax", repr(h), "-order", "1", "-format", "msh41", "-nt", "1"]
    cmd += KINDS[kind] + [geo, "-o", os.path.abspath(out)]
    t0 = time.perf_counter()
    try:
        # In a folder of its own: algorithm 9 writes its points to new_points.pos where it runs.
        with tempfile.TemporaryDirectory() as work:
            p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                               timeout=timeout, cwd=work)
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
    best = None
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "m.msh")
        for _ in range(maxit):
            ok, rc, dt, log, _ = run_gmsh(shape, kind, h, out)
            if not ok:
                raise RuntimeError(f"gmsh failed for {shape} h={h}: rc={rc}\n{log[-2000:]}")
            n, _ = count_msh41(out)
            print(f"  {shape} h={h:.4g}: {n} tets ({dt:.1f} s)", flush=True)
            if best is None or abs(n / target - 1) < abs(best[1] / target - 1):
                best = (h, n)
            if abs(n / target - 1) < tol:
                break
            h = float(f"{h * (n / target) ** (1 / 3):.3g}")
    return best


def load_manifest():
    if os.path.exists(MANIFEST):
        with open(MANIFEST) as f:
            return json.load(f)
    return {}


def save_manifest_entry(name, entry):
    """Re-read the manifest and update one entry (another run may have written meanwhile)."""
    m = load_manifest()
    m[name] = entry
    tmp = MANIFEST + f".{os.getpid()}.tmp"
    with open(tmp, "w") as f:
        json.dump(m, f, indent=1, sort_keys=True)
    os.replace(tmp, MANIFEST)


def main():
    global GMSH
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", default="10k,100k,1m", help="comma list of 10k, 100k, 1m")
    ap.add_argument("--shapes", default=",".join(SHAPES), help="comma list of " + ", ".join(SHAPES))
    ap.add_argument("--kinds", default=",".join(KINDS), help="comma list of " + ", ".join(KINDS))
    ap.add_argument("--force", action="store_true", help="regenerate meshes that exist")
    ap.add_argument("--retry-failed", action="store_true",
                    help="retry kinds recorded as failed in the manifest (by default skipped)")
    ap.add_argument("--gmsh", default=GMSH,
                    help="the Gmsh to run (default: $HEXMERGE_GMSH, else gmsh; the lattice kind needs >= 4.12)")
    ap.add_argument("--find-h", metavar="SHAPE:COUNT[:H0]", action="append",
                    help="search the -clmax giving about COUNT tets (first guess H0) of the first of --kinds "
                         "(default delaunay), print it and exit")
    args = ap.parse_args()
    args.kinds_given = any(a.startswith("--kinds") for a in sys.argv[1:])
    GMSH = args.gmsh

    if args.find_h:
        for spec in args.find_h:
            shape, count, *h0 = spec.split(":")
            count = int(float(count.lower().replace("k", "e3").replace("m", "e6")))
            h, n = find_h(shape, count, kind=args.kinds.split(",")[0] if args.kinds_given else "delaunay",
                          h0=float(h0[0]) if h0 else 5.0)
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
                h = {"tetgen-lattice": H_TETGEN_LATTICE, "lattice": H_LATTICE}.get(kind, H)[shape][size]
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
                         "command": " ".join(cmd[:-1] + [os.path.relpath(out, HERE)])
                         if kind != "tetgen-lattice" else " ".join(cmd),
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
                save_manifest_entry(name, entry)
    return 0


if __name__ == "__main__":
    sys.exit(main())
