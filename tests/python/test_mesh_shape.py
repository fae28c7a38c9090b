"""hexmerge.mesh_shape() and `hexmerge mesh`: CAD shape -> lattice-seeded tets -> hex-dominant.

Shapes: bench/geometry's box, cylinder and bracket as BREP files made by Gmsh's OpenCASCADE
kernel, and the solid of FreeCAD's FEM example material_nl_platewithhole
(resources/examples). Every output goes through the independent checker against the tet mesh
it came from. The hex-volume floors sit a little below what was measured when they were set
(the measured values are in the comments); they guard the mesher and engine together.
"""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest

import hexmerge
from hexmerge import _core, cli
from conftest import ROOT
from meshes import EDGES
from real_parts import tet_scaled_jacobians

pytestmark = pytest.mark.skipif(
    not hexmerge.WITH_OPENCASCADE or not hasattr(_core, "mesh_shape"),
    reason="hexmerge built without OpenCASCADE",
)
needs_tetgen = pytest.mark.skipif(shutil.which("tetgen") is None, reason="tetgen is not installed")

GEOMETRY = ROOT / "bench" / "geometry"
PLATE = ROOT / "resources" / "examples" / "material_nl_platewithhole.brep"

# Gmsh .geo texts for the bad shapes: one face; a solid whose shell lacks a face.
FACE_GEO = 'SetFactory("OpenCASCADE");\nRectangle(1) = {0, 0, 0, 10, 10};\n'
OPEN_SOLID_GEO = """SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 10, 10, 10};
Delete { Volume{1}; }
Surface Loop(10) = {1, 2, 3, 4, 5};
Volume(2) = {10};
Delete { Surface{6}; }
"""

# Shapes with straight edges across the lattice on its faces: a hexagonal prism (swept), and a
# trapezoid prism with a notch cut from one side (a step: not swept).
HEXAGONAL_PRISM_GEO = """SetFactory("OpenCASCADE");
For i In {0:5}
  Point(i + 1) = {20 * Cos(i * Pi / 3), 20 * Sin(i * Pi / 3), 0};
EndFor
For i In {0:5}
  Line(i + 1) = {i + 1, (i + 1) % 6 + 1};
EndFor
Curve Loop(1) = {1, 2, 3, 4, 5, 6};
Plane Surface(1) = {1};
Extrude {0, 0, 30} { Surface{1}; }
"""
NOTCHED_TRAPEZOID_GEO = """SetFactory("OpenCASCADE");
Point(1) = {0, 0, 0}; Point(2) = {50, 0, 0}; Point(3) = {50, 20, 0}; Point(4) = {0, 35, 0};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Extrude {0, 0, 25} { Surface{1}; }
Box(10) = {20, 0, 15, 10, 10, 10};
BooleanDifference(11) = { Volume{1}; Delete; }{ Volume{10}; Delete; };
"""

# A rectangle with rounded corners (radius 8), extruded: fillets meeting lattice faces.
ROUNDED_RECTANGLE_GEO = """SetFactory("OpenCASCADE");
Rectangle(1) = {0, 0, 0, 60, 30, 8};
Extrude {0, 0, 20} { Surface{1}; }
"""

# Ten solids: a box cut in five along x, a cylinder through them all (bench/regions_by_solid.py).
BOX_5_CYLINDER_GEO = """SetFactory("OpenCASCADE");
For i In {0:4}
  Box(i + 1) = {20 * i, 0, 0, 20, 40, 30};
EndFor
Cylinder(6) = {0, 20, 15, 100, 0, 0, 8};
BooleanFragments{ Volume{1:5}; Delete; }{ Volume{6}; Delete; }
"""


# A step no one lattice spacing fits: a 30 x 20 x 10 block with a 13 x 20 x 10 block on it (the
# step's side at x = 13 of 30).
STEP_GEO = """SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 30, 20, 10};
Box(2) = {0, 0, 10, 13, 20, 10};
BooleanUnion{ Volume{1}; Delete; }{ Volume{2}; Delete; }
"""


def gmsh_brep(folder: Path, name: str, geo: Path | str) -> Path:
    """A .geo (file or text) written out as BREP by Gmsh's OpenCASCADE kernel (gmsh -0)."""
    if shutil.which("gmsh") is None:
        pytest.skip("gmsh is not installed")
    if isinstance(geo, str):
        path = folder / f"{name}.geo"
        path.write_text(geo)
        geo = path
    out = folder / f"{name}.brep"
    subprocess.run(["gmsh", "-0", str(geo), "-o", str(out)], check=True, capture_output=True)
    return out


@pytest.fixture(scope="module")
def shapes(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("shapes")
    out = {name: gmsh_brep(folder, name, GEOMETRY / f"{name}.geo")
           for name in ("box", "cylinder", "bracket", "sphere")}
    out["face"] = gmsh_brep(folder, "face", FACE_GEO)
    out["open_solid"] = gmsh_brep(folder, "open_solid", OPEN_SOLID_GEO)
    out["hexagonal_prism"] = gmsh_brep(folder, "hexagonal_prism", HEXAGONAL_PRISM_GEO)
    out["notched_trapezoid"] = gmsh_brep(folder, "notched_trapezoid", NOTCHED_TRAPEZOID_GEO)
    out["box_5_cylinder"] = gmsh_brep(folder, "box_5_cylinder", BOX_5_CYLINDER_GEO)
    out["rounded_rectangle"] = gmsh_brep(folder, "rounded_rectangle", ROUNDED_RECTANGLE_GEO)
    out["step"] = gmsh_brep(folder, "step", STEP_GEO)
    out["plate"] = PLATE
    return out


def assert_checked(mesh: hexmerge.MixedMesh, tets: hexmerge.MixedMesh, report: dict, h: float) -> dict:
    """The checker's verdict on `mesh` against the tet mesh `tets`, and the mesher's accuracy."""
    cells = tets.cell_vertices.reshape(-1, 4)
    result = hexmerge.check(mesh, tets.points, cells, tets.regions)
    assert result["valid"], result["problems"]
    assert result["nonconforming_quads"] == 0
    assert result["cracks"] == 0
    assert result["inverted_cells"] == 0
    assert result["moved_nodes"] == 0 and result["unused_input_nodes"] == 0
    # Same nodes as the tets; boundary quads folding less than 1 degree (the engine's default
    # min_boundary_dihedral_angle = 179) may shave a curved boundary a little.
    assert abs(result["relative_volume_difference"]) < 1e-4
    assert report["input_tets"] == len(cells)
    return result


def boundary_nodes(tets: hexmerge.MixedMesh) -> np.ndarray:
    """Coordinates of the nodes on the tet mesh's boundary (faces of one tet)."""
    t = tets.cell_vertices.reshape(-1, 4).astype(np.int64)
    faces = np.sort(np.concatenate([t[:, [1, 2, 3]], t[:, [0, 3, 2]], t[:, [0, 1, 3]], t[:, [0, 2, 1]]]), axis=1)
    unique, count = np.unique(faces, axis=0, return_counts=True)
    return tets.points[np.unique(unique[count == 1])]


# The surfaces of each shape, as distance functions (bench/geometry, resources/examples).
SURFACES = {
    "sphere": lambda p: np.abs(np.linalg.norm(p, axis=1) - 25),
    "box": lambda p: np.minimum.reduce([np.abs(p[:, 0]), np.abs(p[:, 0] - 100), np.abs(p[:, 1]),
                                        np.abs(p[:, 1] - 40), np.abs(p[:, 2]), np.abs(p[:, 2] - 30)]),
    "cylinder": lambda p: np.minimum.reduce([np.abs(np.hypot(p[:, 0], p[:, 1]) - 20), np.abs(p[:, 2]),
                                             np.abs(p[:, 2] - 100)]),
    "bracket": lambda p: np.minimum.reduce([np.abs(p[:, 0]), np.abs(p[:, 0] - 80), np.abs(p[:, 0] - 10),
                                            np.abs(p[:, 1]), np.abs(p[:, 1] - 40), np.abs(p[:, 2]),
                                            np.abs(p[:, 2] - 10), np.abs(p[:, 2] - 60),
                                            np.abs(np.hypot(p[:, 0] - 50, p[:, 1] - 20) - 8)]),
    "plate": lambda p: np.minimum.reduce([np.abs(np.abs(p[:, 0]) - 200), np.abs(np.abs(p[:, 1]) - 100),
                                          np.abs(p[:, 2]), np.abs(p[:, 2] - 10),
                                          np.abs(np.hypot(p[:, 0], p[:, 1]) - 50)]),
}


# (shape, h, hex volume floor). Measured when set (lattice faces given to TetGen with their
# points, and the selection's block of near-perfect hexahedra taken before the greedy stages):
# box h 10: 1.000; cylinder h 5: 0.325 (h 8 makes TetGen abort, reported as an InputError);
# bracket h 4: 0.854; plate h 10: 0.909. Before both, the greedy kept the lattice core whole or
# lost most of it on small changes (cylinder 0.131, bracket 0.176, plate 0.175).
# Swept (the cylinder and the plate are extrusions): cylinder h 5 0.866, plate h 10 0.991;
# unswept (sweep=False) cylinder h 5 0.442. The core laid before the boundary layers, which keep
# out of its circumspheres (issue 13): cylinder unswept 0.442 -> 0.481, sphere (r 25) h 5
# 0.386 -> 0.402 (torus h 4: 0.282 -> 0.322).
CASES = [("box", 10.0, 0.99, {}), ("cylinder", 5.0, 0.85, {}), ("bracket", 4.0, 0.84, {}),
         ("plate", 10.0, 0.98, {}), ("cylinder", 5.0, 0.47, {"sweep": False}), ("sphere", 5.0, 0.395, {})]
CASE_IDS = ["box", "cylinder", "bracket", "plate", "cylinder-unswept", "sphere"]


@needs_tetgen
@pytest.mark.parametrize(("name", "h", "floor", "options"), CASES, ids=CASE_IDS)
def test_shapes_recombine_and_check(shapes, name: str, h: float, floor: float, options: dict) -> None:
    tets, tet_report = hexmerge.mesh_shape(shapes[name], h, recombine=False, **options)
    assert tets.counts()["tetra"] == tets.nb_cells == tet_report["meshing"]["tets"]
    assert len(tets.cell_vertices) // 4 <= 30000  # keeps the suite fast
    assert np.array_equal(np.unique(tets.regions), [0])  # one solid
    hexmerge.validate(tets.points, tets.cell_vertices.reshape(-1, 4), tets.regions)

    mesh, report = hexmerge.mesh_shape(shapes[name], h, **options)
    assert_checked(mesh, tets, report, h)
    hex_volume = report["volume_fraction"]["hex"]
    print(f"{name} h {h}: {report['input_tets']} tets, hex volume {hex_volume:.3f}, reduction "
          f"{report['element_reduction_percent']:.1f} %, meshing {report['meshing']['seconds']:.2f} s, "
          f"engine {sum(report['phase_seconds'].values()):.2f} s")
    assert hex_volume >= floor
    assert report["element_reduction_percent"] > 0
    # The mesher's report rides along with the engine's.
    meshing = report["meshing"]
    assert meshing["tets"] == report["input_tets"]
    assert meshing["parameters"]["size"] == h and meshing["nb_solids"] == 1
    assert np.allclose(np.abs(np.linalg.det(np.array(meshing["frame"]))), 1.0)


@needs_tetgen
@pytest.mark.parametrize("h", [3.0, 2.2])
def test_a_step_no_spacing_fits_is_all_hexahedra(shapes, h: float) -> None:
    """The step's side at x = 13 of 30: uniform planes about h apart miss it (88.7 % hex volume
    at h 3, 124 tets, 166 pyramids left: measured before the rectilinear lattice); planes placed
    through it (the lattice rectilinear along x) make every element a hexahedron."""
    tets, _ = hexmerge.mesh_shape(shapes["step"], h, recombine=False)
    mesh, report = hexmerge.mesh_shape(shapes["step"], h)
    assert_checked(mesh, tets, report, h)
    assert report["meshing"]["nb_lattice_faces"] == report["meshing"]["nb_faces"]
    assert report["output_counts"]["hex"] == mesh.nb_cells
    assert report["volume_fraction"]["hex"] == pytest.approx(1.0)


def open_core_faces(points: np.ndarray, tets: np.ndarray, meshing: dict) -> tuple[int, list]:
    """The core cells (lattice cells filled by tets of their own corners) and their faces toward
    the transition that no closing pyramid closes: the tets beyond the face's two triangles do
    not share their fourth vertex. Faces with nothing beyond are on the boundary."""
    frame, spacing = np.array(meshing["frame"]), np.array(meshing["spacing"])
    q = points @ frame.T
    c = (q - q[: meshing["nb_surface_nodes"]].min(axis=0)) / spacing  # in cells
    on_lattice = np.all(np.abs(c - np.round(c)) < 1e-6, axis=1)
    ijk = np.round(c).astype(np.int64)
    lattice_node = {tuple(ijk[v]): v for v in np.nonzero(on_lattice)[0]}
    p = points[tets]
    volume = np.abs(np.einsum("ij,ij->i", p[:, 1] - p[:, 0], np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]))) / 6
    filled: dict[tuple, float] = {}
    for t in np.nonzero(on_lattice[tets].all(axis=1))[0]:
        corners = ijk[tets[t]]
        if (corners.max(axis=0) - corners.min(axis=0) <= 1).all():
            key = tuple(corners.min(axis=0))
            filled[key] = filled.get(key, 0.0) + volume[t]
    cell_volume = np.prod(spacing)
    core = {key for key, v in filled.items() if abs(v - cell_volume) < 1e-6 * cell_volume}
    beyond: dict[tuple, list] = {}
    for tet in tets:
        for f in range(4):
            beyond.setdefault(tuple(sorted(np.delete(tet, f))), []).append(tet[f])
    open_faces = []
    for cell in core:
        for axis in range(3):
            for side in (-1, 1):
                neighbour = list(cell)
                neighbour[axis] += side
                if tuple(neighbour) in core:
                    continue
                plane = cell[axis] + (side > 0)
                others = [a for a in range(3) if a != axis]
                corners = []
                for a, b in ((0, 0), (1, 0), (1, 1), (0, 1)):
                    k = list(cell)
                    k[axis], k[others[0]], k[others[1]] = plane, k[others[0]] + a, k[others[1]] + b
                    corners.append(lattice_node[tuple(k)])
                fourth = [v for i in range(4) for v in beyond.get(tuple(sorted(np.delete(corners, i))), [])
                          if (c[v][axis] - plane) * side > 1e-6]
                if fourth and (len(fourth) != 2 or fourth[0] != fourth[1]):
                    open_faces.append((cell, axis, side))
    return len(core), open_faces


