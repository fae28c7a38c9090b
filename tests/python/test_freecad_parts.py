"""hexmerge.mesh_shape() on CAD parts that FreeCAD ships (Debian's freecad-common: the IDF
library's STEP models of electronic packages, /usr/share/freecad/Mod/Idf/Idflibs), parts the
mesher was not developed on (issue 13). Skipped where FreeCAD's data is not installed.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import hexmerge
from conftest import MESHES_SHAPES
from real_parts import tet_scaled_jacobians

IDF = Path("/usr/share/freecad/Mod/Idf/Idflibs")

pytestmark = [
    *MESHES_SHAPES,
    pytest.mark.skipif(not IDF.is_dir(), reason=f"FreeCAD's IDF library is not at {IDF} "
                       "(Debian package freecad-common)"),
]


def mesh_and_check(path: Path, h: float):
    """The tets, their report, their scaled Jacobians, and the checker's verdict on their
    recombination."""
    tets, report = hexmerge.mesh_shape(path, h, recombine=False)
    cells = tets.cell_vertices.reshape(-1, 4).astype(np.int64)
    mesh, _ = hexmerge.recombine(tets.points, cells, tets.regions)
    check = hexmerge.check(mesh, tets.points, cells, tets.regions)
    return report["meshing"], tet_scaled_jacobians(tets.points, cells), check


def test_a_face_whose_outline_runs_along_a_line_and_back() -> None:
    """SOT404.stp (a D2PAK: body, tab, two leads, a pin mark): the wall below each lead's tab is
    one face whose outline runs along the tab's top edge and back, and BRepMesh closes it with
    triangles whose three nodes lie on one line (5e-7 off over 1.2 mm), whose longest side is
    one side of the top face's triangle. TetGen filled those places with tets of no volume
    (at h 0.2851: scaled Jacobian 1.9e-6, 49 tets under 1e-3). The flat triangles go and the
    triangles across are split at their third node: smallest 0.030 (when this was changed)."""
    meshing, sj, check = mesh_and_check(IDF / "SOT404.stp", 0.2851)
    assert meshing["nb_solids"] == 4
    assert meshing["nb_flat_surface_triangles"] > 0
    assert sj.min() > 0.01
    assert check["valid"] and check["cracks"] == 0 and check["nonconforming_quads"] == 0
    assert meshing["max_boundary_distance"] < 1e-3 * 0.2851


@pytest.mark.parametrize("h", [0.812, 0.4777])
def test_lattice_edges_near_a_face_across_a_gap(h: float) -> None:
    """I22_2_5_16withEPL22_6_16.stp (an E core and an I core 0.1 mm above its legs): the lattice
    points on the edges between the legs' top faces and their sides lay within the lattice margin
    of the I core's faces and nodes, across the gap, and were dropped; the edges' sides, split
    only at lattice points, stayed 15.8 mm long, and the tets on the top faces' triangles were
    flat (at h 0.812: 660 elements under scaled Jacobian 0.2, smallest 0.005; at 0.4777: 2,512,
    smallest 3e-4; before that, at 0.812, TetGen added points on those sides, which had no CAD
    face, and the mesh was refused). Such points stay: 10 and 15 under 0.2, smallest 0.16 and
    0.14 (when this was changed)."""
    meshing, sj, check = mesh_and_check(IDF / "I22_2_5_16withEPL22_6_16.stp", h)
    assert meshing["nb_solids"] == 2
    assert sj.min() > 0.05
    assert (sj < 0.2).sum() <= 60
    assert check["valid"] and check["cracks"] == 0 and check["nonconforming_quads"] == 0
    assert meshing["max_boundary_distance"] < 1e-3 * h


def test_a_file_of_faces_is_sewn_into_a_solid() -> None:
    """SOT23.stp holds 73 faces, each in a shell of its own, and no solid (refused before: "the
    shape holds no solid"). Sewn, they close one solid, which is meshed; the report says so.
    SOD_323.stp's faces leave 48 in open shells: refused, naming the count, since they would be
    lost. Local sizes name faces of the shape given, which sewing replaced: refused."""
    meshing, sj, check = mesh_and_check(IDF / "SOT23.stp", 0.2)
    assert meshing["nb_sewn_solids"] == 1 and meshing["nb_solids"] == 1
    assert sj.min() > 0
    assert check["valid"] and check["cracks"] == 0 and check["nonconforming_quads"] == 0
    assert meshing["max_boundary_distance"] < 1e-3 * 0.2
    with pytest.raises(hexmerge.InputError, match="48 face.s. in 2 open one"):
        hexmerge.mesh_shape(IDF / "SOD_323.stp", 0.2, recombine=False)
    with pytest.raises(hexmerge.InputError, match="sewn into 1 solid"):
        hexmerge.mesh_shape(IDF / "SOT23.stp", 0.2, recombine=False, local_sizes="1:0.05")


def test_reading_an_iges_file_prints_nothing_of_opencascade(tmp_path) -> None:
    """OpenCASCADE's IGES reader printed "Total number of loaded entities" (in colour) on standard
    output; hexmerge's command line prints its own lines only. SOT23.igs also holds faces only:
    the command line notes the sewing."""
    import subprocess
    import sys

    from conftest import PYTHON_SRC

    result = subprocess.run(
        [sys.executable, "-m", "hexmerge", "mesh", str(IDF / "SOT23.igs"), "-h", "0.3", "-o",
         str(tmp_path / "sot23.vtu")],
        capture_output=True, text=True, env={"PYTHONPATH": str(PYTHON_SRC), "PATH": "/usr/bin:/bin"},
        check=False)
    assert result.returncode == 0, result.stderr
    assert "loaded entities" not in result.stdout + result.stderr
    assert "sewn, they close 1 solid(s)" in result.stderr
    assert (tmp_path / "sot23.vtu").exists()
