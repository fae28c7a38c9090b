# SPDX-License-Identifier: LGPL-2.1-or-later
"""Material regions of a tetrahedral FemMesh: from its mesh groups, or per solid of its shape.

A region is a positive int per tet; tets of different regions are never merged. Region 0 means
"no region known". Each region may carry a name: the mesh group written into the new mesh for it,
so FreeCAD's CalculiX writer finds the material's elements by group (a group whose name starts
with the material object's Name followed by "_") instead of its slow per-node search.
"""

import numpy as np


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


def from_solids(shape, points, tets, material_names=None, tolerance=1e-7):
    """Regions per solid of a shape, or None when the shape has fewer than two solids.

    The tets are split into connected pieces by the mesh faces that lie on a face shared by two
    solids, and one tet per piece is classified with Part's point-in-solid test, so the cost is
    one OpenCASCADE query per piece plus a few vectorised passes over the tets.

    material_names: {solid index (1-based): group name} for the solids a material references.
    """
    solids = list(getattr(shape, "Solids", []) or [])
    if len(solids) < 2:
        return None
    corners = np.asarray(tets)[:, :4]
    interface = _interface_nodes(shape, solids, points)
    pieces = _pieces(corners, interface)

    ids = np.zeros(len(corners), dtype=np.int32)
    centroids = points[corners].mean(axis=1)
    import FreeCAD
    for piece in np.unique(pieces).tolist():
        members = np.flatnonzero(pieces == piece)
        c = centroids[members[0]]
        v = FreeCAD.Vector(*c.tolist())
        for s, solid in enumerate(solids, start=1):
            if solid.BoundBox.isInside(v) and solid.isInside(v, tolerance, True):
                ids[members] = s
                break
    names = dict(material_names or {})
    return Regions(ids, names, "solids of the shape ({} solids)".format(len(solids)))


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


def _interface_nodes(shape, solids, points):
    """Boolean mask of the mesh points lying on a face shared by two solids."""
    shared = []
    for i, a in enumerate(solids):
        for b in solids[i + 1:]:
            for fa in a.Faces:
                if any(fa.isSame(fb) or _coincident(fa, fb) for fb in b.Faces):
                    shared.append(fa)
    mask = np.zeros(len(points), dtype=bool)
    if not shared:
        return mask
    import FreeCAD
    import Part
    for face in shared:
        bb = face.BoundBox
        tol = 1e-6 * max(bb.DiagonalLength, 1e-12) + 1e-9
        lo = np.array([bb.XMin, bb.YMin, bb.ZMin]) - tol
        hi = np.array([bb.XMax, bb.YMax, bb.ZMax]) + tol
        near = np.flatnonzero(np.all((points >= lo) & (points <= hi), axis=1))
        for p in near.tolist():
            vx = Part.Vertex(FreeCAD.Vector(*points[p].tolist()))
            if face.distToShape(vx)[0] <= tol:
                mask[p] = True
    return mask


def _coincident(fa, fb):
    """Faces of two solids of a compound that are the same surface patch but not shared."""
    if abs(fa.Area - fb.Area) > 1e-9 * max(fa.Area, 1.0):
        return False
    return fa.CenterOfMass.distanceToPoint(fb.CenterOfMass) < 1e-7 * max(fa.BoundBox.DiagonalLength, 1.0)


def _pieces(corners, interface):
    """Connected components of the tets through faces not lying on the interface."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    m = len(corners)
    local = np.array([[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]])
    faces = np.sort(corners[:, local].reshape(-1, 3), axis=1)
    owner = np.repeat(np.arange(m), 4)
    on_interface = interface[faces].all(axis=1)
    faces, owner = faces[~on_interface], owner[~on_interface]
    _, inverse, counts = np.unique(faces, axis=0, return_inverse=True, return_counts=True)
    inverse = inverse.ravel()
    order = np.argsort(inverse, kind="stable")
    shared = counts[inverse[order]] == 2
    pairs = owner[order][shared].reshape(-1, 2)
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(m, m))
    _, labels = connected_components(graph, directed=False)
    return labels