@needs_tetgen
def test_every_core_face_has_its_closer(shapes) -> None:
    """The bracket at h 1.50: TetGen's -i insertion left non-Delaunay tets in the lattice (an
    apex joined to the far corner of the core cell behind its face), core faces without closing
    pyramid, and the engine's block lost a quarter of the core (79.0 % hex volume; 97.7 % now,
    with the points in the PLC). Also 1.30, 1.32, 1.36, 1.38, 1.46, 1.48 (84 to 93.7 %).
    The core as laid (pull_core off: the cells are told by their lattice positions here)."""
    tets, tet_report = hexmerge.mesh_shape(shapes["bracket"], 1.50, recombine=False, pull_core=False)
    cells = tets.cell_vertices.reshape(-1, 4).astype(np.int64)
    nb_core, open_faces = open_core_faces(tets.points, cells, tet_report["meshing"])
    assert nb_core == tet_report["meshing"]["nb_core_cells"]  # TetGen kept every core cell
    assert open_faces == []
    mesh, report = hexmerge.recombine(tets.points, cells, tets.regions)
    assert report["block_hexahedra"] >= nb_core
    assert report["volume_fraction"]["hex"] >= 0.97


@needs_tetgen
def test_boundary_layer_by_default_on_swept_shapes_only(shapes) -> None:
    """boundary_layers = -1 (the default): the swept cylinder gets its ring of layer points
    along the wall; unswept, the layer's points would add a third to the tets and no hexahedra
    (Delaunay does not join them into columns), so there is none. Measured at h 5: unswept
    11,327 tets against 15,047 with one layer, hex volume 62.1 % against 62.3 %, min SJ 0.200
    both."""
    h = 5.0
    _, swept = hexmerge.mesh_shape(shapes["cylinder"], h, recombine=False)
    assert swept["meshing"]["sweep_axis"] >= 0
    assert swept["meshing"]["nb_layer_points"] > 0
    tets, plain = hexmerge.mesh_shape(shapes["cylinder"], h, recombine=False, sweep=False)
    layered, with_layer = hexmerge.mesh_shape(shapes["cylinder"], h, recombine=False, sweep=False,
                                              boundary_layers=1)
    assert plain["meshing"]["nb_layer_points"] == 0
    assert with_layer["meshing"]["nb_layer_points"] > 0
    assert plain["meshing"]["tets"] < 0.8 * with_layer["meshing"]["tets"]
    quality = tet_scaled_jacobians(tets.points, tets.cell_vertices.reshape(-1, 4).astype(np.int64))
    assert quality.min() >= 0.2
    mesh, report = hexmerge.recombine(tets.points, tets.cell_vertices.reshape(-1, 4), tets.regions)
    assert_checked(mesh, tets, report, h)
    _, layered_report = hexmerge.recombine(layered.points, layered.cell_vertices.reshape(-1, 4),
                                           layered.regions)
    assert report["volume_fraction"]["hex"] >= layered_report["volume_fraction"]["hex"] - 0.01


# (shape, h, floor of the smallest tet scaled Jacobian after the flips and node moves). Measured
# when set (needle smoothing on the surface, layer depths spread by 10 %, remove_slivers
# alternated with smooth_nodes): cylinder h 5: 0.0103 (14 tets below 0.2 left, on skinny
# triangles of the lateral face); bracket h 4: 0.140 (56 left); plate h 10: 0.237 (none left).
# Before (flips only): 0.0078 (417 left), 0.039 (86), 0.195 (8). Issue #6 asks for 0.2 at 100k.
# Needles at the seam let off it (normal test against the surface's, partial moves, h / 8):
# cylinder h 5 0.0103 -> 0.0357 (1 tet below 0.2, four surface nodes across the seam); bracket
# h 1.50 (105k tets) 0.0119 -> 0.243 (none below 0.2; its worst were on the hole's seam). Then
# boundary sides of one face swapped within the chord deflection (a lone flat tet on two
# triangles across the seam goes): cylinder h 5 0.249 (h 2.3 / 2.50 / 3.2: 0.191 / 0.195 / 0.206;
# h 2.7 still 0.003, a cluster off the seam).
# The core kept down to lattice_margin (0.3 h) from curved faces, the closing pyramids' apexes
# nudged to 0.2: cylinder h 5 / 2.7 0.200 / 0.201, bracket h 4 / 1.5 0.207 / 0.201 (0.165 at h 4
# before), plate 0.297.
# The surface bisected along Rivara's longest-edge paths: cylinder h 5 / 2.7 0.200 / 0.208,
# bracket h 4 / 1.5 0.240 / 0.209, plate 0.297.
# The cylinder and the plate unswept (sweep=False): swept, their tets stay as TetGen makes them.
SLIVER_CASES = [("cylinder", 5.0, 0.2), ("cylinder", 2.7, 0.2), ("bracket", 4.0, 0.2), ("bracket", 1.5, 0.2), ("plate", 10.0, 0.22)]


