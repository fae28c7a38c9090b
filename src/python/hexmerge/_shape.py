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

#: File name endings read_shape_file() takes.
SHAPE_SUFFIXES = (".step", ".stp", ".brep", ".brp", ".iges", ".igs")


def mesh_parameters() -> list[dict[str, Any]]:
    """The mesher's parameters (the compiled MeshShapeParameters table: size, the options, the
    TetGen program and work folder), in parameters()'s row format (name, type, default,
    default_text, unit, min, max, min_exclusive, choices, label, doc, cli_flag,
    freecad_property). Unit "h": a fraction of the target size. Empty without OpenCASCADE."""
    if not hasattr(_core, "mesh_parameter_table"):
        return []
    return [_api.typed_row(row) for row in _core.mesh_parameter_table()]


def _mesher_names() -> set[str]:
    return {row["name"] for row in mesh_parameters()}


def _require_opencascade() -> None:
    if not WITH_OPENCASCADE or not hasattr(_core, "mesh_shape"):
        raise RuntimeError(
            "hexmerge was built without OpenCASCADE, so mesh_shape() is not available: install "
            "libocct-foundation-dev libocct-modeling-data-dev libocct-modeling-algorithms-dev "
            "libocct-data-exchange-dev libocct-visualization-dev libtbb-dev tetgen and rebuild"
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


def _entries_text(value: Any, entry_text: Callable[[Any], str]) -> str:
    """A ';'-separated option text from the text itself, one entry or a list of entries: text
    entries as they are, the others through entry_text."""
    if isinstance(value, str):
        return value
    if isinstance(value, dict) or not isinstance(value, (list, tuple)):
        value = [value]
    return "; ".join(entry if isinstance(entry, str) else entry_text(entry) for entry in value)


def _entry_number(option: str, entry: Any, what: str, number: Any) -> float:
    if isinstance(number, bool) or not isinstance(number, (int, float, np.floating, np.integer)):
        raise _core.InputError(f"{option}: entry {entry!r} has {what} {number!r}: it must be a number")
    return float(number)


def local_sizes_text(value: Any) -> str:
    """The mesher's ``local_sizes`` text from what Python users give: the text itself
    ("5,6:1.5; Edge3:0.5"), or a list of entries, each such a text, a dict
    ``{"faces": [5, 6], "edges": [3], "size": 1.5}`` or a pair ``(items, size)`` with items a
    face number, "FaceN"/"EdgeN", or a list of those. Faces and edges are numbered from 1."""

    def entry_text(entry: Any) -> str:
        if isinstance(entry, dict):
            unknown = set(entry) - {"faces", "edges", "size"}
            if unknown or "size" not in entry:
                raise _core.InputError(
                    f"local_sizes: entry {entry!r} must have 'size' and 'faces' and/or 'edges' "
                    "(lists of numbers from 1)"
                )
            items = [str(f) for f in entry.get("faces", [])] + [f"Edge{e}" for e in entry.get("edges", [])]
            size = entry["size"]
        elif isinstance(entry, tuple) and len(entry) == 2:
            items, size = entry
            items = [str(i) for i in (items if isinstance(items, (list, tuple)) else [items])]
        else:
            raise _core.InputError(
                f"local_sizes: entry {entry!r} is not ITEMS:SIZE text, a dict with faces/edges and "
                "size, or a pair (items, size)"
            )
        return f"{','.join(items)}:{_entry_number('local_sizes', entry, 'size', size)!r}"

    return _entries_text(value, entry_text)


def face_layers_text(value: Any) -> str:
    """The mesher's ``face_layers`` text from what Python users give: the text itself
    ("3:4:0.5:1.2; Face5:2:0.25"), or a list of entries, each such a text or a dict
    ``{"faces": [3, 5], "layers": 4, "thickness": 0.5, "growth": 1.2}`` (growth optional,
    default 1). Faces are numbered from 1; the thickness is the first layer's, a length."""

    def entry_text(entry: Any) -> str:
        if not isinstance(entry, dict) or set(entry) - {"faces", "layers", "thickness", "growth"} \
                or not {"faces", "layers", "thickness"} <= set(entry):
            raise _core.InputError(
                f"face_layers: entry {entry!r} is not FACES:LAYERS:THICKNESS[:GROWTH] text or a dict "
                "with faces, layers, thickness and optionally growth"
            )
        faces = entry["faces"] if isinstance(entry["faces"], (list, tuple)) else [entry["faces"]]
        fields = [",".join(str(f) for f in faces)]
        for key in ("layers", "thickness", "growth"):
            if key in entry:
                number = _entry_number("face_layers", entry, key, entry[key])
                fields.append(str(int(number)) if key == "layers" and number.is_integer() else repr(number))
        return ":".join(fields)

    return _entries_text(value, entry_text)


def _options(size: Any, given: dict[str, Any]) -> dict[str, str]:
    """The mesher's options (size included) as the text the compiled table parses, type-checked
    here; the table checks the ranges and choices."""
    table = {row["name"]: row for row in mesh_parameters()}
    given = dict(given, size=size)
    if given.get("work_directory") is None:
        given["work_directory"] = ""
    out = {}
    if "local_sizes" in given:
        given["local_sizes"] = local_sizes_text(given["local_sizes"])
    if "face_layers" in given:
        given["face_layers"] = face_layers_text(given["face_layers"])
    for name, value in given.items():
        if table[name]["type"] == "text" and isinstance(value, os.PathLike):
            value = os.fspath(value)
        out[name] = _validate.option_text(name, value, table[name], _core.InputError)
    return out


def _flag(name: str, value: Any, error: type[Exception] = ValueError) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise error(f"{name} must be True or False, got {value!r}")
    return bool(value)


def mesh_shape(
    shape: str | bytes | os.PathLike[str],
    size: float,
    *,
    second_order: bool = False,
    recombine: bool = True,
    progress: Callable[[str, float], Any] | None = None,
    **options: Any,
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
    second_order : bool
        Tet10 with a node on every edge, so the recombined mesh is quadratic (Hexa20, Wedge15,
        Pyramid13, Tet10): inside at the edge's midpoint, on the boundary on the CAD face (or
        CAD edge) the edge lies on, except where that would invert a tet or leave the edge's
        middle half (counted in the report's ``nb_straight_mid_nodes``; ``nb_projected_mid_nodes``
        were put on the CAD).
    recombine : bool
        Merge the tets (default). False returns the tet mesh itself.
    progress : callable(phase: str, fraction: float) -> bool | None, optional
        As for recombine(); called before meshing (phase "mesh shape"), after each step of the
        mesher ("mesh shape: surface", ..., "mesh shape: tetgen", "mesh shape: slivers", with
        the way of placing the points in brackets after the first way, e.g. "mesh shape:
        tetgen (surface only)"; fraction of that way done), after meshing, then by the engine.
        Returning False cancels (hexmerge.Cancelled), between the mesher's steps.
    **options
        The mesher's parameters (mesh_parameters(): boundary_layers, layer_thickness,
        lattice_margin, surface_deflection, frame, sweep, pull_core, tetgen_time_limit, memory_limit,
        tetgen (the TetGen program, a name on PATH or a path), work_directory (keep TetGen's
        files there; default: a temporary folder, removed), local_sizes (finer sizes on faces
        and edges numbered from 1: "5,6:1.5; Edge3:0.5", or a list, see local_sizes_text();
        reported in the report's ``local_sizes``), face_layers (boundary layers of their own on
        faces numbered from 1: "3:4:0.5:1.2" is 4 layers on Face3, the first 0.5 deep, each
        next 1.2 times thicker; or a list, see face_layers_text(); reported in the report's
        ``face_layers``, per entry the nodes that got each layer); fractions of h where they
        are lengths) and the engine's (parameters(); the engine's defaults (conforming)
        otherwise), by name.

    Returns
    -------
    (MixedMesh, dict)
        The mesh (regions: the index of the solid holding each cell) and the report: with
        recombine, recombine()'s report; in both cases the mesher's report under ``"meshing"``
        (counts, ``frame``, ``spacing``, ``sweep_axis`` (the frame axis the tets are swept
        along, -1: not swept), ``sweep_skipped`` (why an extrusion was not swept, "" when it
        was or is none), ``max_boundary_distance`` of the corner nodes to the CAD,
        ``shape_volume`` (the CAD's) and ``mesh_volume`` (the tets'), ``phase_seconds``,
        ``seconds``, ``tets``, ``points``, ``parameters``).

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
    mesher_names = _mesher_names()
    recombine_options = {k: v for k, v in options.items() if k not in mesher_names}
    work_directory = options.get("work_directory")
    if work_directory is not None and not isinstance(work_directory, (str, os.PathLike)):
        raise _core.InputError(f"work_directory must be a folder's path, got {work_directory!r}")
    mesher_options = _options(size, {k: v for k, v in options.items() if k in mesher_names})
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
        points, tets, regions, meshing = _core.mesh_shape(brep, mesher_options, second_order, fn)
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
    shown = {row["name"]: row["default"] for row in mesh_parameters()
             if row["name"] not in ("tetgen", "work_directory")}
    shown.update({k: v for k, v in options.items() if k in shown}, size=float(size))
    meshing["parameters"] = dict(shown, second_order=second_order)
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


