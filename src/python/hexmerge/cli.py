"""The command line: ``hexmerge recombine``, ``hexmerge mesh``, ``hexmerge check``,
``hexmerge parameters``.

Every engine option is generated from the parameter table (and the mesher's options from
mesh_parameters()), so ``--help`` shows the same names, units and defaults as the Python API and
the FreeCAD add-on. main() only parses, loads, calls the library and saves.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from typing import Any, Sequence, TextIO

import numpy as np

from . import __version__, _api, _core, _io, _shape

EXIT_OK = 0
EXIT_ERROR = 1  # bad input, unreadable or unwritable file, failed run
EXIT_USAGE = 2  # argparse's own code for a bad command line
EXIT_INVALID = 3  # `check` ran and found the mesh invalid
EXIT_INTERRUPTED = 130

EXIT_CODES = """exit codes: 0 success, 1 error (bad input, unreadable file, failed run; nothing is
written), 2 bad command line, 3 `check` found the mesh invalid, 130 interrupted"""


class UsageError(Exception):
    """Options that do not go together (exit code 2, like argparse's own errors)."""


def _help(row: dict[str, Any]) -> str:
    unit = f" {row['unit']}" if row["unit"] else ""
    if row["type"] in ("float", "int"):
        lo, hi = (f"{v:g}" for v in (row["min"], row["max"]))
        if math.isinf(row["max"]):
            span = f"{'above' if row['min_exclusive'] else 'at least'} {lo}{unit}"
        else:
            span = f"range {lo}{' (excluded)' if row['min_exclusive'] else ''} to {hi}{unit}"
        extra = f"{span}; default: {row['default_text']}{unit}"
    elif row["type"] == "choice":
        extra = f"one of {', '.join(row['choices'])}; default: {row['default_text']}"
    elif row["type"] == "text":
        extra = f"default: {row['default_text'] or 'none'}"
    else:
        extra = f"default: {'on' if row['default'] else 'off'}"
    return f"{row['doc']} ({extra})".replace("%", "%%")


def add_parameter_options(
    parser: argparse.ArgumentParser,
    rows: list[dict[str, Any]] | None = None,
    title: str = "engine parameters (from hexmerge.parameters())",
    extra: dict[str, dict[str, Any]] | None = None,
) -> None:
    """One option per row of a parameter table (the engine's by default), named by the row's
    ``cli_flag``; unset options keep the default. `extra` gives some rows more argparse
    arguments (``flags``: further option names)."""
    group = parser.add_argument_group(title)
    for row in _api.parameters() if rows is None else rows:
        more = dict((extra or {}).get(row["name"], {}))
        flags = [*more.pop("flags", []), row["cli_flag"]]
        common = dict(dest=row["name"], default=None, help=_help(row))
        if row["type"] == "bool":
            group.add_argument(*flags, action=argparse.BooleanOptionalAction, **common, **more)
        elif row["type"] == "choice":
            group.add_argument(*flags, choices=row["choices"], **common, **more)
        elif row["type"] == "int":
            group.add_argument(*flags, **{"type": int, "metavar": "N", **common, **more})
        elif row["type"] == "text":
            group.add_argument(*flags, **{"metavar": row["name"].upper(), **common, **more})
        else:
            metavar = row["unit"].upper() or "X"
            group.add_argument(*flags, **{"type": float, "metavar": metavar, **common, **more})


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="hexmerge",
        description="Merge tetrahedral meshes into hex-dominant meshes (Meshkat & Talmor). "
        "Reads and writes every volume mesh format meshio handles (.msh, .vtu, .vtk, .inp, "
        ".mesh, .med, .vol, ...).",
        epilog=EXIT_CODES,
    )
    parser.add_argument("--version", action="version", version=f"hexmerge {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    rec = sub.add_parser(
        "recombine",
        help="merge the tets of a mesh file into hexahedra, prisms and pyramids",
        description="Merge the tetrahedra of IN into hexahedra, prisms and pyramids and write "
        "the mixed mesh to OUT. A Tet10 mesh gives quadratic elements that reuse its mid-edge "
        "nodes. Regions (Gmsh physical groups, Medit refs, Netgen indices, Abaqus element sets) "
        "are kept and never merged across.",
        epilog=EXIT_CODES,
    )
    rec.add_argument("input", metavar="IN", help="tetrahedral mesh file")
    rec.add_argument("--input-format", metavar="FMT", help="meshio format of IN (default: from the extension)")
    add_output_options(rec)
    add_parameter_options(rec)

    msh = sub.add_parser(
        "mesh",
        add_help=False,  # -h is the size, as for Gmsh's -clmax
        help="mesh a CAD shape (STEP, BREP, IGES) into a hex-dominant mesh",
        description="Mesh the solid(s) of SHAPE with lattice-seeded tetrahedra (OpenCASCADE "
        "surface, a cubic lattice of spacing H in the shape's frame, boundary layers; TetGen "
        "tetrahedralises), then merge them into hexahedra, prisms and pyramids like "
        "`hexmerge recombine` (same engine options), and write the mesh to OUT. Regions: the "
        "solid holding each element. Needs the `tetgen` program (Debian: apt install tetgen).",
        epilog=EXIT_CODES,
    )
    msh.add_argument("--help", action="help", help="show this help message and exit")
    msh.add_argument("shape", metavar="SHAPE", help="CAD file: .step/.stp, .brep/.brp or .iges/.igs")
    msh.add_argument("--tets-only", action="store_true", help="write the tet mesh, without merging")
    msh.add_argument(
        "--second-order",
        action="store_true",
        help="quadratic elements: a node on every tet edge (on the boundary on the CAD face or edge, "
        "inside at the midpoint), so the output is Tet10 / Pyramid13 / Wedge15 / Hexa20",
    )
    add_output_options(msh)
    if not _shape.mesh_parameters():  # a module built without OpenCASCADE: cmd_mesh says so
        msh.add_argument("-h", "--size", metavar="H", type=_positive_length, help="target element size")
    add_parameter_options(
        msh, _shape.mesh_parameters(), "mesher options (from hexmerge.mesh_parameters(); h: the size H)",
        # The size is also -h (as Gmsh's -clmax), required, checked before any work.
        {"size": dict(flags=["-h"], required=True, type=_positive_length, metavar="H"),
         # Repeatable: one ITEMS:SIZE per option (or several, separated by ';').
         "local_sizes": dict(action="append", metavar="ITEMS:SIZE"),
         # Repeatable likewise: one FACES:LAYERS:THICKNESS[:GROWTH] per option.
         "face_layers": dict(action="append", metavar="FACES:N:THICKNESS[:GROWTH]")},
    )
    add_parameter_options(msh)

    chk = sub.add_parser(
        "check",
        help="check a mixed mesh against the tet mesh it came from",
        description="Check MESH: every element positively oriented, faces paired (no cracks, "
        "quads against quads), every source node used at its exact place, regions kept, volume "
        "against the source's. Without --source, MESH must be a tet mesh and is checked against "
        "itself.",
        epilog=EXIT_CODES,
    )
    chk.add_argument("mesh", metavar="MESH", help="mesh file to check")
    chk.add_argument("--source", metavar="TETMESH", help="the tet mesh MESH was made from")
    chk.add_argument("--json", action="store_true", help="print the report as JSON")

    par = sub.add_parser(
        "parameters",
        help="list the engine parameters",
        description="List the engine parameters (options of `recombine` and `mesh`), or with "
        "--mesh the mesher's options (of `mesh` only).",
    )
    par.add_argument("--json", action="store_true", help="print the table as JSON")
    par.add_argument("--mesh", action="store_true", help="the mesher's options (hexmerge.mesh_parameters())")
    return parser


