"""The post-merge stage's options (same_nodes, post_merge_contractions, post_merge_moves,
post_merge_splits) through the Python API and the CLI, and the checker's view of the nodes the
stage declares changed."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import hexmerge
from conftest import ROOT


def assert_sound(check: dict) -> None:
    """The checker's verdict on an output of the post-merge stage (its changed nodes declared):
    nothing inverted, off the input's boundary or cracked, no quad against two triangles, every
    region's volume kept."""
    assert check["inverted_cells"] == 0
    assert check["off_boundary_nodes"] == 0 and check["volume_not_kept"] == 0
    assert check["nonconforming_quads"] == 0 and check["cracks"] == 0
    assert abs(check["relative_volume_difference"]) < 1e-9

BOX_GEO = """
SetFactory("OpenCASCADE");
Box(1) = {{0, 0, 0, 4, 4, 2}};
Mesh.CharacteristicLengthMax = {size};
"""


def gmsh_box(tmp_path_factory: pytest.TempPathFactory,
             size: float) -> tuple[np.ndarray, np.ndarray, Path]:
    """A Gmsh Delaunay tet mesh of a 4 x 4 x 2 box with edges up to `size`, as the benchmarks'."""
    if shutil.which("gmsh") is None:
        pytest.skip("gmsh is not installed")
    import meshio

    folder = tmp_path_factory.mktemp("postmerge")
    geo = folder / "box.geo"
    geo.write_text(BOX_GEO.format(size=size))
    out = folder / "box.msh"
    subprocess.run(["gmsh", "-3", "-format", "msh22", str(geo), "-o", str(out)], check=True,
                   capture_output=True)
    m = meshio.read(out)
    tets = np.vstack([c.data for c in m.cells if c.type == "tetra"]).astype(np.int64)
    used = np.unique(tets)
    renumber = np.full(len(m.points), -1, dtype=np.int64)
    renumber[used] = np.arange(len(used))
    return np.asarray(m.points[used], dtype=float), renumber[tets], out


@pytest.fixture(scope="module")
def delaunay_box(tmp_path_factory: pytest.TempPathFactory) -> tuple[np.ndarray, np.ndarray, Path]:
    """The box with a few thousand tets."""
    return gmsh_box(tmp_path_factory, 0.33)


@pytest.fixture(scope="module")
def finer_box(tmp_path_factory: pytest.TempPathFactory) -> tuple[np.ndarray, np.ndarray, Path]:
    """The box with about 10,000 tets: enough inner pyramid apexes for vertex splits."""
    return gmsh_box(tmp_path_factory, 0.25)


def test_contractions_are_declared_and_the_checker_verifies_them(delaunay_box) -> None:
    points, tets, _ = delaunay_box
    mesh, report = hexmerge.recombine(points, tets, same_nodes=False, post_merge_moves=False)
    assert report["post_merge"] == "kept"
    assert report["contractions"] > 0 and report["node_moves"] == 0
    # The declared nodes are exactly the input's nodes no cell uses any more (none moved).
    unused = np.setdiff1d(np.unique(tets), np.unique(mesh.cell_vertices))
    assert np.array_equal(np.sort(mesh.changed_nodes), unused)
    assert len(unused) == report["contractions"]
    assert np.array_equal(mesh.points, points)
    check = hexmerge.check(mesh, points, tets)
    assert check["valid"], check["problems"]
    assert check["declared_changed_nodes"] == report["contractions"]
    assert_sound(check)
    # Undeclared, the same mesh fails: its contracted nodes are unused input nodes.
    mesh.changed_nodes = None
    bare = hexmerge.check(mesh, points, tets)
    assert not bare["valid"]
    assert bare["unused_input_nodes"] == report["contractions"]


def test_flips_only_and_same_nodes_declare_nothing(delaunay_box) -> None:
    points, tets, _ = delaunay_box
    same, r0 = hexmerge.recombine(points, tets)
    assert r0["post_merge"] == "off" and same.changed_nodes is None
    flips, r1 = hexmerge.recombine(points, tets, same_nodes=False, post_merge_contractions=False,
                                   post_merge_moves=False)
    assert r1["contractions"] == 0 and r1["node_moves"] == 0 and flips.changed_nodes is None
    assert hexmerge.check(flips, points, tets)["valid"]
    both, r2 = hexmerge.recombine(points, tets, same_nodes=False)
    # Contractions close quads no flip closes: never fewer hexahedra closed than flips alone.
    assert r2["post_merge_closed"] >= r1["post_merge_closed"]
    assert r2["output_cells"] < r0["output_cells"]


