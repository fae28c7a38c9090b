#!/usr/bin/python3.11
"""Fingerprints of the CAD mesher's output (hexmerge._core.mesh_shape), to check that a change
to the mesher (a refactor, a speed-up) leaves its tets identical.

For every case (shape, size h, options): a SHA-1 of the points, tets and regions arrays, and the
mesher's report without its timings (the TetGen command's work folder is written as <work>).
Prints a table case -> hash; --output writes them as JSON, --compare OLD.json reports every
difference (exit status 1 when any).

Shapes: bench/geometry's .geo files and a few more (below) made into BREP by `gmsh -0`, FreeCAD's
plate with a hole (resources/examples), and real parts from a folder of STEP files (--cad,
default /work/shared/cad; the cases whose file is missing are skipped and listed).

Usage (after building the module, see bench/README.md):
  PYTHONPATH=src/python /usr/bin/python3.11 bench/mesher_hashes.py --output /tmp/before.json
  ... mesher_hashes.py --compare /tmp/before.json
  ... mesher_hashes.py --cases cylinder-2.57,plate-6 --compare /tmp/before.json
  ... mesher_hashes.py --compare /tmp/before.json --ignore-new-keys   (a change adding report keys)
  ... mesher_hashes.py --compare /tmp/before.json --option feature_size=0   (a new option off)
"""
import argparse
import hashlib
import json
import os
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
GEOMETRY = os.path.join(ROOT, "bench", "geometry")
sys.path.insert(0, HERE)
import benchlib  # noqa: E402

# Shapes beyond bench/geometry (Gmsh .geo text, OpenCASCADE kernel): straight edges across the
# lattice (hexagonal prism, swept; notched trapezoid, not swept), fillets meeting lattice faces,
# ten solids (regions by solid), a tube and a plate with four holes (swept, holes in the caps).
GEO_TEXTS = {
    "hexagonal_prism": """SetFactory("OpenCASCADE");
For i In {0:5}
  Point(i + 1) = {20 * Cos(i * Pi / 3), 20 * Sin(i * Pi / 3), 0};
EndFor
For i In {0:5}
  Line(i + 1) = {i + 1, (i + 1) % 6 + 1};
EndFor
Curve Loop(1) = {1, 2, 3, 4, 5, 6};
Plane Surface(1) = {1};
Extrude {0, 0, 30} { Surface{1}; }
""",
    "notched_trapezoid": """SetFactory("OpenCASCADE");
Point(1) = {0, 0, 0}; Point(2) = {50, 0, 0}; Point(3) = {50, 20, 0}; Point(4) = {0, 35, 0};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Extrude {0, 0, 25} { Surface{1}; }
Box(10) = {20, 0, 15, 10, 10, 10};
BooleanDifference(11) = { Volume{1}; Delete; }{ Volume{10}; Delete; };
""",
    "rounded_rectangle": """SetFactory("OpenCASCADE");
Rectangle(1) = {0, 0, 0, 60, 30, 8};
Extrude {0, 0, 20} { Surface{1}; }
""",
    "box_5_cylinder": """SetFactory("OpenCASCADE");
For i In {0:4}
  Box(i + 1) = {20 * i, 0, 0, 20, 40, 30};
EndFor
Cylinder(6) = {0, 20, 15, 100, 0, 0, 8};
BooleanFragments{ Volume{1:5}; Delete; }{ Volume{6}; Delete; }
""",
    "tube": """SetFactory("OpenCASCADE");
Cylinder(1) = {0, 0, 0, 0, 0, 40, 15};
Cylinder(2) = {0, 0, 0, 0, 0, 40, 9};
BooleanDifference(3) = { Volume{1}; Delete; }{ Volume{2}; Delete; };
""",
    "plate_four_holes": """SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 80, 50, 8};
For i In {0:3}
  Cylinder(i + 2) = {15 + 50 * (i % 2), 12 + 26 * Floor(i / 2), 0, 0, 0, 8, 5};
EndFor
BooleanDifference(10) = { Volume{1}; Delete; }{ Volume{2:5}; Delete; };
""",
}

