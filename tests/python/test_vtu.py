"""The command line's VTU writer (hexmerge._vtu): raw appended arrays that meshio reads back as
the same mesh its own writer makes, for linear and quadratic cells of every type, with regions."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import hexmerge
from hexmerge import _io, cli
from meshes import cell_volumes, grid

meshio = pytest.importorskip("meshio")


def same_mesh(a, b) -> None:
    assert np.array_equal(a.points, b.points)
    assert [c.type for c in a.cells] == [c.type for c in b.cells]
    for x, y in zip(a.cells, b.cells):
        assert np.array_equal(x.data, y.data), x.type
    assert a.cell_data.keys() == b.cell_data.keys()
    for key in a.cell_data:
        for x, y in zip(a.cell_data[key], b.cell_data[key]):
            assert np.array_equal(x, y), key


def mixed_mesh(path: Path) -> hexmerge.MixedMesh:
    tets = _io.read_tets(path)
    mesh, _ = hexmerge.recombine(tets.points, tets.cells, tets.regions)
    return mesh


@pytest.mark.parametrize("fixture", ["gmsh_tet4", "gmsh_tet10"])
def test_same_arrays_as_meshio(tmp_path: Path, request: pytest.FixtureRequest, fixture: str) -> None:
    mesh = mixed_mesh(request.getfixturevalue(fixture))
    assert len(mesh.cell_blocks()) >= 3  # several cell types in one file
    ours, theirs = tmp_path / "ours.vtu", tmp_path / "theirs.vtu"
    _io.write_atomic(ours, _io.to_meshio(mesh, "vtu"), "vtu")
    meshio.write(theirs, _io.to_meshio(mesh, "vtu"), file_format="vtu")
    assert b'<AppendedData encoding="raw">' in ours.read_bytes()
    a, b = meshio.read(ours), meshio.read(theirs)
    same_mesh(a, b)
    assert set(np.concatenate(a.cell_data["region"]).tolist()) == {7, 9}
    # Read back, the cells are the engine's, with positive volumes (VTK's node orders kept).
    linear = {"tetra10": "tetra", "pyramid13": "pyramid", "wedge15": "wedge", "hexahedron20": "hexahedron"}
    for block in a.cells:
        name = linear.get(block.type, block.type)
        nodes = {"tetra": 4, "pyramid": 5, "wedge": 6, "hexahedron": 8}[name]
        assert (cell_volumes(a.points, name, block.data[:, :nodes]) > 0).all(), block.type


def test_cli_writes_raw_vtu_and_ascii_through_meshio(tmp_path: Path) -> None:
    points, tets, _ = grid(2, "kuhn")
    src = tmp_path / "in.vtu"
    meshio.write(src, meshio.Mesh(points, [("tetra", tets)]))
    out, text = tmp_path / "out.vtu", tmp_path / "text.vtu"
    assert cli.main(["recombine", str(src), "-o", str(out), "--quiet"]) == 0
    assert cli.main(["recombine", str(src), "-o", str(text), "--ascii", "--quiet"]) == 0
    assert b'encoding="raw"' in out.read_bytes()
    assert b'format="ascii"' in text.read_bytes()
    same_mesh(meshio.read(out), meshio.read(text))
    assert [c.type for c in meshio.read(out).cells] == ["hexahedron"]