@needs_tetgen
@pytest.mark.parametrize(("name", "h", "floor"), SLIVER_CASES, ids=[f"{c[0]}-{c[1]:g}" for c in SLIVER_CASES])
def test_flips_raise_the_smallest_scaled_jacobian(shapes, name: str, h: float, floor: float) -> None:
    # One boundary layer (unswept shapes have none by default): its points are what
    # smooth_nodes moves.
    tets, report = hexmerge.mesh_shape(shapes[name], h, recombine=False, sweep=False, boundary_layers=1)
    meshing = report["meshing"]
    quality = tet_scaled_jacobians(tets.points, tets.cell_vertices.reshape(-1, 4).astype(np.int64))
    assert meshing["nb_face_flips"] + meshing["nb_edge_flips"] > 0
    assert meshing["nb_node_moves"] > 0  # smooth_nodes moved layer or Steiner points
    # and boundary nodes along their CAD faces and edges, which keeps them on the CAD; only while
    # a tet at them is below 0.2 (the plate's never are; the bracket's at h 4 were not on its
    # 5 x 4 x 5 lattice, min 0.240 without a move, and are on the 3.33 x 4 x 3.33 one that keeps
    # every spacing above half the cell's diagonal: 2 moves, min 0.202)
    assert (meshing["nb_boundary_node_moves"] > 0) == ((name, h) != ("plate", 10.0))
    assert meshing["max_boundary_distance"] <= 1e-6 * h
    assert meshing["nb_nudged_points"] == 0  # TetGen kept every lattice point the first time
    assert quality.min() >= meshing["min_tet_quality_before"] - 1e-12  # flips never lower it
    assert quality.min() >= floor


@needs_tetgen
def test_core_reaches_the_lattice_margin(shapes) -> None:
    """The lattice points are kept down to lattice_margin (0.3 h) from the curved faces, not that
    plus the layers' depth: more core cells, and the closing pyramids' apexes, which come as near
    the faces, nudged until their tets reach 0.2 (a tet of three surface nodes and an apex was
    0.155 on this cylinder at h 2.7 without). Measured: 598 core cells (480 before), 60.0 % hex
    volume (48.9 %), min SJ 0.200."""
    h = 5.0
    tets, report = hexmerge.mesh_shape(shapes["cylinder"], h, recombine=False, sweep=False)
    meshing = report["meshing"]
    assert meshing["nb_core_cells"] >= 590
    quality = tet_scaled_jacobians(tets.points, tets.cell_vertices.reshape(-1, 4).astype(np.int64))
    assert quality.min() >= 0.2
    mesh, report = hexmerge.mesh_shape(shapes["cylinder"], h, sweep=False)
    assert_checked(mesh, tets, report, h)
    assert report["volume_fraction"]["hex"] >= 0.58


@needs_tetgen
@pytest.mark.parametrize(("name", "h", "options", "gain"), [
    ("sphere", 5.0, {}, 0.025), ("cylinder", 5.0, {"sweep": False}, 0.035)], ids=["sphere", "cylinder-unswept"])
def test_the_core_pulled_towards_the_surface(shapes, name: str, h: float, options: dict, gain: float) -> None:
    """pull_core (the default): the core's boundary nodes and its closing pyramids' apexes move
    towards the curved faces, the moved cells and pyramids kept whole by TetGen constraints and
    split as the lattice's. Measured at h 5: sphere 53.6 -> 57.0 % hex volume, unswept cylinder
    63.9 -> 68.2 %, the tets' minimum 0.2 in both; every core cell becomes a hexahedron."""
    tets, tet_report = hexmerge.mesh_shape(shapes[name], h, recombine=False, **options)
    meshing = tet_report["meshing"]
    assert meshing["strategy"] == "lattice" and meshing["failed_strategies"] == []
    assert meshing["nb_pulled_points"] > 0 and meshing["nb_resplit_cells"] > 0
    cells = tets.cell_vertices.reshape(-1, 4).astype(np.int64)
    assert tet_scaled_jacobians(tets.points, cells).min() >= 0.2
    mesh, report = hexmerge.recombine(tets.points, cells, tets.regions)
    assert_checked(mesh, tets, report, h)
    assert report["output_counts"]["hex"] >= meshing["nb_core_cells"]
    assert meshing["max_boundary_distance"] <= 1e-3 * h

    _, unpulled = hexmerge.mesh_shape(shapes[name], h, pull_core=False, **options)
    assert unpulled["meshing"]["nb_pulled_points"] == 0
    assert unpulled["meshing"]["nb_resplit_cells"] == 0
    assert report["volume_fraction"]["hex"] >= unpulled["volume_fraction"]["hex"] + gain


@needs_tetgen
def test_the_buffer_layer_reaches_the_curved_face(shapes) -> None:
    """buffer_layer (on by default, with the core pulled, the default too): hexahedra from the
    core's closing pyramids' bases to the surface, their tops put into the face's triangles,
    their open side faces closed by pyramids. The unswept cylinder at h 5: 106 of them, every one
    a hexahedron of the output, 68.2 % hex volume without them and 78.0 % with them, the tets'
    minimum 0.2, the boundary on the CAD."""
    h = 5.0
    tets, tet_report = hexmerge.mesh_shape(shapes["cylinder"], h, recombine=False, sweep=False)
    meshing = tet_report["meshing"]
    assert meshing["strategy"] == "lattice" and meshing["failed_strategies"] == []
    assert meshing["nb_buffer_hexes"] >= 80 and meshing["nb_buffer_faces"] == 1
    assert meshing["nb_buffer_pyramids"] > 0
    # The census: every closing pyramid's base once, at the test it fails, or kept. The cylinder's
    # core is a staircase (its concave steps share apexes), and the bases beside its caps, which
    # are lattice faces, have corners nearest a cap, which takes no tops.
    bases = meshing["buffer_bases"]
    assert bases["kept"] == meshing["nb_buffer_hexes"]
    assert sum(v for k, v in bases.items() if k != "considered") == bases["considered"]
    assert bases["apex_shared"] > 0 and bases["no_top_face"] > 0
    cells = tets.cell_vertices.reshape(-1, 4).astype(np.int64)
    assert tet_scaled_jacobians(tets.points, cells).min() >= 0.2
    mesh, report = hexmerge.recombine(tets.points, cells, tets.regions)
    assert_checked(mesh, tets, report, h)
    assert report["output_counts"]["hex"] >= meshing["nb_core_cells"] + meshing["nb_buffer_hexes"]
    assert meshing["max_boundary_distance"] <= 1e-3 * h

    _, without = hexmerge.mesh_shape(shapes["cylinder"], h, sweep=False, buffer_layer=False)
    assert without["meshing"]["nb_buffer_hexes"] == 0 and without["meshing"]["strategy"] == "lattice"
    assert without["meshing"]["buffer_bases"]["considered"] == 0
    assert report["volume_fraction"]["hex"] >= without["volume_fraction"]["hex"] + 0.06


@needs_tetgen
def test_a_tetgen_failure_on_the_buffer_layer_falls_back_to_the_pulled_core(shapes, tmp_path) -> None:
    """TetGen failing on the first way, which made a buffer layer: the next way is the same
    pulled core without the layer, said in the report; the mesh is valid."""
    fake = tetgen_failing_once(tmp_path / "crashed", "kill -SEGV $$")
    tets, report = hexmerge.mesh_shape(shapes["cylinder"], 5.0, recombine=False, sweep=False,
                                       buffer_layer=True, tetgen=str(fake))
    meshing = report["meshing"]
    assert meshing["strategy"] == "lattice without the buffer layer"
    [failure] = meshing["failed_strategies"]
    assert failure.startswith("lattice: TetGen crashed (segmentation fault)"), failure
    assert meshing["nb_buffer_hexes"] == 0 and meshing["nb_pulled_points"] > 0
    mesh, rep = hexmerge.recombine(tets.points, tets.cell_vertices.reshape(-1, 4), tets.regions)
    assert_checked(mesh, tets, rep, 5.0)


def boundary_smallest_angles(tets: hexmerge.MixedMesh) -> np.ndarray:
    """The smallest corner angle, in degrees, of each boundary triangle of a tet mesh."""
    t = tets.cell_vertices.reshape(-1, 4).astype(np.int64)
    faces = np.sort(np.concatenate([t[:, [1, 2, 3]], t[:, [0, 3, 2]], t[:, [0, 1, 3]], t[:, [0, 2, 1]]]), axis=1)
    unique, count = np.unique(faces, axis=0, return_counts=True)
    p = tets.points[unique[count == 1]]
    smallest = np.full(len(p), 180.0)
    for c in range(3):
        u, w = p[:, (c + 1) % 3] - p[:, c], p[:, (c + 2) % 3] - p[:, c]
        angle = np.degrees(np.arctan2(np.linalg.norm(np.cross(u, w), axis=1), np.einsum("ij,ij->i", u, w)))
        smallest = np.minimum(smallest, angle)
    return smallest


@needs_tetgen
def test_no_flat_boundary_triangle_beside_a_refined_edge(tmp_path) -> None:
    # thin_bracket at h 1.565: the gussets' slanted faces (3 mm wide) had a node 5.5e-4 mm from
    # their edge beside three nodes the refinement put on that edge; no collapse can remove such
    # a node (onto any of them it leaves three nodes of the edge in one triangle), so its caps
    # stayed: a boundary triangle of 0.07 degrees and a tet of scaled Jacobian 0.0014 on it. The
    # node is now removed and its ring triangulated anew (and no boundary swap of the sliver
    # removal makes a triangle under 5 degrees where there was none).
    shape = gmsh_brep(tmp_path, "thin_bracket", GEOMETRY / "thin_bracket.geo")
    h = 1.565
    tets, report = hexmerge.mesh_shape(shape, h, recombine=False)
    assert boundary_smallest_angles(tets).min() >= 5.0  # measured 9.08 (0.071 before)
    quality = tet_scaled_jacobians(tets.points, tets.cell_vertices.reshape(-1, 4).astype(np.int64))
    assert quality.min() >= 0.1  # measured 0.117 (0.0014 before)
    assert report["meshing"]["max_boundary_distance"] <= 1e-3 * h
    mesh, merged = hexmerge.mesh_shape(shape, h)
    assert_checked(mesh, tets, merged, h)


