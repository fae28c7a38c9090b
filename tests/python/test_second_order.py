"""Tet10 input gives quadratic output that reuses the input's mid-edge nodes."""

from __future__ import annotations

import numpy as np
import pytest

import hexmerge
from meshes import EDGES, LINEAR_OF, grid, min_corner_determinant, to_tet10


def assert_mid_nodes_at_midpoints(mesh: hexmerge.MixedMesh) -> None:
    for block in mesh.cell_blocks():
        assert block.type in EDGES, block.type
        n = block.data.shape[1] - len(EDGES[block.type])
        for k, (a, b) in enumerate(EDGES[block.type]):
            mid = mesh.points[block.data[:, n + k]]
            ends = 0.5 * (mesh.points[block.data[:, a]] + mesh.points[block.data[:, b]])
            assert np.allclose(mid, ends, atol=1e-12), (block.type, k)
        assert (min_corner_determinant(mesh.points, LINEAR_OF[block.type], block.data[:, :n]) > 0).all()


@pytest.mark.parametrize("split", ["kuhn", "five"])
def test_tet10_grid_gives_hexahedron20(split: str) -> None:
    points, tets, _ = grid(3, split)
    p10, t10 = to_tet10(points, tets)
    mesh, report = hexmerge.recombine(p10, t10)
    assert mesh.order == 2
    assert [b.type for b in mesh.cell_blocks()] == ["hexahedron20"]
    assert report["output_counts"]["hex"] == 27
    assert_mid_nodes_at_midpoints(mesh)
    # The face and interior diagonals' mid nodes are gone; every node left is used.
    used = np.zeros(mesh.nb_points, dtype=bool)
    used[mesh.quadratic_nodes] = True
    assert used.all()
    assert mesh.nb_points == 4**3 + 3 * 4 * 4 * 3  # corners + one node per grid edge
    # Nodes keep the input's coordinates, traced by point_map.
    assert np.array_equal(mesh.points, p10[mesh.point_map])
    # The linear view is the same mesh as a Tet4 run on the corners.
    linear, _ = hexmerge.recombine(points, tets)
    assert np.array_equal(mesh.point_map[mesh.cell_vertices], linear.cell_vertices)


def test_mixed_quadratic_output() -> None:
    points, tets, _ = grid(2, "kuhn")
    p10, t10 = to_tet10(points, tets)
    mesh, _ = hexmerge.recombine(p10, t10, make_hexahedra=False)
    names = {b.type for b in mesh.cell_blocks()}
    assert "wedge15" in names and names <= {"tetra10", "pyramid13", "wedge15"}
    assert_mid_nodes_at_midpoints(mesh)
    report = hexmerge.check(mesh, p10, t10)
    assert report["valid"], report["problems"]


def test_gmsh_tet10(gmsh_tet10) -> None:
    meshio = pytest.importorskip("meshio")
    m = meshio.read(gmsh_tet10)
    t10 = m.cells_dict["tetra10"]
    mesh, _ = hexmerge.recombine(m.points, t10)
    assert mesh.order == 2
    # Straight-sided boxes: Gmsh put every mid-edge node at its edge's midpoint.
    assert_mid_nodes_at_midpoints(mesh)
    tets4 = t10[:, :4]
    assert hexmerge.check(mesh, m.points, tets4)["valid"]


def test_inconsistent_mid_nodes_name_the_element() -> None:
    points, tets, _ = grid(1, "kuhn")
    p10, t10 = to_tet10(points, tets)
    # Give tet 3 its own node for an edge it shares with another tet.
    t10 = t10.copy()
    p10 = np.vstack([p10, p10[t10[3, 4]]])
    t10[3, 4] = len(p10) - 1
    with pytest.raises(ValueError, match=r"\d"):
        hexmerge.recombine(p10, t10)
