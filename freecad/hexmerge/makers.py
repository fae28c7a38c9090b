# SPDX-License-Identifier: LGPL-2.1-or-later
"""Factories for the add-on's document objects (the role of FEM's ObjectsFem.py)."""

import FreeCAD

from . import engine, properties
from .mesh_hexdominant import MeshHexDominant, containing_analysis, is_shape_source


def check_tetrahedral_source(source):
    """Raises ValueError with a message for the user unless `source` is a FEM mesh object holding
    a non-empty, purely tetrahedral mesh."""
    if source is None:
        raise ValueError("no mesh selected: select one tetrahedral FEM mesh object")
    if not hasattr(source, "isDerivedFrom") or not source.isDerivedFrom("Fem::FemMeshObject"):
        raise ValueError("{} is not a FEM mesh object".format(getattr(source, "Label", source)))
    femmesh = source.FemMesh
    if femmesh.VolumeCount == 0:
        raise ValueError("{} has no volume elements (is it empty, or not meshed yet?)"
                         .format(source.Label))
    if femmesh.VolumeCount != femmesh.TetraCount:
        raise ValueError(
            "{} is not tetrahedral: {} of its {} volumes are not tetrahedra (HexMerge needs a "
            "Tet4 or Tet10 mesh)".format(source.Label, femmesh.VolumeCount - femmesh.TetraCount,
                                         femmesh.VolumeCount))
    return source


def check_shape_source(source):
    """Raises ValueError unless `source` is an object with a solid Shape (not a FEM mesh)."""
    if not is_shape_source(source):
        raise ValueError("{} is not a FEM mesh object, and its shape has no solid (recompute it, "
                         "or select a tetrahedral mesh or a solid)".format(source.Label))
    return source


def checked_new_source(source):
    """A tetrahedral FEM mesh object or a solid; ValueError with a message otherwise."""
    if source is None:
        raise ValueError("no mesh selected: select one tetrahedral FEM mesh object or a solid")
    if hasattr(source, "isDerivedFrom") and source.isDerivedFrom("Fem::FemMeshObject"):
        return check_tetrahedral_source(source)
    if not hasattr(source, "isDerivedFrom"):
        raise ValueError("{} is not a FEM mesh object nor a solid".format(source))
    return check_shape_source(source)


def default_target_size(shape):
    """A first target size for a shape: a quarter of its bounding box's shortest side, to two
    significant digits (at least four lattice cells across the thinnest direction)."""
    box = shape.BoundBox
    side = min(box.XLength, box.YLength, box.ZLength) / 4.0
    return float("{:.2g}".format(side))


def set_options(obj, options):
    """Sets properties from engine parameter names, mesher keywords or property names."""
    by_param = {s.parameter: s.name for s in properties.engine_specs() + properties.mesher_specs()}
    by_param.update({s.parameter: s.name for s in properties.addon_specs() if s.parameter})
    by_param["pyramids_as_hexahedra"] = "PyramidsAsHexahedra"
    for key, value in options.items():
        name = by_param.get(key, key)
        if name not in obj.PropertiesList:
            raise ValueError("unknown HexMerge option '{}' (known: {})"
                             .format(key, ", ".join(sorted(by_param))))
        setattr(obj, name, value)


def make_hexdominant_mesh(doc, source, name="HexDominantMesh", recompute=True, analysis=None,
                          **options):
    checked_new_source(source)
    shape_mode = is_shape_source(source)
    obj = doc.addObject("Fem::FemMeshObjectPython", name)
    MeshHexDominant(obj)
    if FreeCAD.GuiUp:
        from .view_mesh_hexdominant import VPMeshHexDominant
        VPMeshHexDominant(obj.ViewObject)
        source.ViewObject.Visibility = False  # the new mesh is drawn where the source was
    obj.SourceMesh = source
    try:
        if shape_mode and not any(k in options for k in ("size", "target_size", "TargetSize")):
            obj.TargetSize = default_target_size(source.Shape)
        if shape_mode:  # the CalculiX defaults of a mesh made from the shape; the options given win
            set_options(obj, engine.CALCULIX_SHAPE_DEFAULTS)
        set_options(obj, {("size" if k == "target_size" else k): v for k, v in options.items()})
    except Exception:
        doc.removeObject(obj.Name)
        raise
    if shape_mode:
        # A shape is not in the analysis; its mesh takes the place of the analysis's meshes.
        if analysis is not None:
            meshes = [o for o in analysis.Group if o.isDerivedFrom("Fem::FemMeshObject")]
            analysis.Group = [o for o in analysis.Group if o not in meshes] + [obj]
    else:
        analysis = containing_analysis(source)
        if analysis is not None:
            # An analysis solves exactly one mesh: the new one takes the source's place.
            analysis.Group = [obj if o == source else o for o in analysis.Group]
    if recompute:
        doc.recompute()
        if "Invalid" in obj.State or "Error" in obj.State:
            raise RuntimeError("{}: recompute failed: {}".format(obj.Label, obj.getStatusString()))
    return obj
