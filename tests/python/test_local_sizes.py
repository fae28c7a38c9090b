"""Local sizes in hexmerge.mesh_shape() (`local_sizes`, `hexmerge mesh --local-size`): faces and
edges meshed finer than h, the rest graded out to h (issue 16, item 7).

The shape is the solid of FreeCAD's FEM example material_nl_platewithhole (400 x 200 x 10 mm, a
hole of radius 50 through it): Face5 is the hole's wall, Edge14 and Edge15 its bottom and top
circles (FreeCAD's and OpenCASCADE's numbering, from 1). Every mesh is validated, its boundary
nodes checked on the CAD, its recombination checked against it by the independent checker.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import hexmerge
from conftest import MESHES_SHAPES
from hexmerge import cli
from hexmerge._shape import mesh_notes
from real_parts import tet_scaled_jacobians
from test_mesh_shape import PLATE, SURFACES, assert_checked, boundary_nodes, gmsh_brep

pytestmark = MESHES_SHAPES

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
    # The boundary on the CAD, the tets as good as the plate's unswept tets at h (floors: below
    # what was measured when set; the node moves that hold the count under 0.2, cff8ad9: 62 ->
    # 47 tets under 0.2, the smallest 0.118 -> 0.090; with the shorter search, 3d67323: 33,
    # 0.103).
    assert SURFACES["plate"](boundary_nodes(fine)).max() <= 1e-3 * H
    assert meshing["max_boundary_distance"] <= 1e-3 * H
    quality = tet_scaled_jacobians(fine.points, fine.cell_vertices.reshape(-1, 4).astype(np.int64))
    print(f"plate h {H} hole {H / 4}: {fine.nb_cells} tets (plain {plain.nb_cells}), min tet SJ "
          f"{quality.min():.3f}, graded points {meshing['nb_graded_points']}, strategy "
          f"{meshing['strategy']}")
    assert quality.min() >= 0.08
    assert (quality < 0.2).sum() <= 55


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


# Two boxes touching as separate closed shells (a compound, as FreeCAD compounds and STEP
# assemblies arrive): gluing splits box 1's x = 30 face (Face2) into the patch it shares with box
# 2's x = 30 face (Face7) and the rest, which renumbers the faces; the numbers given are those of
# the compound as given (FreeCAD's FaceN of it).
TOUCHING_BOXES_GEO = """SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 30, 20, 10};
Box(2) = {30, 5, 2, 15, 8, 6};
"""


def test_local_sizes_and_face_layers_on_touching_solids(tmp_path) -> None:
    from test_mesh_shape import gmsh_brep
    shape = gmsh_brep(tmp_path, "touching_boxes", TOUCHING_BOXES_GEO)
    h, fine = 2.0, 0.5
    tets, report = hexmerge.mesh_shape(shape, h, recombine=False, local_sizes=f"Face2:{fine}",
                                       face_layers="Face1:2:0.25:2")
    meshing = report["meshing"]
    assert meshing["nb_solids"] == 2 and meshing["nb_shared_faces"] == 1
    hexmerge.validate(tets.points, tets.cell_vertices.reshape(-1, 4), tets.regions)
    p = tets.points
    # Face2, both its pieces: the boundary triangles on x = 30 (outside the patch) and the tet
    # sides inside the patch, at most the local size.
    (applied,) = meshing["local_sizes"]
    assert applied["faces"] == [2] and applied["max_side"] <= fine * (1 + 1e-9)
    tris = boundary_triangles(tets)
    on_plane = (np.abs(p[:, 0] - 30) < 1e-9)
    outside = on_plane[tris].all(axis=1)
    assert outside.sum() > 0 and longest_sides(p, tris[outside]).max() <= fine * (1 + 1e-9)
    cells = tets.cell_vertices.reshape(-1, 4)
    edges = np.unique(np.sort(np.concatenate([cells[:, [a, b]] for a in range(4) for b in range(a + 1, 4)]),
                             axis=1), axis=0)
    patch = on_plane & (p[:, 1] > 5 - 1e-9) & (p[:, 1] < 13 + 1e-9) & (p[:, 2] > 2 - 1e-9) & (p[:, 2] < 8 + 1e-9)
    in_patch = patch[edges].all(axis=1)
    assert in_patch.sum() > 100
    assert np.linalg.norm(p[edges[in_patch, 0]] - p[edges[in_patch, 1]], axis=1).max() <= fine * (1 + 1e-9)
    # Face1 (box 1's x = 0 face): its layers at 0.25 and 0.75 over its nodes.
    (layers,) = meshing["face_layers"]
    assert layers["faces"] == [1] and min(layers["nb_per_layer"]) > 0.5 * layers["nb_nodes"] > 0
    face_yz = {(round(y, 9), round(z, 9)) for y, z in p[np.abs(p[:, 0]) < 1e-9][:, 1:]}
    over = np.array([(round(y, 9), round(z, 9)) in face_yz for y, z in p[:, 1:]])
    for k, depth in enumerate([0.25, 0.75]):
        at = over & (np.abs(p[:, 0] - depth) <= 0.1 * depth * (1 + 1e-9))
        assert at.sum() == layers["nb_per_layer"][k]
    # Each region keeps its solid's volume.
    q = p[cells]
    volumes = np.einsum("ij,ij->i", np.cross(q[:, 1] - q[:, 0], q[:, 2] - q[:, 0]), q[:, 3] - q[:, 0]) / 6
    for region, volume in enumerate([30 * 20 * 10, 15 * 8 * 6]):
        assert volumes[tets.regions == region].sum() == pytest.approx(volume, rel=1e-9)


def test_a_face_number_of_the_compound_as_given(tmp_path) -> None:
    from test_mesh_shape import gmsh_brep
    shape = gmsh_brep(tmp_path, "touching_boxes", TOUCHING_BOXES_GEO)
    with pytest.raises(hexmerge.InputError, match=r"Face13 does not exist \(the shape has 12 faces"):
        hexmerge.mesh_shape(shape, 2.0, recombine=False, local_sizes="Face13:0.5")


def test_an_extrusion_with_a_local_size_says_why_it_is_not_swept(plate_meshes, tmp_path, capsys) -> None:
    plain, fine = plate_meshes["plain"][1]["meshing"], plate_meshes["fine hole"][1]["meshing"]
    assert plain["sweep_axis"] >= 0 and plain["sweep_skipped"] == ""
    assert fine["sweep_axis"] == -1
    assert fine["sweep_skipped"].startswith("not swept, though an extrusion: the local size 2.5 on Face5 (a face) "
                                             "needs a graded surface")
    # A shape that is no extrusion has nothing to say.
    from test_mesh_shape import GEOMETRY, gmsh_brep
    bracket = gmsh_brep(tmp_path, "bracket", GEOMETRY / "bracket.geo")
    _, report = hexmerge.mesh_shape(bracket, 3.0, recombine=False, local_sizes="Face2:1.5")
    assert report["meshing"]["sweep_axis"] == -1 and report["meshing"]["sweep_skipped"] == ""
    # The CLI says it as a note (on stderr).
    code = cli.main(["mesh", str(PLATE), "-h", "10", "--local-size", "Face5:5", "-o", str(tmp_path / "p.vtu")])
    assert code == 0
    assert "note: not swept, though an extrusion" in capsys.readouterr().err


def test_local_sizes_on_the_caps_edges_are_swept() -> None:
    """The hole's top circle (Edge15) at 2.5: the sweep splits the hole wall's sides on the first
    plane to the size and repeats them on every plane, so both circles get nodes at most 2.5
    apart, and the plate stays swept: hexahedra and prisms only."""
    tets, report = hexmerge.mesh_shape(PLATE, H, recombine=False, local_sizes="Edge15:2.5")
    meshing = report["meshing"]
    assert meshing["sweep_axis"] >= 0 and meshing["sweep_skipped"] == ""
    (applied,) = meshing["local_sizes"]
    assert applied["nb_segments"] >= 2 * np.pi * 50 / 2.5 and applied["max_side"] <= 2.5 * (1 + 1e-9)
    p = tets.points
    for z in (0.0, 10.0):
        ring = p[on_hole(p) & (np.abs(p[:, 2] - z) < 1e-9)]
        angles = np.sort(np.arctan2(ring[:, 1], ring[:, 0]))
        gaps = np.diff(np.concatenate([angles, angles[:1] + 2 * np.pi]))
        assert 2 * 50 * np.sin(gaps.max() / 2) <= 2.5 * (1 + 1e-9), z  # the longest chord
    mesh, rep = hexmerge.mesh_shape(PLATE, H, local_sizes="Edge15:2.5")
    assert_checked(mesh, tets, rep, H)
    assert rep["output_counts"]["tet"] == 0 and rep["output_counts"]["pyramid"] == 0
    assert rep["volume_fraction"]["hex"] >= 0.95


# feature_size: the CAD's short edges get local sizes of their own. A box (40 x 30 x 20) with a
# 0.4 mm cube cut from a corner (nine edges 0.4 long) and a groove of radius 0.45 across its top.
NOTCHED_BOX_GEO = """SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 40, 30, 20};
Box(2) = {39.6, 29.6, 19.6, 1, 1, 1};
Cylinder(3) = {10, -1, 20, 0, 32, 0, 0.45};
BooleanDifference{ Volume{1}; Delete; }{ Volume{2,3}; Delete; }
"""


def meshed_with_feature_size(shape: str, h: float, feature_size: float):
    """mesh_shape()'s tets at `feature_size`: the tets, the mesher's report, the points, the tets'
    corners and the boundary triangles."""
    tets, report = hexmerge.mesh_shape(shape, h, recombine=False, feature_size=feature_size)
    cells = tets.cell_vertices.reshape(-1, 4).astype(np.int64)
    return tets, report["meshing"], tets.points, cells, boundary_triangles(tets)


def test_short_cad_edges_get_sizes_of_their_own(tmp_path) -> None:
    """At h 4 the notch's nine 0.4 mm edges (0.1 h) get a local size of 0.4 (feature_size 0.1:
    edges under 0.2 h): the surface and the inside grade out from them. Without (feature_size 0)
    BRepMesh joins their ends to nodes 4 mm away: boundary triangles 5.7 mm long beside 0.4 mm
    sides, tets down to 0.051 there (measured when feature_size was added); with them 0.73 mm
    and 0.210."""
    shape = gmsh_brep(tmp_path, "notched_box", NOTCHED_BOX_GEO)
    h = 4.0

    def at_notch(feature_size: float):
        _, meshing, points, cells, triangles = meshed_with_feature_size(shape, h, feature_size)
        near = (points[:, 0] > 39.5) & (points[:, 1] > 29.5) & (points[:, 2] > 19.5)
        longest = longest_sides(points, triangles[near[triangles].any(axis=1)]).max()
        quality = tet_scaled_jacobians(points, cells)[near[cells].any(axis=1)].min()
        return meshing, longest, quality

    meshing, longest, quality = at_notch(0.1)
    assert meshing["nb_feature_edges"] == 9
    assert meshing["nb_graded_points"] > 0
    assert longest < 2 * 0.4  # graded by half the distance from 0.4
    assert quality >= 0.2
    off, longest_off, quality_off = at_notch(0.0)
    assert off["nb_feature_edges"] == 0 and off["nb_graded_points"] == 0
    # (The box's faces are lattice faces, whose triangles refine_facet() keeps under 0.6 h in
    # circumradius: 3.9 mm sides beside the 0.4 mm edges, 5.7 mm before.)
    assert longest_off > 0.75 * h and quality_off < quality
    # The recombination of the graded tets passes the checker.
    mesh, report = hexmerge.mesh_shape(shape, h)
    tets, _ = hexmerge.mesh_shape(shape, h, recombine=False)
    assert_checked(mesh, tets, report, h)


def test_no_lattice_point_beside_a_node_of_a_split_lattice_edge() -> None:
    """A local size on the plate's Face1 and two edges splits the sides of the lattice faces'
    edges near them off the lattice; a lattice point kept on such an edge 0.19 mm from the node
    that split it gave boundary sides of 0.19 mm (local sizes 2 and 3) and tets of 0.040. Lattice
    points on a lattice face are dropped near a surface node that is not at them: 0.625 mm."""
    tets, _ = hexmerge.mesh_shape(PLATE, 6.0, recombine=False, feature_size=0.0,
                                  local_sizes="Face1:3; Edge2,Edge3:2")
    points = tets.points
    triangles = boundary_triangles(tets)
    sides = np.concatenate([np.linalg.norm(points[triangles[:, a]] - points[triangles[:, b]], axis=1)
                            for a, b in ((0, 1), (1, 2), (2, 0))])
    assert sides.min() > 0.25 * 2
    cells = tets.cell_vertices.reshape(-1, 4)
    assert tet_scaled_jacobians(points, cells).min() > 0.1


# Narrow faces: a box (40 x 30 x 20) with a step 0.2 high on half its top (20 x 15): the step's
# two sides are faces 0.2 wide (0.05 h at h 4) along edges 15 and 20 long.
STEPPED_BOX_GEO = """SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 40, 30, 20};
Box(2) = {0, 0, 20, 20, 15, 0.2};
BooleanUnion{ Volume{1}; Delete; }{ Volume{2}; Delete; }
"""


def test_narrow_faces_get_sizes_of_their_own(tmp_path) -> None:
    """At h 4 the step's two sides (0.05 h wide, narrower than 0.1 h) get a local size of three
    times their width (0.6), its three 0.2 mm edges their feature sizes. Without (feature_size 0)
    the sides' triangles run 4 mm along them: tets down to 0.062, 59 under 0.2; with them 0.178,
    2 (measured when the narrow faces' sizes were added). The shape's sweep (found, then failing:
    the step changes the cross-section) gave it no feature sizes before; now it gets them then."""
    shape = gmsh_brep(tmp_path, "stepped_box", STEPPED_BOX_GEO)
    h = 4.0

    def meshed(feature_size: float):
        tets, meshing, points, cells, triangles = meshed_with_feature_size(shape, h, feature_size)
        sj = tet_scaled_jacobians(points, cells)
        x, y, z = (points[triangles][:, :, k] for k in range(3))
        on_side_x = (np.abs(x - 20) < 1e-6) & (y <= 15 + 1e-6)  # the step's side across x
        on_side_y = (np.abs(y - 15) < 1e-6) & (x <= 20 + 1e-6)  # and across y
        on_step = ((on_side_x.all(axis=1) | on_side_y.all(axis=1)) & (z >= 20 - 1e-6).all(axis=1))
        assert on_step.sum() > 0
        return tets, meshing, sj, longest_sides(points, triangles[on_step]).max()

    tets, meshing, sj, longest = meshed(0.1)
    assert meshing["sweep_axis"] == -1
    assert meshing["nb_feature_faces"] == 2 and meshing["nb_feature_edges"] == 3
    assert longest <= 3 * 0.2 * (1 + 1e-6)
    off_tets, off, sj_off, longest_off = meshed(0.0)
    assert off["nb_feature_faces"] == 0 and off["nb_feature_edges"] == 0
    assert longest_off > 0.75 * h
    assert sj.min() > 2 * sj_off.min()
    assert (sj < 0.2).sum() * 10 <= (sj_off < 0.2).sum()
    mesh, report = hexmerge.mesh_shape(shape, h)
    assert_checked(mesh, tets, report, h)


# A plate 40 x 30 x 1.2 with a block standing on its end (x < 6) and a countersunk hole (no
# sweep): at h 8 the plate is 0.15 h thick.
THIN_PLATE_GEO = """SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 40, 30, 1.2};
Cone(2) = {20, 15, -0.1, 0, 0, 1.5, 3, 6};
Box(3) = {0, 0, 1.2, 6, 30, 12};
v() = BooleanUnion{ Volume{1}; Delete; }{ Volume{3}; Delete; };
BooleanDifference{ Volume{v(0)}; Delete; }{ Volume{2}; Delete; }
"""


def test_thin_walls_get_sizes_of_their_own_and_count_in_the_estimate(tmp_path) -> None:
    """Across a wall thinner than 0.2 h the surface gets three times the wall's thickness: at h 8
    the plate's top and bottom (1.2 apart, lattice faces) get points inside until their
    triangles' circumradius is at most 0.6 x 3.6 away from the block and the hole; without
    (feature_size 0) their triangles run to 8 and 40 tets are under scaled Jacobian 0.2 (with:
    none; measured when thin walls were sized). The estimate of step 2 counts the thin walls'
    sizes once they are found (3,760 tets, 603 without), and a memory limit between the two
    refuses the size then, saying why."""
    shape = gmsh_brep(tmp_path, "thin_plate", THIN_PLATE_GEO)
    h = 8.0

    def on_plate(feature_size: float):
        _, meshing, points, cells, triangles = meshed_with_feature_size(shape, h, feature_size)
        x, y, z = (points[triangles][:, :, k] for k in range(3))
        flat = ((np.abs(z) < 1e-9).all(axis=1) | (np.abs(z - 1.2) < 1e-9).all(axis=1))
        far = ((x > 10) & (x < 38) & (y > 2) & (y < 28)  # not on the plate's sides' edges
               & (np.hypot(x - 20, y - 15) > 8)).all(axis=1)
        sj = tet_scaled_jacobians(points, cells)
        return meshing, longest_sides(points, triangles[flat & far]).max(), sj

    meshing, longest, sj = on_plate(0.1)
    assert meshing["nb_thin_wall_patches"] > 0
    assert longest <= 2 * 0.6 * 3 * 1.2 * (1 + 1e-6)  # twice the circumradius
    assert sj.min() >= 0.2
    off, longest_off, _ = on_plate(0.0)
    assert off["nb_thin_wall_patches"] == 0
    assert longest_off > 0.75 * h
    assert meshing["estimated_tets"] > 3 * off["estimated_tets"]
    limit = 2 * off["estimated_tets"] * 3000 / 1e9  # GB: the shape's own estimate fits
    with pytest.raises(hexmerge.InputError, match=r"million tets \(with the sizes of its thin "
                       r"walls\), which need about .* GB .*: give a size of at least"):
        hexmerge.mesh_shape(shape, h, recombine=False, memory_limit=limit)


# A box 120 x 80 x 40, hollowed from its top: walls 1.2 thick, open at the top.
HOLLOW_BOX_GEO = """SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 120, 80, 40};
Box(2) = {1.2, 1.2, 1.2, 117.6, 77.6, 40};
BooleanDifference(3) = { Volume{1}; Delete; }{ Volume{2}; Delete; };
"""


@pytest.mark.parametrize("h", [25.0, 40.0, 55.0])
def test_a_thin_shell_meshes_with_usable_elements_at_many_times_its_walls(tmp_path, h: float) -> None:
    """A shell whose walls are 0.02 h to h / 12 thick (1.2 at h 25 to 55): the walls get sizes of
    three times their thickness, and every element of the recombined mesh has a scaled Jacobian
    of at least 0.2; thinner than the chord deflection, none, and a note says which size gives
    them one. Before walls that thin were sized (h / 12 the least), at h 25 and 40 the
    tets across the walls were flat: 844 and 678 elements under 0.2, the worst 0.060 and 0.049
    (measured when they were sized). The box's volume is kept (its faces are planes)."""
    shape = gmsh_brep(tmp_path, "hollow_box", HOLLOW_BOX_GEO)
    tets, report = hexmerge.mesh_shape(shape, h, recombine=False)
    meshing = report["meshing"]
    assert meshing["nb_thin_wall_patches"] > 0
    mesh, recombined = hexmerge.recombine(tets.points, tets.cell_vertices.reshape(-1, 4), tets.regions)
    result = assert_checked(mesh, tets, recombined, h)
    assert result["min_scaled_jacobian"] >= 0.2
    volume = 120 * 80 * 40 - 117.6 * 77.6 * 38.8
    assert meshing["mesh_volume"] == pytest.approx(volume, rel=1e-9)
    # Every boundary node on one of the box's planes.
    p = boundary_nodes(tets)
    on = [np.abs(p[:, 0] - x) for x in (0, 1.2, 118.8, 120)] + [
        np.abs(p[:, 1] - y) for y in (0, 1.2, 78.8, 80)] + [np.abs(p[:, 2] - z) for z in (0, 1.2, 40)]
    assert np.minimum.reduce(on).max() < 1e-9
    assert meshing["nb_unsized_wall_patches"] == 0
    assert not any("thinner than the surface's chord deflection" in n for n in mesh_notes(meshing))
    if h == 55.0:
        # Thinner than the chord deflection, 0.02 h (h 62: 0.019 h), the walls get no size: the
        # report and a note say so, and which size gives them one (59.4), which does.
        _, thinner = hexmerge.mesh_shape(shape, 62.0, recombine=False)
        unsized = thinner["meshing"]
        assert unsized["nb_thin_wall_patches"] == 0 and unsized["nb_unsized_wall_patches"] > 0
        assert unsized["thinnest_unsized_wall"] == pytest.approx(1.2, abs=1e-9)
        assert unsized["thickest_unsized_wall"] == pytest.approx(1.2, abs=1e-9)
        assert ("walls 1.2 thick are thinner than the surface's chord deflection (0.02 h): they get "
                "no size of their own and the tets across them are flat; a size of at most 59.4 "
                "gives them one") in mesh_notes(unsized)
        _, suggested = hexmerge.mesh_shape(shape, 59.4, recombine=False)
        assert suggested["meshing"]["nb_thin_wall_patches"] > 0
        assert suggested["meshing"]["nb_unsized_wall_patches"] == 0


