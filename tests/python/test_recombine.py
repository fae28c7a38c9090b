"""hexmerge.recombine() on meshes built here, and on one Gmsh made (tests/data): merge results and
invariants of the output."""

from __future__ import annotations

import os
import threading

import numpy as np
import pytest

import hexmerge
from meshes import cell_volumes, cube_points, five_tets, grid, kuhn_tets, min_corner_determinant, orient, tet_volumes

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data")


def assert_sound(mesh: hexmerge.MixedMesh, points: np.ndarray, tets: np.ndarray, regions=None) -> None:
    """Invariants of every output: oriented cells, volume kept, source tets a partition of the
    input whose corners are the cell's, regions kept, and the independent checker agrees."""
    total = 0.0
    for block in mesh.cell_blocks(quadratic=False):
        assert (min_corner_determinant(mesh.points, block.type, block.data) > 0).all(), block.type
        total += cell_volumes(mesh.points, block.type, block.data).sum()
    assert total == pytest.approx(tet_volumes(points, tets).sum(), rel=1e-9)
    src = mesh.source_tets.astype(np.int64)
    assert np.array_equal(np.sort(src), np.arange(len(tets)))
    for c in range(mesh.nb_cells):
        own = tets[src[mesh.source_offsets[c] : mesh.source_offsets[c + 1]]]
        corners = mesh.cell_vertices[mesh.offsets[c] : mesh.offsets[c + 1]]
        assert set(own.reshape(-1)) == set(corners.tolist())
        if regions is not None:
            assert set(regions[src[mesh.source_offsets[c] : mesh.source_offsets[c + 1]]]) == {mesh.regions[c]}
    report = hexmerge.check(mesh, points, tets, regions)
    assert report["valid"], report["problems"]


@pytest.mark.parametrize("name", ["kuhn", "five-even", "five-odd"])
def test_one_cube_gives_one_hex(name: str) -> None:
    points = cube_points()
    corner = list(range(8))
    tets = kuhn_tets(corner) if name == "kuhn" else five_tets(corner, name == "five-odd")
    tets = orient(points, np.array(tets))
    mesh, report = hexmerge.recombine(points, tets)
    assert mesh.counts() == {"tetra": 0, "pyramid": 0, "wedge": 0, "hexahedron": 1}
    assert report["output_counts"]["hex"] == 1
    assert report["input_tets"] == len(tets)
    assert report["element_reduction_percent"] == pytest.approx(100 * (1 - 1 / len(tets)))
    hexa = mesh.cells("hexahedron")[0]
    assert min_corner_determinant(points, "hexahedron", hexa[None])[0] == pytest.approx(1.0)
    assert_sound(mesh, points, tets)


@pytest.mark.parametrize("split", ["kuhn", "five"])
def test_structured_grid_comes_back_all_hex(split: str) -> None:
    points, tets, _ = grid(4, split)
    mesh, report = hexmerge.recombine(points, tets)
    assert mesh.counts()["hexahedron"] == 64 == mesh.nb_cells
    assert report["volume_fraction"]["hex"] == pytest.approx(1.0)
    assert report["nonconforming_quads"] == 0
    assert_sound(mesh, points, tets)


def test_affine_map_and_perturbation_keep_the_hexes() -> None:
    points, tets, _ = grid(3, "kuhn")
    rng = np.random.default_rng(5)
    a = np.array([[1.0, 0.2, 0.1], [0.0, 0.9, 0.15], [0.05, 0.0, 1.1]])
    moved = points @ a.T + rng.uniform(-0.003, 0.003, points.shape)
    tets = orient(moved, tets)
    # The perturbed grid's boundary is no longer flat: boundary quads fold by up to a degree or
    # two, more than the default tolerates on the boundary.
    mesh, _ = hexmerge.recombine(moved, tets, min_boundary_dihedral_angle=170)
    assert mesh.counts()["hexahedron"] == 27
    total = sum(cell_volumes(moved, b.type, b.data).sum() for b in mesh)
    # Quads are no longer flat: the fan volume differs from the tets' by their bending only.
    assert total == pytest.approx(tet_volumes(moved, tets).sum(), rel=1e-3)
    assert hexmerge.check(mesh, moved, tets)["valid"]


