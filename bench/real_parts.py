#!/usr/bin/python3.11
"""The real-parts benchmark (issue 13): hexmerge.mesh_shape on real CAD parts at two sizes.

Parts: every STEP/BREP/IGES file of the shared CAD folder (--cad, default $HEXMERGE_CAD_DIR or
../shared/cad beside the repository; skipped with a message when it is absent), the generated parts of
bench/geometry (GENERATED below: Gmsh .geo files, OpenCASCADE kernel, turned into STEP by
`gmsh -0` at the start of the run) and the CAD or .geo files of an --extra folder. Every part is
read with hexmerge's own reader (hexmerge._core.read_shape_file).

Sizes: for each target tet count (--sizes, default 50k,250k) the size h is found from the
volume: tets ~ c V / h^3. V is OpenCASCADE's volume of the part (through Gmsh: `Mass Volume`).
c is calibrated on a first run at a coarse size (about 10k tets, guessed with the median c of
the parts run so far), h = (c V / N)^(1/3) is run, and rescaled from its tet count, at most
twice, while that is more than 15 % off (tets ~ h^-k, k fitted through the last two runs, 3
when there is one, within [1.5, 3]); the larger size starts from the smaller one's runs. Every
try is a full measured run; the row kept is the last. The h used are
written to bench/results/real-parts-sizes.json; --sizes-from reads them back (one run per part
and size, reproducible).

Each run is a fresh subprocess (this script with --worker) with a timeout (--timeout, default
300 s) and an address-space limit (--memory, default 8 GB, RLIMIT_AS, TetGen included), so a
crash or hang becomes a status: ok, error (the first line of the error message), crash (the
signal, or an exit without result) or timeout. The worker meshes the tets
(hexmerge.mesh_shape(..., recombine=False), default options), recombines them
(hexmerge.recombine, default options: conforming), runs the independent checker (hexmerge.check)
and measures the scaled Jacobian of every element and the angles of the boundary triangles.

Results: bench/results/real-parts-latest.json (written after every run) and Markdown tables on
stdout (with --docs also into docs/benchmarks-real-parts.md, between its table markers).

Usage (after building the module, see bench/README.md):
  PYTHONPATH=src/python /usr/bin/python3.11 bench/real_parts.py            # all parts, 50k and 250k
  ... real_parts.py --parts Kurbel,flanged --sizes 50k --timeout 120
  ... real_parts.py --sizes-from bench/results/real-parts-sizes.json --docs
  ... real_parts.py --table bench/results/real-parts-latest.json           # re-print the tables
  ... real_parts.py --buffer-census bench/results/real-parts-latest.json   # why the bases got no hexahedron
"""
import argparse
import concurrent.futures
import datetime
import json
import math
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time

import benchlib
import run_bench  # (parse_value)

ROOT = benchlib.ROOT
# The shared real parts: ../shared/cad beside the repository, or $HEXMERGE_CAD_DIR.
DEFAULT_CAD = os.environ.get("HEXMERGE_CAD_DIR") or os.path.join(os.path.dirname(ROOT), "shared", "cad")
CAD_SUFFIXES = (".step", ".stp", ".brep", ".brp", ".iges", ".igs")  # hexmerge's SHAPE_SUFFIXES
# Generated parts (bench/geometry/NAME.geo); each file says what it is.
GENERATED = ["flanged_tee", "hex_bolt", "thin_bracket", "touching_boxes", "holed_plate"]
RESULTS = os.path.join(benchlib.RESULTS_DIR, "real-parts-latest.json")
SIZES_FILE = os.path.join(benchlib.RESULTS_DIR, "real-parts-sizes.json")
GMSH_REFERENCE = os.path.join(benchlib.RESULTS_DIR, "gmsh-reference.json")  # bench/gmsh_reference.py
DOCS = os.path.join(ROOT, "docs", "benchmarks-real-parts.md")
TABLE_BEGIN = "<!-- real-parts table: bench/real_parts.py --docs writes from here -->"
TABLE_END = "<!-- real-parts table end -->"
PROBE_TETS = 10_000  # the coarse first run
C_GUESS = 7.0  # tets h^3 / V before any part is measured (measured median: see the sizes file)
TOLERANCE = 0.15  # a count within 15 % of the target is kept
RESCALES = 2  # at most this many runs after the first one aimed at the target
SJ_FLOOR = 0.2  # issue 13: every element's scaled Jacobian at least 0.2

