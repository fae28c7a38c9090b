"""hexmerge.mesh_shape() on small features as KiCad's component models have them: a pin in a hole
closer than the chord deflection, faces far narrower than h, wires thinner than h (straight, bent
by a half or a quarter torus), and a cone BRepMesh cannot triangulate. Every output goes through
the independent checker against the tet mesh it came from.
"""

from __future__ import annotations

import numpy as np

import hexmerge
from hexmerge import cli
from conftest import ROOT
from meshes import tet_volumes
from real_parts import tet_scaled_jacobians
from test_mesh_shape import (assert_checked, boundary_nodes, boundary_smallest_angles, gmsh_brep,
                             needs_tetgen)
from test_mesh_shape import pytestmark as mesh_shape_marks

pytestmark = mesh_shape_marks


# A pin in a hole, 0.01 to 0.05 mm apart (two solids), as KiCad's parts hold pads in their
# bodies: at h 1.5 the triangles of the hole (chords on its void side) cross the pin's, whose
# faces come closer than the chord deflection (0.03 mm) there.
PIN_IN_HOLE_GEO = """SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 20, 20, 10};
Cylinder(2) = {10, 10, 0, 0, 0, 10, 5};
BooleanDifference(3) = { Volume{1}; Delete; }{ Volume{2}; Delete; };
Cylinder(4) = {10.02, 10, 0, 0, 0, 10, 4.97};
"""


@needs_tetgen
def test_faces_closer_than_the_chord_deflection_get_finer_triangles_there(tmp_path) -> None:
    """Where the triangles of two faces cross (every way of placing the points failed on it, "a
    smaller size keeps them apart"), the surface is made again with finer sizes at the crossing
    triangles, round by round: the mesh is valid, each solid's region keeps its volume."""
    shape = gmsh_brep(tmp_path, "pin_in_hole", PIN_IN_HOLE_GEO)
    h = 1.5
    tets, report = hexmerge.mesh_shape(shape, h, recombine=False)
    meshing = report["meshing"]
    assert meshing["nb_crossing_refinements"] >= 1  # measured 3
    assert meshing["max_boundary_distance"] <= 1e-3 * h
    t = tets.cell_vertices.reshape(-1, 4).astype(np.int64)
    volumes = tet_volumes(tets.points, t)
    assert volumes.min() > 0
    expected = [20 * 20 * 10 - np.pi * 5**2 * 10, np.pi * 4.97**2 * 10]
    for region, volume in enumerate(expected):
        got = volumes[tets.regions == region].sum()
        assert abs(got - volume) < 0.01 * volume, (region, got, volume)
    mesh, merged = hexmerge.mesh_shape(shape, h)
    assert_checked(mesh, tets, merged, h)


# Two boxes fused with tops 1e-6 apart (the faces left split): a face 1e-6 tall and 10 long
# between them, as KiCad's barrel jack PJ-063BH has one (1e-6 by 8.6 mm).
MICRO_STEP_GEO = """SetFactory("OpenCASCADE");
Geometry.OCCUnionUnify = 0;
Box(1) = {0, 0, 0, 10, 10, 5};
Box(2) = {10, 0, 0, 10, 10, 5.000001};
BooleanUnion(3) = { Volume{1}; Delete; }{ Volume{2}; Delete; };
"""


@needs_tetgen
def test_a_face_far_narrower_than_h_is_merged_away(tmp_path) -> None:
    """Surface nodes within 1e-5 h are one node: the 1e-6 face's triangles were flat (boundary
    angles of 9e-5 degrees, tets of scaled Jacobian 1.9e-6, 204 under 0.2 at h 1)."""
    shape = gmsh_brep(tmp_path, "micro_step", MICRO_STEP_GEO)
    h = 1.0
    tets, report = hexmerge.mesh_shape(shape, h, recombine=False)
    t = tets.cell_vertices.reshape(-1, 4).astype(np.int64)
    assert tet_scaled_jacobians(tets.points, t).min() >= 0.2  # measured 0.215
    assert boundary_smallest_angles(tets).min() >= 10.0  # measured 19.8
    assert report["meshing"]["max_boundary_distance"] <= 1e-5 * h
    volumes = tet_volumes(tets.points, t)
    assert abs(volumes.sum() - (1000 + 100 * 1e-6)) < 1e-5  # the CAD's volume, to 1e-8
    mesh, merged = hexmerge.mesh_shape(shape, h)
    assert_checked(mesh, tets, merged, h)