@needs_tetgen
@pytest.mark.parametrize(("name", "h", "options"), [(name, h, o) for name, h, _, o in CASES], ids=CASE_IDS)
def test_reported_boundary_distance(shapes, name: str, h: float, options: dict) -> None:
    _, report = hexmerge.mesh_shape(shapes[name], h, recombine=False, **options)
    assert report["meshing"]["max_boundary_distance"] <= 1e-3 * h


@needs_tetgen
@pytest.mark.parametrize(("name", "h", "options"), [(name, h, o) for name, h, _, o in CASES], ids=CASE_IDS)
def test_boundary_nodes_on_the_surfaces(shapes, name: str, h: float, options: dict) -> None:
    tets, _ = hexmerge.mesh_shape(shapes[name], h, recombine=False, **options)
    assert SURFACES[name](boundary_nodes(tets)).max() <= 1e-3 * h


def sweep_planes(tets: hexmerge.MixedMesh, meshing: dict) -> tuple[np.ndarray, np.ndarray]:
    """The nodes in the lattice frame, and the lattice plane along the sweep axis each lies on
    (asserted: to 1e-9 of the spacing); every tet lies between two consecutive planes."""
    axis = meshing["sweep_axis"]
    q = tets.points @ np.array(meshing["frame"]).T
    level = (q[:, axis] - q[:, axis].min()) / meshing["spacing"][axis]
    assert np.abs(level - np.round(level)).max() < 1e-9  # every node on a lattice plane
    level = np.round(level).astype(np.int64)
    cells = tets.cell_vertices.reshape(-1, 4).astype(np.int64)
    assert (level[cells].max(axis=1) - level[cells].min(axis=1) == 1).all()  # every tet in a slab
    return q, level


@needs_tetgen
@pytest.mark.parametrize(("name", "h"), [("cylinder", 5.0), ("cylinder", 8.0), ("plate", 10.0),
                                         ("rounded_rectangle", 3.0)])
def test_extrusions_are_swept(shapes, name: str, h: float) -> None:
    """An extruded shape's tets repeat one cross-section from lattice plane to lattice plane, so
    they recombine into hexahedra and prisms only (cylinder h 5: 86.6 % hex volume, 0.44 unswept;
    h 8 made TetGen drop four surface points by the seam before; the rounded rectangle at h 3:
    98.6 %, 58.7 % while its fillets' layers ended beside the lattice faces in thin triangles)."""
    tets, report = hexmerge.mesh_shape(shapes[name], h, recombine=False)
    meshing = report["meshing"]
    axis = meshing["sweep_axis"]
    assert axis == 2  # the frame's third axis: the normal of the largest planar faces
    q, level = sweep_planes(tets, meshing)
    section = [np.round(np.delete(q[level == k], axis, axis=1), 9) for k in range(level.max() + 1)]
    first = section[0][np.lexsort(section[0].T)]
    for k, s in enumerate(section):  # the same cross-section on every plane
        assert np.array_equal(s[np.lexsort(s.T)], first), k
    mesh, report = hexmerge.mesh_shape(shapes[name], h)
    result = assert_checked(mesh, tets, report, h)
    assert report["output_counts"]["tet"] == report["output_counts"]["pyramid"] == 0
    assert report["volume_fraction"]["hex"] >= 0.75
    assert result["min_scaled_jacobian"] >= 0.3
    _, unswept = hexmerge.mesh_shape(shapes[name], h, recombine=False, sweep=False)
    assert unswept["meshing"]["sweep_axis"] == -1


def holed_plate_geo(thickness: float) -> str:
    """A 48 x 36 plate with a grid of 12 holes of radius 2, about as wide as h
    (bench/geometry/holed_plate.geo, smaller)."""
    return f"""SetFactory("OpenCASCADE");
Box(1) = {{0, 0, 0, 48, 36, {thickness:g}}};
k = 2;
For i In {{0:3}}
  For j In {{0:2}}
    Cylinder(k) = {{12 + 12 * i, 6 + 12 * j, -1, 0, 0, {thickness + 2:g}, 2}}; k += 1;
  EndFor
EndFor
BooleanDifference(100) = {{ Volume{{1}}; Delete; }}{{ Volume{{2:k - 1}}; Delete; }};
"""


@needs_tetgen
def test_a_plate_with_holes_is_swept_into_columns_of_hexahedra_and_prisms(tmp_path) -> None:
    """The swept tets are columns of prisms over one cross-section (every slab's tets rebuilt from
    the first plane's triangles), and prisms and hexahedra poorer than the engine's minimum (0.3)
    but better than the tets they replace are taken: the holes' fine triangles left as tets
    turned their neighbours into pyramids, plane after plane (the benchmark's plate at h 3.4:
    40 % hex volume and 35 % pyramids; now 87 % hex, the rest prisms)."""
    plate = gmsh_brep(tmp_path, "holed_plate", holed_plate_geo(6))
    h = 3.4
    tets, report = hexmerge.mesh_shape(plate, h, recombine=False)
    meshing = report["meshing"]
    assert meshing["sweep_axis"] == 2 and meshing["nb_extruded_triangles"] > 0
    q, level = sweep_planes(tets, meshing)
    # Columns: every tet's corners project onto one triangle of the first plane's cross-section.
    cells = tets.cell_vertices.reshape(-1, 4).astype(np.int64)
    across = np.round(np.delete(q, 2, axis=1), 9)
    _, place = np.unique(across, axis=0, return_inverse=True)
    place = place.ravel()
    columns = {tuple(sorted(set(place[c].tolist()))) for c in cells}
    assert all(len(c) == 3 for c in columns)
    assert len(columns) == meshing["nb_extruded_triangles"]
    mesh, report = hexmerge.mesh_shape(plate, h)
    result = assert_checked(mesh, tets, report, h)
    assert report["output_counts"]["tet"] == report["output_counts"]["pyramid"] == 0
    assert report["volume_fraction"]["hex"] >= 0.75
    assert result["min_scaled_jacobian"] >= 0.1
    # Without the poorer prisms the cascade of pyramids comes back.
    _, strict = hexmerge.mesh_shape(plate, h, lowest_scaled_jacobian=0.3)
    assert strict["output_counts"]["pyramid"] > 0
    assert strict["volume_fraction"]["hex"] < report["volume_fraction"]["hex"]


@needs_tetgen
@pytest.mark.parametrize(("name", "h", "sweep_axis"), [("hexagonal_prism", 2.5, 2), ("hexagonal_prism", 3.0, 2),
                                                       ("hexagonal_prism", 4.0, -1), ("notched_trapezoid", 2.5, -1),
                                                       ("notched_trapezoid", 3.0, -1)])
def test_straight_edges_across_the_lattice(shapes, name: str, h: float, sweep_axis: int) -> None:
    """Lattice faces bounded by straight edges across the lattice: TetGen 1.5 never ended, or lost
    the face, on their nearly collinear loop nodes (every one of these cases at the first run, and
    two after five restarts with other loop starts); with the nodes exactly on one line, TetGen
    runs once, and the mesh checks."""
    options = {} if sweep_axis >= 0 else {"sweep": name != "hexagonal_prism"}
    tets, report = hexmerge.mesh_shape(shapes[name], h, recombine=False, **options)
    meshing = report["meshing"]
    assert meshing["nb_tetgen_restarts"] == 0
    assert meshing["sweep_axis"] == sweep_axis
    assert meshing["max_boundary_distance"] <= 1e-3 * h
    mesh, report = hexmerge.mesh_shape(shapes[name], h, **options)
    assert_checked(mesh, tets, report, h)
    assert report["volume_fraction"]["hex"] >= 0.55


@needs_tetgen
def test_solids_stacked_along_the_axis_are_swept(shapes) -> None:
    """Ten solids, one cross-section (a cylinder through five boxes along x, every piece a solid):
    swept along x, the walls split at the boxes' faces, the cylinder between two solids layered
    on both sides. h 3: 92.8 % hex volume, the rest prisms, min SJ 0.31; unswept 67.9 %, 0.087
    (h 2.5: 94.5 % against 75.0 %)."""
    tets, report = hexmerge.mesh_shape(shapes["box_5_cylinder"], 3.0, recombine=False)
    meshing = report["meshing"]
    assert meshing["sweep_axis"] >= 0 and meshing["nb_solids"] == 10
    assert np.array_equal(np.unique(tets.regions), np.arange(10))
    frame = np.array(meshing["frame"])
    assert np.allclose(np.abs(frame[meshing["sweep_axis"]]), [1, 0, 0])  # along x
    sweep_planes(tets, meshing)
    assert meshing["max_boundary_distance"] <= 1e-3 * 3.0
    mesh, report = hexmerge.mesh_shape(shapes["box_5_cylinder"], 3.0)
    result = assert_checked(mesh, tets, report, 3.0)
    assert report["output_counts"]["tet"] == report["output_counts"]["pyramid"] == 0
    assert report["volume_fraction"]["hex"] >= 0.9
    assert result["min_scaled_jacobian"] >= 0.3


@needs_tetgen
def test_shapes_that_are_no_extrusion_are_not_swept(shapes) -> None:
    for name in ("box", "bracket"):  # all lattice faces; a hole across an L
        _, report = hexmerge.mesh_shape(shapes[name], 10.0, recombine=False)
        assert report["meshing"]["sweep_axis"] == -1, name


@needs_tetgen
def test_box_is_all_hexahedra(shapes) -> None:
    mesh, report = hexmerge.mesh_shape(shapes["box"], 10.0)
    # 100 x 40 x 30 mm at h = 10: a 10 x 4 x 3 lattice, every cell one hexahedron.
    assert report["output_counts"] == {"tet": 0, "pyramid": 0, "prism": 0, "hex": 120}
    assert report["volume_fraction"]["hex"] >= 0.99
    # A box's tets have its volume exactly: no note on it.
    meshing = report["meshing"]
    assert meshing["shape_volume"] == pytest.approx(120000.0, rel=1e-9)
    assert meshing["mesh_volume"] == pytest.approx(120000.0, rel=1e-9)
    assert not any("volume" in note for note in hexmerge.mesh_notes(meshing))