def mesh_notes(meshing: dict[str, Any]) -> list[str]:
    """What the user should know about how the tets were made: the ways of placing points that
    failed (the mesh comes from a simpler one, with fewer hexahedra), faces left coarser than h,
    a volume more than 1 % off the shape's, the CAD's corners and edges too sharp for usable
    elements."""
    notes = []
    if meshing.get("converted_to_millimetres"):
        notes.append(f"the file declares its lengths in {meshing['file_length_unit']}: the shape is "
                     "read in millimetres, and -h and the report's lengths are millimetres")
    if meshing.get("nb_sewn_solids"):
        notes.append(f"the shape held faces, not solids: sewn, they close {meshing['nb_sewn_solids']} "
                     "solid(s), which were meshed")
    notes += [f"meshing failed with the points placed by {failure}" for failure in meshing["failed_strategies"]]
    if notes:
        notes.append(f"the tets were made with the points placed by {meshing['strategy']}")
    if meshing["nb_revolution_faces"]:
        notes.append("OpenCASCADE's surface mesher left a face of the shape without triangles: the "
                     f"surface was made with its {meshing['nb_revolution_faces']} cylinders, cones, "
                     "spheres and tori as surfaces of revolution (the same geometry)")
    if meshing["nb_zipped_faces"]:
        notes.append(f"{meshing['nb_zipped_faces']} sliver face(s) between two edges with the same ends, "
                     "narrower than the surface's chord deflection, got no triangles: the faces across "
                     "them were joined")
    if meshing["nb_crossing_refinements"]:
        notes.append("faces come closer than the surface's chord deflection at places: the surface "
                     f"was made finer there ({meshing['nb_crossing_refinements']} round(s) of halved sizes)")
    if meshing["nb_unrefined_faces"]:
        notes.append(f"the surface of {meshing['nb_unrefined_faces']} face(s) did not refine to h "
                     "(a distorted parametrisation): sides longer than h remain there")
    for applied in meshing.get("local_sizes", []):
        if applied["max_side"] > applied["size"] * (1 + 1e-6):
            items = [f"Face{f}" for f in applied["faces"]] + [f"Edge{e}" for e in applied["edges"]]
            notes.append(f"local size {applied['size']:g} on {','.join(items)}: sides up to "
                         f"{applied['max_side']:.3g} remain there (a face that did not refine)")
    notes += face_layer_notes(meshing)
    volume = volume_note(meshing)
    if volume:
        notes.append(volume)
    sharp = sharp_feature_note(meshing)
    if sharp:
        notes.append(sharp)
    unsized = unsized_wall_note(meshing)
    if unsized:
        notes.append(unsized)
    if meshing.get("sweep_skipped"):
        notes.append(meshing["sweep_skipped"])
    return notes


