"""Cell types as the compiled core numbers them, and their meshio / VTK names.

The values are those of ``hexmerge::CellType`` (``src/hexmerge/mesh/cell_type.h``); the local node
order of every type is VTK's, which is also meshio's. Output cell blocks come in this order.
"""

from __future__ import annotations

TET, PYRAMID, PRISM, HEX = 0, 1, 2, 3

#: Corner count per type value.
NB_VERTICES = (4, 5, 6, 8)
#: Mid-edge node count per type value (edges of the cell).
NB_EDGES = (6, 8, 9, 12)
#: meshio names of the linear cells, by type value.
LINEAR_NAMES = ("tetra", "pyramid", "wedge", "hexahedron")
#: meshio names of the quadratic (serendipity) cells, by type value.
QUADRATIC_NAMES = ("tetra10", "pyramid13", "wedge15", "hexahedron20")
#: The core's own names, by type value (keys of the report's per-type dicts).
CORE_NAMES = ("tet", "pyramid", "prism", "hex")

#: meshio name -> (type value, order).
BY_MESHIO_NAME = {
    **{name: (t, 1) for t, name in enumerate(LINEAR_NAMES)},
    **{name: (t, 2) for t, name in enumerate(QUADRATIC_NAMES)},
}

#: meshio volume cell types that hexmerge cannot take or give (for clear errors).
OTHER_VOLUME_NAMES = frozenset(
    {
        "tetra4",
        "tetra14",
        "tetra15",
        "tetra20",
        "tetra35",
        "tetra56",
        "hexahedron24",
        "hexahedron27",
        "hexahedron64",
        "hexahedron125",
        "hexahedron216",
        "hexahedron343",
        "hexahedron512",
        "hexahedron729",
        "hexahedron1000",
        "wedge18",
        "wedge40",
        "wedge75",
        "wedge126",
        "wedge196",
        "wedge288",
        "wedge405",
        "wedge550",
        "pyramid14",
        "polyhedron",
        "VTK_LAGRANGE_TETRAHEDRON",
        "VTK_LAGRANGE_HEXAHEDRON",
        "VTK_LAGRANGE_WEDGE",
        "VTK_LAGRANGE_PYRAMID",
    }
)


def nodes_per_cell(type_value: int, order: int) -> int:
    """Nodes of one cell of this type and order (1: corners, 2: corners and mid-edge nodes)."""
    n = NB_VERTICES[type_value]
    return n + NB_EDGES[type_value] if order == 2 else n


def meshio_name(type_value: int, order: int) -> str:
    """The meshio cell-block name of this type and order."""
    return (QUADRATIC_NAMES if order == 2 else LINEAR_NAMES)[type_value]