PLATE = os.path.join(ROOT, "resources", "examples", "material_nl_platewithhole.brep")

# (case name, shape, h, options). Shapes: a bench/geometry name, a GEO_TEXTS name, "plate", or
# "cad:FILE" (a STEP file in --cad).
CASES = [
    ("box-4", "box", 4.0, {}),
    ("cylinder-2.57", "cylinder", 2.57, {}),
    ("cylinder-5", "cylinder", 5.0, {}),
    ("cylinder-5-unswept", "cylinder", 5.0, {"sweep": False}),
    ("bracket-3", "bracket", 3.0, {}),
    ("bracket-1.48", "bracket", 1.48, {}),
    ("bracket-4-layers2-principal", "bracket", 4.0, {"boundary_layers": 2, "frame": "principal"}),
    ("sphere-4", "sphere", 4.0, {}),
    ("torus-4", "torus", 4.0, {}),
    ("plate-6", "plate", 6.0, {}),
    ("plate-10-unswept", "plate", 10.0, {"sweep": False}),
    ("hexagonal_prism-2.5", "hexagonal_prism", 2.5, {}),
    ("hexagonal_prism-4", "hexagonal_prism", 4.0, {}),
    ("notched_trapezoid-2.5", "notched_trapezoid", 2.5, {}),
    ("rounded_rectangle-3", "rounded_rectangle", 3.0, {}),
    ("box_5_cylinder-4", "box_5_cylinder", 4.0, {}),
    ("box_5_cylinder-4-unswept", "box_5_cylinder", 4.0, {"sweep": False}),
    ("tube-2.5", "tube", 2.5, {}),
    ("plate_four_holes-3", "plate_four_holes", 3.0, {}),
    ("plate-6-local", "plate", 6.0, {"local_sizes": "Face1:3; Edge2,Edge3:2"}),
    ("bracket-3-local", "bracket", 3.0, {"local_sizes": "Face2:1.5; Edge5:1"}),
    ("gmsh_part", "cad:gmsh_part.step", 4.8, {}),
    ("pyocc_face_recognition", "cad:pyocc_face_recognition_sample_part.stp", 11.0, {}),
    ("gmsh_t20_data", "cad:gmsh_t20_data.step", 2.8, {}),
    # Hexahedra across tube walls (step 8b): the tee's pipes, an unswept tube, the yoke's bores.
    ("flanged_tee-5.5", "flanged_tee", 5.5, {}),
    ("tube-3.5-unswept", "tube", 3.5, {"sweep": False}),
    ("gmsh_U_Joint_2", "cad:gmsh_U_Joint_2.stp", 2.69, {}),
]


def shape_text(shape: str, work: str, cad: str) -> str | None:
    from hexmerge import _core
    if shape.startswith("cad:"):
        path = os.path.join(cad, shape[4:])
        return _core.read_shape_file(path) if os.path.isfile(path) else None
    if shape == "plate":
        return _core.read_shape_file(PLATE)
    geo = os.path.join(GEOMETRY, shape + ".geo")
    if shape in GEO_TEXTS:
        geo = os.path.join(work, shape + ".geo")
        with open(geo, "w") as f:
            f.write(GEO_TEXTS[shape])
    brep = os.path.join(work, shape + ".brep")
    if not os.path.exists(brep):
        benchlib.geo_to_cad(geo, brep)
    return _core.read_shape_file(brep)


def fingerprint(points, tets, regions, report: dict, work: str, drop=()) -> tuple[str, str, dict]:
    """SHA-1 of the mesh and the report, SHA-1 of the mesh alone (points, tets, regions), and
    the report hashed (without its times and the keys in `drop`)."""
    import numpy as np
    h = hashlib.sha1()
    for name, a in (("points", points), ("tets", tets), ("regions", regions)):
        a = np.ascontiguousarray(a)
        h.update(name.encode() + str(a.dtype).encode() + str(a.shape).encode())
        h.update(a.tobytes())
    mesh_sha = h.hexdigest()
    rep = {k: v for k, v in benchlib.jsonable(dict(report)).items()
           if k != "phase_seconds" and k not in drop}
    if "tetgen_command" in rep:
        rep["tetgen_command"] = rep["tetgen_command"].replace(work, "<work>")
    h.update(json.dumps(rep, sort_keys=True).encode())
    return h.hexdigest(), mesh_sha, rep


