# SPDX-License-Identifier: LGPL-2.1-or-later
"""Colours by element type, for the 3D view and the results table's legend. Nothing here touches
FreeCAD or Qt: the view provider hands in what it reads from the view.

FreeCAD 0.20's mesh view draws every outer face of an element as triangles, one colour per
triangle. Its own colouring by element (ElementColor) assumes one entry per triangle, but a
quadratic face is drawn as more triangles than it has entries (a 6-node triangle as 4 triangles
from 3 entries, an 8-node quadrangle as 6 from 4), so on second-order meshes every colour after
the first such face lands on the wrong triangle. face_colors() therefore computes the colour of
each drawn triangle itself, from the faces the view reports (VisibleElementFaces: one (element,
face) pair per drawn face, in drawing order).
"""

# RGB per element type; collapsed pyramids (8 or 20 nodes with a repeated node) are found by
# their nodes. Tet light grey, pyramid red, prism green, hexahedron blue: none near FreeCAD's
# default mesh orange nor the pure green it gives a face with no colour.
TYPE_COLORS = {
    "tetra": (0.80, 0.80, 0.80),
    "pyramid": (0.85, 0.25, 0.25),
    "wedge": (0.30, 0.70, 0.30),
    "hexahedron": (0.25, 0.45, 0.90),
}
TYPE_COLOR_NAMES = {"tetra": "grey", "pyramid": "red", "wedge": "green", "hexahedron": "blue"}
TYPE_LABELS = {"tetra": "tetrahedra", "pyramid": "pyramids", "wedge": "prisms",
               "hexahedron": "hexahedra"}
# The results table's rows (results.CELL_LABELS) -> colour.
LABEL_COLORS = {TYPE_LABELS[k]: rgb for k, rgb in TYPE_COLORS.items()}

CORNERS = {4: 4, 10: 4, 5: 5, 13: 5, 6: 6, 15: 6, 8: 8, 20: 8}
QUADRATIC = (10, 13, 15, 20)
KIND_OF_CORNERS = {4: "tetra", 5: "pyramid", 6: "wedge", 8: "hexahedron"}

# Faces of each linear kind as FreeCAD's mesh view numbers them (1-based, as VisibleElementFaces
# reports them): their corner counts (ViewProviderFEMMeshBuilder::createMesh, FreeCAD 0.20).
FACE_CORNERS = {
    "tetra": (3, 3, 3, 3),
    "pyramid": (4, 3, 3, 3, 3),
    "wedge": (3, 3, 4, 4, 4),
    "hexahedron": (4, 4, 4, 4, 4, 4),
}
# Triangles the view draws for a face: (corners, quadratic) -> count.
TRIANGLES = {(3, False): 1, (4, False): 2, (3, True): 4, (4, True): 6}


def element_kind(nodes):
    """Linear kind of a stored volume from its node ids (SMESH order): "tetra", "pyramid",
    "wedge" or "hexahedron"; a hexahedron with five distinct corners is a collapsed pyramid."""
    corners = CORNERS[len(nodes)]
    if corners == 8 and len(set(nodes[:8])) == 5:
        return "pyramid"
    return KIND_OF_CORNERS[corners]


def stored_kind(nodes):
    """The kind as FreeCAD stores it (a collapsed pyramid is a hexahedron to the view)."""
    return KIND_OF_CORNERS[CORNERS[len(nodes)]]


def face_colors(visible_faces, element_nodes, color_by_type=True):
    """RGB of every triangle the mesh view draws, in drawing order.

    visible_faces: [(element id, face number)] as the view reports them (one per drawn face);
    element_nodes: function element id -> node ids. Raises ValueError when a face number does not
    exist for its element (the view's numbering differs from FACE_CORNERS).
    """
    colors = []
    cache = {}
    for element, face in visible_faces:
        known = cache.get(element)
        if known is None:
            nodes = element_nodes(element)
            known = cache[element] = (element_kind(nodes), stored_kind(nodes), len(nodes) in QUADRATIC)
        kind, stored, quadratic = known
        faces = FACE_CORNERS[stored]
        if not 1 <= face <= len(faces):
            raise ValueError("element {} ({}) has no face {} in the mesh view's numbering"
                             .format(element, stored, face))
        count = TRIANGLES[(faces[face - 1], quadratic)]
        colors.extend([TYPE_COLORS[kind]] * count)
    return colors


def legend():
    """"hexahedra blue, prisms green, pyramids red, tetrahedra grey"."""
    return ", ".join("{} {}".format(TYPE_LABELS[k], TYPE_COLOR_NAMES[k])
                     for k in ("hexahedron", "wedge", "pyramid", "tetra"))
