"""Input validation with friendly messages (the compiled module only checks what numpy cannot).

Everything here raises ``ValueError`` naming the node or element at fault, with 0-based ids.
Geometric problems (inverted, flat or duplicate tets, faces shared by three tets) are found by
the core, whose ``InputError`` is a ``ValueError`` too.
"""

from __future__ import annotations

from typing import Any, Callable, Mapping

import numpy as np

from . import _core

INDEX_MAX = np.iinfo(np.uint32).max - 1  # NO_INDEX (2**32 - 1) is the core's sentinel


def _shape(a: np.ndarray) -> str:
    return "(" + ", ".join(str(s) for s in a.shape) + ("," if a.ndim == 1 else "") + ")"


def points_array(points: Any) -> np.ndarray:
    """(N, 3) float64, C-contiguous, every coordinate finite."""
    try:
        a = np.asarray(points)
    except (TypeError, ValueError) as e:  # ragged lists
        raise ValueError(f"points must be an array of shape (N, 3): {e}") from None
    if a.dtype == object or not (np.issubdtype(a.dtype, np.number) and not np.issubdtype(a.dtype, np.complexfloating)):
        raise ValueError(f"points must be real numbers, got an array of {a.dtype}")
    if a.ndim != 2 or a.shape[1] != 3:
        raise ValueError(f"points must be an array of shape (N, 3), got shape {_shape(a)}")
    if a.shape[0] == 0:
        raise ValueError("the mesh is empty: it has no nodes")
    a = np.ascontiguousarray(a, dtype=np.float64)
    bad = ~np.isfinite(a).all(axis=1)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        x, y, z = (float(c) for c in a[i])
        more = int(bad.sum()) - 1
        tail = f" (and {more} more)" if more else ""
        raise ValueError(f"node {i} has a non-finite coordinate ({x}, {y}, {z}){tail}")
    return a


def cells_array(cells: Any, nb_points: int) -> np.ndarray:
    """(M, 4) or (M, 10) uint32 node ids, each in [0, nb_points)."""
    try:
        a = np.asarray(cells)
    except (TypeError, ValueError) as e:
        raise ValueError(f"cells must be an array of shape (M, 4) or (M, 10): {e}") from None
    if a.ndim == 2 and a.shape[0] == 0:
        raise ValueError("the mesh is empty: it has no tetrahedra")
    if a.dtype == object or not np.issubdtype(a.dtype, np.integer):
        raise ValueError(f"cells must be integer node ids, got an array of {a.dtype}")
    if a.ndim != 2 or a.shape[1] not in (4, 10):
        hint = ""
        if a.ndim == 2 and a.shape[1] in (5, 6, 8, 13, 15, 20):
            hint = (
                f": {a.shape[1]} nodes per cell are not tetrahedra, and hexmerge merges "
                "tetrahedral meshes only"
            )
        raise ValueError(
            "cells must be an array of shape (M, 4) (linear tets) or (M, 10) (quadratic tets), "
            f"got shape {_shape(a)}{hint}"
        )
    low = a < 0
    high = a >= nb_points
    bad = low | high
    if bad.any():
        e, k = (int(v) for v in np.argwhere(bad)[0])
        raise ValueError(
            f"element {e} refers to node {int(a[e, k])}, but the nodes are numbered "
            f"0 to {nb_points - 1}"
        )
    if nb_points > INDEX_MAX:
        raise ValueError(f"the mesh has {nb_points} nodes; at most {INDEX_MAX} are supported")
    return np.ascontiguousarray(a, dtype=np.uint32)


def regions_array(regions: Any, nb_cells: int) -> np.ndarray | None:
    """None, or (M,) int32 region ids."""
    if regions is None:
        return None
    a = np.asarray(regions)
    if a.dtype == object or not np.issubdtype(a.dtype, np.integer):
        raise ValueError(f"regions must be integer region ids, got an array of {a.dtype}")
    if a.shape != (nb_cells,):
        raise ValueError(
            f"regions must have one id per element, shape ({nb_cells},), got shape {_shape(a)}"
        )
    info = np.iinfo(np.int32)
    bad = (a < info.min) | (a > info.max)
    if bad.any():
        e = int(np.flatnonzero(bad)[0])
        raise ValueError(f"element {e} has region id {int(a[e])}, outside the 32-bit range")
    return np.ascontiguousarray(a, dtype=np.int32)


def _table() -> dict[str, dict[str, Any]]:
    return {row["name"]: row for row in _core.parameter_table()}


def option_text(name: str, value: Any, row: Mapping[str, Any],
                error: type[Exception] = ValueError) -> str:
    """One option as the text the core parses; the core checks ranges and choices. A value of
    the wrong type raises `error`."""
    kind = row["type"]
    if kind == "bool":
        if isinstance(value, (bool, np.bool_)):
            return "true" if value else "false"
        if isinstance(value, str) and value.lower() in ("true", "false"):
            return value.lower()
        raise error(f"option {name!r} must be True or False, got {value!r}")
    if kind in ("float", "int"):
        is_number = isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(
            value, (bool, np.bool_)
        )
        if not is_number:
            raise error(f"option {name!r} must be a number, got {value!r}")
        try:
            number = float(value)
        except OverflowError:  # a Python int beyond any float
            number = float("inf") if value > 0 else float("-inf")
        if not np.isfinite(number):
            raise error(
                f"option {name!r} must be a finite number in [{row['min']}, {row['max']}], got {value!r}"
            )
        if kind == "int":
            if number != int(number):
                raise error(f"option {name!r} must be a whole number, got {value!r}")
            return str(int(value))
        return repr(number)
    if kind == "choice":
        if not isinstance(value, str):
            raise error(
                f"option {name!r} must be one of {', '.join(row['choices'])}, got {value!r}"
            )
        return value
    if not isinstance(value, str):
        raise error(f"option {name!r} must be text, got {value!r}")
    return value


def options_text(options: Mapping[str, Any]) -> dict[str, str]:
    """{name: text} for the core; unknown names raise ValueError listing the valid ones."""
    table = _table()
    out = {}
    for name, value in options.items():
        row = table.get(name)
        if row is None:
            raise ValueError(f"unknown option {name!r}; the options are: {', '.join(table)}")
        out[name] = option_text(name, value, row)
    return out


def progress_function(progress: Callable[[str, float], Any] | None) -> Callable[[str, float], Any] | None:
    if progress is not None and not callable(progress):
        raise ValueError(f"progress must be a callable(phase, fraction) or None, got {progress!r}")
    return progress