# A wire of radius 0.4 bent into a U (two rods and a half torus), as KiCad's axial parts have
# their leads.
U_WIRE_GEO = """SetFactory("OpenCASCADE");
Cylinder(1) = {0, 0, 0, 0, 0, 10, 0.4};
Torus(2) = {1.5, 0, 10, 1.5, 0.4, Pi};
Rotate {{1, 0, 0}, {1.5, 0, 10}, Pi/2} { Volume{2}; }
Cylinder(3) = {3, 0, 0, 0, 0, 10, 0.4};
BooleanUnion(4) = { Volume{1}; Delete; }{ Volume{2, 3}; Delete; };
"""


@needs_tetgen
def test_points_on_the_axes_of_wires_thinner_than_h(tmp_path) -> None:
    """Tubes thinner than 0.75 h get points on their axes; without them TetGen joined the
    wire's own surface nodes across it (at h 0.6: min scaled Jacobian 0.091, 146 tets under
    0.2)."""
    shape = gmsh_brep(tmp_path, "u_wire", U_WIRE_GEO)
    h = 0.6
    tets, report = hexmerge.mesh_shape(shape, h, recombine=False)
    assert report["meshing"]["nb_axis_points"] > 0  # measured 21
    quality = tet_scaled_jacobians(tets.points, tets.cell_vertices.reshape(-1, 4).astype(np.int64))
    assert quality.min() >= 0.2  # measured 0.2105
    assert report["meshing"]["max_boundary_distance"] <= 1e-3 * h
    mesh, merged = hexmerge.mesh_shape(shape, h)
    assert_checked(mesh, tets, merged, h)


# A wire of radius 0.4 bent by a quarter torus (centre circle of radius 1.5 about (1.5, 0, 10) in
# the plane y = 0) from a rod along z at x = 3 to a rod along -x at z = 11.5, as KiCad's vertical
# axial parts have their leads.
L_WIRE_GEO = """SetFactory("OpenCASCADE");
Cylinder(1) = {3, 0, 0, 0, 0, 10, 0.4};
Torus(2) = {1.5, 0, 10, 1.5, 0.4, Pi/2};
Rotate {{1, 0, 0}, {1.5, 0, 10}, Pi/2} { Volume{2}; }
Cylinder(3) = {1.5, 0, 11.5, -10, 0, 0, 0.4};
BooleanUnion(4) = { Volume{1}; Delete; }{ Volume{2, 3}; Delete; };
"""


@needs_tetgen
def test_points_on_the_centre_circle_of_a_bent_wire(tmp_path) -> None:
    """A torus bent by less than half a turn gets points on its centre circle too, and the
    points lie h / 2 apart: with points h apart on the rods only, at h 0.9 15 tets were under
    scaled Jacobian 0.2 (min 0.147), at h 0.7 261 (min 0.083)."""
    shape = gmsh_brep(tmp_path, "l_wire", L_WIRE_GEO)
    h = 0.9
    tets, report = hexmerge.mesh_shape(shape, h, recombine=False)
    points = tets.points
    # Within half the radius of the bend's centre circle (the sliver stage moves them a little;
    # the surface's nodes are a radius away).
    off_circle = np.hypot(np.hypot(points[:, 0] - 1.5, points[:, 2] - 10) - 1.5, points[:, 1])
    in_bend = (off_circle < 0.2) & (points[:, 0] > 1.5) & (points[:, 2] > 10)
    # The quarter circle, 2.36 long, in pieces of h / 2: measured 8 (4 without: the sliver
    # stage's own).
    assert in_bend.sum() >= 6
    quality = tet_scaled_jacobians(points, tets.cell_vertices.reshape(-1, 4).astype(np.int64))
    assert quality.min() >= 0.2  # measured 0.227
    assert report["meshing"]["max_boundary_distance"] <= 1e-3 * h
    mesh, merged = hexmerge.mesh_shape(shape, h)
    assert_checked(mesh, tets, merged, h)


# A box with a step 0.002 high along a diagonal of its top face (a triangular plate fused on
# it): faces far narrower than any mesh of size h, as KiCad's models have them.
TINY_STEP_GEO = """SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 10, 10, 10};
Point(101) = {0, 0, 10}; Point(102) = {10, 0, 10}; Point(103) = {0, 10, 10};
Line(101) = {101, 102}; Line(102) = {102, 103}; Line(103) = {103, 101};
Curve Loop(101) = {101, 102, 103}; Plane Surface(101) = {101};
Extrude {0, 0, 0.002} { Surface{101}; }
BooleanUnion(3) = { Volume{1}; Delete; }{ Volume{2}; Delete; };
"""


