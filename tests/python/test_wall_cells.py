"""hexmerge.mesh_shape(): hexahedra across tube walls (the wall cells, docs/mesher.md step 8b).

A pipe tee with flanges (bench/geometry/flanged_tee.geo: walls 6 mm between coaxial cylinders
of radii 30 and 24, flanges 12 mm thick) meshes at h 5.5 with its walls one cell thick: the
lattice's core fits in the flanges only. Every output goes through the independent checker
against the tet mesh it came from.
"""

from __future__ import annotations

import numpy as np
import pytest

import hexmerge
from real_parts import tet_scaled_jacobians
from test_mesh_shape import GEOMETRY, assert_checked, boundary_nodes, gmsh_brep, needs_tetgen
from test_mesh_shape import pytestmark as mesh_shape_marks

pytestmark = mesh_shape_marks


@pytest.fixture(scope="module")
def tee(tmp_path_factory: pytest.TempPathFactory):
    return gmsh_brep(tmp_path_factory.mktemp("tee"), "flanged_tee", GEOMETRY / "flanged_tee.geo")


def on_tee_walls(p: np.ndarray, h: float) -> np.ndarray:
    """The points near the pipes' cylinders (radii 30 and 24; the run's axis x, the branch's z),
    away from the flanges and the saddle where they meet, and their distances to them."""
    run, branch = np.hypot(p[:, 1], p[:, 2]), np.hypot(p[:, 0], p[:, 1])
    d_run = np.minimum(np.abs(run - 30), np.abs(run - 24))
    d_branch = np.minimum(np.abs(branch - 30), np.abs(branch - 24))
    near_run = (d_run < 0.1 * h) & (np.abs(p[:, 0]) < 80) & ((np.abs(p[:, 0]) > 40) | (p[:, 2] < 0))
    near_branch = (d_branch < 0.1 * h) & (p[:, 2] > 40) & (p[:, 2] < 80)
    return np.where(near_run, d_run, np.where(near_branch, d_branch, np.nan))


@needs_tetgen
def test_a_pipe_tees_walls_get_hexahedra_across_them(tee) -> None:
    """At h 5.512 (its 50k size of the real-parts benchmark): both pipes' walls get cells (1,346
    when measured), their quads in the four cylinders' triangles; every cell a hexahedron of the
    output; 66.0 % hex volume with them, 29.8 % without (buffer_layer=False turns both off); the
    mesh valid and conforming, every tet at 0.2 or more, its volume the shape's to 0.2 %, and the
    boundary on the CAD: the nodes on the pipes' cylinders within 1e-3 h of them."""
    h = 5.512
    tets, tet_report = hexmerge.mesh_shape(tee, h, recombine=False)
    meshing = tet_report["meshing"]
    assert meshing["strategy"] == "lattice" and meshing["failed_strategies"] == []
    assert meshing["nb_walls"] == 2 and meshing["nb_wall_faces"] == 4
    assert meshing["nb_wall_hexes"] >= 1200
    cells = tets.cell_vertices.reshape(-1, 4).astype(np.int64)
    assert tet_scaled_jacobians(tets.points, cells).min() >= 0.15
    assert abs(meshing["mesh_volume"] / meshing["shape_volume"] - 1) < 2e-3
    assert meshing["max_boundary_distance"] <= 1e-3 * h
    distance = on_tee_walls(boundary_nodes(tets), h)
    distance = distance[~np.isnan(distance)]
    assert len(distance) > meshing["nb_wall_hexes"]
    assert distance.max() <= 1e-3 * h

    mesh, report = hexmerge.recombine(tets.points, cells, tets.regions)
    assert_checked(mesh, tets, report, h)
    # Every cell a hexahedron, but those split into pyramids (a face nothing closes).
    assert meshing["nb_split_open_cells"] <= 0.02 * meshing["nb_wall_hexes"]
    assert (report["output_counts"]["hex"]
            >= meshing["nb_core_cells"] + meshing["nb_wall_hexes"] - meshing["nb_split_open_cells"])
    assert report["volume_fraction"]["hex"] >= 0.60

    _, without = hexmerge.mesh_shape(tee, h, buffer_layer=False)
    assert without["meshing"]["nb_wall_hexes"] == 0 and without["meshing"]["nb_walls"] == 0
    assert report["volume_fraction"]["hex"] >= without["volume_fraction"]["hex"] + 0.25


@needs_tetgen
def test_walls_go_before_the_buffer_layer_but_not_where_the_core_stands(tee) -> None:
    """The walls are laid before the buffer layer, which then takes none of their cylinders: at
    h 3.5 (walls 1.7 h thick, the core in places) both pipes keep their cells (5,696 when
    measured; after the buffer layer, which took the cylinders for a few tops, none) and the mesh
    is 77.3 % hexahedra (40.0 % before). At h 3 the core stands in most of the walls: under half
    of a wall's columns clear of it, the wall is left to the core and the buffer layer."""
    tets, report = hexmerge.mesh_shape(tee, 3.5, recombine=False)
    meshing = report["meshing"]
    assert meshing["nb_walls"] == 2 and meshing["nb_wall_hexes"] >= 5000
    cells = tets.cell_vertices.reshape(-1, 4).astype(np.int64)
    mesh, recombined = hexmerge.recombine(tets.points, cells, tets.regions)
    assert_checked(mesh, tets, recombined, 3.5)
    assert recombined["volume_fraction"]["hex"] >= 0.7

    _, coarse_core = hexmerge.mesh_shape(tee, 3.0, recombine=False)
    assert coarse_core["meshing"]["nb_walls"] == 0 and coarse_core["meshing"]["nb_core_cells"] > 0
    assert coarse_core["meshing"]["nb_buffer_hexes"] > 0
