# SPDX-License-Identifier: LGPL-2.1-or-later
"""Material regions of a tetrahedral FemMesh: from its mesh groups, or per solid of its shape.

A region is a positive int per tet; tets of different regions are never merged. Region 0 means
"no region known". Each region may carry a name: the mesh group written into the new mesh for it,
so FreeCAD's CalculiX writer finds the material's elements by group (a group whose name starts
with the material object's Name followed by "_") instead of its slow per-node search.
"""

import numpy as np

from . import engine


class Regions:
    """ids: (M,) int32 region per tet; names: {region id: group name}; source: how they were found."""

    def __init__(self, ids, names, source):
        self.ids = ids
        self.names = names
        self.source = source

    @property
    def count(self):
        return len(np.unique(self.ids)) if len(self.ids) else 0


def from_groups(femmesh, element_ids, materials=()):
    """Regions from the "Volume" groups of a FemMesh, or None when it has none.

    element_ids: (M,) FemMesh ids of the tets, in array order.
    materials:   material object Names of the analysis; when given, only groups named after one
                 of them ("<Name>_...") count, so user mesh groups do not split regions.
    """
    groups = []
    for g in femmesh.Groups:
        if femmesh.getGroupElementType(g) != "Volume":
            continue
        name = femmesh.getGroupName(g)
        if materials and not any(name.startswith(m + "_") for m in materials):
            continue
        groups.append((name, np.asarray(femmesh.getGroupElements(g), dtype=np.int64)))
    if not groups:
        return None
    position = {int(e): i for i, e in enumerate(np.asarray(element_ids).tolist())}
    ids = np.zeros(len(element_ids), dtype=np.int32)
    names = {}
    for r, (name, members) in enumerate(groups, start=1):
        pos = [position[e] for e in members.tolist() if e in position]
        ids[pos] = r
        names[r] = name
    return Regions(ids, names, "mesh groups")


def from_solids(shape, points, tets, material_names=None):
    """Regions per solid of a shape, or None when the shape has fewer than two solids.

    The work is done in C++ with OpenCASCADE (hexmerge.regions_by_solid, on the shape's BREP
    text): the tets are cut into connected pieces at the faces two solids share, and a few tets
    per piece are classified, so 1M tets take well under a second per few solids.
    Region s + 1 is solid s of shape.Solids; 0 marks a tet in no solid.

    material_names: {solid index (1-based): group name} for the solids a material references.
    """
    solids = list(getattr(shape, "Solids", []) or [])
    if len(solids) < 2:
        return None
    hexmerge = engine.module()
    if not getattr(hexmerge, "WITH_OPENCASCADE", False):
        raise ValueError(
            "the shape has {} solids, but the HexMerge engine was built without OpenCASCADE, "
            "which finds the solid of each tet: install the OpenCASCADE -dev packages and rebuild "
            "(README), or switch 'Respect regions' off".format(len(solids)))
    found, report = hexmerge.regions_by_solid(shape.exportBrepToString(), points,
                                              np.asarray(tets)[:, :4])
    ids = (found + 1).astype(np.int32)
    names = dict(material_names or {})
    source = "solids of the shape ({} solids, {} pieces, OpenCASCADE)".format(
        len(solids), report["nb_pieces"])
    if report["nb_unassigned_tets"]:
        source += ", {} tets in no solid".format(report["nb_unassigned_tets"])
    return Regions(ids, names, source)


def material_solids(analysis, part):
    """{solid index of part (1-based): "<material Name>_Solids"} for the solid materials of an
    analysis. A reference may name a solid of `part` or of any other object (the examples
    reference the boxes a compound was made of): it is matched to part's solids by geometry.
    A material with no references takes the solids left over."""
    if analysis is None or part is None:
        return {}
    solids = part.Shape.Solids
    names, fallback = {}, None
    for obj in analysis.Group:
        if getattr(obj, "Category", None) != "Solid" or not hasattr(obj, "References"):
            continue
        if not obj.References:
            fallback = obj.Name
            continue
        for ref_obj, subs in obj.References:
            for sub in subs:
                if not sub.startswith("Solid"):
                    continue
                ref = ref_obj.Shape.Solids[int(sub[5:]) - 1]
                for s, solid in enumerate(solids, start=1):
                    if ref.isSame(solid) or _same_solid(ref, solid):
                        names[s] = obj.Name + "_Solids"
    if fallback:
        for s in range(1, len(solids) + 1):
            names.setdefault(s, fallback + "_Solids")
    return names


def _same_solid(a, b):
    size = max(a.BoundBox.DiagonalLength, 1e-12)
    return (abs(a.Volume - b.Volume) <= 1e-6 * abs(b.Volume)
            and a.CenterOfMass.distanceToPoint(b.CenterOfMass) <= 1e-6 * size)


def analysis_materials(analysis):
    """Names of the solid material objects of an analysis."""
    if analysis is None:
        return []
    return [o.Name for o in analysis.Group
            if getattr(o, "Category", None) == "Solid" and hasattr(o, "References")]