@needs_tetgen
def test_shape_as_text_bytes_and_paths(shapes) -> None:
    path = shapes["box"]
    text = path.read_text()
    runs = [hexmerge.mesh_shape(s, 10.0, recombine=False)[0] for s in (text, text.encode(), path, str(path))]
    for mesh in runs[1:]:
        assert np.array_equal(mesh.points, runs[0].points)
        assert np.array_equal(mesh.cell_vertices, runs[0].cell_vertices)
    assert _core.read_shape_file(str(path)).startswith("DBRep_DrawableShape")


@needs_tetgen
def test_second_order(shapes) -> None:
    h = 8.0
    tets10, _ = hexmerge.mesh_shape(shapes["bracket"], h, recombine=False, second_order=True)
    assert tets10.order == 2 and [b.type for b in tets10] == ["tetra10"]
    cells10 = tets10.cells("tetra10")
    mesh, report = hexmerge.mesh_shape(shapes["bracket"], h, second_order=True)
    assert mesh.order == 2
    assert {b.type for b in mesh} <= {"tetra10", "pyramid13", "wedge15", "hexahedron20"}
    assert "hexahedron20" in {b.type for b in mesh}
    # Every mid-edge node is the midpoint of its edge (VTK order) or, on the boundary, on the CAD.
    for m in (mesh, tets10):
        for block in m:
            n = block.data.shape[1] - len(EDGES[block.type])
            for k, (a, b) in enumerate(EDGES[block.type]):
                ends = 0.5 * (m.points[block.data[:, a]] + m.points[block.data[:, b]])
                mid = m.points[block.data[:, n + k]]
                straight = np.all(np.abs(mid - ends) <= 1e-12, axis=1)
                assert np.all(straight | (SURFACES["bracket"](mid) < 1e-6 * h))
    # One node per edge, shared by the tets around it.
    corners = len(np.unique(cells10[:, :4]))
    edges = {tuple(sorted(e)) for t in cells10[:, :4] for e in t[[[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]]]}
    assert tets10.nb_points == corners + len(edges)
    result = hexmerge.check(mesh, tets10.points, cells10, tets10.regions)
    assert result["valid"], result["problems"]
    assert result["nonconforming_quads"] == 0 and result["cracks"] == 0
    linear, _ = hexmerge.mesh_shape(shapes["bracket"], h)
    assert report["output_counts"] == linear_counts(linear)


def linear_counts(mesh: hexmerge.MixedMesh) -> dict[str, int]:
    names = {"tetra": "tet", "pyramid": "pyramid", "wedge": "prism", "hexahedron": "hex"}
    return {names[k]: v for k, v in mesh.counts().items()}


@needs_tetgen
def test_engine_options_and_progress(shapes) -> None:
    phases = []
    mesh, report = hexmerge.mesh_shape(
        shapes["bracket"], 8.0, boundary_layers=0, frame="global", make_pyramids=False,
        progress=lambda phase, fraction: phases.append((phase, fraction)),
    )
    assert report["output_counts"]["pyramid"] == 0
    assert report["meshing"]["nb_layer_points"] == 0
    assert report["meshing"]["parameters"]["frame"] == "global"
    assert phases[0] == ("mesh shape", 0.0) and ("mesh shape", 1.0) in phases
    # The mesher's own steps, in order, each fraction up to 1 before the engine's phases.
    steps = [p for p, _ in phases if p.startswith("mesh shape: ")]
    for step in ("surface", "lattice", "core", "layers", "tetgen", "regions", "slivers", "polish",
                 "check"):
        assert f"mesh shape: {step}" in steps
    assert steps.index("mesh shape: surface") < steps.index("mesh shape: tetgen") < steps.index(
        "mesh shape: check")
    fractions = [f for p, f in phases if p.startswith("mesh shape: ")]
    assert fractions == sorted(fractions) and fractions[-1] == 0.95
    with pytest.raises(hexmerge.Cancelled):
        hexmerge.mesh_shape(shapes["box"], 10.0, progress=lambda phase, fraction: False)
    # Cancelled inside the mesher: no later step runs.
    seen = []

    def stop_after_tetgen(phase: str, fraction: float) -> bool:
        seen.append(phase)
        return phase != "mesh shape: tetgen"

    with pytest.raises(hexmerge.Cancelled):
        hexmerge.mesh_shape(shapes["box"], 10.0, progress=stop_after_tetgen)
    assert seen[-1] == "mesh shape: tetgen"


@pytest.mark.parametrize(
    ("shape", "kwargs", "message"),
    [
        ("open_solid", {"size": 2.0}, "not closed.*open shell"),
        ("face", {"size": 2.0}, "holds no solid"),
        ("box", {"size": 0.0}, "parameter 'size' must be greater than 0 mm"),
        ("box", {"size": -1.0}, "parameter 'size' must be greater than 0 mm"),
        ("box", {"size": 500.0}, "larger than the shape"),
        ("box", {"size": "ten"}, "option 'size' must be a number"),
        ("box", {"size": 10.0, "tetgen": "/nonexistent/tetgen"}, "TetGen.*/nonexistent/tetgen.*not found"),
        ("box", {"size": 10.0, "boundary_layers": 7}, "parameter 'boundary_layers' must be between -1 and 3"),
        ("box", {"size": 10.0, "boundary_layers": 1.5}, "option 'boundary_layers' must be a whole number"),
        ("box", {"size": 10.0, "frame": "diagonal"}, "parameter 'frame' must be one of auto, principal, global"),
        ("box", {"size": 10.0, "sweep": "yes"}, "option 'sweep' must be True or False"),
        ("box", {"size": 10.0, "tetgen_time_limit": -1.0}, "'tetgen_time_limit' must be between 0 and 86400 s"),
        ("box", {"size": 10.0, "tetgen_time_limit": 1e6}, "'tetgen_time_limit' must be between 0 and 86400 s"),
        ("box", {"size": 10.0, "layer_thickness": 5.0}, "layer_thickness"),
        ("missing", {"size": 10.0}, "no such file"),
        ("not brep", {"size": 10.0}, "file name must end in"),
        ("garbage", {"size": 10.0}, "neither BREP text"),
    ],
)
def test_bad_input(shapes, tmp_path, shape, kwargs, message) -> None:
    if shape == "missing":
        shape = tmp_path / "missing.step"
    elif shape == "not brep":
        shape = tmp_path / "part.txt"
        shape.write_text("hello")
    elif shape == "garbage":
        shape = "not\na shape"
    else:
        shape = shapes[shape]
    with pytest.raises(hexmerge.InputError, match=message):
        hexmerge.mesh_shape(shape, **kwargs)


@pytest.mark.parametrize(("script", "limit", "message"), [
    ("exit 0", 0.0, "TetGen lost the shape's surface \\(no tets inside\\)"),
    ("sleep 30", 0.5, "TetGen did not finish within 0.5 s"),
])
def test_tetgen_failures_are_reported(shapes, tmp_path, script, limit, message) -> None:
    """A TetGen that leaves no tets, or never ends (as TetGen 1.5 did on some lattice faces), is
    run once for each of the 5 ways of placing the points (its facets are triangles: run again,
    it would fail the same way; the way without layers is not tried when no layers are asked
    for unswept shapes, the default), then the meshing fails saying so."""
    fake = tmp_path / "tetgen"
    fake.write_text(f"#!/bin/sh\necho started >> {tmp_path / 'runs'}\n{script}\n")
    fake.chmod(0o755)
    with pytest.raises(hexmerge.InputError, match=message):
        hexmerge.mesh_shape(shapes["box"], 10.0, tetgen=str(fake), tetgen_time_limit=limit)
    assert (tmp_path / "runs").read_text().count("started") == 5


def tetgen_failing_once(flag: Path, failure: str) -> Path:
    """A `tetgen` beside `flag` that runs the shell lines `failure` the first time (while `flag`
    does not exist, which it then creates) and the real TetGen after."""
    fake = flag.parent / "tetgen"
    fake.write_text(f"""#!/bin/sh
if [ ! -e {flag} ]; then
  touch {flag}
  {failure}
fi
exec {shutil.which("tetgen")} "$@"
""")
    fake.chmod(0o755)
    return fake


@pytest.mark.parametrize(("crash", "how"), [
    ("kill -ABRT $$", "TetGen stopped on an internal error"),
    ("kill -SEGV $$", "TetGen crashed \\(segmentation fault\\)"),
])
def test_a_tetgen_crash_falls_back_to_the_next_strategy(shapes, tmp_path, capsys, crash, how) -> None:
    """TetGen crashing on the lattice faces (as TetGen 1.5 does on FreeCAD's plate with a hole at
    h 2.5): the next way of placing the points (the lattice at 0.95 of the size) is tried, the
    report names the failure in our words with TetGen's reason, and the mesh is valid. TetGen's
    crash text is never shown."""
    fake = tetgen_failing_once(tmp_path / "crashed", f"""echo "Opening $2."
  echo "Error:  Invalid PLC."
  echo "  Two segments (1, 2) and (3, 4) intersect."
  echo "terminate called after throwing an instance of 'int'" >&2
  {crash}""")
    tets, report = hexmerge.mesh_shape(shapes["bracket"], 3.0, recombine=False, tetgen=str(fake),
                                       pull_core=False)
    meshing = report["meshing"]
    assert meshing["strategy"] == "lattice at 0.95 of the size"
    assert meshing["nb_lattice_faces"] > 0
    assert meshing["spacing"][0] < 0.97 * 3.0
    [failure] = meshing["failed_strategies"]
    assert re.fullmatch(f"lattice: {how} \\(it reports: Invalid PLC. Two segments \\(1, 2\\) and "
                        "\\(3, 4\\) intersect.\\)(; faces? .* of the shape)?", failure), failure
    mesh, rep = hexmerge.recombine(tets.points, tets.cell_vertices.reshape(-1, 4), tets.regions)
    assert_checked(mesh, tets, rep, 3.0)
    # The CLI says so (no silent fallback), in our words.
    (tmp_path / "crashed").unlink()
    capsys.readouterr()
    assert main(["mesh", str(shapes["bracket"]), "-h", "3", "-o", str(tmp_path / "b.vtu"),
                 "--tetgen", str(fake), "--no-pull-core"]) == 0
    err = capsys.readouterr().err
    assert "note: meshing failed with the points placed by lattice: TetGen " in err, err
    # (The core not pulled, as above: the lattice without pulling would repeat the first way.)
    assert "the tets were made with the points placed by lattice at 0.95 of the size" in err, err
    assert "terminate called" not in err and "Aborted" not in err, err