def add_output_options(parser: argparse.ArgumentParser) -> None:
    """The options of a command that writes a mesh (recombine, mesh)."""
    parser.add_argument("-o", "--output", metavar="OUT", required=True, help="output mesh file")
    parser.add_argument(
        "--output-format",
        metavar="FMT",
        help="meshio format of OUT (default: from the extension; e.g. gmsh22 for Gmsh 2.2 .msh)",
    )
    parser.add_argument("--ascii", action="store_true", help="write ASCII instead of binary where the format has both")
    parser.add_argument(
        "--collapse-pyramids",
        action="store_true",
        help="write pyramids as degenerate hexahedra (apex repeated), for formats and solvers "
        "without pyramids such as Abaqus/CalculiX .inp; for CalculiX add --pyramid-placement "
        "no_boundary_node (recombined tets) or no_curved_boundary_node (meshes from CAD): "
        "collapsed pyramids at the boundary overstate peak stresses (docs/fem-accuracy.md)",
    )
    parser.add_argument("--stats", metavar="JSON", help="write the run's report to this JSON file")
    parser.add_argument(
        "--progress",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="show progress on stderr (default: when stderr is a terminal)",
    )
    parser.add_argument("-q", "--quiet", action="store_true", help="print nothing on success")


def _positive_length(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not math.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"the size must be a positive length, got {text}")
    return value


