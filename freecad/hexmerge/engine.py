# SPDX-License-Identifier: LGPL-2.1-or-later
"""Access to the HexMerge engine (the Python module `hexmerge`): importing it, its parameter
tables, typing options by the table. Nothing here touches FreeCAD."""

import os
import sys

from .resources import ROOT

# Options of the add-on itself (not engine parameters).
PYRAMIDS_AS_HEXAHEDRA_DOC = (
    "FreeCAD 0.20's CalculiX writer leaves pyramids out of the input file. When on, every "
    "pyramid is stored as a collapsed hexahedron (base, apex four times), which the writer emits "
    "as C3D8 (C3D20 for quadratic meshes), so the solver sees every element.")

TABLE_KEYS = ("name", "type", "default", "unit", "min", "max", "min_exclusive", "choices", "label",
              "doc", "cli_flag", "freecad_property")

# Engine options whose table default is not the accurate choice for CalculiX (issue 15,
# docs/fem-accuracy.md). CalculiX has no pyramid element: a pyramid goes out as a collapsed
# hexahedron, and one with a node on the boundary overstated the peak stress by up to 21 %
# where the tets were within 1 %. The add-on's objects start from these.
CALCULIX_DEFAULTS = {"pyramid_placement": "no_boundary_node"}
# A mesh made from the shape starts from these instead: no_boundary_node took every hexahedron
# of the plate with a hole made unswept (its pyramids' bases lie on the plate's faces) and most
# of the cylinder's. Pyramids off the nodes of the curved parts of the boundary (the flat faces
# keep theirs; the second-order ones written as two tied C3D10, calculix.QUADRATIC_PYRAMID) keep
# the hexahedra (plate 12 / 8 mm 88.3 / 96.1 %, cylinder 8 / 5 mm 69.7 / 80.1 %) and, in second
# order (the default), put the peaks within 1 % at the finer sizes: plate +0.38 / -0.16 %,
# cylinder's bore +1.33 / +0.32 %; with pyramids only off the curved faces (a node on them
# allowed) +0.90 / -0.32 % and +1.73 / +2.90 %. On real parts at about 50k tets it keeps 0 to
# 8.6 points less hexahedron volume than off the faces (docs/fem-accuracy.md).
CALCULIX_SHAPE_DEFAULTS = {"pyramid_placement": "no_curved_boundary_node"}


def calculix_options(options=None):
    """The engine options for a mesh that CalculiX will solve: `options` (the user's choices,
    kept as given) over CALCULIX_DEFAULTS."""
    return dict(CALCULIX_DEFAULTS, **(options or {}))


class Cancelled(Exception):
    """The user cancelled the run through the progress callback."""


def module():
    """The hexmerge Python module, with a clear message when it is not built or not importable."""
    try:
        import hexmerge
        return hexmerge
    except ImportError:
        # A checkout linked into FreeCAD's Mod folder: the module is built into src/python.
        built = os.path.join(ROOT, "src", "python")
        if os.path.isdir(os.path.join(built, "hexmerge")) and built not in sys.path:
            sys.path.append(built)
    try:
        import hexmerge
    except ImportError as e:
        raise ImportError(
            "the HexMerge engine (Python module 'hexmerge') cannot be imported into FreeCAD's "
            "Python: build it with the README's setup command ({})".format(e)) from e
    return hexmerge


def parameter_table():
    """The engine's parameter table as a list of dicts (TABLE_KEYS), whatever the module
    returns rows as."""
    rows = []
    for r in module().parameters():
        get = (lambda k, r=r: r.get(k)) if isinstance(r, dict) else (lambda k, r=r: getattr(r, k, None))
        rows.append({k: get(k) for k in TABLE_KEYS})
    return rows


def mesh_parameter_table():
    """The mesher's parameters (hexmerge.mesh_parameters()), in parameter_table()'s row format."""
    return [{k: r.get(k) for k in TABLE_KEYS} for r in module().mesh_parameters()]


def typed_options(options):
    """The options with the engine's table types; ValueError for a name the engine does not know."""
    table = {r["name"]: r for r in parameter_table()}
    out = {}
    for name, value in options.items():
        if name not in table:
            raise ValueError("unknown HexMerge option '{}' (known: {})"
                             .format(name, ", ".join(table)))
        kind = table[name]["type"]
        out[name] = (float(value) if kind == "float" else int(value) if kind == "int"
                     else bool(value) if kind == "bool" else str(value))
    return out