def test_regions_are_never_merged_across() -> None:
    points, tets, cube = grid(3, "kuhn")
    # Region boundaries cut through cubes: tets of one cube in two regions.
    regions = (np.arange(len(tets)) % 6 < 3).astype(np.int32) + 1
    mesh, _ = hexmerge.recombine(points, tets, regions)
    assert mesh.counts()["hexahedron"] == 0
    assert_sound(mesh, points, tets, regions)
    # Along cube boundaries: every cube still merges.
    regions = np.where(cube % 3 < 1, 4, 8).astype(np.int32)
    mesh, _ = hexmerge.recombine(points, tets, regions)
    assert mesh.counts()["hexahedron"] == 27
    assert set(mesh.regions.tolist()) == {4, 8}
    assert_sound(mesh, points, tets, regions)


def test_regions_ignored_when_asked() -> None:
    points, tets, _ = grid(2, "kuhn")
    regions = (np.arange(len(tets)) % 2).astype(np.int32)
    mesh, _ = hexmerge.recombine(points, tets, regions, respect_regions=False)
    assert mesh.counts()["hexahedron"] == 8


def test_gmsh_mesh_recombines_soundly(gmsh_tet4) -> None:
    meshio = pytest.importorskip("meshio")
    m = meshio.read(gmsh_tet4)
    tets = m.cells_dict["tetra"]
    regions = np.concatenate([d for d, c in zip(m.cell_data["gmsh:physical"], m.cells) if c.type == "tetra"])
    mesh, report = hexmerge.recombine(m.points, tets, regions)
    assert report["input_tets"] == len(tets)
    assert mesh.nb_cells < len(tets)
    for block in mesh.cell_blocks():
        assert (min_corner_determinant(mesh.points, block.type, block.data) > 0).all()
    src = np.sort(mesh.source_tets.astype(np.int64))
    assert np.array_equal(src, np.arange(len(tets)))
    result = hexmerge.check(mesh, m.points, tets, regions)
    assert result["valid"], result["problems"]


def test_gmsh_mesh_keeps_its_volume(gmsh_tet4) -> None:
    meshio = pytest.importorskip("meshio")
    m = meshio.read(gmsh_tet4)
    tets = m.cells_dict["tetra"]
    mesh, _ = hexmerge.recombine(m.points, tets)
    assert abs(hexmerge.check(mesh, m.points, tets)["relative_volume_difference"]) < 1e-5


def test_element_types_can_be_switched_off() -> None:
    points, tets, _ = grid(2, "kuhn")
    mesh, _ = hexmerge.recombine(points, tets, make_hexahedra=False)
    assert mesh.counts()["hexahedron"] == 0
    assert mesh.counts()["wedge"] > 0
    mesh, _ = hexmerge.recombine(points, tets, make_hexahedra=False, make_prisms=False, make_pyramids=True)
    assert set(np.unique(mesh.types).tolist()) <= {0, 1}


def test_defaults_given_explicitly_change_nothing() -> None:
    points, tets, _ = grid(2, "five")
    defaults = {row["name"]: row["default"] for row in hexmerge.parameters()}
    a, _ = hexmerge.recombine(points, tets)
    b, _ = hexmerge.recombine(points, tets, **defaults)
    assert np.array_equal(a.types, b.types) and np.array_equal(a.cell_vertices, b.cell_vertices)


def test_parameter_table() -> None:
    rows = hexmerge.parameters()
    names = [r["name"] for r in rows]
    assert len(set(names)) == len(names)
    assert {"min_dihedral_angle", "max_face_angle", "min_scaled_jacobian", "conformity"} <= set(names)
    for r in rows:
        assert r["type"] in ("float", "int", "bool", "choice") and r["doc"] and r["label"]
        if r["type"] in ("float", "int"):
            assert r["min"] <= r["default"] <= r["max"]
        if r["type"] == "choice":
            assert r["default"] in r["choices"]
    assert next(r for r in rows if r["name"] == "min_dihedral_angle")["unit"] == "deg"