@needs_tetgen
def test_a_tetgen_failure_on_the_pulled_core_falls_back_to_the_lattice_as_laid(shapes, tmp_path) -> None:
    """TetGen failing on the first way, which pulled the sphere's core: the next way is the same
    lattice with the core as laid (not a smaller size), said in the report; the mesh is valid."""
    fake = tetgen_failing_once(tmp_path / "crashed", "kill -SEGV $$")
    tets, report = hexmerge.mesh_shape(shapes["sphere"], 5.0, recombine=False, tetgen=str(fake))
    meshing = report["meshing"]
    assert meshing["strategy"] == "lattice, core not pulled"
    [failure] = meshing["failed_strategies"]
    assert failure.startswith("lattice: TetGen crashed (segmentation fault)"), failure
    assert meshing["nb_pulled_points"] == 0 and meshing["spacing"][0] > 0.97 * 5.0
    mesh, rep = hexmerge.recombine(tets.points, tets.cell_vertices.reshape(-1, 4), tets.regions)
    assert_checked(mesh, tets, rep, 5.0)


# A random part of bench/random_parts.py (seed 20261204, its part 006, written by FreeCAD): at
# h 4.4417 its core is pulled and the buffer layer's hexahedra stand on it.
PULLED_PYRAMID_SIDE = ROOT / "tests" / "data" / "pulled_pyramid_side.brep"


@needs_tetgen
def test_a_pulled_pyramids_sides_cross_no_face() -> None:
    """pull_core moved an apex and its base's corners each clear of the faces, but a pyramid's
    side between them crossed the surface: TetGen stopped ("a segment and a subface intersect",
    faces 13 and 1), with the buffer layer and without, and the mesh fell back to the core not
    pulled (69.9 % hex volume against 80.3). A moved pyramid's way from its base to its apex now
    keeps clear of the faces, as an inner apex's does."""
    h = 4.441692740424754
    tets, tet_report = hexmerge.mesh_shape(PULLED_PYRAMID_SIDE, h, recombine=False)
    meshing = tet_report["meshing"]
    assert meshing["strategy"] == "lattice" and meshing["failed_strategies"] == []
    assert meshing["nb_pulled_points"] > 0 and meshing["nb_buffer_hexes"] > 0
    cells = tets.cell_vertices.reshape(-1, 4).astype(np.int64)
    mesh, report = hexmerge.recombine(tets.points, cells, tets.regions)
    assert_checked(mesh, tets, report, h)
    assert report["volume_fraction"]["hex"] >= 0.78


@needs_tetgen
def test_tetgen_gets_the_lattice_faces_as_triangles(shapes, tmp_path) -> None:
    """TetGen 1.5 triangulating a lattice face from its loops stopped ("Two segments ... intersect"
    on the thin bracket's base face with the slot at h 0.6, or a failed assertion, depending on
    the vertex each loop started at) or never ended (its flips on the cocircular nodes of straight
    sides: thin_bracket at h 0.574, 297 s of TetGen in four runs past the time limit and 14 GB,
    11 s once the faces went as triangles). Every facet it is given is now a triangle."""
    polys = tmp_path / "polys"
    polys.mkdir()
    fake = tmp_path / "tetgen"
    fake.write_text(f"""#!/bin/sh
for last; do :; done
cp "$last" {polys}/$(ls {polys} | wc -l)-$(basename "$last")
exec {shutil.which("tetgen")} "$@"
""")
    fake.chmod(0o755)
    tets, report = hexmerge.mesh_shape(shapes["bracket"], 3.0, recombine=False, tetgen=str(fake))
    meshing = report["meshing"]
    assert meshing["strategy"] == "lattice" and meshing["nb_tetgen_restarts"] == 0
    assert meshing["nb_lattice_faces"] > 0
    # The points' Delaunay tets first (the diagonals of the cells' cocircular corners), then the
    # complex.
    assert sorted(p.name for p in polys.iterdir()) == ["0-shape.node", "1-shape.poly"]
    poly = polys / "1-shape.poly"
    lines = [line.split() for line in poly.read_text().splitlines()]
    at = int(lines[0][0]) + 1  # after the points
    polygon_sizes = []
    for _ in range(int(lines[at][0])):
        nb_polygons, nb_holes = int(lines[at + 1][0]), int(lines[at + 1][1])
        polygon_sizes += [int(line[0]) for line in lines[at + 2:at + 2 + nb_polygons]]
        assert nb_holes == 0
        at += 1 + nb_polygons + nb_holes
    assert polygon_sizes and set(polygon_sizes) == {3}
    mesh, rep = hexmerge.recombine(tets.points, tets.cell_vertices.reshape(-1, 4), tets.regions)
    assert_checked(mesh, tets, rep, 3.0)


def test_sizes_that_do_not_fit_in_memory_are_refused_before_any_work(shapes) -> None:
    """The tets are estimated from the shape's volume and area; a size needing more memory than
    the limit (or the system has) is refused at once, with the estimate and a size that fits."""
    started = time.perf_counter()
    with pytest.raises(hexmerge.InputError, match=r"size 0.05 would make about .* million tets, "
                       r"which need about .* GB .*: give a size of at least"):
        hexmerge.mesh_shape(shapes["box"], 0.05)
    with pytest.raises(hexmerge.InputError, match=r"memory_limit is 0.001 GB"):
        hexmerge.mesh_shape(shapes["box"], 2.0, memory_limit=0.001)
    assert time.perf_counter() - started < 10
    with pytest.raises(hexmerge.InputError, match="parameter 'memory_limit' must be between 0 and 1e\\+06 GB"):
        hexmerge.mesh_shape(shapes["box"], 2.0, memory_limit=-1.0)
    # The estimate is within a factor 4 of the tets made (it counts every face as refined to h:
    # shapes of planar lattice faces make fewer).
    for name, h in (("box", 4.0), ("bracket", 3.0), ("cylinder", 3.0)):
        tets, report = hexmerge.mesh_shape(shapes[name], h, recombine=False)
        made, estimated = len(tets.cell_vertices) // 4, report["meshing"]["estimated_tets"]
        assert made / 4 < estimated < 4 * made, (name, made, estimated)


TOUCHING_GEO = """SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 30, 20, 10};
Box(2) = {30, 5, 2, 15, 8, 6};   // touches box 1 over an 8 x 6 patch of its +x face
Cylinder(3) = {10, 10, 10, 0, 0, 12, 6};   // stands on box 1's top face
"""
OVERLAPPING_GEO = """SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 30, 20, 10};
Box(2) = {25, 5, 2, 15, 8, 6};   // 5 mm inside box 1
"""


def test_touching_solids_are_meshed_conformally_one_region_each(tmp_path) -> None:
    """Solids that touch as separate closed shells (a compound, as STEP assemblies and FreeCAD
    compounds arrive) are glued: a conforming mesh, one region per solid, each region's volume
    that of its solid."""
    shape = gmsh_brep(tmp_path, "touching", TOUCHING_GEO)
    h = 2.0
    tets, report = hexmerge.mesh_shape(shape, h, recombine=False)
    meshing = report["meshing"]
    assert meshing["nb_solids"] == 3 and meshing["nb_shared_faces"] == 2
    mesh, rep = hexmerge.recombine(tets.points, tets.cell_vertices.reshape(-1, 4), tets.regions)
    assert_checked(mesh, tets, rep, h)
    cells = tets.cell_vertices.reshape(-1, 4)
    p = tets.points[cells]
    volumes = np.einsum("ij,ij->i", np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), p[:, 3] - p[:, 0]) / 6
    assert (volumes > 0).all()
    expected = [30 * 20 * 10, 15 * 8 * 6, np.pi * 36 * 12]
    for region, volume in enumerate(expected):
        got = volumes[tets.regions == region].sum()
        assert abs(got - volume) < 0.01 * volume, (region, got, volume)
    # The regions come from the triangles on the faces; classifying every tet by geometry agrees.
    by_geometry, _ = hexmerge.regions_by_solid(shape.read_text(), tets.points, cells, classify_every_tet=True)
    assert np.array_equal(by_geometry, tets.regions)
    # No face between two regions is a boundary face: every interface triangle has a tet on
    # each side (the mesh is one conforming piece).
    faces = np.sort(np.concatenate([cells[:, [1, 2, 3]], cells[:, [0, 2, 3]], cells[:, [0, 1, 3]],
                                    cells[:, [0, 1, 2]]]), axis=1)
    _, counts = np.unique(faces, axis=0, return_counts=True)
    assert counts.max() == 2
    # The outer boundary: the boxes' faces less the patch they share (on both), the cylinder's
    # side and top (its bottom is box 1's, taken from box 1's top).
    boundary_area_expected = (2 * (30 * 20 + 30 * 10 + 20 * 10) + 2 * (15 * 8 + 15 * 6 + 8 * 6) - 2 * 8 * 6
                              + 2 * np.pi * 6 * 12)
    unique, counts = np.unique(faces, axis=0, return_counts=True)
    q = tets.points[unique[counts == 1]]
    area = 0.5 * np.linalg.norm(np.cross(q[:, 1] - q[:, 0], q[:, 2] - q[:, 0]), axis=1).sum()
    assert abs(area - boundary_area_expected) < 0.01 * boundary_area_expected, (area, boundary_area_expected)


