"""mesh_shape(): a hex-dominant mesh straight from a CAD shape (STEP, BREP, IGES, BREP text).

The compiled mesher (``hexmerge._core.mesh_shape``, ``src/occ/hexmerge/occ/mesh_shape.h``) makes
lattice-seeded tets of the shape with OpenCASCADE and TetGen; recombine() merges them. This
module resolves the shape, checks the options, adds the mid-edge nodes for second order, and
merges the two reports.
"""

from __future__ import annotations

import os
import time
from pathlib import Path
from typing import Any, Callable

import numpy as np

from . import _api, _core, _validate
from ._regions import WITH_OPENCASCADE

#: The mesher's options, in the row format of parameters() (name, type, default, unit, min,
#: max, choices, label, doc). Lengths are fractions of the target size h (unit "h"). The
#: compiled mesher checks every value again; tests/python/test_mesh_shape.py checks that these
#: defaults are the compiled function's.
_MESH_TABLE: tuple[dict[str, Any], ...] = (
    dict(name="boundary_layers", type="int", default=1, unit="", min=0, max=3, choices=[],
         label="Boundary layers",
         doc="Layers of points offset from the curved and unaligned faces along the inward "
         "normal, so that the boundary becomes prisms"),
    dict(name="layer_thickness", type="float", default=0.3, unit="h", min=0.1, max=1.0, choices=[],
         label="Layer thickness",
         doc="Thickness of one boundary layer, as a fraction of the target size h"),
    dict(name="lattice_margin", type="float", default=0.3, unit="h", min=0.1, max=2.0, choices=[],
         label="Lattice margin",
         doc="Lattice points nearer than this to a face off the lattice planes (or to the "
         "outermost boundary layer) are dropped; a fraction of h"),
    dict(name="surface_deflection", type="float", default=0.02, unit="h", min=0.001, max=0.5,
         choices=[], label="Surface deflection",
         doc="Chord deflection of the surface triangulation on curved faces, as a fraction of h"),
    dict(name="frame", type="choice", default="auto", unit="", min=0, max=0,
         choices=["auto", "principal", "global"], label="Lattice frame",
         doc="Orientation of the lattice: auto (normals of the largest planar faces, else the "
         "principal axes of inertia), principal (principal axes of inertia), global (x, y, z)"),
    dict(name="sweep", type="bool", default=True, unit="", min=0, max=1, choices=[],
         label="Sweep extrusions",
         doc="Where the shape is one cross-section extruded along a lattice axis between two planar "
         "caps (plates with holes, cylinders, profiles; one solid or several), sweep the tets "
         "too: the same cross-section on every lattice plane, so that they recombine into "
         "hexahedra and prisms only"),
    dict(name="tetgen_time_limit", type="float", default=0.0, unit="s", min=0.0, max=86400.0,
         choices=[], label="TetGen time limit",
         doc="Time limit of one TetGen run (0: 30 s plus 1 ms per point); a run past it, or one "
         "that leaves no tet, is restarted with the lattice faces' loops started elsewhere, up to "
         "5 times, then the meshing fails"),
    dict(name="memory_limit", type="float", default=0.0, unit="GB", min=0.0, max=1e6, choices=[],
         label="Memory limit",
         doc="Memory the meshing and recombination may take (0: what the system has available); "
         "a size whose estimated tets would need more is refused before any work"),
)

#: File name endings read_shape_file() takes.
SHAPE_SUFFIXES = (".step", ".stp", ".brep", ".brp", ".iges", ".igs")


def mesh_parameters() -> list[dict[str, Any]]:
    """The options of mesh_shape() besides the size, in parameters()'s row format (name, type,
    default, default_text, unit, min, max, choices, label, doc). Unit "h": a fraction of the
    target size."""
    rows = []
    for row in _MESH_TABLE:
        row = dict(row, choices=list(row["choices"]))
        d = row["default"]
        row["default_text"] = (d if isinstance(d, str) else str(d).lower() if isinstance(d, bool)
                               else f"{d:g}")
        rows.append(row)
    return rows


def _require_opencascade() -> None:
    if not WITH_OPENCASCADE or not hasattr(_core, "mesh_shape"):
        raise RuntimeError(
            "hexmerge was built without OpenCASCADE, so mesh_shape() is not available: install "
            "libocct-foundation-dev libocct-modeling-data-dev libocct-modeling-algorithms-dev "
            "libocct-visualization-dev libtbb-dev tetgen and rebuild"
        )


def is_brep_text(text: str) -> bool:
    """True for OpenCASCADE BREP text (what FreeCAD's Shape.exportBrepToString() gives)."""
    return text.lstrip().startswith("DBRep_DrawableShape") or "CASCADE Topology" in text[:4096]


