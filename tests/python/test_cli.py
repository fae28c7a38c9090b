"""The command line end to end on small files: formats, regions, quadratic node order, errors."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import hexmerge
from hexmerge import cli
from conftest import PYTHON_SRC
from meshes import EDGES, grid, min_corner_determinant

meshio = pytest.importorskip("meshio")


VTK_QUADRATIC = {24: "tetra10", 27: "pyramid13", 26: "wedge15", 25: "hexahedron20"}


def read_legacy_vtk(path: Path) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """The points and quadratic cells of an ASCII legacy .vtk file as Gmsh writes it (a small
    reader of our own: the oracle must not go through meshio's node-order tables)."""
    words = path.read_text().split()
    i = words.index("POINTS")
    n = int(words[i + 1])
    points = np.array(words[i + 3 : i + 3 + 3 * n], dtype=float).reshape(n, 3)
    i = words.index("CELLS")
    nc, size = int(words[i + 1]), int(words[i + 2])
    flat = np.array(words[i + 3 : i + 3 + size], dtype=np.int64)
    i = words.index("CELL_TYPES")
    types = np.array(words[i + 2 : i + 2 + nc], dtype=int)
    cells: dict[str, list] = {}
    k = 0
    for t in types:
        m = flat[k]
        if t in VTK_QUADRATIC:
            cells.setdefault(VTK_QUADRATIC[t], []).append(flat[k + 1 : k + 1 + m])
        k += m + 1
    return points, {name: np.array(rows) for name, rows in cells.items()}


def run(*args: object) -> int:
    return cli.main([str(a) for a in args])


def write_grid(path: Path, split: str = "kuhn", regions: bool = True, **kwargs) -> tuple[np.ndarray, np.ndarray]:
    points, tets, cube = grid(3, split)
    r = np.where(cube % 3 == 0, 5, 6)
    # Two blocks, one per region: Gmsh 4.1 keeps one physical tag per block.
    order = np.argsort(r, kind="stable")
    tets, r = tets[order], r[order]
    blocks = [("tetra", tets[r == v]) for v in (5, 6)]
    cell_data, cell_sets = {}, {}
    if regions:
        if path.suffix == ".inp":
            cell_sets = {"Steel": [np.arange(len(blocks[0][1])), np.empty(0, int)],
                         "Alu": [np.empty(0, int), np.arange(len(blocks[1][1]))]}
        key = {".msh": "gmsh:physical", ".mesh": "medit:ref"}.get(path.suffix, "region")
        cell_data[key] = [np.full(len(b[1]), v) for b, v in zip(blocks, (5, 6))]
        if key == "gmsh:physical":
            cell_data["gmsh:geometrical"] = [np.full(len(b[1]), i + 1) for i, b in enumerate(blocks)]
    point_data = {}
    if path.suffix == ".msh":
        kwargs.setdefault("file_format", "gmsh")  # meshio would take ANSYS for .msh
        if kwargs["file_format"] == "gmsh":  # Gmsh 4.1 puts every node in an entity
            point_data["gmsh:dim_tags"] = hexmerge._io._node_entities(len(points), [b[1] for b in blocks])
    mesh = meshio.Mesh(points, blocks, point_data=point_data, cell_data=cell_data, cell_sets=cell_sets or None)
    meshio.write(path, mesh, **kwargs)
    return points, tets


def cells_as_sets(mesh) -> set[tuple[str, tuple]]:
    """Cells by type and the coordinates of their nodes in order (node numbering may differ)."""
    out = set()
    for block in mesh.cells:
        for row in block.data:
            out.add((block.type, tuple(map(tuple, np.round(mesh.points[row], 12)))))
    return out


@pytest.mark.parametrize(
    "suffix, fmt",
    [(".vtu", None), (".msh", None), (".msh", "gmsh22"), (".inp", None), (".mesh", None), (".vtk", None)],
)
def test_recombine_round_trip(tmp_path: Path, capsys, suffix: str, fmt: str | None) -> None:
    src = tmp_path / f"in{suffix}"
    write_grid(src, "five", **({"file_format": fmt} if fmt else {}))
    out = tmp_path / f"out{suffix}"
    args = ["recombine", src, "-o", out] + (["--output-format", fmt] if fmt else [])
    assert run(*args) == 0
    assert "27 hex" in capsys.readouterr().out
    m = meshio.read(out)
    assert [b.type for b in m.cells] == ["hexahedron"] * len(m.cells)
    hexes = np.concatenate([b.data for b in m.cells])
    assert len(hexes) == 27
    assert (min_corner_determinant(m.points, "hexahedron", hexes) > 0).all()
    # The API gives the same cells.
    t = hexmerge._io.read_tets(src)
    mesh, _ = hexmerge.recombine(t.points, t.cells, t.regions)
    assert cells_as_sets(m) == cells_as_sets(mesh.to_meshio())
    # Regions survive the trip (two regions, kept in the format's own way).
    assert t.regions is not None and len(set(t.regions.tolist())) == 2
    mixed, _ = hexmerge._io.read_mixed(out)
    if suffix == ".inp":  # Abaqus keeps regions as element sets, named as in the input
        assert set(meshio.read(out).cell_sets) == {"Steel", "Alu"}
    else:
        assert mixed.regions is not None and set(mixed.regions.tolist()) == set(t.regions.tolist())
    assert run("check", out, "--source", src) == 0


def test_gmsh_quadratic_node_order(tmp_path: Path, gmsh_tet10: Path) -> None:
    """Tet10 from Gmsh -> quadratic .msh (4.1 and 2.2) -> Gmsh itself converts to VTK: every
    mid-edge node of every element sits at its edge's midpoint in VTK order."""
    if shutil.which("gmsh") is None:
        pytest.skip("gmsh is not installed")
    for fmt in ("gmsh", "gmsh22"):
        out = tmp_path / f"q-{fmt}.msh"
        assert run("recombine", gmsh_tet10, "-o", out, "--output-format", fmt, "-q") == 0
        vtk = tmp_path / f"q-{fmt}.vtk"
        subprocess.run(["gmsh", str(out), "-0", "-format", "vtk", "-o", str(vtk)], check=True, capture_output=True)
        m = hexmerge._io.read(out)
        for points, cells in (
            (m.points, {b.type: b.data for b in m.cells if b.type in EDGES}),
            read_legacy_vtk(vtk),
        ):
            # Gmsh 4.8 writes quadratic pyramids to VTK as linear ones: pyramid13's Gmsh order is
            # checked through the .msh only.
            assert set(cells) >= {"tetra10", "wedge15"}, set(cells)
            for name, data in cells.items():
                n = data.shape[1] - len(EDGES[name])
                for k, (a, b) in enumerate(EDGES[name]):
                    mid = points[data[:, n + k]]
                    ends = 0.5 * (points[data[:, a]] + points[data[:, b]])
                    assert np.allclose(mid, ends, atol=1e-9), (fmt, name, k)
        assert run("check", out, "--source", gmsh_tet10) == 0


def test_quadratic_vtu_and_inp(tmp_path: Path, gmsh_tet10: Path) -> None:
    out = tmp_path / "q.vtu"
    assert run("recombine", gmsh_tet10, "-o", out, "-q") == 0
    assert {b.type for b in meshio.read(out).cells} >= {"tetra10", "pyramid13", "wedge15"}
    inp = tmp_path / "q.inp"
    assert run("recombine", gmsh_tet10, "-o", inp, "-q", "--no-make-pyramids") == 0
    assert run("check", inp, "--source", gmsh_tet10) == 0


def test_pyramids_and_abaqus(tmp_path: Path, gmsh_tet4: Path, capsys) -> None:
    out = tmp_path / "out.inp"
    assert run("recombine", gmsh_tet4, "-o", out) == 1
    assert "no pyramid element" in capsys.readouterr().err
    assert not out.exists()
    assert run("recombine", gmsh_tet4, "-o", out, "--collapse-pyramids", "-q") == 0
    m = meshio.read(out)
    assert "pyramid" not in {b.type for b in m.cells}
    hexes = np.concatenate([b.data for b in m.cells if b.type == "hexahedron"])
    collapsed = hexes[(hexes[:, 4] == hexes[:, 5]) & (hexes[:, 5] == hexes[:, 6]) & (hexes[:, 6] == hexes[:, 7])]
    assert len(collapsed) > 0


def test_help_lists_every_parameter(capsys) -> None:
    with pytest.raises(SystemExit) as info:
        run("recombine", "--help")
    assert info.value.code == 0
    text = " ".join(capsys.readouterr().out.split())
    for row in hexmerge.parameters():
        flag = "--" + row["name"].replace("_", "-")
        assert flag in text
        assert f"default: {row['default_text']}" in text or row["type"] == "bool"
    # Angles show their unit next to the default.
    dangle = next(r for r in hexmerge.parameters() if r["name"] == "min_dihedral_angle")
    assert f"default: {dangle['default_text']} deg" in text


def test_options_reach_the_engine(tmp_path: Path) -> None:
    src = tmp_path / "in.vtu"
    write_grid(src)
    out = tmp_path / "out.vtu"
    stats = tmp_path / "stats.json"
    assert run("recombine", src, "-o", out, "--no-make-hexahedra", "--min-dihedral-angle", "170", "--stats", stats, "-q") == 0
    report = json.loads(stats.read_text())
    assert report["options"] == {"min_dihedral_angle": 170.0, "make_hexahedra": False}
    assert report["report"]["output_counts"]["hex"] == 0
    assert report["report"]["input_tets"] == 27 * 6
    assert "hexahedron" not in {b.type for b in meshio.read(out).cells}


def test_check_json_and_tets_alone(tmp_path: Path, capsys) -> None:
    src = tmp_path / "in.vtu"
    write_grid(src)
    assert run("check", src, "--json") == 0
    report = json.loads(capsys.readouterr().out)
    assert report["valid"] is True and report["counts"]["tet"] == 162
    out = tmp_path / "out.vtu"
    assert run("recombine", src, "-o", out, "-q") == 0
    assert run("check", out) == 1  # mixed mesh without its source
    assert "--source" in capsys.readouterr().err


def test_check_finds_a_moved_node(tmp_path: Path, capsys) -> None:
    src = tmp_path / "in.vtu"
    write_grid(src)
    out = tmp_path / "out.vtu"
    assert run("recombine", src, "-o", out, "-q") == 0
    m = meshio.read(out)
    m.points[10] += 0.01
    meshio.write(out, m)
    capsys.readouterr()
    assert run("check", out, "--source", src, "--json") == cli.EXIT_INVALID
    report = json.loads(capsys.readouterr().out)
    assert not report["valid"] and report["moved_nodes"] >= 1
    assert any("node 10" in p for p in report["problems"])


@pytest.mark.parametrize("fault", ["inverted", "nan", "hexahedra", "missing", "garbage", "empty-folder"])
def test_bad_input_fails_cleanly(tmp_path: Path, capsys, fault: str) -> None:
    points, tets, _ = grid(2, "kuhn")
    src = tmp_path / "in.vtu"
    if fault == "inverted":
        tets[7, [1, 2]] = tets[7, [2, 1]]
    if fault == "nan":
        points[3, 2] = np.nan
    cells = [("hexahedron", np.arange(8)[None])] if fault == "hexahedra" else [("tetra", tets)]
    if fault != "missing":
        meshio.write(src, meshio.Mesh(points, cells))
    if fault == "garbage":
        src.write_text("not a mesh")
    out = tmp_path / ("nowhere/out.vtu" if fault == "empty-folder" else "out.vtu")
    code = run("recombine", src, "-o", out)
    err = capsys.readouterr().err
    assert code == 1
    assert err.splitlines()[-1].startswith("hexmerge: error:")
    expected = {
        "inverted": "tetrahedron 7",
        "nan": "node 3",
        "hexahedra": "unsupported cell type 'hexahedron'",
        "missing": "no such file",
        "garbage": "cannot read",
        "empty-folder": "does not exist",
    }[fault]
    assert expected in err
    assert not out.exists()
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []  # no temp file left


def test_failed_run_keeps_an_existing_output(tmp_path: Path) -> None:
    points, tets, _ = grid(1, "kuhn")
    tets[0, [1, 2]] = tets[0, [2, 1]]
    src = tmp_path / "in.vtu"
    meshio.write(src, meshio.Mesh(points, [("tetra", tets)]))
    out = tmp_path / "out.vtu"
    out.write_text("previous result")
    assert run("recombine", src, "-o", out, "-q") == 1
    assert out.read_text() == "previous result"


def test_usage_errors() -> None:
    with pytest.raises(SystemExit) as info:
        run("recombine", "in.vtu")  # no -o
    assert info.value.code == 2
    with pytest.raises(SystemExit) as info:
        run("recombine", "in.vtu", "-o", "out.vtu", "--min-dihedral-angle", "wide")
    assert info.value.code == 2
    with pytest.raises(SystemExit) as info:
        run("recombine", "in.vtu", "-o", "out.vtu", "--conformity", "sometimes")
    assert info.value.code == 2


def test_out_of_range_option(tmp_path: Path, capsys) -> None:
    src = tmp_path / "in.vtu"
    write_grid(src)
    out = tmp_path / "out.vtu"
    assert run("recombine", src, "-o", out, "--min-dihedral-angle", "10") == 1
    assert "min_dihedral_angle" in capsys.readouterr().err
    assert not out.exists()


def test_module_entry_point(tmp_path: Path) -> None:
    src = tmp_path / "in.msh"
    write_grid(src, file_format="gmsh22")
    out = tmp_path / "out.vtu"
    env = dict(os.environ, PYTHONPATH=str(PYTHON_SRC))
    done = subprocess.run(
        [sys.executable, "-m", "hexmerge", "recombine", str(src), "-o", str(out), "--progress"],
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    assert "%" in done.stderr  # progress lines
    assert out.exists()
    done = subprocess.run([sys.executable, "-m", "hexmerge", "parameters", "--json"], env=env, capture_output=True, text=True, check=True)
    assert [r["name"] for r in json.loads(done.stdout)] == [r["name"] for r in hexmerge.parameters()]
