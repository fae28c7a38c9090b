"""The real-parts benchmark's element measures (bench/real_parts.py), which bench/gmsh_reference.py
uses on Gmsh's own tet meshes: the scaled Jacobian of plain tet arrays and of a MixedMesh, and the
boundary triangles' smallest angles, on hand-made tets."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

import real_parts

REGULAR = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 3**0.5 / 2, 0.0], [0.5, 3**0.5 / 6, (2 / 3) ** 0.5]])


def test_regular_tet_is_one_flat_is_zero_reversed_is_minus_one() -> None:
    flat = REGULAR.copy()
    flat[3, 2] = 0.0  # the apex in the base's plane
    points = np.vstack([REGULAR, flat])
    tets = np.array([[0, 1, 2, 3], [4, 5, 6, 7], [0, 2, 1, 3]])
    sj = real_parts.tet_scaled_jacobians(points, tets)
    assert sj == pytest.approx([1.0, 0.0, -1.0], abs=1e-12)


def test_tets_measure_the_same_as_a_mixed_mesh_of_tets() -> None:
    rng = np.random.default_rng(13)
    points = rng.random((30, 3))
    tets = np.array([rng.choice(30, 4, replace=False) for _ in range(50)])
    mesh = SimpleNamespace(nb_cells=len(tets), types=np.zeros(len(tets), dtype=int), offsets=4 * np.arange(len(tets)),
                           cell_vertices=tets.ravel(), points=points)
    assert np.array_equal(real_parts.scaled_jacobians(mesh), real_parts.tet_scaled_jacobians(points, tets))


def test_boundary_triangles_are_faces_of_one_tet() -> None:
    apex = 2 * REGULAR[[0, 1, 2]].mean(axis=0) - REGULAR[3]  # the mirror image of the apex
    points = np.vstack([REGULAR, apex])
    angles = real_parts.boundary_triangle_angles(points, np.array([[0, 1, 2, 3], [0, 2, 1, 4]]))
    assert len(angles) == 6  # the shared face is inside
    assert angles == pytest.approx(np.full(6, 60.0))
