# SPDX-License-Identifier: LGPL-2.1-or-later
"""HexMerge for FreeCAD FEM: hex-dominant meshes from tetrahedral FEM meshes.

Macro API:
    import freecad.hexmerge as hm
    obj = hm.make_hexdominant_mesh(doc, doc.FEMMeshGmsh, min_scaled_jacobian=0.4)
    obj = hm.make_hexdominant_mesh(doc, doc.Box, target_size=250, analysis=doc.Analysis)
    femmesh, report = hm.recombine_femmesh(doc.FEMMeshGmsh.FemMesh)
"""

__version__ = "0.1.0"

__all__ = ["make_hexdominant_mesh", "recombine_femmesh", "__version__"]


def make_hexdominant_mesh(doc, source, name="HexDominantMesh", analysis=None, **options):
    """Adds a hex-dominant mesh object linked to `source`, recomputes it and returns it.

    source: a tetrahedral FEM mesh object (recombined), or a solid -- a Part feature or any
    object with a solid Shape -- meshed with HexMerge's mesher (hexmerge.mesh_shape) at
    target_size, then recombined.
    options: engine parameters by name (min_dihedral_angle=150, conformity="conforming", ...;
    see hexmerge.parameters()) or property name, pyramids_as_hexahedra (default True),
    linear_hexahedron ("C3D8I if parallelepiped", "C3D8I", "C3D8") and quadratic_hexahedron
    ("C3D20", "C3D20R"): the CalculiX element of the hexahedra in the .inp; for a
    shape also target_size (default: a quarter of the shape's thinnest side), second_order
    (default True) and the mesher's options (boundary_layers=1, ...; hexmerge.mesh_parameters()).
    If a source mesh is a member of an analysis, the new object takes its place there (an
    analysis solves exactly one mesh); a shape's mesh replaces the meshes of `analysis`, if
    given. The source itself is never modified. Raises ValueError (nothing created) when the
    source is neither a non-empty tetrahedral FEM mesh nor a solid, RuntimeError when the
    mesher or engine fails.
    """
    from .makers import make_hexdominant_mesh as make
    return make(doc, source, name, analysis=analysis, **options)


def recombine_femmesh(femmesh, **options):
    """Recombines a tetrahedral FemMesh; returns (new FemMesh, report dict). The input is not
    modified. Options as for make_hexdominant_mesh, plus regions="auto"|"none" and shape=<Part
    shape> (regions per solid when the mesh has no "Volume" groups). Like the add-on's mesh
    objects, it starts from the engine options that keep a CalculiX answer at least as accurate
    as the tets' (engine.CALCULIX_DEFAULTS: no pyramid with a node on the boundary; options given
    override them, pyramid_placement="anywhere" is the engine's own default); the report's
    "options" lists the engine options used."""
    from . import engine
    from .jobs import recombine_femmesh as recombine
    engine_options = {k: v for k, v in options.items() if k not in ("regions", "shape",
                                                                   "pyramids_as_hexahedra",
                                                                   "progress")}
    others = {k: v for k, v in options.items() if k not in engine_options}
    used = engine.calculix_options(engine_options)
    femmesh, report = recombine(femmesh, **others, **used)
    report["options"] = used
    return femmesh, report