def shape_text(shape: str | bytes | os.PathLike[str]) -> str:
    """BREP text from BREP text (str or bytes) or from the path of a STEP, BREP or IGES file."""
    return _shape_text_and_unit(shape)[0]


#: Length units that need no word: OpenCASCADE reads STEP and IGES files in millimetres.
_MILLIMETRES = ("", "mm", "millimetre", "millimeter", "millimetres", "millimeters")


def _shape_text_and_unit(shape: str | bytes | os.PathLike[str]) -> tuple[str, str]:
    """shape_text() and the length unit a STEP or IGES file declares ("" otherwise)."""
    if isinstance(shape, bytes):
        shape = shape.decode("utf-8", errors="replace")
        if not is_brep_text(shape):
            raise _core.InputError("the bytes are no BREP text (no 'CASCADE Topology' header)")
        return shape, ""
    if isinstance(shape, str) and is_brep_text(shape):
        return shape, ""
    if isinstance(shape, (str, os.PathLike)):
        path = os.fspath(shape)
        if not isinstance(path, str) or not path.strip():
            raise _core.InputError("shape is empty: give a STEP, BREP or IGES file or BREP text")
        if "\n" in path:
            raise _core.InputError(
                "shape is neither BREP text (no 'CASCADE Topology' header) nor a file name"
            )
        if not Path(path).is_file():
            raise _core.InputError(f"{path}: no such file")
        return _core.read_shape_file(path, with_unit=True)
    raise _core.InputError(
        "shape must be BREP text (str or bytes) or the path of a STEP, BREP or IGES file, got "
        f"{type(shape).__name__}"
    )


def _number(name: str, value: Any) -> float:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise _core.InputError(f"{name} must be a number, got {value!r}")
    value = float(value)
    if not np.isfinite(value):
        raise _core.InputError(f"{name} must be finite, got {value!r}")
    return value


def _options(size: Any, given: dict[str, Any]) -> tuple[float, dict[str, Any]]:
    """The size and the mesher's table options, type-checked (the core checks the ranges)."""
    size = _number("size", size)
    if size <= 0:
        raise _core.InputError(f"size must be a positive length, got {size:g}")
    out = {}
    for row in _MESH_TABLE:
        name, value = row["name"], given[row["name"]]
        if row["type"] == "int":
            if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
                raise _core.InputError(f"{name} must be a whole number, got {value!r}")
            out[name] = int(value)
        elif row["type"] == "float":
            out[name] = _number(name, value)
        elif row["type"] == "bool":
            out[name] = _flag(name, value, _core.InputError)
        elif not isinstance(value, str) or value not in row["choices"]:
            raise _core.InputError(f"{name} must be one of {', '.join(row['choices'])}, got {value!r}")
        else:
            out[name] = value
    return size, out


def _flag(name: str, value: Any, error: type[Exception] = ValueError) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise error(f"{name} must be True or False, got {value!r}")
    return bool(value)


