"""hexmerge.regions_by_solid(): solids of a BREP shape per tet (the OpenCASCADE layer)."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

import hexmerge
from conftest import BOX_GEO
from meshes import grid

pytestmark = pytest.mark.skipif(
    not hexmerge.WITH_OPENCASCADE, reason="hexmerge built without OpenCASCADE"
)


@pytest.fixture(scope="module")
def boxes_brep(tmp_path_factory: pytest.TempPathFactory) -> str:
    """The two unit boxes of conftest.BOX_GEO (sharing the face x = 1) as BREP text, by Gmsh."""
    if shutil.which("gmsh") is None:
        pytest.skip("gmsh is not installed")
    folder = tmp_path_factory.mktemp("brep")
    geo = folder / "boxes.geo"
    geo.write_text(BOX_GEO)
    out = folder / "boxes.brep"
    subprocess.run(["gmsh", "-0", str(geo), "-o", str(out)], check=True, capture_output=True)
    return out.read_text()


def physical_regions(path: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    meshio = pytest.importorskip("meshio")
    m = meshio.read(path)
    tets = m.cells_dict["tetra" if "tetra" in m.cells_dict else "tetra10"]
    phys = np.concatenate(
        [d for d, c in zip(m.cell_data["gmsh:physical"], m.cells) if c.type.startswith("tetra")]
    )
    return m.points, tets, phys


@pytest.mark.parametrize("fixture", ["gmsh_tet4", "gmsh_tet10"])
def test_solids_match_gmsh_volumes(request, boxes_brep, fixture) -> None:
    points, tets, phys = physical_regions(request.getfixturevalue(fixture))
    solids, report = hexmerge.regions_by_solid(boxes_brep, points, tets)
    assert solids.dtype == np.int32 and solids.shape == (len(tets),)
    # Physical volume 7 is the box at x < 1, 9 the one at x > 1; Gmsh writes them in that order.
    assert np.array_equal(solids, np.where(phys == 7, 0, 1))
    assert report["nb_solids"] == 2
    assert report["nb_shared_faces"] == 1
    assert report["nb_pieces"] == 2
    assert report["nb_unassigned_tets"] == 0
    every, _ = hexmerge.regions_by_solid(boxes_brep, points, tets, classify_every_tet=True)
    assert np.array_equal(every, solids)


def test_solids_feed_recombine(boxes_brep, gmsh_tet4) -> None:
    points, tets, _ = physical_regions(gmsh_tet4)
    solids, _ = hexmerge.regions_by_solid(boxes_brep, points, tets, threads=1)
    mesh, _ = hexmerge.recombine(points, tets, solids)
    assert hexmerge.check(mesh, points, tets, solids)["valid"]


def test_tets_outside_the_shape(boxes_brep) -> None:
    points, tets, _ = grid(2)
    solids, report = hexmerge.regions_by_solid(boxes_brep, points + 10.0, tets)
    assert (solids == -1).all()
    assert report["nb_unassigned_tets"] == len(tets)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"brep": ""}, "brep is empty"),
        ({"brep": 42}, "BREP text"),
        ({"tolerance": 0.0}, "tolerance"),
        ({"tolerance": "small"}, "tolerance"),
        ({"samples_per_piece": 0}, "samples_per_piece"),
        ({"threads": 1.5}, "threads"),
        ({"classify_every_tet": "yes"}, "classify_every_tet"),
        ({"cells": np.zeros((3, 8), dtype=int)}, "not tetrahedra"),
    ],
)
def test_bad_input(boxes_brep, kwargs, message) -> None:
    points, tets, _ = grid(1)
    args = {"brep": boxes_brep, "points": points, "cells": tets, **kwargs}
    with pytest.raises(ValueError, match=message):
        hexmerge.regions_by_solid(**args)


def test_text_without_a_solid() -> None:
    points, tets, _ = grid(1)
    with pytest.raises(hexmerge.InputError, match="cannot be read"):
        hexmerge.regions_by_solid("not a BREP", points, tets)
