"""HexMerge: merge tetrahedral meshes into hex-dominant meshes (Meshkat & Talmor).

>>> mesh, report = hexmerge.recombine(points, tets)          # numpy arrays in
>>> mesh.cells("hexahedron"), report["element_reduction_percent"]
>>> mesh, report = hexmerge.mesh_shape("part.step", 2.0)  # from CAD: OpenCASCADE + TetGen

The engine is the compiled module ``hexmerge._core``; this package validates input, converts
Tet10 meshes and offers the command line (``python -m hexmerge``, or ``hexmerge``).
"""

from __future__ import annotations

try:
    from . import _core
except ImportError as e:  # pragma: no cover - depends on the build
    raise ImportError(
        "hexmerge._core is not built for this interpreter: build the project with "
        "`cmake -S . -B build -DPython_EXECUTABLE=/usr/bin/python3.11 && cmake --build build` "
        f"(the module lands in src/python/hexmerge). Cause: {e}"
    ) from e

from ._api import CellBlock, MixedMesh, cell_types, check, parameters, recombine, validate
from ._regions import WITH_OPENCASCADE, regions_by_solid
from ._shape import mesh_notes, mesh_parameters, mesh_shape, sharp_feature_note

InputError = _core.InputError
Cancelled = _core.Cancelled
ResourceError = _core.ResourceError

__version__ = "0.1.0"

__all__ = [
    "Cancelled",
    "CellBlock",
    "InputError",
    "MixedMesh",
    "ResourceError",
    "WITH_OPENCASCADE",
    "cell_types",
    "check",
    "mesh_notes",
    "mesh_parameters",
    "mesh_shape",
    "parameters",
    "recombine",
    "regions_by_solid",
    "sharp_feature_note",
    "validate",
]
