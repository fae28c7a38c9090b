"""Bad input raises ValueError naming the node or element at fault."""

from __future__ import annotations

import numpy as np
import pytest

import hexmerge
from meshes import grid


@pytest.fixture
def cube() -> tuple[np.ndarray, np.ndarray]:
    points, tets, _ = grid(1, "kuhn")
    return points, tets


def test_nan_and_infinite_coordinates(cube) -> None:
    points, tets = cube
    for bad in (np.nan, np.inf, -np.inf):
        p = points.copy()
        p[5, 1] = bad
        with pytest.raises(ValueError, match="node 5"):
            hexmerge.recombine(p, tets)


@pytest.mark.parametrize("bad_id", [8, 100, -1])
def test_node_id_out_of_range(cube, bad_id: int) -> None:
    points, tets = cube
    tets = tets.copy()
    tets[2, 3] = bad_id
    with pytest.raises(ValueError, match=rf"element 2 refers to node {bad_id}\b"):
        hexmerge.recombine(points, tets)


def test_inverted_tet(cube) -> None:
    points, tets = cube
    tets = tets.copy()
    tets[4, [1, 2]] = tets[4, [2, 1]]
    with pytest.raises(hexmerge.InputError, match=r"\b4\b") as info:
        hexmerge.recombine(points, tets)
    assert info.value.entity == "element" and info.value.index == 4
    assert isinstance(info.value, ValueError)


def test_flat_tet() -> None:
    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [0, 0, 1.0]])
    tets = np.array([[0, 1, 2, 4], [0, 1, 2, 3]])
    with pytest.raises(ValueError, match=r"\b1\b"):
        hexmerge.recombine(points, tets)


def test_repeated_vertex(cube) -> None:
    points, tets = cube
    tets = tets.copy()
    tets[1, 3] = tets[1, 0]
    with pytest.raises(ValueError, match=r"\b1\b"):
        hexmerge.recombine(points, tets)


def test_duplicate_tet(cube) -> None:
    points, tets = cube
    tets = np.vstack([tets, tets[[2]][:, [1, 2, 0, 3]]])  # same tet, rotated: still positive
    with pytest.raises(ValueError, match=r"\b(2|6)\b"):
        hexmerge.recombine(points, tets)


def test_face_shared_by_three_tets() -> None:
    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0.1, 0.1, 1], [0.2, 0.3, 2], [0.3, 0.2, -1.0]])
    tets = np.array([[0, 1, 2, 3], [0, 1, 2, 4], [0, 2, 1, 5]])
    with pytest.raises(ValueError, match=r"\d"):
        hexmerge.recombine(points, tets)


def test_empty_mesh() -> None:
    with pytest.raises(ValueError, match="empty"):
        hexmerge.recombine(np.zeros((0, 3)), np.zeros((0, 4), dtype=int))
    with pytest.raises(ValueError, match="no tetrahedra"):
        hexmerge.recombine(np.zeros((4, 3)), np.zeros((0, 4), dtype=int))


@pytest.mark.parametrize(
    "points_shape, cells_shape, message",
    [
        ((8, 2), (6, 4), r"points must be an array of shape \(N, 3\), got shape \(8, 2\)"),
        ((24,), (6, 4), r"points must be an array of shape \(N, 3\)"),
        ((8, 3), (6, 3), r"cells must be an array of shape \(M, 4\).*got shape \(6, 3\)"),
        ((8, 3), (1, 8), r"tetrahedral meshes only"),
        ((8, 3), (24,), r"got shape \(24,\)"),
    ],
)
def test_wrong_shapes(points_shape, cells_shape, message: str) -> None:
    points = np.zeros(points_shape)
    cells = np.zeros(cells_shape, dtype=np.int64)
    with pytest.raises(ValueError, match=message):
        hexmerge.recombine(points, cells)


def test_wrong_dtypes(cube) -> None:
    points, tets = cube
    with pytest.raises(ValueError, match="integer node ids"):
        hexmerge.recombine(points, tets.astype(float))
    with pytest.raises(ValueError, match="real numbers"):
        hexmerge.recombine(points.astype(str), tets)


def test_wrong_regions(cube) -> None:
    points, tets = cube
    with pytest.raises(ValueError, match=r"one id per element, shape \(6,\)"):
        hexmerge.recombine(points, tets, regions=np.zeros(5, dtype=int))
    with pytest.raises(ValueError, match="element 1 has region id"):
        hexmerge.recombine(points, tets, regions=np.array([0, 2**40, 0, 0, 0, 0]))


def test_unknown_and_bad_options(cube) -> None:
    points, tets = cube
    with pytest.raises(ValueError, match="unknown option 'min_angle'.*min_dihedral_angle"):
        hexmerge.recombine(points, tets, min_angle=3)
    with pytest.raises(ValueError, match="min_dihedral_angle"):
        hexmerge.recombine(points, tets, min_dihedral_angle=10.0)
    with pytest.raises(ValueError, match="make_prisms.*True or False"):
        hexmerge.recombine(points, tets, make_prisms=1)
    with pytest.raises(ValueError, match="conformity"):
        hexmerge.recombine(points, tets, conformity="sometimes")
    with pytest.raises(ValueError, match="no element type"):
        hexmerge.recombine(points, tets, make_hexahedra=False, make_prisms=False, make_pyramids=False)
    with pytest.raises(ValueError, match="progress"):
        hexmerge.recombine(points, tets, progress="yes")