# Scaled Jacobian corner frames {v, a, b, c} and scale per type, in the order of CellType
# (tet, pyramid, prism, hex): a copy of src/hexmerge/mesh/cell_type.cpp's table, so that the
# per-element count below is the checker's measure (the worker checks that its minimum equals
# the checker's).
CORNERS = [
    ([(0, 1, 2, 3), (1, 2, 0, 3), (2, 0, 1, 3), (3, 0, 2, 1)], 2 ** 0.5),
    ([(0, 1, 3, 4), (1, 2, 0, 4), (2, 3, 1, 4), (3, 0, 2, 4)], 2 ** 0.5),
    ([(0, 1, 2, 3), (1, 2, 0, 4), (2, 0, 1, 5), (3, 5, 4, 0), (4, 3, 5, 1), (5, 4, 3, 2)], 2 / 3 ** 0.5),
    ([(0, 1, 3, 4), (1, 2, 0, 5), (2, 3, 1, 6), (3, 0, 2, 7), (4, 7, 5, 0), (5, 4, 6, 1), (6, 5, 7, 2),
      (7, 6, 4, 3)], 1.0),
]
NB_VERTICES = [4, 5, 6, 8]


# --------------------------------------------------------------------------- measures
def corner_scaled_jacobians(p, corners, scale):
    """Verdict's scaled Jacobian of cells of one type (src/hexmerge/geometry/quality.cpp): p holds
    their vertices' coordinates (cells x vertices x 3); the smallest corner determinant of the
    unit edge vectors over the type's corner frames {v, a, b, c}, times its scale, capped at 1."""
    import numpy as np

    worst = np.full(len(p), np.inf)
    for v, a, b, c in corners:
        e = [p[:, k] - p[:, v] for k in (a, b, c)]
        length = np.prod([np.linalg.norm(x, axis=1) for x in e], axis=0)
        det = np.einsum("ij,ij->i", e[0], np.cross(e[1], e[2]))
        worst = np.minimum(worst, np.divide(det, length, out=np.zeros_like(det), where=length > 0))
    return np.minimum(1.0, worst * scale)


def scaled_jacobians(mesh):
    """Verdict's scaled Jacobian of every cell of a MixedMesh (corner_scaled_jacobians per type)."""
    import numpy as np

    sj = np.empty(mesh.nb_cells)
    for t, (corners, scale) in enumerate(CORNERS):
        cells = np.flatnonzero(mesh.types == t)
        if len(cells) == 0:
            continue
        vertices = mesh.cell_vertices[mesh.offsets[cells][:, None] + np.arange(NB_VERTICES[t])]
        sj[cells] = corner_scaled_jacobians(mesh.points[vertices], corners, scale)
    return sj


def tet_scaled_jacobians(points, tets):
    """Verdict's scaled Jacobian of every tet of a plain tet mesh (points n x 3, tets m x 4 vertex
    indices, Gmsh's and hexmerge's orientation): the same measure as scaled_jacobians'."""
    corners, scale = CORNERS[0]
    return corner_scaled_jacobians(points[tets], corners, scale)


def boundary_triangle_angles(points, tets):
    """The smallest corner angle, in degrees, of every boundary triangle of a tet mesh (faces of
    one tet only; faces between two solids are inside)."""
    import numpy as np

    faces = np.sort(tets[:, [[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]]].reshape(-1, 3), axis=1)
    faces, counts = np.unique(faces, axis=0, return_counts=True)
    p = points[faces[counts == 1]]
    smallest = np.full(len(p), 180.0)
    for i in range(3):  # atan2 of the sine and cosine: exact down to tiny angles, unlike arccos
        u, w = p[:, (i + 1) % 3] - p[:, i], p[:, (i + 2) % 3] - p[:, i]
        sine = np.linalg.norm(np.cross(u, w), axis=1)
        smallest = np.minimum(smallest, np.degrees(np.arctan2(sine, np.einsum("ij,ij->i", u, w))))
    return smallest


# --------------------------------------------------------------------------- worker
def first_line(e: BaseException) -> str:
    lines = str(e).strip().splitlines()
    return f"{type(e).__name__}: {lines[0] if lines else ''}".strip()


