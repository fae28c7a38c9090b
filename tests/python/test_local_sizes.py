"""Local sizes in hexmerge.mesh_shape() (`local_sizes`, `hexmerge mesh --local-size`): faces and
edges meshed finer than h, the rest graded out to h (issue 16, item 7).

The shape is the solid of FreeCAD's FEM example material_nl_platewithhole (400 x 200 x 10 mm, a
hole of radius 50 through it): Face5 is the hole's wall, Edge14 and Edge15 its bottom and top
circles (FreeCAD's and OpenCASCADE's numbering, from 1). Every mesh is validated, its boundary
nodes checked on the CAD, its recombination checked against it by the independent checker.
"""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

import hexmerge
from hexmerge import _core, cli
from test_mesh_shape import PLATE, SURFACES, assert_checked, boundary_nodes, tet_scaled_jacobians

pytestmark = [
    pytest.mark.skipif(not hexmerge.WITH_OPENCASCADE or not hasattr(_core, "mesh_shape"),
                       reason="hexmerge built without OpenCASCADE"),
    pytest.mark.skipif(shutil.which("tetgen") is None, reason="tetgen is not installed"),
]

H = 10.0
HOLE = 5  # the hole's wall
BOTTOM_CIRCLE = 14


def boundary_triangles(tets: hexmerge.MixedMesh) -> np.ndarray:
    """The boundary triangles (faces of one tet), as node triples."""
    t = tets.cell_vertices.reshape(-1, 4).astype(np.int64)
    faces = np.concatenate([t[:, [1, 2, 3]], t[:, [0, 3, 2]], t[:, [0, 1, 3]], t[:, [0, 2, 1]]])
    unique, count = np.unique(np.sort(faces, axis=1), axis=0, return_counts=True)
    return unique[count == 1]


def longest_sides(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    p = points[triangles]
    return np.max([np.linalg.norm(p[:, a] - p[:, b], axis=1) for a, b in ((0, 1), (1, 2), (2, 0))], axis=0)


def on_hole(points: np.ndarray) -> np.ndarray:
    """Per point, whether it lies on the hole's wall (radius 50)."""
    return np.abs(np.hypot(points[:, 0], points[:, 1]) - 50) < 1e-6


def hole_and_outer_sides(tets: hexmerge.MixedMesh) -> tuple[np.ndarray, np.ndarray]:
    """Longest sides of the boundary triangles on the hole's wall, and on the outer walls."""
    tris = boundary_triangles(tets)
    p = tets.points
    normal = np.cross(p[tris[:, 1]] - p[tris[:, 0]], p[tris[:, 2]] - p[tris[:, 0]])
    # The wall: nodes on the hole, normal across the plate (the caps have chords of the hole too).
    hole = on_hole(p)[tris].all(axis=1) & (np.abs(normal[:, 2]) < 0.5 * np.linalg.norm(normal, axis=1))
    outer = (np.abs(np.abs(p[:, 0]) - 200) < 1e-6)[tris].all(axis=1) | (
        np.abs(np.abs(p[:, 1]) - 100) < 1e-6)[tris].all(axis=1)
    sides = longest_sides(p, tris)
    return sides[hole], sides[outer]


@pytest.fixture(scope="module")
def plate_meshes() -> dict[str, tuple[hexmerge.MixedMesh, dict]]:
    """The plate's tets at h 10, without and with the hole at h / 4."""
    return {
        "plain": hexmerge.mesh_shape(PLATE, H, recombine=False),
        "fine hole": hexmerge.mesh_shape(PLATE, H, recombine=False, local_sizes=f"{HOLE}:{H / 4}"),
    }


def test_a_local_size_makes_its_face_finer(plate_meshes) -> None:
    plain, _ = plate_meshes["plain"]
    fine, report = plate_meshes["fine hole"]
    meshing = report["meshing"]
    hexmerge.validate(fine.points, fine.cell_vertices.reshape(-1, 4), fine.regions)
    plain_hole, plain_outer = hole_and_outer_sides(plain)
    fine_hole, fine_outer = hole_and_outer_sides(fine)
    # The hole's triangles: at most the local size (they were up to h), and many more of them.
    assert plain_hole.max() > H / 4
    assert fine_hole.max() <= H / 4 * (1 + 1e-9)
    assert len(fine_hole) > 8 * len(plain_hole)
    # The outer walls, far from the hole, keep the size h (lattice faces: cut along the lattice
    # cells' diagonals, as without the local size).
    assert np.isclose(fine_outer.max(), plain_outer.max()) and fine_outer.max() <= np.sqrt(2) * H * (1 + 1e-9)
    assert np.median(fine_outer) >= H / 2
    # The report says what was applied.
    (applied,) = meshing["local_sizes"]
    assert applied["faces"] == [HOLE] and applied["edges"] == [] and applied["size"] == H / 4
    assert applied["nb_triangles"] > 0 and applied["max_side"] <= H / 4 * (1 + 1e-9)
    assert meshing["nb_graded_points"] > 0
    assert meshing["sweep_axis"] == -1  # local sizes: not swept
    assert meshing["parameters"]["local_sizes"] == f"{HOLE}:{H / 4}"
    # The boundary on the CAD, the tets as good as the plate's unswept tets at h (floor: below
    # what was measured when set).
    assert SURFACES["plate"](boundary_nodes(fine)).max() <= 1e-3 * H
    assert meshing["max_boundary_distance"] <= 1e-3 * H
    quality = tet_scaled_jacobians(fine.points, fine.cell_vertices.reshape(-1, 4).astype(np.int64))
    print(f"plate h {H} hole {H / 4}: {fine.nb_cells} tets (plain {plain.nb_cells}), min tet SJ "
          f"{quality.min():.3f}, graded points {meshing['nb_graded_points']}, strategy "
          f"{meshing['strategy']}")
    assert quality.min() >= 0.1


def test_the_graded_mesh_recombines_and_checks(plate_meshes) -> None:
    tets, _ = plate_meshes["fine hole"]
    mesh, report = hexmerge.mesh_shape(PLATE, H, local_sizes=[(HOLE, H / 4)])
    assert report["input_tets"] == tets.nb_cells  # the same tets as the list form's text
    result = assert_checked(mesh, tets, report, H)
    print(f"recombined: hex volume {report['volume_fraction']['hex']:.3f}, min SJ "
          f"{result['min_scaled_jacobian']:.3f}")
    assert report["volume_fraction"]["hex"] >= 0.5
    assert result["min_scaled_jacobian"] > 0


def test_a_local_size_on_an_edge() -> None:
    tets, report = hexmerge.mesh_shape(PLATE, H, recombine=False,
                                       local_sizes=[{"edges": [BOTTOM_CIRCLE], "size": 2.0}])
    hexmerge.validate(tets.points, tets.cell_vertices.reshape(-1, 4), tets.regions)
    (applied,) = report["meshing"]["local_sizes"]
    assert applied["edges"] == [BOTTOM_CIRCLE] and applied["nb_segments"] >= 2 * np.pi * 50 / 2
    assert applied["max_side"] <= 2.0 * (1 + 1e-9)
    # The boundary triangles with a side on the bottom circle have it at most 2 long; on the top
    # circle, 5 mm away (graded: 2 + 0.5 * 10), they are up to 7.
    tris = boundary_triangles(tets)
    p = tets.points
    circle = on_hole(p) & (np.abs(p[:, 2]) < 1e-9)
    top = on_hole(p) & (np.abs(p[:, 2] - 10) < 1e-9)
    for ring, most in ((circle, 2.0), (top, 7.0)):
        sides = [np.linalg.norm(p[a] - p[b]) for t in tris for a, b in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0]))
                 if ring[a] and ring[b]]
        assert sides and max(sides) <= most * (1 + 1e-9)
    assert SURFACES["plate"](boundary_nodes(tets)).max() <= 1e-3 * H


