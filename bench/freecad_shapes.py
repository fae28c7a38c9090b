"""The solids of FreeCAD's own FEM examples and Path documents as BREP files, for
bench/real_parts.py --extra (issue 13: parts the mesher was not developed on).

Run it with FreeCAD's interpreter (Debian: freecad, freecad-common):

    freecadcmd bench/freecad_shapes.py [OUT_DIR]        # default /tmp/freecad-shapes

It builds every example of FreeCAD's `femexamples` that has a setup() (cantilevers, the plate with
a hole, compounds of boxes, a ring, a ball less two balls, ...) and writes the solid shape each
FEM mesh object meshes; it opens the Path workbench's test documents and tool-bit shapes
(PathTests/*.fcstd, Tools/Shape/*.fcstd) and writes the last solid of each chain of features
(the one no other solid feature uses), a shape met twice only once. Files are named
`<example or document>_<object>.brep`; a line per file (or per example that failed to build)
on stdout.

Then, with this repository's module:

    PYTHONPATH=src/python /usr/bin/python3.11 bench/real_parts.py --cad /nonexistent \
        --extra /tmp/freecad-shapes --no-generated --sizes 2k,20k,100k
"""
import glob
import importlib
import os
import sys

import FreeCAD  # noqa: F401  (freecadcmd's interpreter)

FREECAD = "/usr/share/freecad/Mod"
SKIP = {"__init__", "manager", "examplesgui"}


def solids_meshed(doc):
    """The shapes the document's FEM mesh objects mesh: (object, shape) with solids."""
    for o in doc.Objects:
        if not o.TypeId.startswith("Fem::FemMesh"):
            continue
        part = getattr(o, "Part", None) or getattr(o, "Shape", None)
        if part is not None and hasattr(part, "Shape") and part.Shape.Solids:
            yield part.Name, part.Shape


def last_solids(doc):
    """The solid features no other solid feature uses, a shape met twice (volume and faces) once."""
    seen = set()
    for o in doc.Objects:
        if not hasattr(o, "Shape") or not o.Shape.Solids:
            continue
        if any(hasattr(x, "Shape") and x.Shape.Solids for x in o.InList):
            continue
        key = (round(o.Shape.Volume, 6), len(o.Shape.Faces))
        if key not in seen:
            seen.add(key)
            yield o.Name, o.Shape


def write(out_dir, name, shape):
    path = os.path.join(out_dir, name + ".brep")
    shape.exportBrep(path)
    box = shape.BoundBox
    print(f"{path}: {len(shape.Solids)} solid(s), {len(shape.Faces)} faces, "
          f"{box.XLength:.4g} x {box.YLength:.4g} x {box.ZLength:.4g}")


def main(out_dir):
    os.makedirs(out_dir, exist_ok=True)
    examples = sorted(os.path.basename(p)[:-3] for p in glob.glob(f"{FREECAD}/Fem/femexamples/*.py"))
    for name in examples:
        if name in SKIP:
            continue
        module = importlib.import_module("femexamples." + name)
        if not hasattr(module, "setup"):
            continue
        try:
            doc = module.setup()
        except Exception as e:  # an example FreeCAD cannot build here (a missing solver, ...)
            print(f"{name}: not built ({e})")
            continue
        for obj, shape in solids_meshed(doc):
            write(out_dir, f"{name}_{obj}", shape)
        FreeCAD.closeDocument(doc.Name)
    documents = sorted(glob.glob(f"{FREECAD}/Path/PathTests/*.[fF][cC][sS]td")
                       + glob.glob(f"{FREECAD}/Path/Tools/Shape/*.fcstd"))
    for path in documents:
        doc = FreeCAD.openDocument(path)
        doc.recompute()
        base = os.path.basename(path).split(".")[0]
        for obj, shape in last_solids(doc):
            write(out_dir, f"{base}_{obj}", shape)
        FreeCAD.closeDocument(doc.Name)


main(sys.argv[-1] if len(sys.argv) > 1 and not sys.argv[-1].endswith(".py") else "/tmp/freecad-shapes")
