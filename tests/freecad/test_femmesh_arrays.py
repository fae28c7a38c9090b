# SPDX-License-Identifier: LGPL-2.1-or-later
"""Node-order tables and FemMesh <-> arrays, without the engine (freecadcmd -t)."""

import os
import tempfile
import unittest

import numpy as np

import Fem
from freecad.hexmerge import femmesh_arrays as fa

# Reference elements in VTK order (corners), positively oriented.
CORNERS = {
    "tetra": [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)],
    "pyramid": [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0.5, 0.5, 1)],
    "wedge": [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (0, 1, 1)],
    "hexahedron": [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0),
                   (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)],
}
# SMESH's mid-edge numbering on its own corner positions (DESIGN.md).
SMESH_EDGES = {
    "tetra10": "01 12 20 03 13 23",
    "pyramid13": "01 12 23 30 04 14 24 34",
    "wedge15": "01 12 20 34 45 53 03 14 25",
    "hexahedron20": "01 12 23 30 45 56 67 74 04 15 26 37",
}


def reference_element(name):
    """Points of one VTK-ordered element (quadratic: mid-edge points on VTK's edge order)."""
    linear = fa.LINEAR_OF[name]
    pts = [np.array(p, float) for p in CORNERS[linear]]
    if name != linear:
        pts += [(pts[a] + pts[b]) / 2 for a, b in fa.EDGES[linear]]
    return np.array(pts)


def vtk_signed_volume(p):
    return np.linalg.det(np.array([p[1] - p[0], p[2] - p[0], p[3] - p[0]])) / 6


class NodeOrderTables(unittest.TestCase):

    def test_tables_are_permutations(self):
        for name, perm in fa.SMESH_FROM_VTK.items():
            self.assertEqual(sorted(perm), list(range(fa.NODES_PER_CELL[name])), name)
            inv = fa.VTK_FROM_SMESH[name]
            self.assertEqual([perm[i] for i in inv], list(range(len(perm))), name)

    def test_quadratic_tables_follow_smesh_edge_numbering(self):
        # Derived again: SMESH corners, then the mid-node of each SMESH edge.
        for name, edges in SMESH_EDGES.items():
            linear = fa.LINEAR_OF[name]
            corners = fa.SMESH_FROM_VTK[linear]
            vtk_edges = [frozenset(e) for e in fa.EDGES[linear]]
            derived = list(corners)
            for e in edges.split():
                a, b = corners[int(e[0])], corners[int(e[1])]
                derived.append(len(corners) + vtk_edges.index(frozenset((a, b))))
            self.assertEqual(tuple(derived), fa.SMESH_FROM_VTK[name], name)
            self.assertEqual(fa.SMESH_FROM_VTK[name][:len(corners)], corners, name)

    def test_smesh_order_has_negative_vtk_volume(self):
        # The frame at corner 0 (its three neighbours) is right-handed in VTK order and
        # left-handed in SMESH order: the base is reversed.
        frame = {"tetra": [0, 1, 2, 3], "pyramid": [0, 1, 3, 4], "wedge": [0, 1, 2, 3],
                 "hexahedron": [0, 1, 3, 4]}
        for name in fa.LINEAR_CELLS:
            p = reference_element(name)
            smesh = p[list(fa.SMESH_FROM_VTK[name])]
            self.assertGreater(vtk_signed_volume(p[frame[name]]), 0, name)
            self.assertLess(vtk_signed_volume(smesh[frame[name]]), 0, name)

    def test_quadratic_mid_nodes_sit_on_smesh_edges(self):
        for name, edges in SMESH_EDGES.items():
            p = reference_element(name)[list(fa.SMESH_FROM_VTK[name])]
            n = fa.NODES_PER_CELL[fa.LINEAR_OF[name]]
            for k, e in enumerate(edges.split()):
                np.testing.assert_allclose(p[n + k], (p[int(e[0])] + p[int(e[1])]) / 2,
                                           err_msg="{} edge {}".format(name, e))