def test_moved_nodes_are_declared_inside_the_domain_and_the_checker_verifies_them(
        delaunay_box) -> None:
    points, tets, _ = delaunay_box
    mesh, report = hexmerge.recombine(points, tets, same_nodes=False)
    assert report["post_merge"] == "kept"
    assert report["node_moves"] > 0
    moved = np.flatnonzero(np.any(mesh.points != points, axis=1))
    unused = np.setdiff1d(np.unique(tets), np.unique(mesh.cell_vertices))
    assert len(moved) > 0
    # Declared: exactly the moved nodes and the unused ones.
    assert np.array_equal(np.sort(mesh.changed_nodes), np.union1d(moved, unused))
    # A moved node on the boundary stays in its face of the box (0..4, 0..4, 0..2), exactly,
    # and none is on an edge of it (two such coordinates).
    on_face = ((points[moved][:, :2] == 0) | (points[moved][:, :2] == 4)).sum(axis=1) + \
        ((points[moved][:, 2] == 0) | (points[moved][:, 2] == 2))
    assert (on_face <= 1).all()
    for axis, values in ((0, (0, 4)), (1, (0, 4)), (2, (0, 2))):
        sliding = np.isin(points[moved][:, axis], values)
        assert np.array_equal(mesh.points[moved][sliding, axis], points[moved][sliding, axis])
    check = hexmerge.check(mesh, points, tets)
    assert check["valid"], check["problems"]
    assert_sound(check)
    # Undeclared, the moved nodes fail the check.
    mesh.changed_nodes = None
    assert not hexmerge.check(mesh, points, tets)["valid"]


def test_a_moved_boundary_node_fails_the_check_even_when_declared(delaunay_box) -> None:
    points, tets, _ = delaunay_box
    mesh, _ = hexmerge.recombine(points, tets)
    corner = int(np.argmin(points.sum(axis=1)))  # the box corner at the origin
    mesh.points = mesh.points.copy()
    mesh.points[corner] -= 0.05
    mesh.changed_nodes = np.array([corner])
    check = hexmerge.check(mesh, points, tets)
    assert not check["valid"]
    assert check["off_boundary_nodes"] == 1
    assert check["volume_not_kept"] == 1


def test_cli_takes_the_contraction_option(delaunay_box, tmp_path: Path) -> None:
    _, _, path = delaunay_box
    out, stats = tmp_path / "out.vtu", tmp_path / "stats.json"
    cmd = [sys.executable, "-m", "hexmerge", "recombine", str(path), "-o", str(out), "--quiet",
           "--stats", str(stats), "--no-same-nodes"]
    env_path = str(ROOT / "src" / "python")
    for flag, expect_contractions in (("--no-post-merge-contractions", False),
                                      ("--post-merge-contractions", True)):
        subprocess.run(cmd + [flag], check=True, capture_output=True,
                       env={"PYTHONPATH": env_path, "PATH": "/usr/bin:/bin"})
        report = json.loads(stats.read_text())["report"]
        assert report["post_merge"] == "kept"
        assert (report["contractions"] > 0) == expect_contractions
    for flag, expect_moves in (("--no-post-merge-moves", False), ("--post-merge-moves", True)):
        subprocess.run(cmd + [flag], check=True, capture_output=True,
                       env={"PYTHONPATH": env_path, "PATH": "/usr/bin:/bin"})
        report = json.loads(stats.read_text())["report"]
        assert (report["node_moves"] > 0) == expect_moves


def test_vertex_splits_add_declared_inner_nodes_and_the_checker_verifies_them(finer_box) -> None:
    points, tets, _ = finer_box
    off, r0 = hexmerge.recombine(points, tets, same_nodes=False)
    assert r0["vertex_splits"] == 0 and len(off.points) == len(points)  # off by default
    mesh, report = hexmerge.recombine(points, tets, same_nodes=False, post_merge_splits=True)
    assert report["post_merge"] == "kept"
    splits = report["vertex_splits"]
    assert splits > 0
    # One node added per split, past the input's, declared, used by cells, inside the box.
    added = np.arange(len(points), len(mesh.points))
    assert len(added) == splits
    assert np.isin(added, mesh.changed_nodes).all()
    assert np.isin(added, mesh.cell_vertices).all()
    inside = mesh.points[added]
    assert ((inside > 0).all(axis=1) & (inside[:, :2] < 4).all(axis=1) & (inside[:, 2] < 2)).all()
    assert np.array_equal(mesh.point_map, np.arange(len(mesh.points)))
    # A node not declared is the input's, bit for bit.
    undeclared = np.setdiff1d(np.arange(len(points)), mesh.changed_nodes)
    assert np.array_equal(mesh.points[undeclared], points[undeclared])
    check = hexmerge.check(mesh, points, tets)
    assert check["valid"], check["problems"]
    assert check["declared_changed_nodes"] == len(mesh.changed_nodes)
    assert_sound(check)
    # Undeclared, the added nodes are not the input's: the check fails.
    mesh.changed_nodes = None
    assert not hexmerge.check(mesh, points, tets)["valid"]


def test_cli_takes_the_split_option(finer_box, tmp_path: Path) -> None:
    _, _, path = finer_box
    out, stats = tmp_path / "out.vtu", tmp_path / "stats.json"
    cmd = [sys.executable, "-m", "hexmerge", "recombine", str(path), "-o", str(out), "--quiet",
           "--stats", str(stats), "--no-same-nodes"]
    env = {"PYTHONPATH": str(ROOT / "src" / "python"), "PATH": "/usr/bin:/bin"}
    for flag, expect_splits in (("--no-post-merge-splits", False), ("--post-merge-splits", True)):
        subprocess.run(cmd + [flag], check=True, capture_output=True, env=env)
        report = json.loads(stats.read_text())["report"]
        assert report["post_merge"] == "kept"
        assert (report["vertex_splits"] > 0) == expect_splits
