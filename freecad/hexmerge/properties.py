# SPDX-License-Identifier: LGPL-2.1-or-later
"""Document-object properties built from the engine's parameter table (and the add-on's own).

Each engine parameter becomes one property: its name the table's ``freecad_property``, its group
from GROUPS, its tooltip the table's doc (with the unit and range), its type from the table's
type and unit: float with unit "deg" -> App::PropertyAngle, float with unit "mm" ->
App::PropertyLength, other float -> App::PropertyFloatConstraint, int ->
App::PropertyIntegerConstraint, bool -> App::PropertyBool, choice -> App::PropertyEnumeration.
A parameter added to the engine appears here with no change.

The mesher's parameters (hexmerge.mesh_parameters(): used when the source is a shape) are built
the same way into the group "Shape meshing" (those whose ``freecad_property`` is empty, the
TetGen program and its work folder, are not shown), with the add-on's SecondOrder.
"""

import math

from . import calculix
from . import engine

# Property groups, by parameter name; parameters not listed go to "Engine".
GROUPS = {
    "min_dihedral_angle": "Tolerances",
    "max_face_angle": "Tolerances",
    "min_scaled_jacobian": "Tolerances",
    "make_hexahedra": "Element types",
    "make_prisms": "Element types",
    "make_pyramids": "Element types",
    "conformity": "Conformity",
    "respect_regions": "Material boundaries",
}


class PropertySpec:
    """One data property: FreeCAD type, name, group, doc, default, and the engine parameter it
    feeds (None for the add-on's own)."""

    def __init__(self, kind, name, group, doc, default, parameter=None, row=None):
        self.kind = kind
        self.name = name
        self.group = group
        self.doc = doc
        self.default = default
        self.parameter = parameter
        self.row = row

    def add_to(self, obj):
        if self.name in obj.PropertiesList:
            return
        obj.addProperty(self.kind, self.name, self.group, self.doc)
        self.reset(obj)

    def reset(self, obj):
        if self.kind == "App::PropertyEnumeration":
            setattr(obj, self.name, list(self.row["choices"]))
            setattr(obj, self.name, self.default)
        elif self.kind == "App::PropertyFloatConstraint":
            setattr(obj, self.name, (float(self.default), float(self.row["min"]),
                                     float(self.row["max"]), _step(self.row)))
        elif self.kind == "App::PropertyIntegerConstraint":
            setattr(obj, self.name, (int(float(self.default)), int(self.row["min"]),
                                     int(self.row["max"]), 1))
        else:
            setattr(obj, self.name, self.default)

    def value(self, obj):
        """The property's value as the engine takes it."""
        v = getattr(obj, self.name)
        if self.kind == "App::PropertyAngle":
            return float(v.getValueAs("deg")) if hasattr(v, "getValueAs") else float(v)
        if self.kind == "App::PropertyLength":  # in the document's length unit, mm
            return float(v.Value) if hasattr(v, "Value") else float(v)
        return v


def _step(row):
    span = float(row["max"]) - float(row["min"])
    return 0.05 if span <= 2 else 1.0


def _doc(row):
    doc = row.get("doc") or ""
    unit = row.get("unit") or ""
    if row["type"] in ("float", "int") and math.isinf(float(row["max"])):
        doc += " [{} {}{}]".format("above" if row.get("min_exclusive") else "at least",
                                   _num(row["min"]), " " + unit if unit else "")
    elif row["type"] in ("float", "int"):
        doc += " [{}{} .. {}{}]".format(_num(row["min"]), " excluded" if row.get("min_exclusive") else "",
                                        _num(row["max"]), " " + unit if unit else "")
    elif row["type"] == "choice":
        doc += " (one of: {})".format(", ".join(row["choices"]))
    return doc + " Default: {}.".format(row["default"])


def _num(x):
    x = float(x)
    return str(int(x)) if x == int(x) else str(x)


def _default(row):
    d = row["default"]
    if row["type"] == "bool":
        return d if isinstance(d, bool) else str(d).lower() in ("true", "1", "yes", "on")
    if row["type"] == "float":
        return float(d)
    if row["type"] == "int":
        return int(float(d))
    return str(d)


