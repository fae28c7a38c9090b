# SPDX-License-Identifier: LGPL-2.1-or-later
"""FemMesh <-> numpy arrays, with the node-order tables between VTK and SMESH.

HexMerge's engine speaks VTK (and meshio) local node order; FreeCAD's FemMesh stores SMESH order.
SMESH order is VTK order with the base face reversed (a valid SMESH element has a negative
VTK-style signed volume). Mid-edge nodes follow SMESH's own edge numbering:

    Tet10   01 12 20 03 13 23
    Pyra13  01 12 23 30 04 14 24 34
    Penta15 01 12 20 34 45 53 03 14 25
    Hexa20  01 12 23 30 45 56 67 74 04 15 26 37

Each table ``SMESH_FROM_VTK[cell]`` lists, for each SMESH position, the VTK position of the node
stored there: ``smesh_nodes = vtk_nodes[table]``. The tables are written out (not derived at
import) so they can be read and reviewed; tests/freecad/test_femmesh_arrays.py derives them again
from the edge lists above and checks every element's orientation and mid-edge positions.

CalculiX: FreeCAD 0.20's writer picks the element type from the node count and silently leaves
5- and 13-node elements (pyramids) out of the input file. A pyramid can instead be stored as a
collapsed hexahedron -- base, then the apex four times (Hexa8), and for Pyra13 the top edges'
mid-nodes also on the apex (Hexa20) -- which the writer emits as C3D8 / C3D20. The tables
``COLLAPSED_HEXA_FROM_PYRAMID`` give that layout in VTK order.

This module imports nothing from FreeCAD at module level; it only calls FemMesh methods on the
object it is given, so it can run wherever a FemMesh exists.
"""

import numpy as np

# VTK/meshio cell block names, in the order HexMerge returns them.
LINEAR_CELLS = ("tetra", "pyramid", "wedge", "hexahedron")
QUADRATIC_CELLS = ("tetra10", "pyramid13", "wedge15", "hexahedron20")

NODES_PER_CELL = {
    "tetra": 4, "pyramid": 5, "wedge": 6, "hexahedron": 8,
    "tetra10": 10, "pyramid13": 13, "wedge15": 15, "hexahedron20": 20,
}
CELL_BY_NODE_COUNT = {n: name for name, n in NODES_PER_CELL.items()}

# SMESH position -> VTK position.
SMESH_FROM_VTK = {
    "tetra": (0, 2, 1, 3),
    "pyramid": (0, 3, 2, 1, 4),
    "wedge": (0, 2, 1, 3, 5, 4),
    "hexahedron": (0, 3, 2, 1, 4, 7, 6, 5),
    "tetra10": (0, 2, 1, 3, 6, 5, 4, 7, 9, 8),
    "pyramid13": (0, 3, 2, 1, 4, 8, 7, 6, 5, 9, 12, 11, 10),
    "wedge15": (0, 2, 1, 3, 5, 4, 8, 7, 6, 11, 10, 9, 12, 14, 13),
    "hexahedron20": (0, 3, 2, 1, 4, 7, 6, 5, 11, 10, 9, 8, 15, 14, 13, 12, 16, 19, 18, 17),
}

# Each is a permutation, so its inverse is VTK position -> SMESH position.
VTK_FROM_SMESH = {name: tuple(int(i) for i in np.argsort(perm)) for name, perm in SMESH_FROM_VTK.items()}

# Collapsed hexahedra (VTK hexahedron / hexahedron20 order) built from a VTK pyramid / pyramid13:
# hex position -> pyramid position. Pyramid13 mid-edges (VTK): 5:01 6:12 7:23 8:30 9:04 10:14
# 11:24 12:34. The collapsed top face's corners and edge mid-nodes are all the apex (4).
COLLAPSED_HEXA_FROM_PYRAMID = {
    "pyramid": (0, 1, 2, 3, 4, 4, 4, 4),
    "pyramid13": (0, 1, 2, 3, 4, 4, 4, 4, 5, 6, 7, 8, 4, 4, 4, 4, 9, 10, 11, 12),
}
COLLAPSED_HEXA_NAME = {"pyramid": "hexahedron", "pyramid13": "hexahedron20"}


