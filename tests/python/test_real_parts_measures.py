"""The real-parts benchmark's element measures (bench/real_parts.py), which bench/gmsh_reference.py
uses on Gmsh's own tet meshes: the scaled Jacobian of plain tet arrays and of a MixedMesh, and the
boundary triangles' smallest angles, on hand-made tets; and gmsh_reference's measures of Gmsh's
hex-dominant meshes (cells, volume fractions, quads against triangles) on hand-made .msh files;
the buffer layer's census of hand-made rows; fetch_gmsh's dependency closure on a hand-made
package index."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

import fetch_gmsh
import gmsh_reference
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


# Two unit cubes side by side along x: the first a hexahedron, the second as given.
CUBES = [(x, y, z) for z in (0, 1) for y in (0, 1) for x in (0, 1, 2)]  # node i + 1 at CUBES[i]
HEX_A = [1, 2, 5, 4, 7, 8, 11, 10]
HEX_B = [2, 3, 6, 5, 8, 9, 12, 11]
# The second cube as six tets around its diagonal from (1,0,0) to (2,1,1): its face at x = 1 (nodes
# 2, 5, 11, 8) is split by the diagonal 2-11, two of the tets' faces.
TETS_B = [[2, 3, 6, 12], [2, 6, 5, 12], [2, 5, 11, 12], [2, 11, 8, 12], [2, 8, 9, 12], [2, 9, 3, 12]]


def write_msh2(path, cells, nodes=CUBES) -> str:
    """An ASCII MSH 2.2 file of the nodes (CUBES') and cells [(Gmsh type, node ids)]."""
    lines = ["$MeshFormat", "2.2 0 8", "$EndMeshFormat", "$Nodes", str(len(nodes))]
    lines += [f"{i + 1} {x} {y} {z}" for i, (x, y, z) in enumerate(nodes)]
    lines += ["$EndNodes", "$Elements", str(len(cells))]
    lines += [f"{i + 1} {kind} 2 1 1 " + " ".join(map(str, ids)) for i, (kind, ids) in enumerate(cells)]
    lines += ["$EndElements"]
    path.write_text("\n".join(lines) + "\n")
    return str(path)


def test_gmsh_hex_dominant_quads_against_triangles(tmp_path) -> None:
    msh = write_msh2(tmp_path / "mixed.msh", [(5, HEX_A)] + [(4, t) for t in TETS_B] + [(140, [2, 5, 11, 8])])
    row = gmsh_reference.measure_mixed(msh)
    assert row["cells"] == {"tet": 6, "pyramid": 0, "prism": 0, "hex": 1}
    assert row["trihedra"] == 1
    assert row["volume"] == pytest.approx(2.0)
    assert row["volume_fraction"]["hex"] == pytest.approx(0.5)
    assert row["volume_fraction"]["tet"] == pytest.approx(0.5)
    assert row["nonconforming_quads"] == 1  # the hexahedron's face at x = 1, against two tets
    assert row["min_sj"] > 0 and row["nonpositive_sj"] == 0
    # Made conforming, the mesh cannot keep that hexahedron: none of its volume is conforming.
    assert row["conforming_hexes"] == 0 and row["conforming_hex_fraction"] == 0.0
    assert row["usable_hex_fraction"] == 0.0


def test_gmsh_hex_dominant_conforming_but_unusable_hexahedron(tmp_path) -> None:
    # The second cube's far top edge brought down and in, to (1.2, y, 0.1): its corners at x = 2
    # nearly flat (scaled Jacobian about 0.12), its face against the first still shared.
    nodes = [(1.2, y, 0.1) if (x, z) == (2, 1) else (x, y, z) for (x, y, z) in CUBES]
    row = gmsh_reference.measure_mixed(write_msh2(tmp_path / "squashed.msh", [(5, HEX_A), (5, HEX_B)], nodes))
    assert row["nonconforming_quads"] == 0
    assert row["conforming_hexes"] == 2 and row["conforming_hex_fraction"] == pytest.approx(1.0)
    assert row["below_sj_floor"] == 1
    assert row["usable_hexes"] == 1  # the first cube only
    assert row["usable_hex_fraction"] == pytest.approx(1.0 / row["volume"])


def test_gmsh_hex_dominant_conforming_hexahedra(tmp_path) -> None:
    row = gmsh_reference.measure_mixed(write_msh2(tmp_path / "hexes.msh", [(5, HEX_A), (5, HEX_B)]))
    assert row["cells"]["hex"] == 2 and row["volume_fraction"]["hex"] == pytest.approx(1.0)
    assert row["nonconforming_quads"] == 0  # the shared face is the other hexahedron's, the rest boundary
    assert row["min_sj"] == pytest.approx(1.0) and row["below_sj_floor"] == 0
    assert row["conforming_hexes"] == row["usable_hexes"] == 2
    assert row["conforming_hex_fraction"] == pytest.approx(1.0)


def test_gmsh_hex_dominant_without_volume_cells(tmp_path) -> None:
    row = gmsh_reference.measure_mixed(write_msh2(tmp_path / "surface.msh", [(2, [1, 2, 5])]))
    assert row["tets"] == 0 and row["cells"]["hex"] == 0 and row["volume_fraction"] == {}


def test_buffer_census_counts_every_base_once() -> None:
    # The mesher's counts: each base counted once, at the first test it fails, or kept.
    def bases(considered, apex, face, later, kept, **tests):
        return dict(considered=considered, apex_shared=apex, no_top_face=face, dropped_later=later, kept=kept,
                    **tests)

    rows = [
        {"part": "a", "target": "50k", "status": "ok", "buffer_bases": bases(10, 4, 2, 1, 1, folds=2)},
        {"part": "b", "target": "50k", "status": "ok", "buffer_bases": bases(6, 1, 0, 0, 3, two_faces=2)},
        {"part": "c", "target": "50k", "status": "ok", "buffer_bases": bases(0, 0, 0, 0, 0)},  # no core
        {"part": "a", "target": "250k", "status": "error"},
    ]
    lines = real_parts.buffer_census({"rows": rows}).splitlines()
    assert lines[2:] == ["| a | 50k | 10 | 4 | 2 | 2 | 1 | 1 |", "| b | 50k | 6 | 1 | 0 | 2 | 0 | 3 |",
                         "| all | 50k | 16 | 5 | 2 | 4 | 1 | 4 |"]


def test_fetch_gmsh_takes_every_package_gmsh_needs_and_no_more() -> None:
    index = {
        "gmsh": {"Depends": "libgmsh4 (= 4.13.1), libc6 (>= 2.38)"},
        "libgmsh4": {"Depends": "libocct-data-exchange-7.8 | libocct-foreign, libblas.so.3, debconf (>= 0.5)"},
        "libocct-data-exchange-7.8": {"Depends": "libc6"},
        "libocct-foreign": {"Depends": "libunused"},
        "libunused": {},
        "libblas3": {"Provides": "libblas.so.3", "Pre-Depends": "libc6:any"},
        "libc6": {"Depends": "libgcc-s1"},
        "libgcc-s1": {"Depends": "libc6"},  # a cycle
        "debconf": {"Depends": "perl-base"},
        "perl-base": {},
    }
    # The first of each alternative, a virtual package by its provider, no maintainer-script tools.
    assert fetch_gmsh.closure(index, "gmsh") == [
        "gmsh", "libblas3", "libc6", "libgcc-s1", "libgmsh4", "libocct-data-exchange-7.8"]
    with pytest.raises(SystemExit, match="libmissing"):
        fetch_gmsh.closure({"gmsh": {"Depends": "libmissing"}}, "gmsh")