def mesh_shape(
    shape: str | bytes | os.PathLike[str],
    size: float,
    *,
    boundary_layers: int = 1,
    layer_thickness: float = 0.3,
    lattice_margin: float = 0.3,
    surface_deflection: float = 0.02,
    frame: str = "auto",
    sweep: bool = True,
    tetgen_time_limit: float = 0.0,
    memory_limit: float = 0.0,
    tetgen: str = "tetgen",
    work_directory: str | os.PathLike[str] | None = None,
    second_order: bool = False,
    recombine: bool = True,
    progress: Callable[[str, float], Any] | None = None,
    **recombine_options: Any,
) -> tuple[_api.MixedMesh, dict[str, Any]]:
    """A hex-dominant mesh of a solid CAD shape: lattice-seeded tets, then recombine().

    Parameters
    ----------
    shape : str, bytes or path
        BREP text (FreeCAD: ``Shape.exportBrepToString()``) or the path of a STEP (.step,
        .stp), BREP (.brep, .brp) or IGES (.iges, .igs) file. One or more closed solids.
    size : float
        Target element size h in the shape's units: the lattice spacing and the surface's
        longest edge. Positive and not larger than the shape.
    boundary_layers, layer_thickness, lattice_margin, surface_deflection, frame, sweep,
    tetgen_time_limit, memory_limit
        The mesher's options, see mesh_parameters() (fractions of h where they are lengths).
    tetgen : str
        The TetGen program (a name on PATH or a path).
    work_directory : path, optional
        Keep TetGen's files there; default: a temporary folder, removed.
    second_order : bool
        Tet10 with a node on every edge, so the recombined mesh is quadratic (Hexa20, Wedge15,
        Pyramid13, Tet10): inside at the edge's midpoint, on the boundary on the CAD face (or
        CAD edge) the edge lies on, except where that would invert a tet or leave the edge's
        middle half (counted in the report's ``nb_straight_mid_nodes``; ``nb_projected_mid_nodes``
        were put on the CAD).
    recombine : bool
        Merge the tets (default). False returns the tet mesh itself.
    progress : callable(phase: str, fraction: float) -> bool | None, optional
        As for recombine(); called before and after meshing (phase "mesh shape"), then by the
        engine. Returning False cancels (hexmerge.Cancelled).
    **recombine_options
        Engine parameters, see parameters(); the engine's defaults (conforming) otherwise.

    Returns
    -------
    (MixedMesh, dict)
        The mesh (regions: the index of the solid holding each cell) and the report: with
        recombine, recombine()'s report; in both cases the mesher's report under ``"meshing"``
        (counts, ``frame``, ``spacing``, ``sweep_axis`` (the frame axis the tets are swept
        along, -1: not swept), ``max_boundary_distance`` of the corner nodes to the CAD, ``phase_seconds``, ``seconds``, ``tets``, ``points``, ``parameters``).

    Raises
    ------
    hexmerge.InputError (a ValueError)
        A shape that cannot be read or holds no closed solid, a size that is not positive or
        larger than the shape, a bad option, TetGen missing or failing; unknown engine
        options raise ValueError.
    RuntimeError
        The module was built without OpenCASCADE.
    """
    _require_opencascade()
    second_order = _flag("second_order", second_order)
    recombine = _flag("recombine", recombine)
    fn = _validate.progress_function(progress)
    size, options = _options(size, dict(
        boundary_layers=boundary_layers, layer_thickness=layer_thickness,
        lattice_margin=lattice_margin, surface_deflection=surface_deflection, frame=frame,
        sweep=sweep, tetgen_time_limit=tetgen_time_limit, memory_limit=memory_limit))
    if not isinstance(tetgen, (str, os.PathLike)) or not os.fspath(tetgen):
        raise _core.InputError(f"tetgen must be the TetGen program's name or path, got {tetgen!r}")
    if work_directory is not None and not isinstance(work_directory, (str, os.PathLike)):
        raise _core.InputError(f"work_directory must be a folder's path, got {work_directory!r}")
    if work_directory is not None and os.fspath(work_directory):
        # Made when missing; the first part of the path that exists must be a folder.
        for part in (Path(work_directory), *Path(work_directory).parents):
            if part.exists():
                if not part.is_dir():
                    raise _core.InputError(f"work_directory {work_directory}: {part} is not a folder")
                break
    if recombine:
        _validate.options_text(recombine_options)  # unknown options fail before the meshing
    elif recombine_options:
        raise ValueError(
            f"engine options ({', '.join(recombine_options)}) need recombine=True"
        )
    brep, file_unit = _shape_text_and_unit(shape)

    if fn is not None and fn("mesh shape", 0.0) is False:
        raise _core.Cancelled("cancelled")
    start = time.perf_counter()
    try:
        points, tets, regions, meshing = _core.mesh_shape(
            brep, size, tetgen=os.fspath(tetgen),
            work_directory="" if work_directory is None else os.fspath(work_directory),
            second_order=second_order, **options)
    except _core.InputError as e:
        if file_unit.lower() in _MILLIMETRES:
            raise
        raise _core.InputError(f"{e} (the file declares its lengths in {file_unit}: the shape is read "
                               "in millimetres, and so is the size)") from None
    meshing = dict(meshing)
    meshing["seconds"] = time.perf_counter() - start
    # STEP and IGES files are read in millimetres, whatever unit they declare: say which.
    meshing["file_length_unit"] = file_unit
    meshing["converted_to_millimetres"] = file_unit.lower() not in _MILLIMETRES
    meshing["tets"] = int(len(tets))
    meshing["points"] = int(len(points))
    meshing["parameters"] = dict(size=size, **options, second_order=second_order)
    if fn is not None and fn("mesh shape", 1.0) is False:
        raise _core.Cancelled("cancelled")

    cells = np.asarray(tets)
    if not recombine:
        name = "tetra10" if second_order else "tetra"
        mesh = _api.MixedMesh.from_blocks(points, [(name, cells)], [regions])
        mesh.point_map = np.arange(len(points))
        return mesh, {"meshing": meshing}
    mesh, report = _api.recombine(points, cells, regions, progress=fn, **recombine_options)
    report = dict(report)
    report["meshing"] = meshing
    return mesh, report