# Faces of each linear type (VTK local order, outward), as in src/hexmerge/mesh/cell_type.h, and
# VTK's edge order (the k-th mid-edge node of a quadratic cell is node corners + k).
FACES = {
    "tetra": ((1, 2, 3), (0, 3, 2), (0, 1, 3), (0, 2, 1)),
    "pyramid": ((0, 3, 2, 1), (0, 1, 4), (1, 2, 4), (2, 3, 4), (3, 0, 4)),
    "wedge": ((0, 2, 1), (3, 4, 5), (0, 1, 4, 3), (1, 2, 5, 4), (2, 0, 3, 5)),
    "hexahedron": ((0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6),
                   (3, 0, 4, 7)),
}
EDGES = {
    "tetra": ((0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)),
    "pyramid": ((0, 1), (1, 2), (2, 3), (3, 0), (0, 4), (1, 4), (2, 4), (3, 4)),
    "wedge": ((0, 1), (1, 2), (2, 0), (3, 4), (4, 5), (5, 3), (0, 3), (1, 4), (2, 5)),
    "hexahedron": ((0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4), (0, 4),
                   (1, 5), (2, 6), (3, 7)),
}
LINEAR_OF = dict(zip(QUADRATIC_CELLS, LINEAR_CELLS), **{n: n for n in LINEAR_CELLS})


def face_nodes(name, face):
    """Local nodes of one face of a (linear or quadratic) cell: corners, then for a quadratic
    cell the mid-edge node of each face edge (SMESH Tria6 / Quad8 order: 01, 12, 20 / 30)."""
    linear = LINEAR_OF[name]
    if name == linear:
        return tuple(face)
    corners = NODES_PER_CELL[linear]
    edges = [frozenset(e) for e in EDGES[linear]]
    mids = [corners + edges.index(frozenset((face[i], face[(i + 1) % len(face)])))
            for i in range(len(face))]
    return tuple(face) + tuple(mids)


def outer_cells(blocks):
    """Per block, a boolean (M,) array: the cells with a face that no other cell has (the cells
    FreeCAD's mesh view draws)."""
    keys = {3: [], 4: []}
    owners = {3: [], 4: []}
    for b, (name, cells) in enumerate(blocks):
        cells = np.asarray(cells)
        for face in FACES[LINEAR_OF[name]]:
            n = len(face)
            keys[n].append(np.sort(cells[:, face_nodes(name, face)[:n]], axis=1))
            owners[n].append(np.stack([np.full(len(cells), b), np.arange(len(cells))], axis=1))
    outer = [np.zeros(len(cells), dtype=bool) for _, cells in blocks]
    for n in (3, 4):
        if not keys[n]:
            continue
        key = np.concatenate(keys[n])
        owner = np.concatenate(owners[n])
        if not len(key):
            continue
        _, inverse, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
        once = owner[counts[inverse.ravel()] == 1]
        for b in range(len(blocks)):
            outer[b][once[once[:, 0] == b, 1]] = True
    return outer


def boundary_faces(blocks):
    """Faces of a mixed mesh that belong to one cell only: {3 or 4 corners: (F, k) node ids}.

    A quad face whose two triangles (on either diagonal) are faces of other cells is inside the
    mesh (a quad meeting two triangles), so neither it nor those triangles is on the boundary.
    """
    faces = {3: [], 4: []}
    for name, cells in blocks:
        cells = np.asarray(cells)
        if not len(cells):
            continue
        for face in FACES[LINEAR_OF[name]]:
            faces[len(face)].append(cells[:, face_nodes(name, face)])
    out = {}
    keys_once = {}
    for n in (3, 4):
        if not faces[n]:
            continue
        width = max(f.shape[1] for f in faces[n])
        all_faces = np.concatenate([f for f in faces[n] if f.shape[1] == width])
        key = np.sort(all_faces[:, :n], axis=1)
        _, first, inverse, counts = np.unique(key, axis=0, return_index=True,
                                              return_inverse=True, return_counts=True)
        once = counts[inverse.ravel()] == 1
        out[n] = all_faces[once]
        keys_once[n] = key[once]
    if 3 in out and 4 in out and len(out[4]):
        tri_set = {tuple(k) for k in keys_once[3].tolist()}
        q = out[4][:, :4]
        drop_quad = np.zeros(len(q), dtype=bool)
        drop_tri = set()
        for i, (a, b, c, d) in enumerate(q.tolist()):
            for t1, t2 in (((a, b, c), (a, c, d)), ((a, b, d), (b, c, d))):
                k1, k2 = tuple(sorted(t1)), tuple(sorted(t2))
                if k1 in tri_set and k2 in tri_set:
                    drop_quad[i] = True
                    drop_tri.update((k1, k2))
        out[4] = out[4][~drop_quad]
        if drop_tri:
            keep = np.array([tuple(k) not in drop_tri for k in keys_once[3].tolist()])
            out[3] = out[3][keep]
    return out