@needs_tetgen
def test_faces_far_narrower_than_h_are_merged_away(tmp_path) -> None:
    """The step's diagonal wall, 0.002 high (6.7e-4 h at h 3, under 9e-4 h), is merged away: its
    nodes and those near them become one (the box's sides, which the step's other walls joined,
    lose their notch), and the boundary stays within that of the CAD. Kept, its triangles had
    angles of 0.07 degrees and 85 tets were under scaled Jacobian 0.2 (min 0.0015)."""
    shape = gmsh_brep(tmp_path, "tiny_step", TINY_STEP_GEO)
    h = 3.0
    tets, report = hexmerge.mesh_shape(shape, h, recombine=False)
    meshing = report["meshing"]
    assert meshing["nb_narrow_faces"] == 1
    t = tets.cell_vertices.reshape(-1, 4).astype(np.int64)
    assert tet_scaled_jacobians(tets.points, t).min() >= 0.2  # measured 0.308
    assert boundary_smallest_angles(tets).min() >= 20.0  # measured 31.0
    assert meshing["max_boundary_distance"] <= 9e-4 * h  # measured 6.7e-4 h
    # The step's volume (0.1) is within the merge: the box's, or the box's and the step's.
    assert 1000 - 1e-9 <= tet_volumes(tets.points, t).sum() <= 1000.1 + 1e-9
    mesh, merged = hexmerge.mesh_shape(shape, h)
    assert_checked(mesh, tets, merged, h)
    # At h 2 the wall is 1e-3 h high: kept as a face.
    assert hexmerge.mesh_shape(shape, 2.0, recombine=False)[1]["meshing"]["nb_narrow_faces"] == 0


# A cone (base radius 1.5 at z = 1.5, apex at z = 2.4013) closed by a disc, its apex a degenerated
# edge and its face's parameters running from -pi to pi, as a cone of a KiCad connector model
# (AMASS XT60, from Debian's kicad-packages3d) has them: valid CAD (OpenCASCADE's checker passes
# it, Gmsh meshes it) on which BRepMesh makes no triangle at any deflection. Written by
# OpenCASCADE from a cone face and a disc made of its base edges.
APEX_CONE = ROOT / "tests" / "data" / "apex_cone.brep"
APEX_CONE_VOLUME = np.pi * 1.5**2 * (2.40129092854134 - 1.5) / 3


def apex_cone_distance(p: np.ndarray) -> np.ndarray:
    """Distance to the cone's side or its base."""
    r, z = np.hypot(p[:, 0], p[:, 1]), p[:, 2]
    height = 2.40129092854134 - 1.5
    slant = np.hypot(1.5, height)
    side = np.abs(r * height + (z - 1.5) * 1.5 - 1.5 * height) / slant
    return np.minimum(side, np.abs(z - 1.5))


@needs_tetgen
def test_a_face_brepmesh_cannot_triangulate_is_meshed_as_a_surface_of_revolution(tmp_path, capsys) -> None:
    """BRepMesh leaves the cone's face without triangles (the error was "OpenCASCADE could not
    triangulate face 0"): the shape is triangulated again with the cone as a surface of
    revolution, the same geometry; the mesh is valid, its boundary on the cone and the disc, its
    volume the cone's, and the report and the command line say what was done."""
    shape = APEX_CONE
    h = 0.25
    tets, report = hexmerge.mesh_shape(shape, h, recombine=False)
    assert report["meshing"]["nb_revolution_faces"] == 1
    assert apex_cone_distance(boundary_nodes(tets)).max() <= 1e-3 * h
    t = tets.cell_vertices.reshape(-1, 4).astype(np.int64)
    volumes = tet_volumes(tets.points, t)
    assert volumes.min() > 0
    assert abs(volumes.sum() - APEX_CONE_VOLUME) < 0.01 * APEX_CONE_VOLUME
    mesh, merged = hexmerge.mesh_shape(shape, h)
    assert_checked(mesh, tets, merged, h)
    capsys.readouterr()
    assert cli.main(["mesh", str(shape), "-h", str(h), "-o", str(tmp_path / "cone.vtu")]) == 0
    err = capsys.readouterr().err
    assert "note: OpenCASCADE's surface mesher left a face of the shape without triangles" in err, err
