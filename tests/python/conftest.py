"""pytest setup: import hexmerge from the checkout (src/python) and the benchmarks' measures
(bench/real_parts.py), shared mesh fixtures."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PYTHON_SRC = ROOT / "src" / "python"
for folder in (PYTHON_SRC, ROOT / "bench"):
    if str(folder) not in sys.path:
        sys.path.insert(0, str(folder))

import hexmerge  # noqa: E402 (from the checkout, put on the path above)
from hexmerge import _core  # noqa: E402

# The marks of a module whose tests mesh shapes: hexmerge built with OpenCASCADE, TetGen found.
MESHES_SHAPES = [
    pytest.mark.skipif(not hexmerge.WITH_OPENCASCADE or not hasattr(_core, "mesh_shape"),
                       reason="hexmerge built without OpenCASCADE"),
    pytest.mark.skipif(shutil.which("tetgen") is None, reason="tetgen is not installed"),
]

BOX_GEO = """
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 1};
Box(2) = {1, 0, 0, 1, 1, 1};
Coherence;
Physical Volume(7) = {1};
Physical Volume(9) = {2};
Mesh.CharacteristicLengthMax = 0.34;
"""


def gmsh_mesh(folder: Path, name: str, order: int, fmt: str = "msh22") -> Path:
    """A small two-region tet mesh of two unit boxes side by side, made by Gmsh."""
    if shutil.which("gmsh") is None:
        pytest.skip("gmsh is not installed")
    geo = folder / f"{name}.geo"
    geo.write_text(BOX_GEO)
    out = folder / f"{name}.msh"
    subprocess.run(
        ["gmsh", "-3", "-order", str(order), "-format", fmt, str(geo), "-o", str(out)],
        check=True,
        capture_output=True,
    )
    return out


@pytest.fixture(scope="session")
def gmsh_tet4(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return gmsh_mesh(tmp_path_factory.mktemp("gmsh4"), "boxes", 1)


@pytest.fixture(scope="session")
def gmsh_tet10(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return gmsh_mesh(tmp_path_factory.mktemp("gmsh10"), "boxes10", 2)