def worker(path: str, size: float, options: dict | None = None) -> dict:
    """Mesh (with the mesher's `options`, hexmerge.mesh_parameters()), recombine and check one part
    at one size (in this process); the result row."""
    import numpy as np
    import hexmerge
    from hexmerge import _core

    out = {"phase": "read"}
    try:
        start = time.perf_counter()
        brep = _core.read_shape_file(path)
        out["read_s"] = time.perf_counter() - start
        out["phase"] = "mesh"
        tets, rep = hexmerge.mesh_shape(brep, size, recombine=False, **(options or {}))
        meshing = rep["meshing"]
        points = tets.points
        cells = tets.cell_vertices.reshape(-1, 4).astype(np.int64)
        regions = tets.regions
        out.update(mesh_s=meshing["seconds"], tets=meshing["tets"], points=meshing["points"],
                   tetgen_s=meshing["phase_seconds"].get("tetgen"), mesh_phase_s=meshing["phase_seconds"],
                   boundary_distance=meshing["max_boundary_distance"],
                   solids=meshing["nb_solids"], sweep_axis=meshing["sweep_axis"],
                   tetgen_restarts=meshing["nb_tetgen_restarts"],
                   nudged_points=meshing["nb_nudged_points"], buffer_bases=meshing["buffer_bases"],
                   min_boundary_angle=float(boundary_triangle_angles(points, cells).min()))
        out["phase"] = "recombine"
        start = time.perf_counter()
        mesh, report = hexmerge.recombine(points, cells, regions)
        out["recombine_s"] = time.perf_counter() - start
        out.update(volume=report["input_volume"],
                   counts=report["output_counts"], volume_fraction=report["volume_fraction"],
                   reduction=report["element_reduction_percent"], strategy=report["selection_strategy"],
                   recombine_phase_s=report["phase_seconds"])
        out["phase"] = "check"
        check = hexmerge.check(mesh, points, cells, regions)
        sj = scaled_jacobians(mesh)
        # The elements at the CAD's sharp corners and edges (a node on them), where the CAD
        # itself may force a scaled Jacobian under 0.2.
        sharp = np.isin(mesh.point_map, np.asarray(meshing["sharp_nodes"], dtype=np.int64))
        at_sharp = np.add.reduceat(sharp[mesh.cell_vertices].astype(np.int64), mesh.offsets[:-1]) > 0
        out.update(sharp_features=len(meshing["sharp_features"]),
                   below_sj_floor_at_sharp=int(((sj < SJ_FLOOR) & at_sharp).sum()),
                   min_sj_off_sharp=float(sj[~at_sharp].min()) if (~at_sharp).any() else None)
        out.update(valid=check["valid"], cracks=check["cracks"], nonconforming_quads=check["nonconforming_quads"],
                   inverted=check["inverted_cells"], min_sj=check["min_scaled_jacobian"],
                   problems=list(check["problems"])[:3],
                   below_sj_floor=int((sj < SJ_FLOOR).sum()),
                   below_sj_floor_by_type={name: int(((sj < SJ_FLOOR) & (mesh.types == t)).sum())
                                           for t, name in enumerate(("tet", "pyramid", "prism", "hex"))})
        if abs(float(sj.min()) - check["min_scaled_jacobian"]) > 1e-9:
            raise RuntimeError(f"bench/real_parts.py's scaled Jacobians disagree with the checker: "
                               f"min {sj.min()} against {check['min_scaled_jacobian']}")
        out["phase"] = "done"
        out["status"] = "ok"
    except Exception as e:  # a failure is the result: its first line, and where it happened
        out["status"] = "error"
        out["error"] = first_line(e)
        out["error_text"] = str(e)[:1000]
    return out


# --------------------------------------------------------------------------- driver
def parse_count(text: str) -> int:
    t = text.strip().lower()
    scale = {"k": 1_000, "m": 1_000_000}.get(t[-1:], 1)
    return int(float(t.rstrip("km")) * scale)


