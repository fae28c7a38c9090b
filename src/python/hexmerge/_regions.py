"""regions_by_solid(): the solid of a CAD shape holding each tet (OpenCASCADE, in C++)."""

from __future__ import annotations

from typing import Any

import numpy as np

from . import _core, _validate

#: True when the compiled module was built with OpenCASCADE (regions_by_solid() works).
WITH_OPENCASCADE: bool = bool(getattr(_core, "with_opencascade", False))


def regions_by_solid(
    brep: str | bytes,
    points: Any,
    cells: Any,
    *,
    tolerance: float = 1e-6,
    samples_per_piece: int = 5,
    classify_every_tet: bool = False,
    threads: int = 0,
) -> tuple[np.ndarray, dict[str, Any]]:
    """The solid of a shape that holds each tet of a mesh: material regions from CAD.

    Parameters
    ----------
    brep : str or bytes
        The shape as BREP text (FreeCAD: ``shape.exportBrepToString()``; OpenCASCADE:
        ``BRepTools::Write``). Its solids are numbered from 0 in the order of FreeCAD's
        ``Shape.Solids``.
    points : (N, 3) array of float
        Node coordinates.
    cells : (M, 4) or (M, 10) array of int
        Tetrahedra (0-based node ids); only the corners count.
    tolerance : float
        Distance under which a node lies on a face shared by two solids, as a fraction of the
        shape's bounding-box diagonal, in (0, 0.01].
    samples_per_piece : int
        The tets are cut into connected pieces at the faces the solids share; this many tets
        per piece are classified, and a piece whose samples disagree is classified tet by tet.
    classify_every_tet : bool
        Classify every tet's centroid instead (slow; a reference).
    threads : int
        Worker threads, 0 for one per hardware thread.

    Returns
    -------
    (np.ndarray, dict)
        int32 (M,) solid index per tet, -1 for a tet in no solid; and a report (counts of
        solids, shared faces, interface nodes, pieces, classified points, unassigned tets,
        and ``phase_seconds``).

    Raises
    ------
    ValueError
        Bad arrays or options, or a BREP text that holds no solid (hexmerge.InputError).
    RuntimeError
        The module was built without OpenCASCADE.
    """
    if not WITH_OPENCASCADE:
        raise RuntimeError(
            "hexmerge was built without OpenCASCADE, so regions_by_solid() is not available: "
            "install libocct-foundation-dev libocct-modeling-data-dev "
            "libocct-modeling-algorithms-dev libocct-data-exchange-dev libocct-visualization-dev "
            "libtbb-dev and rebuild"
        )
    if isinstance(brep, bytes):
        brep = brep.decode("utf-8", errors="replace")
    if not isinstance(brep, str):
        raise ValueError(f"brep must be the shape's BREP text (str), got {type(brep).__name__}")
    if not brep.strip():
        raise ValueError("brep is empty: pass the shape's BREP text")
    p = _validate.points_array(points)
    c = _validate.cells_array(cells, len(p))
    tolerance = _number("tolerance", tolerance)
    if not 0.0 < tolerance <= 0.01:
        raise ValueError(f"tolerance must be in (0, 0.01], got {tolerance!r}")
    samples_per_piece = _whole("samples_per_piece", samples_per_piece, 1, 1000)
    threads = _whole("threads", threads, 0, 1024)
    if not isinstance(classify_every_tet, (bool, np.bool_)):
        raise ValueError(f"classify_every_tet must be True or False, got {classify_every_tet!r}")
    return _core.regions_by_solid(
        brep, p, np.ascontiguousarray(c[:, :4]), tolerance, samples_per_piece,
        bool(classify_every_tet), threads,
    )


def _number(name: str, value: Any) -> float:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"{name} must be a number, got {value!r}")
    return float(value)


def _whole(name: str, value: Any, low: int, high: int) -> int:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise ValueError(f"{name} must be a whole number, got {value!r}")
    if not low <= int(value) <= high:
        raise ValueError(f"{name} must be in [{low}, {high}], got {value!r}")
    return int(value)