# The tets' volume is noted where it differs from the shape's by more than this fraction.
VOLUME_NOTE = 0.01


def volume_note(meshing: dict[str, Any]) -> str | None:
    """A line saying how far the tets' volume is from the shape's, where that is more than 1 %
    of it (the chords of curved faces of small radius at a coarse size); None otherwise."""
    shape, mesh = meshing.get("shape_volume", 0.0), meshing.get("mesh_volume", 0.0)
    if not shape > 0 or abs(mesh / shape - 1) <= VOLUME_NOTE:
        return None
    change = 100 * (mesh / shape - 1)
    return (f"the tets' volume is {abs(change):.1f} % {'less' if change < 0 else 'more'} than the "
            f"shape's ({mesh:.6g} against {shape:.6g}): the chords of its curved faces at this size; "
            "a smaller size or surface deflection follows them closer")


def face_layer_notes(meshing: dict[str, Any]) -> list[str]:
    """One line per face-layer entry that did not get all its layers at all its nodes."""
    notes = []
    for applied in meshing.get("face_layers", []):
        items = ",".join(f"Face{f}" for f in applied["faces"])
        per_layer = applied["nb_per_layer"]
        if applied["nb_nodes"] and all(n == applied["nb_nodes"] for n in per_layer):
            continue
        if not any(per_layer):
            notes.append(f"boundary layers on {items}: none placed (the points were placed by "
                         f"{meshing['strategy']}, which places no layers)")
            continue
        counts = ", ".join(f"{n}" for n in per_layer)
        notes.append(f"boundary layers on {items}: nodes per layer {counts} of the face's "
                     f"{applied['nb_nodes']} (no room deeper, or a point too near another)")
    return notes