# A box with two voids inside it, a ball and a box (closed shells of their own, no opening).
VOIDS_GEO = """SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 40, 30, 20};
Sphere(2) = {20, 15, 10, 6};
Box(3) = {5, 5, 5, 6, 6, 6};
BooleanDifference{ Volume{1}; Delete; }{ Volume{2, 3}; Delete; }
"""
# Two boxes that touch and, between them, enclose a void: a U and a lid on it.
ENCLOSED_BETWEEN_GEO = """SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 30, 20, 10};
Box(2) = {5, 5, 4, 20, 10, 6};
BooleanDifference{ Volume{1}; Delete; }{ Volume{2}; Delete; }
Box(3) = {0, 0, 10, 30, 20, 4};
"""


@pytest.mark.parametrize("name, h, volumes", [
    ("voids", 4.0, [40 * 30 * 20 - 4 / 3 * np.pi * 216 - 216]),
    ("voids", 2.0, [40 * 30 * 20 - 4 / 3 * np.pi * 216 - 216]),
    ("enclosed_between", 2.0, [30 * 20 * 10 - 20 * 10 * 6, 30 * 20 * 4]),
])
def test_voids_the_solids_enclose_stay_empty(tmp_path, name: str, h: float, volumes: list) -> None:
    """TetGen carves the outside away from the convex hull only: a void inside a solid, or
    between solids, was filled with tets (FreeCAD's electrostatics example, a ball less two
    balls inside it: 1,008 tets under scaled Jacobian 0.2 in the small balls at h 357, and their
    volume in the mesh). Those tets go; each region keeps its solid's volume."""
    geo = VOIDS_GEO if name == "voids" else ENCLOSED_BETWEEN_GEO
    shape = gmsh_brep(tmp_path, name, geo)
    tets, report = hexmerge.mesh_shape(shape, h, recombine=False)
    assert report["meshing"]["nb_void_tets"] > 0
    cells = tets.cell_vertices.reshape(-1, 4).astype(np.int64)
    assert np.isin(np.arange(len(tets.points)), cells).all()  # every node in a tet
    p = tets.points[cells]
    volume = np.einsum("ij,ij->i", np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), p[:, 3] - p[:, 0]) / 6
    assert (volume > 0).all()
    for region, expected in enumerate(volumes):
        got = volume[tets.regions == region].sum()
        assert abs(got - expected) < 0.005 * expected, (region, got, expected)
    centroid = p.mean(axis=1)
    if name == "voids":
        in_ball = np.linalg.norm(centroid - [20, 15, 10], axis=1) < 5.5
        in_box = (np.abs(centroid - 8) < 2.9).all(axis=1)
    else:
        in_box = ((np.abs(centroid - [15, 10, 7]) < [9.9, 4.9, 2.9])).all(axis=1)
        in_ball = np.zeros_like(in_box)
    assert not in_ball.any() and not in_box.any()
    mesh, rep = hexmerge.recombine(tets.points, cells, tets.regions)
    result = assert_checked(mesh, tets, rep, h)
    assert result["min_scaled_jacobian"] >= 0.2


def test_overlapping_solids_are_refused_by_name(tmp_path) -> None:
    shape = gmsh_brep(tmp_path, "overlapping", OVERLAPPING_GEO)
    with pytest.raises(hexmerge.InputError, match=r"Solid1 and Solid2 of the shape overlap \(common volume 240"):
        hexmerge.mesh_shape(shape, 2.0)


def test_bad_flags(shapes) -> None:
    with pytest.raises(ValueError, match="unknown option 'no_such_option'"):
        hexmerge.mesh_shape(shapes["box"], 10.0, no_such_option=1)
    with pytest.raises(ValueError, match="need recombine=True"):
        hexmerge.mesh_shape(shapes["box"], 10.0, recombine=False, min_dihedral_angle=140)
    with pytest.raises(ValueError, match="second_order must be True or False"):
        hexmerge.mesh_shape(shapes["box"], 10.0, second_order="yes")


# ---- the command line -------------------------------------------------------------------------

meshio = pytest.importorskip("meshio")


def main(argv: list[str]) -> int:
    """cli.main's exit code, argparse's own errors (SystemExit) included."""
    try:
        return cli.main(argv)
    except SystemExit as e:
        return int(e.code)


@needs_tetgen
def test_cli_mesh(shapes, tmp_path, capsys) -> None:
    out, tets, stats = tmp_path / "bracket.msh", tmp_path / "bracket-tets.vtu", tmp_path / "r.json"
    assert cli.main(["mesh", str(shapes["bracket"]), "-h", "4", "-o", str(out), "--stats", str(stats)]) == 0
    line = capsys.readouterr().out
    for text in ("tets", "hex volume", "reduction", "non-conforming quads",
                 "min scaled Jacobian", "max boundary distance", " s -> "):
        assert text in line, line
    assert "swept" not in line  # the bracket is no extrusion
    report = json.loads(stats.read_text())
    assert report["size"] == 4.0 and report["report"]["meshing"]["tets"] == report["report"]["input_tets"]
    assert cli.main(["mesh", str(shapes["bracket"]), "-h", "4", "-o", str(tets), "--tets-only"]) == 0
    capsys.readouterr()
    # The independent checker on the files: the mixed mesh against the tets.
    assert cli.main(["check", str(out), "--source", str(tets)]) == cli.EXIT_OK
    assert "valid" in capsys.readouterr().out
    written = meshio.read(out)
    assert {c.type for c in written.cells} <= {"tetra", "pyramid", "wedge", "hexahedron"}
    assert (np.concatenate(written.cell_data["gmsh:physical"]) == 1).all()  # solid 1


@needs_tetgen
def test_cli_mesh_options(shapes, tmp_path, capsys) -> None:
    out, stats = tmp_path / "plate.vtu", tmp_path / "r.json"
    args = ["mesh", str(shapes["plate"]), "-h", "10", "-o", str(out), "--second-order", "--layers", "0",
            "--frame", "global", "--no-sweep", "--min-scaled-jacobian", "0.2", "--stats",
            str(stats), "-q"]
    assert cli.main(args) == 0
    assert capsys.readouterr().out == ""
    report = json.loads(stats.read_text())
    assert report["mesh_options"] == {"boundary_layers": 0, "frame": "global", "sweep": False}
    assert report["report"]["meshing"]["sweep_axis"] == -1  # the plate is an extrusion
    assert report["options"] == {"min_scaled_jacobian": 0.2}
    assert report["order"] == 2
    types = {c.type for c in meshio.read(out).cells}
    assert types <= {"tetra10", "pyramid13", "wedge15", "hexahedron20"} and "hexahedron20" in types
    assert cli.main(["mesh", str(shapes["plate"]), "-h", "10", "-o", str(tmp_path / "swept.vtu")]) == 0
    assert "tets swept along lattice axis 2," in capsys.readouterr().out


@pytest.mark.parametrize(
    ("args", "code", "message"),
    [
        (["-h", "0"], cli.EXIT_USAGE, "the size must be a positive length"),
        (["-h", "ten"], cli.EXIT_USAGE, "not a number"),
        (["-h", "4", "--tets-only", "--min-dihedral-angle", "140"], cli.EXIT_USAGE, "--tets-only"),
        (["-h", "500"], cli.EXIT_ERROR, "larger than the shape"),
        (["-h", "4", "--tetgen", "/nonexistent/tetgen"], cli.EXIT_ERROR, "not found"),
        (["-h", "4", "--layers", "9"], cli.EXIT_ERROR, "parameter 'boundary_layers' must be between -1 and 3"),
    ],
)
def test_cli_mesh_errors(shapes, tmp_path, capsys, args, code, message) -> None:
    out = tmp_path / "out.msh"
    assert main(["mesh", str(shapes["bracket"]), "-o", str(out), *args]) == code
    err = capsys.readouterr().err
    assert message in err and err.strip().splitlines()[-1].startswith("hexmerge")
    assert not out.exists()


@pytest.mark.parametrize(("shape", "message"), [("open_solid", "open shell"), ("face", "holds no solid")])
def test_cli_mesh_bad_shapes(shapes, tmp_path, capsys, shape, message) -> None:
    out = tmp_path / "out.msh"
    assert main(["mesh", str(shapes[shape]), "-h", "2", "-o", str(out)]) == cli.EXIT_ERROR
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and message in err and str(shapes[shape]) in err
    assert not out.exists()