def shape_facts(path: str) -> dict:
    """Solids, volume and bounding box of a CAD file as OpenCASCADE reads it, through Gmsh's
    `Mass` and `BoundingBox` (for the first size guess only). Empty when Gmsh cannot read it."""
    with tempfile.TemporaryDirectory() as work:
        geo = os.path.join(work, "facts.geo")
        with open(geo, "w") as f:
            f.write('SetFactory("OpenCASCADE");\nMerge "%s";\nv() = Volume{:};\n'
                    'For i In {0:#v()-1}\n  bb() = BoundingBox Volume{v(i)};\n'
                    '  m = Mass Volume{v(i)};\n'
                    '  Printf("facts %%.17g %%.17g %%.17g %%.17g %%.17g %%.17g %%.17g", m, bb(0), bb(1), bb(2), '
                    'bb(3), bb(4), bb(5));\nEndFor\n' % os.path.abspath(path))
        try:
            p = subprocess.run(["gmsh", "-0", geo, "-o", os.path.join(work, "x.geo_unrolled")], cwd=work,
                               capture_output=True, text=True, timeout=300)
        except subprocess.TimeoutExpired:
            return {}
    rows = [[float(x) for x in line.split()[1:]] for line in p.stdout.splitlines() if line.startswith("facts ")]
    if not rows:
        return {}
    lo = [min(r[1 + i] for r in rows) for i in range(3)]
    hi = [max(r[4 + i] for r in rows) for i in range(3)]
    return {"solids": len(rows), "volume": sum(r[0] for r in rows), "bbox": [lo, hi]}


def find_parts(args, work: str) -> list:
    """(name, path) of every part, the generated ones made into STEP files in `work`."""
    parts = []
    if os.path.isdir(args.cad):
        parts += [(os.path.splitext(f)[0], os.path.join(args.cad, f)) for f in sorted(os.listdir(args.cad))
                  if f.lower().endswith(CAD_SUFFIXES)]
    else:
        print(f"real_parts: no CAD folder {args.cad} (the shared real parts): skipping them", file=sys.stderr)
    geos = [os.path.join(benchlib.GEOMETRY_DIR, g + ".geo") for g in GENERATED] if not args.no_generated else []
    if args.extra:
        if not os.path.isdir(args.extra):
            raise SystemExit(f"real_parts: --extra {args.extra}: no such folder")
        for f in sorted(os.listdir(args.extra)):
            if f.lower().endswith(CAD_SUFFIXES):
                parts.append((os.path.splitext(f)[0], os.path.join(args.extra, f)))
            elif f.endswith(".geo"):
                geos.append(os.path.join(args.extra, f))
    wanted = [w for w in args.parts.split(",") if w] if args.parts else None
    keep = lambda name: wanted is None or any(w in name for w in wanted)  # noqa: E731
    for geo in geos:
        name = os.path.splitext(os.path.basename(geo))[0]
        if keep(name):
            parts.append((name, benchlib.geo_to_cad(geo, os.path.join(work, name + ".step"))))
    parts = [(n, p) for n, p in parts if keep(n)]
    names = [n for n, _ in parts]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise SystemExit(f"real_parts: two parts are named {', '.join(dup)}")
    return parts