WEDGE_GEO = """SetFactory("OpenCASCADE");
Point(1) = {0, 0, 0}; Point(2) = {40, 0, 0}; Point(3) = {40, 8.14, 0};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 1};
Curve Loop(1) = {1, 2, 3}; Plane Surface(1) = {1};
w() = Extrude {0, 0, 30} { Surface{1}; };
Box(2) = {30, -10, 10, 10, 10, 10};
BooleanUnion{ Volume{w(1)}; Delete; }{ Volume{2}; Delete; }
"""


def test_a_wedge_is_no_thin_wall(tmp_path) -> None:
    """A prism whose faces meet at 11.5 degrees along an edge (a block on it so that it is not
    swept) is 0.05 h to 0.2 h thick across a band of that edge at h 4, but no wall: its thickness
    grows with the distance from the edge (by a fifth of it), and sizes of three times the
    thickness make the same tets there, smaller and more of them (with faces up to 45 degrees
    apart counted as walls: 20 patches, 1,343 -> 2,424 tets, elements under 0.2 27 -> 64). Its
    faces get no sizes of their own, and the mesh is the one made without feature sizes."""
    shape = gmsh_brep(tmp_path, "wedge", WEDGE_GEO)
    h = 4.0
    tets, meshing, _, cells, _ = meshed_with_feature_size(shape, h, 0.1)
    assert meshing["nb_thin_wall_patches"] == 0
    _, _, _, cells_off, _ = meshed_with_feature_size(shape, h, 0.0)
    assert len(cells) == len(cells_off)