class ProgressPrinter:
    """Progress on stderr: one updating line on a terminal, a line per phase and 10 % else."""

    def __init__(self, stream: TextIO, tty: bool) -> None:
        self.stream, self.tty = stream, tty
        self.phase, self.step, self.dirty = "", -1, False

    def __call__(self, phase: str, fraction: float) -> bool:
        pct = max(0, min(100, int(fraction * 100)))
        if self.tty:
            self.stream.write(f"\r{phase}: {pct:3d} %\x1b[K")
            self.dirty = True
        elif phase != self.phase or pct // 10 != self.step:
            self.stream.write(f"{phase}: {pct} %\n")
        self.phase, self.step = phase, pct // 10
        self.stream.flush()
        return True

    def close(self) -> None:
        if self.dirty:
            self.stream.write("\r\x1b[K")
            self.stream.flush()


def _jsonable(value: Any) -> Any:
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _summary(path: str, report: dict[str, Any], out: str) -> str:
    counts = ", ".join(f"{n} {name}" for name, n in report["output_counts"].items() if n)
    return (
        f"{path}: {report['input_tets']} tets -> {report['output_cells']} cells ({counts}); "
        f"reduction {report['element_reduction_percent']:.1f} %, hex volume "
        f"{100 * report['volume_fraction'].get('hex', 0.0):.1f} %, "
        f"{report['nonconforming_quads']} non-conforming quads -> {out}"
    )


def _given(args: argparse.Namespace, rows: list[dict[str, Any]]) -> dict[str, Any]:
    """The options of a table that were given on the command line."""
    options = {row["name"]: getattr(args, row["name"]) for row in rows}
    return {k: v for k, v in options.items() if v is not None}


def _output_format(args: argparse.Namespace, source: str) -> str:
    """OUT's format, and OUT and --stats checked against the input and each other, before any
    work."""
    fmt = _io.format_of(args.output, args.output_format)
    _io.check_targets({"output": args.output, "--stats file": args.stats}, [source])
    return fmt


def _progress_printer(args: argparse.Namespace) -> ProgressPrinter | None:
    show = args.progress if args.progress is not None else sys.stderr.isatty()
    return ProgressPrinter(sys.stderr, sys.stderr.isatty()) if show else None


def _write_output(
    args: argparse.Namespace, fmt: str, mesh: _api.MixedMesh, stats: dict[str, Any], **to_meshio: Any
) -> None:
    """Writes OUT and the --stats file, both or neither."""
    out_mesh = _io.to_meshio(mesh, fmt, collapse_pyramids=args.collapse_pyramids, **to_meshio)
    kwargs: dict[str, Any] = {}
    if args.ascii and fmt in ("gmsh", "gmsh22", "vtu", "vtk"):
        kwargs["binary"] = False
    text_files = {args.stats: json.dumps(_jsonable(stats), indent=2) + "\n"} if args.stats else {}
    _io.write_atomic(args.output, out_mesh, fmt, text_files=text_files, **kwargs)


