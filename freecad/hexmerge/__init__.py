# SPDX-License-Identifier: LGPL-2.1-or-later
"""HexMerge for FreeCAD FEM: hex-dominant meshes from tetrahedral FEM meshes.

Macro API:
    import freecad.hexmerge as hm
    obj = hm.make_hexdominant_mesh(doc, doc.FEMMeshGmsh, min_scaled_jacobian=0.4)
    femmesh, report = hm.recombine_femmesh(doc.FEMMeshGmsh.FemMesh)
"""

__version__ = "0.1.0"

__all__ = ["make_hexdominant_mesh", "recombine_femmesh", "__version__"]


def make_hexdominant_mesh(doc, source, name="HexDominantMesh", **options):
    """Adds a hex-dominant mesh object linked to `source`, recomputes it and returns it.

    options: engine parameters by name (min_dihedral_angle=150, conformity="conforming", ...;
    see hexmerge.parameters()) or property name, and pyramids_as_hexahedra (default True).
    If the source is a member of an analysis, the new object takes its place there (an analysis
    solves exactly one mesh); the source itself is never modified. Raises ValueError (nothing
    created) when the source is not a non-empty tetrahedral FEM mesh, RuntimeError when the
    engine fails.
    """
    from .makers import make_hexdominant_mesh as make
    return make(doc, source, name, **options)


def recombine_femmesh(femmesh, **options):
    """Recombines a tetrahedral FemMesh; returns (new FemMesh, report dict). The input is not
    modified. Options as for make_hexdominant_mesh, plus regions="auto"|"none" and shape=<Part
    shape> (regions per solid when the mesh has no "Volume" groups)."""
    from .hexmergetools import recombine_femmesh as recombine
    return recombine(femmesh, **options)