def test_cell_types_follow_vtk() -> None:
    rows = hexmerge.cell_types()
    assert [(r["value"], r["meshio_name"], r["nb_vertices"], r["vtk_id"]) for r in rows] == [
        (0, "tetra", 4, 10),
        (1, "pyramid", 5, 14),
        (2, "wedge", 6, 13),
        (3, "hexahedron", 8, 12),
    ]
    assert [r["meshio_quadratic_name"] for r in rows] == ["tetra10", "pyramid13", "wedge15", "hexahedron20"]
    assert [r["nb_edges"] for r in rows] == [6, 8, 9, 12]


def test_output_arrays() -> None:
    points, tets, _ = grid(2, "kuhn")
    mesh, _ = hexmerge.recombine(points.tolist(), tets.tolist())  # lists are fine too
    assert mesh.points.dtype == np.float64 and mesh.points.shape == points.shape
    assert mesh.types.dtype == np.uint8
    assert mesh.offsets[0] == 0 and mesh.offsets[-1] == len(mesh.cell_vertices)
    assert len(mesh.source_offsets) == mesh.nb_cells + 1
    assert mesh.regions is None and mesh.order == 1
    assert np.array_equal(mesh.point_map, np.arange(len(points)))
    meshio = pytest.importorskip("meshio")
    m = mesh.to_meshio()
    assert isinstance(m, meshio.Mesh) and m.cells[0].type == "hexahedron"


def test_progress_is_reported_and_can_cancel() -> None:
    points, tets, _ = grid(3, "kuhn")
    calls = []
    hexmerge.recombine(points, tets, progress=lambda phase, f: calls.append((phase, f)))
    assert calls and all(isinstance(p, str) and 0.0 <= f <= 1.0 for p, f in calls)
    with pytest.raises(hexmerge.Cancelled):
        hexmerge.recombine(points, tets, progress=lambda phase, f: False)


def test_an_error_in_the_progress_callback_propagates() -> None:
    points, tets, _ = grid(2, "kuhn")

    def boom(phase: str, fraction: float) -> bool:
        raise ZeroDivisionError("from the callback")

    with pytest.raises(ZeroDivisionError, match="from the callback"):
        hexmerge.recombine(points, tets, progress=boom)


def test_runs_in_threads() -> None:
    """The GIL is released during the core's work: concurrent runs give the same results."""
    points, tets, _ = grid(4, "five")
    results = [None] * 4

    def run(i: int) -> None:
        results[i] = hexmerge.recombine(points, tets, threads=1)[0]

    workers = [threading.Thread(target=run, args=(i,)) for i in range(4)]
    for w in workers:
        w.start()
    for w in workers:
        w.join()
    for r in results:
        assert r is not None and r.counts()["hexahedron"] == 64


def _recombine_with_bound(points, tets, **options):
    """Runs with the optimality bound; skips when the module was built without GLPK."""
    try:
        return hexmerge.recombine(points, tets, optimality_bound=True, **options)
    except hexmerge.InputError as error:
        if "GLPK" in str(error):
            pytest.skip("built without GLPK")
        raise


def test_bound_fields_are_none_unless_asked() -> None:
    points, tets, _ = grid(2, "kuhn")
    _, report = hexmerge.recombine(points, tets)
    for key in ("bound_elements", "bound_best_elements", "bound_proved", "bound_conforming", "gap_percent",
                "hex_volume_bound", "hex_volume_bound_proved"):
        assert report[key] is None


def test_bound_on_a_structured_grid_is_reached() -> None:
    points, tets, _ = grid(3, "kuhn")
    _, report = _recombine_with_bound(points, tets, bound_time_limit=5)
    assert report["bound_elements"] == report["bound_best_elements"] == report["output_cells"] == 27
    assert report["bound_proved"] is True and report["bound_conforming"] is True
    assert report["gap_percent"] == 0.0
    assert report["hex_volume_bound"] == pytest.approx(1.0) and report["hex_volume_bound_proved"] is True
    assert "bound" in report["phase_seconds"]