def cmd_recombine(args: argparse.Namespace) -> int:
    options = _given(args, _api.parameters())
    fmt = _output_format(args, args.input)
    tets = _io.read_tets(args.input, args.input_format)
    printer = _progress_printer(args)
    start = time.perf_counter()
    try:
        mesh, report = _api.recombine(tets.points, tets.cells, tets.regions, progress=printer, **options)
    finally:
        if printer:
            printer.close()
    seconds = time.perf_counter() - start
    stats = {
        "input": str(args.input),
        "output": str(args.output),
        "order": mesh.order,
        "options": options,
        "wall_seconds": seconds,
        "report": report,
    }
    _write_output(args, fmt, mesh, stats, region_key=tets.region_key, region_names=tets.region_names)
    if not args.quiet:
        print(_summary(args.input, report, args.output))
        if tets.ignored:
            left = ", ".join(f"{n} {name}" for name, n in tets.ignored.items())
            print(f"note: left out the input's lower-dimensional cells ({left})", file=sys.stderr)
    return EXIT_OK


def _mesh_summary(args: argparse.Namespace, mesh: _api.MixedMesh, report: dict[str, Any], seconds: float) -> str:
    meshing = report["meshing"]
    swept = f" swept along lattice axis {meshing['sweep_axis']}" if meshing["sweep_axis"] >= 0 else ""
    head = (
        f"{args.shape}: h {args.size:g}: {meshing['tets']} tets{swept}, max boundary distance "
        f"{meshing['max_boundary_distance']:.2g}"
    )
    if "output_counts" not in report:
        return f"{head}; {seconds:.2f} s -> {args.output}"
    counts = ", ".join(f"{n} {name}" for name, n in report["output_counts"].items() if n)
    mins = [v for k, v in report["min_scaled_jacobian"].items() if report["output_counts"].get(k)]
    return (
        f"{head} -> {report['output_cells']} cells ({counts}); hex volume "
        f"{100 * report['volume_fraction'].get('hex', 0.0):.1f} %, reduction "
        f"{report['element_reduction_percent']:.1f} %, {report['nonconforming_quads']} "
        f"non-conforming quads, min scaled Jacobian {min(mins):.3f}; {seconds:.2f} s -> {args.output}"
    )


def cmd_mesh(args: argparse.Namespace) -> int:
    try:
        _shape._require_opencascade()
    except RuntimeError as e:
        print(f"hexmerge mesh: error: {e}", file=sys.stderr)
        return EXIT_ERROR
    mesher = _given(args, _shape.mesh_parameters())
    size = mesher.pop("size")
    options = _given(args, _api.parameters())
    if args.tets_only and options:
        raise UsageError(
            "--tets-only writes the tets without merging them: leave out the engine options "
            f"({', '.join(r['cli_flag'] for r in _api.parameters() if r['name'] in options)})"
        )
    fmt = _output_format(args, args.shape)
    printer = _progress_printer(args)
    start = time.perf_counter()
    try:
        mesh, report = _shape.mesh_shape(
            args.shape, size, second_order=args.second_order, recombine=not args.tets_only, progress=printer,
            **mesher, **options,
        )
    finally:
        if printer:
            printer.close()
    seconds = time.perf_counter() - start
    stats = {
        "input": str(args.shape),
        "output": str(args.output),
        "order": mesh.order,
        "size": args.size,
        "mesh_options": mesher,
        "options": options,
        "wall_seconds": seconds,
        "report": report,
    }
    # Regions are solid indices from 0; files get solid numbers from 1 (Gmsh physical tags
    # must be positive), named Solid1, Solid2... in Abaqus element sets.
    if mesh.regions is not None:
        mesh.regions = mesh.regions + 1
    names = {int(r): f"Solid{int(r)}" for r in np.unique(mesh.regions)} if mesh.regions is not None else {}
    _write_output(args, fmt, mesh, stats, region_key="region", region_names=names)
    if not args.quiet:
        print(_mesh_summary(args, mesh, report, seconds))
        for note in _shape.mesh_notes(report["meshing"]):
            print(f"hexmerge mesh: note: {note}", file=sys.stderr)
    return EXIT_OK