class MeshArrays:
    """A volume mesh as arrays, in VTK node order.

    points:      (N, 3) float64
    point_ids:   (N,) int64, the FemMesh node id of each point
    blocks:      list of (cell name, (M, k) int64 indices into points)
    element_ids: list of (M,) int64 FemMesh element ids, one array per block (or None)
    """

    def __init__(self, points, point_ids, blocks, element_ids=None):
        self.points = points
        self.point_ids = point_ids
        self.blocks = blocks
        self.element_ids = element_ids

    @property
    def cell_count(self):
        return sum(len(cells) for _, cells in self.blocks)


class NotTetrahedralError(ValueError):
    """The FemMesh holds volume elements other than tetrahedra, or no volumes at all."""


def femmesh_to_arrays(femmesh):
    """Reads every node and volume of a FemMesh into VTK-ordered arrays.

    Faces and edges are ignored. Returns a MeshArrays whose blocks follow LINEAR_CELLS /
    QUADRATIC_CELLS order (only types present).
    """
    nodes = femmesh.Nodes  # {id: Vector}
    point_ids = np.fromiter(nodes.keys(), dtype=np.int64, count=len(nodes))
    points = np.array([(v.x, v.y, v.z) for v in nodes.values()], dtype=np.float64).reshape(-1, 3)
    index_of = _index_map(point_ids)

    by_count = {}
    for eid in femmesh.Volumes:
        ids = femmesh.getElementNodes(eid)
        by_count.setdefault(len(ids), ([], []))
        by_count[len(ids)][0].append(ids)
        by_count[len(ids)][1].append(eid)

    blocks, element_ids = [], []
    for name in LINEAR_CELLS + QUADRATIC_CELLS:
        n = NODES_PER_CELL[name]
        if n not in by_count:
            continue
        smesh = index_of(np.array(by_count[n][0], dtype=np.int64))
        blocks.append((name, smesh[:, VTK_FROM_SMESH[name]]))
        element_ids.append(np.array(by_count[n][1], dtype=np.int64))
    unknown = set(by_count) - set(CELL_BY_NODE_COUNT)
    if unknown:
        raise ValueError("the mesh has volume elements with {} nodes, which HexMerge does not know"
                         .format(sorted(unknown)))
    return MeshArrays(points, point_ids, blocks, element_ids)


def tetrahedra(arrays):
    """The single tetra or tetra10 block of a MeshArrays, or NotTetrahedralError saying why not."""
    names = [name for name, cells in arrays.blocks if len(cells)]
    if not names:
        raise NotTetrahedralError("the mesh has no volume elements (is it empty, or not meshed yet?)")
    if names not in (["tetra"], ["tetra10"]):
        raise NotTetrahedralError(
            "the mesh is not tetrahedral: it holds {} (HexMerge needs only Tet4 or only Tet10)"
            .format(", ".join("{} {}".format(len(c), n) for n, c in arrays.blocks)))
    name, cells = arrays.blocks[[n for n, _ in arrays.blocks].index(names[0])]
    return name, cells, arrays.element_ids[[n for n, _ in arrays.blocks].index(names[0])]


def to_smesh_order(name, cells):
    """VTK-ordered (M, k) cells -> SMESH-ordered cells of the same type."""
    return np.asarray(cells)[:, SMESH_FROM_VTK[name]]