KINDS = {"int": "App::PropertyIntegerConstraint", "bool": "App::PropertyBool",
         "choice": "App::PropertyEnumeration"}
FLOAT_KINDS = {"deg": "App::PropertyAngle", "mm": "App::PropertyLength"}


def _spec(row, group):
    kind = (FLOAT_KINDS.get(row.get("unit"), "App::PropertyFloatConstraint")
            if row["type"] == "float" else KINDS[row["type"]])
    return PropertySpec(kind, row["freecad_property"], group, _doc(row), _default(row),
                        row["name"], row)


def engine_specs():
    specs = []
    for row in engine.parameter_table():
        # The add-on meshes for CalculiX: its defaults where they differ from the engine's.
        row = dict(row, default=engine.CALCULIX_DEFAULTS.get(row["name"], row["default"]))
        specs.append(_spec(row, GROUPS.get(row["name"], "Engine")))
    return specs


SHAPE_GROUP = "Shape meshing"


def mesher_specs():
    """The mesher's table (hexmerge.mesh_parameters(); the rows with a FreeCAD property) and
    SecondOrder: the options of the shape mode."""
    specs = [_spec(row, SHAPE_GROUP) for row in engine.mesh_parameter_table()
             if row["freecad_property"]]
    specs.append(PropertySpec("App::PropertyBool", "SecondOrder", SHAPE_GROUP,
                              "When the source is a shape: quadratic elements (a node at the "
                              "midpoint of every tet edge, so hexahedra become Hexa20)", True,
                              "second_order", {"name": "second_order", "label": "Second order"}))
    return specs


def addon_specs():
    return [
        PropertySpec("App::PropertyLink", "SourceMesh", "Source",
                     "The tetrahedral FEM mesh object to recombine, or a solid (Part feature or "
                     "any object with a solid Shape) to mesh with HexMerge's mesher and "
                     "recombine (never modified)", None),
        PropertySpec("App::PropertyBool", "PyramidsAsHexahedra", "CalculiX",
                     engine.PYRAMIDS_AS_HEXAHEDRA_DOC, True),
        # Element types of the .inp (calculix.py rewrites what FreeCAD 0.20's writer writes).
        PropertySpec("App::PropertyEnumeration", "LinearHexahedron", "CalculiX",
                     calculix.LINEAR_HEXAHEDRON_DOC, calculix.LINEAR_HEXAHEDRON[0],
                     "linear_hexahedron", {"name": "linear_hexahedron", "label": "Linear hexahedra",
                                           "choices": calculix.LINEAR_HEXAHEDRON}),
        PropertySpec("App::PropertyEnumeration", "QuadraticHexahedron", "CalculiX",
                     calculix.QUADRATIC_HEXAHEDRON_DOC, calculix.QUADRATIC_HEXAHEDRON[0],
                     "quadratic_hexahedron", {"name": "quadratic_hexahedron",
                                              "label": "Quadratic hexahedra",
                                              "choices": calculix.QUADRATIC_HEXAHEDRON}),
        PropertySpec("App::PropertyEnumeration", "QuadraticPyramid", "CalculiX",
                     calculix.QUADRATIC_PYRAMID_DOC, calculix.QUADRATIC_PYRAMID[0],
                     "quadratic_pyramid", {"name": "quadratic_pyramid",
                                           "label": "Quadratic pyramids",
                                           "choices": calculix.QUADRATIC_PYRAMID}),
    ]


def all_specs():
    return addon_specs() + mesher_specs() + engine_specs()


def engine_values(obj):
    """{engine parameter: value} from an object's properties (properties it lacks are skipped)."""
    return {s.parameter: s.value(obj) for s in engine_specs() if s.name in obj.PropertiesList}


def mesher_values(obj):
    """{mesh_shape() keyword: value} (size, the mesher's options, second_order)."""
    return {s.parameter: s.value(obj) for s in mesher_specs() if s.name in obj.PropertiesList}