def _print_check(report: dict[str, Any]) -> None:
    counts = ", ".join(f"{n} {name}" for name, n in report["counts"].items() if n)
    print(f"{report['nb_cells']} cells ({counts})")
    worst = report["worst_cell"]
    print(f"min scaled Jacobian {report['min_scaled_jacobian']:.4g}" + (f" (cell {worst})" if worst is not None else ""))
    for key in (
        "inverted_cells",
        "cracks",
        "overshared_faces",
        "nonconforming_quads",
        "unused_input_nodes",
        "moved_nodes",
        "region_mismatches",
    ):
        print(f"{key.replace('_', ' ')}: {report[key]}")
    print(
        f"volume {report['output_volume']:.9g} against {report['input_volume']:.9g} "
        f"(relative difference {report['relative_volume_difference']:.3g})"
    )
    if report.get("worst_region") is not None:
        print(
            f"largest region volume difference {report['max_region_volume_difference']:.3g} "
            f"(region {report['worst_region']})"
        )
    for line in report["problems"]:
        print(f"  {line}")
    print("valid" if report["valid"] else "INVALID")


def cmd_check(args: argparse.Namespace) -> int:
    mesh, raw = _io.read_mixed(args.mesh)
    if args.source:
        source = _io.read_tets(args.source)
        points, cells, regions = source.points, source.cells, source.regions
    else:
        if mesh.counts()["tetra"] != mesh.nb_cells:
            raise _io.MeshFileError(
                f"{args.mesh}: the mesh has other cells than tetrahedra; give the tet mesh it "
                "came from with --source TETMESH"
            )
        points = mesh.points
        cells = mesh.cell_vertices.reshape(-1, 4)
        regions = mesh.regions
    report = _api.check(mesh, points, cells, regions)
    if args.json:
        print(json.dumps(_jsonable(report), indent=2))
    else:
        _print_check(report)
    return EXIT_OK if report["valid"] else EXIT_INVALID


def cmd_parameters(args: argparse.Namespace) -> int:
    rows = _shape.mesh_parameters() if args.mesh else _api.parameters()
    if args.json:
        print(json.dumps(_jsonable(rows), indent=2))
        return EXIT_OK
    for row in rows:
        print(f"{row['cli_flag']}: {_help(row).replace('%%', '%')}")
    return EXIT_OK


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    command = {
        "recombine": cmd_recombine,
        "mesh": cmd_mesh,
        "check": cmd_check,
        "parameters": cmd_parameters,
    }[args.command]
    try:
        return command(args)
    except KeyboardInterrupt:
        print("hexmerge: interrupted; nothing written", file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:  # stdout closed early (`hexmerge check --json | head`)
        sys.stderr.close()
        return EXIT_OK
    except UsageError as e:
        print(f"hexmerge {args.command}: error: {e}", file=sys.stderr)
        return EXIT_USAGE
    except _core.Cancelled:
        print("hexmerge: cancelled; nothing written", file=sys.stderr)
        return EXIT_ERROR
    except MemoryError as e:  # ResourceError (threads) is one too
        detail = str(e) if isinstance(e, _core.ResourceError) or str(e).startswith("out of memory") else "out of memory"
        print(f"hexmerge: error: {detail}; nothing written", file=sys.stderr)
        return EXIT_ERROR
    except (ValueError, OSError) as e:  # InputError and MeshFileError are ValueErrors
        where = ""
        if isinstance(e, _core.InputError) and args.command in ("recombine", "mesh"):
            source = str(args.input if args.command == "recombine" else args.shape)
            where = "" if source in str(e) else f"{source}: "
        print(f"hexmerge: error: {where}{e}", file=sys.stderr)
        return EXIT_ERROR