class Runner:
    """Runs workers and keeps the results file and the sizes file up to date."""

    def __init__(self, args, header):
        self.args = args
        self.header = header
        self.rows = []
        self.lock = threading.Lock()
        self.sizes = {}
        if os.path.exists(SIZES_FILE):
            with open(SIZES_FILE) as f:
                self.sizes = json.load(f).get("parts", {})
        self.fixed = {}
        if args.sizes_from:
            with open(args.sizes_from) as f:
                self.fixed = json.load(f).get("parts", {})

    def c_guess(self) -> float:
        with self.lock:
            cs = [row["c"] for row in self.rows if row.get("status") == "ok" and row.get("c")]
        return statistics.median(cs) if cs else C_GUESS

    def run(self, name: str, path: str, size: float, facts: dict, target: str) -> dict:
        cmd = [sys.executable, os.path.abspath(__file__), "--worker", path, "--size", repr(size)]
        for option in self.args.option:
            cmd += ["--option", option]
        env = dict(os.environ)
        env["PYTHONPATH"] = os.pathsep.join(
            [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p] + [os.path.join(ROOT, "src", "python")])
        kind, payload, err, seconds = benchlib.run_worker(cmd, self.args.timeout, env,
                                                          int(self.args.memory * 2**30))
        row = {"part": name, "target": target, "h": size, "wall_s": seconds}
        if kind == "result":
            row.update(payload)
        elif kind == "timeout":
            row.update(status="timeout", error=f"timeout after {self.args.timeout:g} s")
        else:
            tail = [line for line in err.strip().splitlines() if line.strip()][-1:] or [""]
            if payload < 0:
                sig = signal.Signals(-payload).name if -payload in signal.valid_signals() else str(-payload)
                row.update(status="crash", error=f"signal {sig}: {tail[0]}".rstrip(": "))
            else:
                row.update(status="crash", error=f"exit {payload} without result: {tail[0]}".rstrip(": "))
        if row["status"] != "ok" and err.strip():
            row["stderr_tail"] = err.strip().splitlines()[-5:]
        if row.get("tets") and facts.get("volume"):
            row["c"] = row["tets"] * size**3 / facts["volume"]
        print(f"  {name} {target} h {size:.4g}: {row['status']}"
              + (f", {row['tets']:,} tets" if row.get("tets") else "")
              + (f", {row['error']}" if row.get("error") else "") + f" ({seconds:.1f} s)", file=sys.stderr, flush=True)
        return row

    def measure(self, name: str, path: str, facts: dict, target: str, previous: dict | None) -> dict:
        """The row of one part at one target count: the h of --sizes-from, else a search."""
        wanted = parse_count(target)
        fixed = self.fixed.get(name, {}).get(target, {}).get("h")
        tries = []
        if fixed:
            row = self.run(name, path, fixed, facts, target)
            tries.append((fixed, row.get("tets"), row["status"]))
            row["search_tries"] = self.fixed[name][target].get("tries", [])  # how h was found
        else:  # calibrate c on a coarse run, or on the smaller size's count
            if previous and previous.get("tets"):
                size = benchlib.rescaled_size(previous["h"], previous["tets"], wanted,
                                              benchlib.count_exponent([t[:2] for t in previous["tries"]]))
            elif facts.get("volume"):
                probe = self.run(name, path, (self.c_guess() * facts["volume"] / PROBE_TETS) ** (1 / 3),
                                 facts, target)
                tries.append((probe["h"], probe.get("tets"), probe["status"]))
                c = probe.get("c") or self.c_guess()
                size = (c * facts["volume"] / wanted) ** (1 / 3)
            else:  # Gmsh cannot read the file either; hexmerge's reader says what it finds
                return self.keep(name, target, tries, facts, dict(
                    part=name, target=target, h=None, status="error",
                    error="no size: Gmsh reads no solid from the file (its volume is unknown)"))
            # A part whose small features set the count (KiCad's 400-pin Samtec connector: about
            # 70k tets at any coarse size) asks for sizes past its extent: at most half of it.
            largest = max(hi - lo for lo, hi in zip(*facts["bbox"])) if facts.get("bbox") else math.inf
            size = min(size, 0.5 * largest)
            row = self.run(name, path, size, facts, target)
            tries.append((size, row.get("tets"), row["status"]))
            for _ in range(RESCALES):
                if not row.get("tets") or abs(row["tets"] / wanted - 1) <= TOLERANCE:
                    break
                known = (previous["tries"] if previous else []) + tries
                size = min(0.5 * largest, benchlib.rescaled_size(
                    size, row["tets"], wanted, benchlib.count_exponent([t[:2] for t in known])))
                if size == tries[-1][0]:
                    break  # at half the extent already
                row = self.run(name, path, size, facts, target)
                tries.append((size, row.get("tets"), row["status"]))
        return self.keep(name, target, tries, facts, row)

    def keep(self, name, target, tries, facts, row):
        row["tries"] = tries
        row["volume_cad"] = facts.get("volume")
        row["solids_cad"] = facts.get("solids")
        with self.lock:
            self.rows.append(row)
            self.sizes.setdefault(name, {})[target] = (
                self.fixed[name][target] if "search_tries" in row
                else {"h": row["h"], "tets": row.get("tets"), "tries": tries})
            self.save()
        return row

    def save(self):
        os.makedirs(benchlib.RESULTS_DIR, exist_ok=True)
        data = dict(self.header, rows=self.rows)
        for path, content in ((RESULTS, data), (SIZES_FILE, {"note": "h per part and target count, "
                              "written by bench/real_parts.py (read back with --sizes-from)",
                              "parts": self.sizes})):
            tmp = path + ".tmp"
            with open(tmp, "w") as f:
                json.dump(benchlib.jsonable(content), f, indent=1, sort_keys=False)
            os.replace(tmp, path)


# --------------------------------------------------------------------------- tables
def pct(row, kind):
    vf = row.get("volume_fraction") or {}
    return f"{100 * vf[kind]:.1f}" if kind in vf else "–"