def option_texts(options: dict) -> dict:
    """The mesher's options as the text its compiled table parses (hexmerge._validate)."""
    from hexmerge import _shape, _validate
    rows = {row["name"]: row for row in _shape.mesh_parameters()}
    return {name: _validate.option_text(name, value, rows[name]) for name, value in options.items()}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cases", help="comma-separated case names (default: all)")
    ap.add_argument("--cad", default="/work/shared/cad", help="folder of the STEP parts")
    ap.add_argument("--tetgen", default="tetgen")
    ap.add_argument("--option", action="append", default=[], metavar="NAME=VALUE",
                    help="a mesher option for every case (repeatable; a case's own wins), e.g. "
                    "feature_size=0 to compare with a version before that option")
    ap.add_argument("--output", help="JSON file to write")
    ap.add_argument("--compare", metavar="JSON", help="an earlier output to compare with")
    ap.add_argument("--ignore-new-keys", action="store_true",
                    help="with --compare: leave the report keys the earlier output lacks out of "
                    "the fingerprints (a change that adds report fields, nothing else)")
    args = ap.parse_args()
    old = {}
    if args.compare and args.ignore_new_keys:
        with open(args.compare) as f:
            old = json.load(f)

    from hexmerge import _core

    common = {}
    for text in args.option:
        key, _, value = text.partition("=")
        try:
            common[key] = json.loads(value)  # numbers, true / false
        except json.JSONDecodeError:
            common[key] = value
    wanted = set(args.cases.split(",")) if args.cases else None
    cases = [c for c in CASES if wanted is None or c[0] in wanted]
    if wanted is not None and len(cases) != len(wanted):
        unknown = wanted - {c[0] for c in cases}
        print(f"unknown cases: {', '.join(sorted(unknown))}", file=sys.stderr)
        return 2
    results, skipped = {}, []
    with tempfile.TemporaryDirectory(prefix="mesher-hashes-") as work:
        for name, shape, size, options in cases:
            brep = shape_text(shape, work, args.cad)
            if brep is None:
                skipped.append(name)
                continue
            run_dir = os.path.join(work, "run")
            start = time.perf_counter()
            try:
                given = dict(common, **options, size=size, tetgen=args.tetgen, work_directory=run_dir)
                points, tets, regions, report = _core.mesh_shape(brep, option_texts(given))
            except ValueError as e:  # InputError: the failure's message is the fingerprint
                sha = hashlib.sha1(("error: " + str(e).replace(run_dir, "<work>")).encode()).hexdigest()
                results[name] = {"sha1": sha, "error": str(e).splitlines()[0]}
                print(f"{name:32s} {sha}  error: {str(e).splitlines()[0]}", flush=True)
                continue
            seconds = time.perf_counter() - start
            drop = ()
            if name in old and "report" in old[name]:
                drop = set(dict(report)) - set(old[name]["report"]) - {"phase_seconds"}
            sha, mesh_sha, rep = fingerprint(points, tets, regions, report, run_dir, drop)
            results[name] = {"sha1": sha, "mesh_sha1": mesh_sha, "tets": int(len(tets)),
                             "points": int(len(points)), "report": rep, "seconds": seconds}
            print(f"{name:32s} {sha}  {len(tets):7d} tets {seconds:6.2f} s", flush=True)
    if skipped:
        print(f"skipped (no file in {args.cad}): {', '.join(skipped)}")
    if args.output:
        with open(args.output, "w") as f:
            json.dump(results, f, indent=1)
    if not args.compare:
        return 0
    return benchlib.compare_hashes(results, args.compare)

if __name__ == "__main__":
    sys.exit(main())