def test_cli_parameters_mesh(capsys) -> None:
    assert cli.main(["parameters", "--mesh", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert [r["name"] for r in rows] == [r["name"] for r in hexmerge.mesh_parameters()]
    assert cli.main(["parameters", "--mesh"]) == 0
    assert "--layers:" in capsys.readouterr().out


def quadratic_volume(points: np.ndarray, tets10: np.ndarray) -> float:
    """Volume of a Tet10 mesh with curved edges: (1/3) of the flux of x through its boundary
    Tri6 faces (x . (x_u x x_v) is of degree 4 in the face's parameters; a degree-4 rule is exact)."""
    faces = np.concatenate([tets10[:, [1, 2, 3, 5, 9, 8]], tets10[:, [0, 3, 2, 7, 9, 6]],
                            tets10[:, [0, 1, 3, 4, 8, 7]], tets10[:, [0, 2, 1, 6, 5, 4]]])
    key = np.sort(faces[:, :3], axis=1)
    _, first, count = np.unique(key, axis=0, return_index=True, return_counts=True)
    x = points[faces[first[count == 1]]]  # (F, 6, 3): corners a b c, mids ab bc ca
    a, b = 0.445948490915965, 0.091576213509771
    rule = [(a, a, 0.223381589678011), (1 - 2 * a, a, 0.223381589678011), (a, 1 - 2 * a, 0.223381589678011),
            (b, b, 0.109951743655322), (1 - 2 * b, b, 0.109951743655322), (b, 1 - 2 * b, 0.109951743655322)]
    flux = 0.0
    for u, v, w in rule:
        s = 1 - u - v  # Tri6 shape functions in (u, v): corner a at u = v = 0, b at u = 1, c at v = 1
        n = [s * (2 * s - 1), u * (2 * u - 1), v * (2 * v - 1), 4 * s * u, 4 * u * v, 4 * v * s]
        du = [-(4 * s - 1), 4 * u - 1, 0, 4 * (s - u), 4 * v, -4 * v]
        dv = [-(4 * s - 1), 0, 4 * v - 1, -4 * u, 4 * u, 4 * (s - v)]
        p = np.einsum("k,fkc->fc", n, x)
        pu = np.einsum("k,fkc->fc", du, x)
        pv = np.einsum("k,fkc->fc", dv, x)
        flux += 0.5 * w * np.einsum("fc,fc->", p, np.cross(pu, pv))
    return flux / 3.0


@needs_tetgen
def test_second_order_boundary_mid_nodes_on_the_cad(shapes) -> None:
    """Second order from CAD: every boundary mid-edge node of the cylinder (r 20, height 100) lies
    on its surface (the wall: at the radius), the inner ones at their edges' midpoints; the
    volume is nearer the cylinder's than with straight edges; the recombined mesh checks."""
    for h, options in ((5.0, {}), (5.0, {"sweep": False})):
        tets10, report = hexmerge.mesh_shape(shapes["cylinder"], h, recombine=False, second_order=True,
                                             **options)
        meshing = report["meshing"]
        cells = tets10.cells("tetra10").astype(np.int64)
        points = tets10.points
        faces = np.sort(np.concatenate([cells[:, [1, 2, 3]], cells[:, [0, 3, 2]], cells[:, [0, 1, 3]],
                                        cells[:, [0, 2, 1]]]), axis=1)
        unique, count = np.unique(faces, axis=0, return_counts=True)
        outer = unique[count == 1]
        boundary_edges = {tuple(sorted(e)) for f in outer for e in ((f[0], f[1]), (f[1], f[2]), (f[0], f[2]))}
        mid_of = {}
        for k, (i, j) in enumerate(EDGES["tetra10"]):
            for a, b, m in zip(cells[:, i], cells[:, j], cells[:, 4 + k]):
                mid_of[(min(a, b), max(a, b))] = m
        on_boundary = np.array([e in boundary_edges for e in mid_of])
        ends = np.array(list(mid_of.keys()))
        mids = points[np.array(list(mid_of.values()))]
        straight = 0.5 * (points[ends[:, 0]] + points[ends[:, 1]])
        # Inside: the midpoint, exactly.
        assert np.array_equal(mids[~on_boundary], straight[~on_boundary])
        # On the boundary: on the CAD, none kept straight on this shape.
        assert meshing["nb_straight_mid_nodes"] == 0
        assert meshing["nb_projected_mid_nodes"] == int(on_boundary.sum())
        assert SURFACES["cylinder"](mids[on_boundary]).max() < 1e-6 * 20
        r_ends = np.hypot(points[ends[:, 0], 0], points[ends[:, 0], 1]), np.hypot(points[ends[:, 1], 0],
                                                                                    points[ends[:, 1], 1])
        z = mids[:, 2]
        wall = on_boundary & (np.abs(r_ends[0] - 20) < 1e-9) & (np.abs(r_ends[1] - 20) < 1e-9) \
            & (np.abs(z) > 1e-9) & (np.abs(z - 100) > 1e-9)
        assert wall.sum() > 100
        assert np.allclose(np.hypot(mids[wall, 0], mids[wall, 1]), 20, rtol=1e-6, atol=0)
        # The straight midpoints of the wall's edges around it are inside (chords): those moved.
        assert (np.hypot(straight[wall, 0], straight[wall, 1]) < 20 - 1e-3).sum() > 100
        # Volume: the curved Tet10 mesh is nearer the cylinder's than the straight one.
        exact = np.pi * 20**2 * 100
        straight_points = points.copy()
        straight_points[np.array(list(mid_of.values()))] = straight
        curved_error = abs(quadratic_volume(points, cells) - exact)
        straight_error = abs(quadratic_volume(straight_points, cells) - exact)
        assert curved_error < 0.1 * straight_error, (curved_error, straight_error)
        # The same corners and tets as in first order.
        linear, _ = hexmerge.mesh_shape(shapes["cylinder"], h, recombine=False, **options)
        corners = linear.nb_points
        assert np.array_equal(points[:corners], linear.points)
        assert np.array_equal(cells[:, :4], linear.cell_vertices.reshape(-1, 4))
        # Recombined: quadratic cells on the same nodes, passing the checker.
        mesh, _ = hexmerge.mesh_shape(shapes["cylinder"], h, second_order=True, **options)
        assert mesh.order == 2 and "hexahedron20" in {b.type for b in mesh}
        assert np.array_equal(mesh.points, points[mesh.point_map])  # the nodes it uses, unmoved
        result = hexmerge.check(mesh, points, cells, tets10.regions)
        assert result["valid"], result["problems"]
        assert result["nonconforming_quads"] == 0 and result["cracks"] == 0
        assert result["inverted_cells"] == 0


# An assembly exported as one file per part: the file itself holds only the references.
EXTERNAL_PARTS_STEP = """ISO-10303-21;
HEADER;
FILE_DESCRIPTION(('assembly of two parts in their own files'),'2;1');
FILE_NAME('asm.stp','2026-12-07T00:00:00',(''),(''),'','','');
FILE_SCHEMA(('AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }'));
ENDSEC;
DATA;
#1=APPLICATION_CONTEXT('automotive design');
#2=PRODUCT_CONTEXT('',#1,'mechanical');
#3=PRODUCT('asm','asm','',(#2));
#4=PRODUCT_DEFINITION_FORMATION('','',#3);
#5=PRODUCT_DEFINITION_CONTEXT('part definition',#1,'design');
#6=PRODUCT_DEFINITION('design','',#4,#5);
#7=DOCUMENT_TYPE('geometry');
#8=DOCUMENT_FILE('left_part.stp','','',#7,'',$);
#9=DOCUMENT_FILE('right_part.stp','','',#7,'',$);
#10=DOCUMENT_FILE('left_part.stp','','',#7,'',$);
ENDSEC;
END-ISO-10303-21;
"""


def test_a_step_file_whose_parts_are_in_other_files_is_refused_naming_them(tmp_path) -> None:
    """A STEP assembly exported one file per part (the CAX-IF s1 model's FOOT.stp names
    FOOT_FRONT_000.stp and FOOT_BACK_000.stp) holds no shape: the error says which files hold
    its parts, each once, in the order the file names them."""
    path = tmp_path / "asm.stp"
    path.write_text(EXTERNAL_PARTS_STEP)
    with pytest.raises(hexmerge.InputError) as error:
        hexmerge.mesh_shape(path, 5.0)
    assert str(error.value).endswith(
        "asm.stp: the STEP file holds no shape: its parts are in other files (left_part.stp, "
        "right_part.stp), which it only names; mesh those, or export the assembly with its parts "
        "in one file")
    # A STEP file with no shape and no such reference: the plain message.
    path.write_text(EXTERNAL_PARTS_STEP.replace("DOCUMENT_FILE", "DOCUMENT_FILE_NOT"))
    with pytest.raises(hexmerge.InputError, match=r"the STEP file holds no shape$"):
        hexmerge.mesh_shape(path, 5.0)


INCH_UNIT = ("#9000 = ( LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT(.MILLI.,.METRE.) );\n"
             "#9001 = LENGTH_MEASURE_WITH_UNIT(LENGTH_MEASURE(25.4),#9000);\n"
             "#9002 = DIMENSIONAL_EXPONENTS(1.,0.,0.,0.,0.,0.,0.);\n")


@needs_tetgen
def test_a_step_file_in_inches_is_said_to_be_read_in_millimetres(tmp_path, capsys) -> None:
    """OpenCASCADE reads STEP files in millimetres whatever unit they declare; the report, the
    CLI and any error about the size say so (a user thinking in inches gave -h in inches)."""
    if shutil.which("gmsh") is None:
        pytest.skip("gmsh is not installed")
    mm = tmp_path / "box.step"
    subprocess.run(["gmsh", "-0", str(GEOMETRY / "box.geo"), "-o", str(mm)], check=True, capture_output=True)
    text = mm.read_text()
    unit = re.search(r"^(#\d+) = \( LENGTH_UNIT\(\) NAMED_UNIT\(\*\) SI_UNIT\(\.MILLI\.,\.METRE\.\) \);$", text, re.M)
    assert unit, "Gmsh's STEP length unit line not found"
    inch = tmp_path / "box_inch.step"
    inch.write_text(text.replace(unit.group(0), f"{unit.group(1)} = ( CONVERSION_BASED_UNIT('INCH',#9001) "
                                 "LENGTH_UNIT() NAMED_UNIT(#9002) );\n" + INCH_UNIT))
    assert _core.read_shape_file(str(mm), with_unit=True)[1].lower() == "millimetre"
    assert _core.read_shape_file(str(inch), with_unit=True)[1] == "INCH"
    tets, report = hexmerge.mesh_shape(mm, 10.0, recombine=False)
    assert not report["meshing"]["converted_to_millimetres"]
    box_mm = tets.points.max(axis=0) - tets.points.min(axis=0)
    tets, report = hexmerge.mesh_shape(inch, 254.0, recombine=False)
    assert report["meshing"]["file_length_unit"] == "INCH" and report["meshing"]["converted_to_millimetres"]
    np.testing.assert_allclose(tets.points.max(axis=0) - tets.points.min(axis=0), 25.4 * box_mm, rtol=1e-9)
    with pytest.raises(hexmerge.InputError, match=r"the file declares its lengths in INCH: the shape is read "
                       r"in millimetres, and so is the size"):
        hexmerge.mesh_shape(inch, 0.5)
    capsys.readouterr()
    assert main(["mesh", str(inch), "-h", "254", "-o", str(tmp_path / "b.vtu"), "--tets-only"]) == 0
    err = capsys.readouterr().err
    assert "note: the file declares its lengths in INCH: the shape is read in millimetres" in err, err