def collapse_pyramids(name, cells):
    """VTK pyramids (5 or 13 nodes) -> collapsed VTK hexahedra (8 or 20 nodes) and their name."""
    return COLLAPSED_HEXA_NAME[name], np.asarray(cells)[:, COLLAPSED_HEXA_FROM_PYRAMID[name]]


def arrays_to_femmesh(points, point_ids, blocks, regions=None, group_names=None,
                      pyramids_as_hexahedra=False, first_element_id=1, with_faces=True,
                      outer_first=True):
    """Builds a new FemMesh from VTK-ordered blocks.

    points, point_ids:  the nodes; every point is added with its id (unused ones too, so node ids
                        stay those of the source mesh)
    blocks:             list of (cell name, (M, k) indices into points), VTK order
    regions:            list of (M,) int arrays per block, or None
    group_names:        {region id: name}: a "Volume" group per name holding its regions' elements
    pyramids_as_hexahedra: store pyramids as collapsed hexahedra (CalculiX-ready)
    with_faces:         also add the boundary faces as face elements (Tria3/Quad4, Tria6/Quad8).
                        FreeCAD's CalculiX writer finds the faces of a load through them
                        (getFacesByFace); without them it falls back to getccxVolumesByFace,
                        which knows only tetrahedra and misplaces loads on other elements.
    outer_first:        number the volumes with a face on the boundary first. FreeCAD 0.20's mesh
                        view draws only those and keeps element ids in 16 bits when it colours by
                        element (ids wrap at 65536), so colour by type stays right as long as
                        fewer than 65536 volumes touch the boundary.

    Returns (femmesh, element_ids per block).
    """
    import Fem  # FreeCAD's; imported here so the tables above load anywhere

    femmesh = Fem.FemMesh()
    for pid, (x, y, z) in zip(point_ids.tolist(), points.tolist()):
        femmesh.addNode(x, y, z, pid)

    outer = outer_cells(blocks) if outer_first else [np.ones(len(c), dtype=bool) for _, c in blocks]
    ids_of = []
    eid = first_element_id
    for first_pass in (True, False):  # the outer cells of every block, then the others
        for b, (_, cells) in enumerate(blocks):
            if first_pass:
                ids_of.append(np.zeros(len(cells), dtype=np.int64))
            chosen = outer[b] if first_pass else ~outer[b]
            ids_of[b][chosen] = np.arange(eid, eid + int(chosen.sum()), dtype=np.int64)
            eid += int(chosen.sum())

    element_ids = []
    members = {}
    for b, (name, cells) in enumerate(blocks):
        cells = np.asarray(cells)
        if pyramids_as_hexahedra and name in COLLAPSED_HEXA_NAME:
            name, cells = collapse_pyramids(name, cells)
        smesh = point_ids[to_smesh_order(name, cells)] if len(cells) else cells
        ids = ids_of[b]
        for nodes, i in zip(smesh.tolist(), ids.tolist()):
            femmesh.addVolume(nodes, i)
        element_ids.append(ids)
        if regions is not None and group_names:
            reg = np.asarray(regions[b])
            for r in np.unique(reg).tolist():
                if r in group_names:
                    members.setdefault(r, []).append(ids[reg == r])

    if with_faces:
        for n, faces in sorted(boundary_faces(blocks).items()):
            for nodes in point_ids[faces].tolist():
                femmesh.addFace(nodes, eid)
                eid += 1

    if group_names:
        by_name = {}  # several regions (solids) may share one material group
        for r, name in sorted(group_names.items()):
            by_name.setdefault(name, []).extend(members.get(r, []))
        for name, parts in by_name.items():
            if parts:
                gid = femmesh.addGroup(name, "Volume")
                femmesh.addGroupElements(gid, np.concatenate(parts).tolist())
    return femmesh, element_ids


def _index_map(ids):
    """A vectorised id -> position lookup for an array of unique ids."""
    order = np.argsort(ids)
    sorted_ids = ids[order]

    def lookup(query):
        pos = np.searchsorted(sorted_ids, query)
        pos = np.clip(pos, 0, len(sorted_ids) - 1)
        if len(sorted_ids) == 0 or np.any(sorted_ids[pos] != query):
            raise ValueError("an element refers to a node that the mesh does not have")
        return order[pos]

    return lookup