def error_summary(row) -> str:
    """The first line of the error; when it ends with a colon (TetGen's output follows), with the
    next non-empty line too."""
    lines = [line.strip() for line in (row.get("error_text") or "").splitlines() if line.strip()]
    first = row.get("error", "")
    if first.endswith(":") and len(lines) > 1:
        return f"{first} {lines[1]}"
    return first


def short(text: str, width: int = 200) -> str:
    """A message cut to `width` characters for a table cell."""
    text = text.replace("|", "/")
    return text if len(text) <= width else text[:width - 1].rstrip() + "…"


def cell(row, key, spec):
    v = row.get(key)
    return "–" if v is None else format(v, spec)


def gmsh_cells(row, gmsh) -> list:
    """The "Gmsh min SJ" and "Gmsh min boundary angle" cells of a row: Gmsh's own tet mesh at the
    same h (bench/gmsh_reference.py's row `gmsh`, or None), its status when it failed, "h differs"
    when it was made at another h."""
    if gmsh is None:
        return ["–", "–"]
    if row.get("h") is None or gmsh.get("h") is None or abs(gmsh["h"] - row["h"]) > 1e-9 * row["h"]:
        return ["h differs"] * 2
    if gmsh["status"] != "ok":
        return [gmsh["status"]] * 2
    return [cell(gmsh, "min_sj", ".2g"), cell(gmsh, "min_boundary_angle", ".2g")]


def same_h_gmsh(row, gmsh) -> bool:
    """Whether both meshed at the same h: the rows whose min SJ can be compared."""
    return (gmsh is not None and row["status"] == "ok" and gmsh["status"] == "ok"
            and abs(gmsh["h"] - row["h"]) <= 1e-9 * row["h"])


def markdown(data, reference=None) -> str:
    """The tables of a results file; with `reference` (bench/gmsh_reference.py's results), two
    more columns per row: Gmsh's own tet mesh's min SJ and min boundary angle at the same h."""
    m = data["machine"]
    lines = [f"Commit `{data['commit']}`, {m['nproc']} CPUs ({m['cpu_model']}), {data['date']}; "
             f"timeout {data['options']['timeout']:g} s, memory limit {data['options']['memory']:g} GB, "
             f"{data['options']['jobs']} run(s) at a time; hexmerge defaults (conforming)."
             + (f" Gmsh columns: Gmsh {reference['gmsh_version']}'s own tet mesh at the same h "
                f"(`{reference['command']}`, bench/gmsh_reference.py, {reference['date']})." if reference else ""), ""]
    gmsh = {(r["part"], r["target"]): r for r in reference["rows"]} if reference else {}
    targets = []
    for row in data["rows"]:
        if row["target"] not in targets:
            targets.append(row["target"])
    worst = None
    for target in targets:
        rows = sorted((r for r in data["rows"] if r["target"] == target), key=lambda r: r["part"].lower())
        lines += [f"### About {target} tets", "",
                  "| part | h | status | s (mesh + recombine) | tets | hex vol % | prism vol % | pyramid vol % "
                  "| tet vol % | min SJ | min boundary angle ° | boundary dist / h | non-conf. quads | cracks "
                  "| SJ < 0.2 | of which at sharp CAD | min SJ off sharp CAD | volume vs CAD % |"
                  + (" Gmsh min SJ | Gmsh min boundary angle ° |" if reference else ""),
                  "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
                  + ("---|---|" if reference else "")]
        for r in rows:
            status = r["status"] if r["status"] == "ok" else short(f"{r['status']}: {error_summary(r)}")
            if r["status"] == "ok" and not r.get("valid"):
                status = "ok, **invalid**"
            meshed = [t for t in r.get("search_tries", []) + r.get("tries", []) if t[2] == "ok"]
            if r["status"] != "ok" and meshed:  # the size search met a size that meshes
                status += f" (ok at h {meshed[-1][0]:.4g}: {meshed[-1][1]:,} tets)"
            seconds = (f"{r['mesh_s'] + r['recombine_s']:.1f}" if r.get("recombine_s") is not None
                       else (f"{r['mesh_s']:.1f} (mesh)" if r.get("mesh_s") is not None else "–"))
            bdist = (f"{r['boundary_distance'] / r['h']:.1e}" if r.get("boundary_distance") is not None else "–")
            # The mesh's volume against OpenCASCADE's: a little less where faces are curved (their
            # triangles are chords), more where a void was filled.
            volume = (f"{100 * (r['volume'] - r['volume_cad']) / r['volume_cad']:+.2f}"
                      if r.get("volume") and r.get("volume_cad") else "–")
            lines.append(" | ".join([
                f"| {r['part']}", cell(r, "h", ".4g"), status, seconds, cell(r, "tets", ","),
                pct(r, "hex"), pct(r, "prism"), pct(r, "pyramid"), pct(r, "tet"), cell(r, "min_sj", ".2g"),
                cell(r, "min_boundary_angle", ".2g"), bdist, cell(r, "nonconforming_quads", ","),
                cell(r, "cracks", ","), cell(r, "below_sj_floor", ","),
                cell(r, "below_sj_floor_at_sharp", ","), cell(r, "min_sj_off_sharp", ".2g"), volume]
                + (gmsh_cells(r, gmsh.get((r["part"], target))) if reference else [])) + " |")
        ok = [r for r in rows if r["status"] == "ok"]
        both = [(r, gmsh[r["part"], target]) for r in ok if same_h_gmsh(r, gmsh.get((r["part"], target)))]
        hexes = [100 * r["volume_fraction"]["hex"] for r in ok]
        lines += ["", f"- {target}: {len(ok)} of {len(rows)} parts meshed"
                  + (f" ({sum(1 for r in ok if r.get('valid'))} valid by the checker)" if ok else "")
                  + (f"; median hex volume {statistics.median(hexes):.1f} %" if hexes else "")
                  + (f"; min SJ >= 0.2 on {sum(1 for r in ok if r['min_sj'] >= SJ_FLOOR)}" if ok else "")
                  + (f" (off the CAD's sharp corners and edges on "
                     f"{sum(1 for r in ok if (r.get('min_sj_off_sharp') or 1) >= SJ_FLOOR)})" if ok else "")
                  + (f"; min SJ below Gmsh's on {sum(1 for r, g in both if r['min_sj'] < g['min_sj'])} of "
                     f"{len(both)} (both meshed at the same h)" if reference else ""), ""]
        for r in ok:
            if worst is None or r["min_sj"] < worst["min_sj"]:
                worst = r
    if worst:
        lines.append(f"Worst min SJ: {worst['min_sj']:.3g} ({worst['part']}, {worst['target']}).")
    return "\n".join(lines)


