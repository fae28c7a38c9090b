"""Boundary layers on chosen faces in hexmerge.mesh_shape() (`face_layers`,
`hexmerge mesh --face-layer`): the faces listed get layers of nodes at the depths asked for
(first thickness, growth rate), the rest keeps the global layers (issue 16, item 7).

Shapes: bench/geometry/box.geo (100 x 40 x 30 mm; Face1 is x = 0) and FreeCAD's plate with a
hole (Face5 the hole's wall, radius 50). Distances are measured from the face itself; every mesh
is validated and its recombination checked by the independent checker.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import hexmerge
from conftest import MESHES_SHAPES
from hexmerge import cli
from test_mesh_shape import GEOMETRY, PLATE, assert_checked, gmsh_brep

pytestmark = MESHES_SHAPES

H = 10.0
LAYERS, FIRST, GROWTH = 3, 1.0, 1.5
DEPTHS = [FIRST * sum(GROWTH ** j for j in range(k)) for k in range(1, LAYERS + 1)]  # 1, 2.5, 4.75
JITTER = 0.1  # the mesher varies each node's depths by up to 10 %


def tet_volume(tets: hexmerge.MixedMesh) -> float:
    p, c = tets.points, tets.cell_vertices.reshape(-1, 4)
    a, b, d, e = (p[c[:, i]] for i in range(4))
    return float(np.abs(np.einsum("ij,ij->i", np.cross(b - a, d - a), e - a)).sum() / 6)


@pytest.fixture(scope="module")
def box(tmp_path_factory: pytest.TempPathFactory):
    return gmsh_brep(tmp_path_factory.mktemp("face_layers"), "box", GEOMETRY / "box.geo")


@pytest.fixture(scope="module")
def layered_box(box):
    tets, report = hexmerge.mesh_shape(box, H, recombine=False,
                                       face_layers=f"Face1:{LAYERS}:{FIRST}:{GROWTH}")
    return tets, report["meshing"]


def test_the_face_gets_its_layers_at_the_depths_asked(layered_box) -> None:
    tets, meshing = layered_box
    hexmerge.validate(tets.points, tets.cell_vertices.reshape(-1, 4), tets.regions)
    (applied,) = meshing["face_layers"]
    assert (applied["faces"], applied["layers"], applied["thickness"], applied["growth"]) == \
        ([1], LAYERS, FIRST, GROWTH)
    p = tets.points
    # The face's nodes off its edges, and the nodes inside the box over them.
    on_face = p[np.abs(p[:, 0]) < 1e-9]
    off_edges = on_face[(on_face[:, 1] > 1e-6) & (on_face[:, 1] < 40 - 1e-6) &
                        (on_face[:, 2] > 1e-6) & (on_face[:, 2] < 30 - 1e-6)]
    assert applied["nb_nodes"] == len(off_edges) > 10
    face_yz = {(round(y, 9), round(z, 9)) for y, z in off_edges[:, 1:]}
    inside = p[(p[:, 0] > 1e-9) & (p[:, 0] < DEPTHS[-1] * (1 + JITTER) * 1.01)]
    over_face = np.array([(round(y, 9), round(z, 9)) in face_yz for y, z in inside[:, 1:]], dtype=bool)
    for k, depth in enumerate(DEPTHS):
        # Layer k: a node straight over a node of the face (offset along its normal), at the depth
        # asked for within the variation; as many as the report counts.
        at = over_face & (np.abs(inside[:, 0] - depth) <= JITTER * depth * (1 + 1e-9))
        assert int(at.sum()) == applied["nb_per_layer"][k], (k, depth)
        # Every node of the face with room (its layer point at least half its depth from the
        # box's other faces, the mesher's clearance) has its point in this layer.
        layer_yz = {(round(y, 9), round(z, 9)) for y, z in inside[at, 1:]}
        room = np.minimum.reduce([off_edges[:, 1], 40 - off_edges[:, 1], off_edges[:, 2],
                                  30 - off_edges[:, 2]]) >= 0.5 * depth * (1 + JITTER)
        assert room.sum() >= 0.5 * len(off_edges)
        missing = [(y, z) for y, z in off_edges[room, 1:] if (round(y, 9), round(z, 9)) not in layer_yz]
        assert not missing, (k, depth, missing)
    assert applied["nb_points"] == sum(applied["nb_per_layer"])
    # Nothing between the face and its first layer, nor between the layers, over the face.
    x = np.sort(inside[over_face, 0])
    assert x.min() >= DEPTHS[0] * (1 - JITTER) * (1 - 1e-9)
    bands = [(d * (1 - JITTER), d * (1 + JITTER)) for d in DEPTHS]
    assert all(any(lo - 1e-9 <= v <= hi + 1e-9 for lo, hi in bands) for v in x)
    # The faces not listed keep their lattice (the box's other faces are lattice faces).
    assert meshing["nb_lattice_faces"] == 5


def test_the_layered_box_recombines_and_checks(box, layered_box) -> None:
    tets, _ = layered_box
    mesh, report = hexmerge.mesh_shape(box, H, face_layers=[{"faces": [1], "layers": LAYERS,
                                                            "thickness": FIRST, "growth": GROWTH}])
    assert report["input_tets"] == tets.nb_cells  # the same tets as the text form's
    result = assert_checked(mesh, tets, report, H)  # the recombined mesh keeps the tets' volume
    assert tet_volume(tets) == pytest.approx(100 * 40 * 30, rel=1e-9)
    assert result["min_scaled_jacobian"] > 0
    print(f"box h {H}, 3 layers on Face1: {tets.nb_cells} tets, hex volume "
          f"{report['volume_fraction']['hex']:.3f}, prisms {report['output_counts'].get('wedge', 0)}")


def test_layers_on_the_hole_of_a_plate_are_swept() -> None:
    """A curved wall of an extrusion: the hole's wall (radius 50) at h 5 gets 2 layers, 0.5 then
    1 deep, radially into the plate, on the sweep's first plane and repeated on every plane: the
    plate stays swept, its volume kept, and recombines into hexahedra and prisms only."""
    tets, report = hexmerge.mesh_shape(PLATE, 5.0, recombine=False, face_layers="Face5:2:0.5:2")
    hexmerge.validate(tets.points, tets.cell_vertices.reshape(-1, 4), tets.regions)
    meshing = report["meshing"]
    assert meshing["sweep_axis"] >= 0 and meshing["sweep_skipped"] == ""
    (applied,) = meshing["face_layers"]
    assert applied["nb_per_layer"] == [applied["nb_nodes"]] * 2 and applied["nb_nodes"] > 0
    p = tets.points
    r = np.hypot(p[:, 0], p[:, 1])
    planes = np.unique(np.round(p[np.abs(r - 50) < 1e-6, 2], 9))  # the hole's nodes' heights
    assert len(planes) >= 3
    for depth in (0.5, 1.5):
        at = np.abs(r - 50 - depth) <= JITTER * depth + 1e-9
        # The same points on every plane (the first plane's repeated).
        assert int(at.sum()) == applied["nb_nodes"] * len(planes), depth
    # Nothing between the wall and the first layer.
    assert (r[(r > 50 + 1e-6)] >= 50 + 0.5 * (1 - JITTER) - 1e-9).all()
    assert tet_volume(tets) == pytest.approx(400 * 200 * 10 - np.pi * 50 ** 2 * 10, rel=2e-3)
    mesh, rep = hexmerge.mesh_shape(PLATE, 5.0, face_layers="Face5:2:0.5:2")
    assert_checked(mesh, tets, rep, 5.0)
    assert rep["output_counts"]["tet"] == 0 and rep["output_counts"]["pyramid"] == 0
    assert rep["volume_fraction"]["hex"] >= 0.95


def test_layers_on_a_cap_are_not_swept_and_say_why() -> None:
    tets, report = hexmerge.mesh_shape(PLATE, 10.0, recombine=False, face_layers="Face6:1:2")
    meshing = report["meshing"]
    assert meshing["sweep_axis"] == -1
    assert meshing["sweep_skipped"].startswith("not swept, though an extrusion: the face layers on Face6 lie on "
                                               "a cap")
    hexmerge.validate(tets.points, tets.cell_vertices.reshape(-1, 4), tets.regions)


@pytest.mark.parametrize(
    ("face_layers", "message"),
    [
        ("9:2:1", r"boundary layers on Face9: Face9 does not exist \(the shape has 6 faces, Face1 to Face6\)"),
        ("1:2:20", "the first layer's thickness 20 is larger than the size 10"),
        ("1:0:1", "has 0 layers: give a whole number from 1 to 10"),
        ("1:11:1", "has 11 layers"),
        ("1:2.5:1", "has 2.5 layers"),
        ("1:2:0", "has thickness '0': it must be a length > 0"),
        ("1:2:1:0.5", "has growth rate '0.5': give a number from 1 to 3"),
        ("1:2", "entry '1:2' is not FACES:LAYERS:THICKNESS"),
        ("Edge1:2:1", "names 'Edge1': boundary layers go on faces"),
        ([{"faces": [1], "layers": 2}], "is not FACES:LAYERS:THICKNESS"),
        ([{"faces": [1], "layers": 2, "thickness": "1"}], "has thickness '1': it must be a number"),
    ],
)
def test_bad_face_layers(box, face_layers, message) -> None:
    with pytest.raises(hexmerge.InputError, match=message):
        hexmerge.mesh_shape(box, H, recombine=False, face_layers=face_layers)


def test_no_room_for_the_first_layer_is_an_error() -> None:
    # The plate is 10 thick: a first layer 9 deep from its top face (Face6) would lie 1 from the
    # bottom face, nearer than half its depth, at every node.
    with pytest.raises(hexmerge.InputError,
                       match="boundary layers on Face6: no room for a first layer 9 deep at any of its"):
        hexmerge.mesh_shape(PLATE, 10.0, recombine=False, face_layers="6:1:9")


def test_cli_face_layer(box, tmp_path, capsys) -> None:
    out, stats = tmp_path / "box.vtu", tmp_path / "stats.json"
    code = cli.main(["mesh", str(box), "-h", "10", "--face-layer", "1:2:1", "--face-layer", "Face2:1:0.5",
                     "-o", str(out), "--stats", str(stats), "-q"])
    assert code == 0 and out.exists()
    meshing = json.loads(stats.read_text())["report"]["meshing"]
    assert [(a["faces"], a["layers"], a["thickness"]) for a in meshing["face_layers"]] == \
        [([1], 2, 1.0), ([2], 1, 0.5)]
    assert all(min(a["nb_per_layer"]) > 0 for a in meshing["face_layers"])

    code = cli.main(["mesh", str(box), "-h", "10", "--face-layer", "Face8:2:1", "-o", str(tmp_path / "x.vtu")])
    assert code != 0
    err = capsys.readouterr().err
    assert "Face8 does not exist" in err and "Traceback" not in err
    assert not (tmp_path / "x.vtu").exists()