@pytest.mark.parametrize(
    ("local_sizes", "message"),
    [
        ("9:2", r"Face9 does not exist \(the shape has 7 faces, Face1 to Face7\)"),
        ("Edge16:2", r"Edge16 does not exist \(the shape has 15 edges"),
        ("5:20", "local size 20 is larger than the size 10"),
        ("5:0", "entry '5:0' has size '0': it must be a number > 0"),
        ("5:-1", "it must be a number > 0"),
        ("5:0.001", r"smaller than the size / 1000"),
        ("5-2", "entry '5-2' is not ITEMS:SIZE"),
        ("Vertex3:2", "names 'Vertex3': items are N or FaceN"),
        ("0:2", "names '0'"),
        ([("x", 2)], "names 'x'"),
        ([{"faces": [5]}], "must have 'size'"),
        ([(5, "2")], "has size '2': it must be a number"),
        (3.5, "is not ITEMS:SIZE text"),
    ],
)
def test_bad_local_sizes(local_sizes, message) -> None:
    with pytest.raises(hexmerge.InputError, match=message):
        hexmerge.mesh_shape(PLATE, H, recombine=False, local_sizes=local_sizes)


def test_cli_local_size(tmp_path, capsys) -> None:
    out, stats = tmp_path / "plate.vtu", tmp_path / "stats.json"
    code = cli.main(["mesh", str(PLATE), "-h", "10", "--local-size", "Face5:5", "--local-size", "Edge14:2.5",
                     "-o", str(out), "--stats", str(stats), "-q"])
    assert code == 0 and out.exists()
    meshing = json.loads(stats.read_text())["report"]["meshing"]
    assert [(a["faces"], a["edges"], a["size"]) for a in meshing["local_sizes"]] == [([5], [], 5.0), ([], [14], 2.5)]
    assert all(a["max_side"] <= a["size"] * (1 + 1e-9) for a in meshing["local_sizes"])

    code = cli.main(["mesh", str(PLATE), "-h", "10", "--local-size", "Face8:2", "-o", str(tmp_path / "x.vtu")])
    assert code != 0
    err = capsys.readouterr().err
    assert "Face8 does not exist" in err and "Traceback" not in err
    assert not (tmp_path / "x.vtu").exists()