def test_bound_on_a_gmsh_mesh_is_below_our_count(gmsh_tet4) -> None:
    meshio = pytest.importorskip("meshio")
    m = meshio.read(gmsh_tet4)
    _, report = _recombine_with_bound(m.points, m.cells_dict["tetra"], bound_time_limit=2, conformity="allow")
    assert isinstance(report["bound_proved"], bool) and report["bound_conforming"] is False
    assert 0 < report["bound_elements"] <= report["bound_best_elements"] <= report["output_cells"]
    assert report["gap_percent"] >= 0.0
    expected = 100.0 * (report["output_cells"] - report["bound_elements"]) / report["bound_elements"]
    assert report["gap_percent"] == pytest.approx(expected)
    # Allowed to leave quads open, the selection's hexahedra are one set the volume bound covers.
    assert report["volume_fraction"]["hex"] <= report["hex_volume_bound"] + 1e-9 <= 1.0 + 1e-9


def test_conforming_groups_take_hexahedra_no_pyramid_can_close() -> None:
    """Eight cubes of five tets, the inner node moved and the grid sheared (no cube near-perfect:
    no block): no quad face can be closed by a pyramid, so one at a time (group_size=0) no
    hexahedron conforms; as one group all eight do, and the report counts it."""
    points, tets, _ = grid(2, "five")
    points[13] += [0.1, 0.075, 0.05]  # the inner node, at (0.5, 0.5, 0.5)
    points[:, 0] += 0.5 * points[:, 2]  # no corner square (scaled Jacobian at most 0.894)
    tets = orient(points, tets)
    alone, before = hexmerge.recombine(points, tets, group_size=0)
    assert alone.counts()["hexahedron"] == 0
    assert before["groups"] == before["group_seeds"] == 0
    mesh, report = hexmerge.recombine(points, tets)
    assert mesh.counts()["hexahedron"] == 8 == mesh.nb_cells
    assert (report["groups"], report["group_hexahedra"]) == (1, 8)
    assert report["groups_failed"] == report["groups_capped"] == 0
    check = hexmerge.check(mesh, points, tets)
    assert check["valid"] and check["nonconforming_quads"] == 0 and check["cracks"] == 0
    capped, given_up = hexmerge.recombine(points, tets, group_size=7)
    assert given_up["groups_capped"] > 0 and given_up["groups"] == 0
    assert np.array_equal(capped.cell_vertices, alone.cell_vertices)
    with pytest.raises(ValueError, match="group_size"):
        hexmerge.recombine(points, tets, group_size=-1)


def test_prisms_in_planes_by_chance_leave_the_hexahedra_their_tets() -> None:
    """Gmsh's frontal points (Gmsh 4.13.1, bench/fetch_gmsh.py: `gmsh -3 -clmax 3.4 -setnumber
    Mesh.Algorithm3D 9 -setnumber Mesh.Recombine3DAll 0 bench/geometry/bracket.geo`, 9,774 tets)
    lie in planes over much of the bracket: 55 % of its tets are in prisms with planar quads, as a
    swept mesh's are, but the mesh is no sweep. Taken into the block before the hexahedra (as a
    sweep's must be), they left 12.0 % of the volume in hexahedra (4,775 cells); only those beside
    the block's hexahedra are taken now."""
    data = np.load(os.path.join(DATA, "gmsh_frontal_bracket.npz"))
    points, tets = data["points"], data["tets"].astype(np.int64)
    mesh, report = hexmerge.recombine(points, tets)
    assert report["volume_fraction"]["hex"] > 0.2
    assert mesh.nb_cells < 4700
    check = hexmerge.check(mesh, points, tets)
    assert check["valid"], check["problems"]
    assert check["nonconforming_quads"] == 0 and check["cracks"] == 0
    assert abs(check["relative_volume_difference"]) < 1e-9