def buffer_census(data) -> str:
    """The buffer layer's census (the mesher's `buffer_bases`, docs/mesher.md step 8a) of the
    rows that have one: per part and size, the core's closing pyramids' bases and why they got
    no hexahedron to the surface, then the totals per size."""
    rows = [r for r in data["rows"] if r.get("status") == "ok" and r.get("buffer_bases")]
    lines = ["| part | size | bases | apex shared | corner nearest a face that takes no top | "
             "other tests | dropped later | kept |", "|---|---|---|---|---|---|---|---|"]
    totals = {}
    for r in sorted(rows, key=lambda r: (parse_count(r["target"]), r["part"])):
        b = r["buffer_bases"]
        if not b["considered"]:
            continue
        other = b["considered"] - b["apex_shared"] - b["no_top_face"] - b["dropped_later"] - b["kept"]
        values = [b["considered"], b["apex_shared"], b["no_top_face"], other, b["dropped_later"], b["kept"]]
        total = totals.setdefault(r["target"], [0] * len(values))
        for k, v in enumerate(values):
            total[k] += v
        lines.append(f"| {r['part']} | {r['target']} | " + " | ".join(f"{v:,}" for v in values) + " |")
    for target, total in totals.items():
        lines.append(f"| all | {target} | " + " | ".join(f"{v:,}" for v in total) + " |")
    return "\n".join(lines)


def write_docs(table: str) -> None:
    text = open(DOCS).read() if os.path.exists(DOCS) else ""
    if TABLE_BEGIN in text and TABLE_END in text:
        head, rest = text.split(TABLE_BEGIN, 1)
        tail = rest.split(TABLE_END, 1)[1]
    else:
        head, tail = (text or "# Real-parts benchmark\n\n"), "\n"
    with open(DOCS + ".tmp", "w") as f:
        f.write(f"{head}{TABLE_BEGIN}\n\n{table}\n\n{TABLE_END}{tail}")
    os.replace(DOCS + ".tmp", DOCS)