class FemMeshRoundTrip(unittest.TestCase):
    def setUp(self):
        work = tempfile.TemporaryDirectory(prefix="hexmerge_test_")
        self.addCleanup(work.cleanup)
        self.work = work.name

    def one_element_mesh(self, name, **kw):
        p = reference_element(name)
        cells = np.arange(len(p))[None, :]
        ids = np.arange(1, len(p) + 1) * 10  # node ids unlike positions
        return fa.arrays_to_femmesh(p, ids, [(name, cells)], **kw)[0], p, ids

    def test_every_type_round_trips(self):
        for name in fa.LINEAR_CELLS + fa.QUADRATIC_CELLS:
            m, p, ids = self.one_element_mesh(name)
            self.assertEqual(m.VolumeCount, 1, name)
            back = fa.femmesh_to_arrays(m)
            (bname, cells), = back.blocks
            self.assertEqual(bname, name)
            np.testing.assert_allclose(back.points[cells[0]], p, err_msg=name)

    def test_femmesh_sees_the_right_type(self):
        expected = {"tetra": "TetraCount", "pyramid": "PyramidCount", "wedge": "PrismCount",
                    "hexahedron": "HexaCount"}
        for name, attr in expected.items():
            m, _, _ = self.one_element_mesh(name)
            self.assertEqual(getattr(m, attr), 1, name)

    def test_med_file_keeps_every_type(self):
        # SMESH's own reader checks the element; a wrong order would come back reordered.
        for name in fa.LINEAR_CELLS + fa.QUADRATIC_CELLS:
            m, p, _ = self.one_element_mesh(name)
            path = os.path.join(self.work, "e.med")
            m.write(path)
            back = fa.femmesh_to_arrays(Fem.read(path))
            (bname, cells), = back.blocks
            self.assertEqual(bname, name)
            np.testing.assert_allclose(back.points[cells[0]], p, err_msg=name)

    def test_pyramids_as_collapsed_hexahedra_reach_the_inp(self):
        for name, ccx in (("pyramid", "C3D8"), ("pyramid13", "C3D20")):
            m, p, ids = self.one_element_mesh(name, pyramids_as_hexahedra=True)
            self.assertEqual(m.VolumeCount, 1)
            self.assertEqual(m.PyramidCount, 0)
            path = os.path.join(self.work, "e.inp")
            m.writeABAQUS(path, 1, False)
            text = open(path).read()
            self.assertIn("TYPE=" + ccx, text, name)
            # base corners and apex, each once among the distinct nodes
            (hexname, cells), = fa.femmesh_to_arrays(m).blocks
            self.assertEqual(len(set(cells[0][:8].tolist())), 5)

    def test_pyramids_left_as_pyramids_are_dropped_by_the_writer(self):
        # The fact that makes the option necessary (DESIGN.md).
        m, _, _ = self.one_element_mesh("pyramid")
        path = os.path.join(self.work, "e.inp")
        m.writeABAQUS(path, 1, False)
        self.assertNotIn("C3D", open(path).read().split("** Volume elements")[-1][:200])

    def test_boundary_faces_of_two_tets(self):
        cells = np.array([[0, 1, 2, 3], [1, 2, 3, 4]])
        faces = fa.boundary_faces([("tetra", cells)])
        self.assertEqual(len(faces[3]), 6)  # 8 faces, the shared one removed

    def test_groups_and_faces_written(self):
        p = reference_element("hexahedron")
        m, _ = fa.arrays_to_femmesh(p, np.arange(1, 9), [("hexahedron", np.arange(8)[None])],
                                    regions=[np.array([3])], group_names={3: "Mat_Solids"})
        self.assertEqual(m.FaceCount, 6)
        self.assertEqual(m.VolumeCount, 1)
        (g,) = m.Groups
        self.assertEqual(m.getGroupName(g), "Mat_Solids")
        self.assertEqual(m.getGroupElementType(g), "Volume")

    def test_outer_volumes_numbered_first(self):
        # 3 x 3 x 3 hexahedra, the middle one in a block of its own: every
        # volume with a boundary face gets a smaller id than the inner one (FreeCAD 0.20's view
        # colours only ids below 65536 right, and draws only the outer volumes).
        n = 3
        grid = np.array([(i, j, k) for k in range(n + 1) for j in range(n + 1) for i in range(n + 1)],
                        float)
        node = lambda i, j, k: i + (n + 1) * (j + (n + 1) * k)  # noqa: E731
        hexes = []
        for i in range(n):
            for j in range(n):
                for k in range(n):
                    hexes.append([node(i + a, j + b, k + c) for a, b, c in
                                  ((0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0),
                                   (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1))])
        hexes = np.array(hexes)
        middle = 13  # (1, 1, 1)
        blocks = [("hexahedron", hexes[[middle]]), ("hexahedron", np.delete(hexes, middle, axis=0))]
        outer = fa.outer_cells(blocks)
        self.assertEqual([o.tolist() for o in outer], [[False], [True] * 26])
        m, ids = fa.arrays_to_femmesh(grid, np.arange(1, len(grid) + 1), blocks, with_faces=False)
        self.assertEqual(ids[0].tolist(), [27])
        self.assertEqual(sorted(ids[1].tolist()), list(range(1, 27)))
        self.assertEqual(sorted(m.Volumes), list(range(1, 28)))
        m, ids = fa.arrays_to_femmesh(grid, np.arange(1, len(grid) + 1), blocks, with_faces=False,
                                      outer_first=False)
        self.assertEqual(ids[0].tolist(), [1])

    def test_not_tetrahedral_and_empty(self):
        with self.assertRaises(fa.NotTetrahedralError):
            fa.tetrahedra(fa.femmesh_to_arrays(Fem.FemMesh()))
        m, _, _ = self.one_element_mesh("hexahedron")
        with self.assertRaisesRegex(fa.NotTetrahedralError, "not tetrahedral"):
            fa.tetrahedra(fa.femmesh_to_arrays(m))


if __name__ == "__main__":
    unittest.main()
