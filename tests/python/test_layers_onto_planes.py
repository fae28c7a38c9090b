# SPDX-License-Identifier: LGPL-2.1-or-later
"""Boundary layers carried onto the planes a curved wall meets at a right angle (issue 15).

A quarter of a thick-walled tube (bore 50, outside 100, length 20; symmetry planes x = 0 and
y = 0, FreeCAD's cylinder of bench/fem_accuracy.py) is swept along z. The bore's layer used to
end before the symmetry planes in a wedge, with a hexahedron of the full depth on the plane, and
CalculiX's first-order hoop stress peaked two nodes from it (docs/fem-accuracy.md). Now every
bore node on a plane has a layer node on that plane at the layer's depth.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import hexmerge
from meshes import cell_volumes
from test_mesh_shape import assert_checked, boundary_nodes, gmsh_brep, needs_tetgen
from test_mesh_shape import pytestmark as mesh_shape_marks

pytestmark = mesh_shape_marks  # the same skips (built without OpenCASCADE)

A, B, LENGTH = 50.0, 100.0, 20.0
QUARTER_TUBE_GEO = f"""SetFactory("OpenCASCADE");
Cylinder(1) = {{0, 0, 0, 0, 0, {LENGTH:g}, {B:g}}};
Cylinder(2) = {{0, 0, 0, 0, 0, {LENGTH:g}, {A:g}}};
Box(3) = {{0, 0, 0, {2 * B:g}, {2 * B:g}, {LENGTH:g}}};
BooleanDifference(4) = {{ Volume{{1}}; Delete; }}{{ Volume{{2}}; Delete; }};
BooleanIntersection(5) = {{ Volume{{4}}; Delete; }}{{ Volume{{3}}; Delete; }};
"""


@pytest.fixture(scope="module")
def quarter_tube(tmp_path_factory: pytest.TempPathFactory):
    return gmsh_brep(tmp_path_factory.mktemp("quarter_tube"), "quarter_tube", QUARTER_TUBE_GEO)


def mesh_volume(mesh: hexmerge.MixedMesh) -> float:
    """The recombined mesh's volume, cell type by cell type."""
    total = 0.0
    for name, cells in mesh.to_meshio().cells_dict.items():
        total += float(np.abs(cell_volumes(mesh.points, name, cells)).sum())
    return total


def plane_layer_depths(points: np.ndarray, h: float) -> tuple[list[float], list[float]]:
    """Per bore node on x = 0 or y = 0: the radial depth of the nearest other node on the same
    plane at the same z within 0.7 h of the bore (nan: none). Also the depths of the layer
    nodes off the planes: per bore node off them, the nearest node along its radius (within
    0.7 h, and within 2 degrees of its angle)."""
    r = np.hypot(points[:, 0], points[:, 1])
    theta = np.degrees(np.arctan2(points[:, 1], points[:, 0]))
    depth = r - A
    bore = np.abs(depth) < 1e-6 * A
    on_plane, off_plane = [], []
    for n in np.flatnonzero(bore):
        same_z = np.abs(points[:, 2] - points[n, 2]) < 1e-6 * LENGTH
        near = same_z & (depth > 1e-6 * A) & (depth < 0.7 * h)
        for axis in (0, 1):
            if abs(points[n, axis]) < 1e-9 * A:
                candidates = near & (np.abs(points[:, axis]) < 1e-9 * A)
                on_plane.append(float(depth[candidates].min()) if candidates.any() else math.nan)
        if abs(points[n, 0]) > 1e-9 * A and abs(points[n, 1]) > 1e-9 * A:
            candidates = near & (np.abs(theta - theta[n]) < 2.0)
            if candidates.any():
                off_plane.append(float(depth[candidates].min()))
    return on_plane, off_plane


@needs_tetgen
@pytest.mark.parametrize(("h", "thickness"), [(8.0, 0.3), (5.0, 0.3), (3.0, 0.3), (5.0, 0.15)])
def test_the_bore_layer_goes_on_onto_the_symmetry_planes(quarter_tube, h: float, thickness: float) -> None:
    tets, report = hexmerge.mesh_shape(quarter_tube, h, recombine=False, layer_thickness=thickness)
    meshing = report["meshing"]
    assert meshing["sweep_axis"] == 2 and meshing["strategy"] == "lattice"
    on_plane, off_plane = plane_layer_depths(tets.points, h)
    # Every slab's plane has bore nodes on both planes.
    assert len(on_plane) >= 2 * (round(LENGTH / h) + 1)
    assert not any(math.isnan(d) for d in on_plane), on_plane
    # The layer on the planes is as deep as the bore's layer elsewhere (its depths vary by up to
    # 10 % from node to node, around layer_thickness h).
    assert len(off_plane) > len(on_plane)
    for depths in (off_plane, on_plane):
        assert 0.89 * thickness * h <= min(depths) and max(depths) <= 1.11 * thickness * h, depths
    # The layer nodes on the planes are nodes of the planes' triangles (TetGen got them as points
    # of those facets, not as points inside).
    p = tets.points
    depth = np.hypot(p[:, 0], p[:, 1]) - A
    layer_on_plane = ((np.abs(p[:, 0]) < 1e-9 * A) | (np.abs(p[:, 1]) < 1e-9 * A)) & \
        (depth > 1e-6 * A) & (depth < 1.11 * thickness * h)
    on_boundary = {tuple(q) for q in np.round(boundary_nodes(tets), 9)}
    assert layer_on_plane.sum() == len(on_plane)
    assert all(tuple(q) in on_boundary for q in np.round(p[layer_on_plane], 9))

    mesh, report = hexmerge.mesh_shape(quarter_tube, h, layer_thickness=thickness)
    result = assert_checked(mesh, tets, report, h)
    assert result["min_scaled_jacobian"] >= 0.3
    # No wedge at the planes: every cell at a bore node on a plane is a hexahedron of the layer.
    p = mesh.points
    depth = np.hypot(p[:, 0], p[:, 1]) - A
    corner = (np.abs(depth) < 1e-6 * A) & ((np.abs(p[:, 0]) < 1e-9 * A) | (np.abs(p[:, 1]) < 1e-9 * A))
    blocks = mesh.to_meshio().cells_dict
    for name, cells in blocks.items():
        at_corner = corner[cells].any(axis=1)
        if name != "hexahedron":
            assert not at_corner.any(), name
        else:
            assert (depth[cells[at_corner]].max(axis=1) <= 1.11 * thickness * h).all()
    # Volume: the tets' (the checker compared the cells with them), against the quarter tube's.
    exact = math.pi / 4 * (B * B - A * A) * LENGTH
    assert abs(mesh_volume(mesh) / exact - 1) < 0.01