def unsized_wall_note(meshing: dict[str, Any]) -> str | None:
    """A line saying that walls thinner than the surface's chord deflection got no size of
    their own (the tets across them are flat) and the size that would give them one; None when
    there are none."""
    if not meshing.get("nb_unsized_wall_patches"):
        return None
    thinnest, thickest = meshing["thinnest_unsized_wall"], meshing["thickest_unsized_wall"]
    walls = f"{thinnest:.3g}" if thickest <= thinnest * 1.001 else f"{thinnest:.3g} to {thickest:.3g}"
    deflection = meshing["parameters"]["surface_deflection"]
    return (f"walls {walls} thick are thinner than the surface's chord deflection "
            f"({deflection:g} h): they get no size of their own and the tets across them are flat; "
            f"a size of at most {0.99 * thinnest / deflection:.3g} gives them one")


def sharp_feature_note(meshing: dict[str, Any]) -> str | None:
    """A line naming the CAD's face corners and edges sharper than 8.13 degrees that
    mesh_shape() found (its report's ``meshing``; the five sharpest, faces and edges numbered as
    FreeCAD's FaceN, EdgeN), where no element can reach a scaled Jacobian of 0.2; None when
    there are none."""
    sharp = sorted(meshing.get("sharp_features", []), key=lambda f: f["angle"])
    if not sharp:
        return None
    named = "; ".join(_sharp_feature_text(f) for f in sharp[:5])
    more = f"; and {len(sharp) - 5} more (the report's sharp_features)" if len(sharp) > 5 else ""
    return (f"the CAD has {len(sharp)} corner(s) or edge(s) sharper than 8.13 degrees, where no "
            f"element can reach a scaled Jacobian of 0.2: {named}{more}")


def _sharp_feature_text(feature: dict[str, Any]) -> str:
    at = ", ".join(f"{x:.6g}" for x in feature["point"])
    if feature["kind"] == "corner":
        first, second = feature["edges"]
        return (f"Face{feature['faces'][0]}'s corner between Edge{first} and Edge{second}, "
                f"{feature['angle']:.3g} degrees, at ({at})")
    first, second = feature["faces"]
    return (f"Edge{feature['edges'][0]} between Face{first} and Face{second}, "
            f"{feature['angle']:.3g} degrees inside the solid, at ({at})")