def gmsh_reference(path) -> dict | None:
    """bench/gmsh_reference.py's results for the Gmsh columns: `path`, or by default
    bench/results/gmsh-reference.json when it exists; None for an empty path."""
    if path == "" or (path is None and not os.path.exists(GMSH_REFERENCE)):
        return None
    with open(path or GMSH_REFERENCE) as f:
        return json.load(f)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cad", default=DEFAULT_CAD, help="folder of the shared real parts (default: %(default)s)")
    ap.add_argument("--extra", help="another folder of parts (STEP, BREP, IGES or Gmsh .geo files)")
    ap.add_argument("--no-generated", action="store_true", help="leave out bench/geometry's generated parts")
    ap.add_argument("--parts", help="comma list; a part runs when its name holds one of them")
    ap.add_argument("--sizes", default="50k,250k", help="target tet counts (default: %(default)s)")
    ap.add_argument("--sizes-from", metavar="JSON", help="take h from this sizes file (real-parts-sizes.json)")
    ap.add_argument("--timeout", type=float, default=300, help="seconds per run (default: %(default)s)")
    ap.add_argument("--memory", type=float, default=8, help="GB of address space per run (default: %(default)s)")
    ap.add_argument("--jobs", type=int, default=1, help="parts run at a time (default: %(default)s)")
    ap.add_argument("--docs", action="store_true", help=f"also write the tables into {os.path.relpath(DOCS, ROOT)}")
    ap.add_argument("--table", metavar="JSON", help="print the tables of an earlier results file and exit")
    ap.add_argument("--buffer-census", metavar="JSON",
                    help="print the buffer layer's census (why the core's bases got no hexahedron) of a results file and exit")
    ap.add_argument("--gmsh-reference", metavar="JSON",
                    help="Gmsh's own tet mesh at the same sizes (bench/gmsh_reference.py) for the tables' Gmsh "
                    f"columns (default: {os.path.relpath(GMSH_REFERENCE, ROOT)} when it exists; '' for none)")
    ap.add_argument("--option", action="append", default=[], metavar="NAME=VALUE",
                    help="a mesher option (hexmerge.mesh_parameters()), repeatable: buffer_layer=true")
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    ap.add_argument("--size", type=float, help=argparse.SUPPRESS)
    args = ap.parse_args()

    if args.worker:
        options = {}
        for option in args.option:
            name, _, value = option.partition("=")
            options[name] = run_bench.parse_value(value)
        print(benchlib.RESULT_MARKER + json.dumps(benchlib.jsonable(worker(args.worker, args.size, options))),
              flush=True)
        return 0
    if args.buffer_census:
        with open(args.buffer_census) as f:
            print(buffer_census(json.load(f)))
        return 0
    if args.table:
        with open(args.table) as f:
            table = markdown(json.load(f), gmsh_reference(args.gmsh_reference))
        print(table)
        if args.docs:
            write_docs(table)
        return 0

    benchlib.stop_workers_on_signals()
    targets = [t.strip().lower() for t in args.sizes.split(",") if t.strip()]
    targets.sort(key=parse_count)
    header = {"commit": benchlib.git_commit(), "machine": benchlib.machine(),
              "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
              "options": {"timeout": args.timeout, "memory": args.memory, "jobs": args.jobs,
                          "sizes": targets, "sizes_from": args.sizes_from, "mesher": args.option}}
    with tempfile.TemporaryDirectory() as work:
        parts = find_parts(args, work)
        if not parts:
            print("real_parts: no parts to run", file=sys.stderr)
            return 1
        runner = Runner(args, header)
        print(f"real_parts: {len(parts)} parts, sizes {', '.join(targets)}", file=sys.stderr)
        with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
            facts = dict(zip([n for n, _ in parts], pool.map(shape_facts, [p for _, p in parts])))
            previous = {}  # every part at the smaller size first: its counts calibrate the larger
            for target in targets:
                rows = pool.map(lambda part: runner.measure(*part, facts[part[0]], target, previous.get(part[0])),
                                parts)
                previous = {r["part"]: r for r in rows if r["status"] == "ok"}
    table = markdown(dict(header, rows=runner.rows), gmsh_reference(args.gmsh_reference))
    print(table)
    if args.docs:
        write_docs(table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
