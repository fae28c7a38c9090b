"""Every conformity mode and every option inside its documented range gives a mesh the checker
calls valid (issue 14, items 4 and 5): no crack where quads may meet triangles (allow,
last_resort), no flat or inverted element whatever min_scaled_jacobian says."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import hexmerge
from meshes import grid

CORPUS = Path(__file__).resolve().parents[1] / "fuzz" / "corpus"


def read_tets(path: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """A mesh of the fuzzers' seed corpus (tests/fuzz/make_corpus.py)."""
    lines = [l for l in path.read_text().splitlines() if not l.startswith("#")]
    n = int(lines[0].split()[1])
    points = np.array([l.split() for l in lines[1 : 1 + n]], dtype=float)
    m = int(lines[1 + n].split()[1])
    rows = [list(map(int, l.split())) for l in lines[2 + n : 2 + n + m]]
    cells = np.array([r[:4] for r in rows])
    regions = np.array([r[4] for r in rows]) if len(rows[0]) > 4 else None
    return points, cells, regions


def meshes() -> list[tuple[str, np.ndarray, np.ndarray, np.ndarray | None]]:
    out = [(p.stem, *read_tets(p)) for p in sorted(CORPUS.glob("*.tets"))]
    rng = np.random.default_rng(7)
    for seed in range(3):
        points, tets, _ = grid(4, "five" if seed % 2 else "kuhn")
        inner = (points > 0).all(axis=1) & (points < 4).all(axis=1)
        points = points + inner[:, None] * rng.uniform(-0.06, 0.06, points.shape)
        out.append((f"jittered grid {seed}", points, tets, None))
    return out


MESHES = meshes()


def expect_valid(name: str, points, cells, regions, **options) -> dict:
    mesh, _ = hexmerge.recombine(points, cells, regions, **options)
    report = hexmerge.check(mesh, points, cells, regions)
    assert report["valid"], (name, options, report["problems"][:3])
    assert report["min_scaled_jacobian"] > 0, (name, options)
    return report


@pytest.mark.parametrize("conformity", ["allow", "last_resort"])
@pytest.mark.parametrize("finder", ["programs", "exhaustive"])
def test_non_conforming_modes_leave_no_crack(conformity: str, finder: str) -> None:
    for name, points, cells, regions in MESHES:
        for options in (
            {},
            {"min_dihedral_angle": 100.0, "min_boundary_dihedral_angle": 120.0},
            {"make_pyramids": False},
            {"min_dihedral_angle": 95.0, "max_face_angle": 170.0, "min_scaled_jacobian": 0.05},
        ):
            expect_valid(name, points, cells, regions, conformity=conformity, finder=finder, **options)


@pytest.mark.parametrize("conformity", ["conforming", "allow", "last_resort"])
def test_the_loosest_options_make_no_flat_or_inverted_element(conformity: str) -> None:
    loosest = {"min_dihedral_angle": 90.0, "max_face_angle": 180.0, "min_boundary_dihedral_angle": 90.0}
    for name, points, cells, regions in MESHES:
        for min_sj in (0.0, -1.0, -0.3):
            expect_valid(name, points, cells, regions, conformity=conformity, min_scaled_jacobian=min_sj, **loosest)
