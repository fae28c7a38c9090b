"""Reading tet meshes and writing mixed meshes with meshio (every volume format it handles).

meshio keeps every cell in VTK's node order and converts the formats that differ (Gmsh's
second-order cells, for one) when reading and writing.
"""

from __future__ import annotations

import contextlib
import io
import os
import re
import stat
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from . import _cells, _vtu
from ._api import MixedMesh
from ._meshio import PREFERRED_FORMAT, meshio as _meshio

#: cell_data keys that carry a region (material, solid) id, by priority.
REGION_KEYS = (
    "gmsh:physical",
    "medit:ref",
    "netgen:index",
    "region",
    "CellEntityIds",
    "material",
    "gmsh:geometrical",
)
_SURFACE_OR_LOWER = {"vertex", "line", "line3", "triangle", "triangle6", "triangle7", "quad", "quad8", "quad9"}


class MeshFileError(ValueError):
    """A file that cannot be read or written as asked."""


@dataclass
class TetFile:
    """A tet mesh read from a file: arrays for recombine() plus what writing back needs."""

    points: np.ndarray
    cells: np.ndarray  # (M, 4) or (M, 10)
    regions: np.ndarray | None
    region_key: str | None = None
    region_names: dict[int, str] = field(default_factory=dict)  # from Abaqus element sets
    ignored: dict[str, int] = field(default_factory=dict)  # lower-dimensional cells left out


#: Text formats with no end marker and no counts, whose writers end the last line with a newline:
#: a file cut short inside a line is refused (an .inp cut inside a node id would give an element
#: a wrong node). (.msh has $End markers and counts, legacy .vtk counts: checked otherwise.)
_TEXT_SUFFIXES = {".inp"}
#: Largest node tag accepted for n nodes, and at all: meshio maps tags through an array as long
#: as the largest tag (sparse tags near 1e12 needed 8 GB), in 32 bits for Gmsh 2.2.
_MAX_TAG_FACTOR = 64
_MAX_TAG_FLOOR = 1 << 20
_MAX_TAG_GMSH22 = (1 << 31) - 2


def _is_text(head: bytes) -> bool:
    return b"\0" not in head and all(b >= 9 for b in head[:4096])


def _section_markers(data: bytes) -> list[bytes]:
    """The names of the lines `$Name` (a Gmsh section's start or end), in file order: what
    re.findall(rb"(?m)^\\$(\\w+)\\s*$", data) gives, found with bytes.find (a multiline regex
    over a 1M-tet file took a second)."""
    names = []
    begin = data.find(b"$")  # a rare byte: found fast (a search for "\n$" is not)
    while begin >= 0:
        line = begin == 0 or data[begin - 1] == 0x0A
        at, begin = begin, data.find(b"$", begin + 1)
        if not line:
            continue
        stop = data.find(b"\n", at)
        m = re.fullmatch(rb"\$(\w+)\s*", data[at : len(data) if stop < 0 else stop])
        if m:
            names.append(m.group(1))
    return names


def _check_gmsh_nodes(path: Path, data: bytes) -> None:
    """Refuses an ASCII Gmsh file cut short (a section not closed) or whose node tags meshio
    cannot map: tags that are not positive whole numbers, or so sparse that its tag table would
    not fit in memory."""
    start = data.find(b"$MeshFormat")
    nodes = data.find(b"$Nodes")
    end = data.find(b"$EndNodes", nodes)
    if start < 0 or nodes < 0 or end < 0:
        return  # meshio reports what is missing
    version = data[start : start + 64].split(None, 3)[1:3]  # a slice: no copy of the file
    if len(version) < 2 or version[1] != b"0":
        return  # binary: meshio checks the tags itself
    # Every section closed: a file cut short loses its last $End... line.
    opened = None
    for name in _section_markers(data):
        if opened is None:
            opened = name
        elif name == b"End" + opened:
            opened = None
        else:
            break
    if opened is not None:
        raise MeshFileError(f"{path}: section ${opened.decode()} is not closed: the file is cut short or damaged")
    words = data[nodes + len(b"$Nodes") : end].split()
    try:
        if version[0].startswith(b"2"):
            count = int(words[0])
            tags = [words[1 + 4 * i] for i in range(count)]
        else:  # 4.x: numEntityBlocks numNodes minTag maxTag, then per block dim tag param n
            count, tags, i = int(words[1]), [], 4
            while i < len(words) and len(tags) < count:
                n = int(words[i + 3])
                tags += words[i + 4 : i + 4 + n]
                i += 4 + n + 3 * n
    except (ValueError, IndexError):
        return  # malformed: meshio reports it
    values = None
    if b"\0" not in data[nodes:end]:  # numpy's bytes drop trailing NULs, which int() refuses
        try:
            values = np.array(tags, dtype=np.bytes_).astype(np.int64)  # int() of each word, in C
        except (ValueError, OverflowError):
            pass
    if values is None or (values.size and values.min() <= 0):
        for word in tags:  # the first word at fault, named
            try:
                tag = int(word)
            except ValueError:
                raise MeshFileError(f"{path}: node tag {word.decode(errors='replace')} is not a whole number") from None
            if tag <= 0:
                raise MeshFileError(f"{path}: node tag {tag} is not positive (Gmsh numbers nodes from 1)")
    largest = int(values.max()) if values is not None and values.size else max((int(w) for w in tags), default=0)
    limit = max(_MAX_TAG_FACTOR * len(tags), _MAX_TAG_FLOOR)
    if version[0].startswith(b"2"):
        limit = min(limit, _MAX_TAG_GMSH22)
    if largest > limit:
        raise MeshFileError(
            f"{path}: node tags are too sparse to read (largest {largest} for {len(tags)} nodes; "
            f"at most {limit}): renumber the nodes"
        )


def _check_vtk_counts(path: Path, data: bytes, mesh: Any) -> None:
    """A legacy ASCII .vtk file declares how many points and cells it has: fewer read means the
    file was cut short."""
    head = data[:1024].split(b"\n")
    if len(head) < 3 or head[2].strip().upper() != b"ASCII":
        return
    for keyword, got, what in (
        (rb"\bPOINTS\s+(\d+)", len(mesh.points), "points"),
        (rb"\bCELLS\s+(\d+)", sum(len(b.data) for b in mesh.cells), "cells"),
    ):
        m = re.search(keyword, data)
        if m and int(m.group(1)) != got:
            raise MeshFileError(
                f"{path}: the file declares {int(m.group(1))} {what} but holds {got}: it is cut short or damaged"
            )


def read(path: str | os.PathLike[str], file_format: str | None = None) -> Any:
    """The meshio mesh in a file. Refuses, in our words, what meshio would read wrongly (a text
    file cut inside a line, a legacy .vtk with fewer points or cells than it declares, Gmsh node
    tags too sparse to map) or fail on with its own text."""
    meshio = _meshio()

    path = Path(path)
    if not path.is_file():
        raise MeshFileError(f"{path}: no such file")
    with open(path, "rb") as f:
        data = f.read()
    suffix = path.suffix.lower()
    if suffix in _TEXT_SUFFIXES and data and _is_text(data[:4096]) and not data.endswith((b"\n", b"\r")):
        raise MeshFileError(f"{path}: the file ends inside a line: it is cut short")
    if suffix == ".msh" or (file_format or "").startswith("gmsh"):
        _check_gmsh_nodes(path, data)
    if suffix == ".mesh" and _is_text(data[:4096]) and data.split()[-1:] != [b"End"]:
        # Medit ends with the keyword End: without it the file was cut short.
        raise MeshFileError(f"{path}: the file does not end with the keyword End: it is cut short")
    del data
    said = io.StringIO()
    try:
        with contextlib.redirect_stdout(said), contextlib.redirect_stderr(said):
            mesh = meshio.read(path, file_format=file_format)
    except SystemExit:  # meshio 5.0 prints its error and calls sys.exit(1) when no reader fits
        text = " ".join(said.getvalue().split()) or "no reader fits"
        raise MeshFileError(f"{path}: cannot read the mesh ({text})") from None
    except MemoryError:
        raise MeshFileError(f"{path}: cannot read the mesh: out of memory") from None
    except Exception as e:  # meshio raises ReadError, KeyError, ValueError... for bad files
        raise MeshFileError(f"{path}: cannot read the mesh: {_reader_error(e)}") from None
    if suffix == ".vtk":
        with open(path, "rb") as f:
            _check_vtk_counts(path, f.read(), mesh)
    for block in mesh.cells:
        data = np.asarray(block.data)
        if data.size and (data.min() < 0 or data.max() >= len(mesh.points)):
            raise MeshFileError(
                f"{path}: a {block.type} cell refers to a node the file does not define"
            )
    return mesh


def _reader_error(e: Exception) -> str:
    """meshio's exception as a sentence: its own messages are kept, its internals (a KeyError on
    a missing node id, numpy's 'need at least one array to concatenate') are said plainly."""
    if isinstance(e, KeyError):
        return f"it refers to {e.args[0] if e.args else 'an id'}, which the file does not define"
    text = str(e)
    if "need at least one array to concatenate" in text:
        return "it has no cells"
    if isinstance(e, (ValueError, IndexError)) and ("reshape" in text or "index" in text):
        return "it is cut short or damaged"
    return f"{type(e).__name__}: {text}" if text else f"{type(e).__name__} (damaged file?)"


def _block_regions(mesh: Any, b: int) -> tuple[str | None, np.ndarray | None]:
    for key in REGION_KEYS:
        data = mesh.cell_data.get(key)
        if data is not None and b < len(data) and data[b] is not None:
            return key, np.asarray(data[b]).reshape(-1)
    return None, None


def _regions_from_sets(mesh: Any, volume_blocks: list[int]) -> tuple[list[np.ndarray] | None, dict[int, str]]:
    """Regions from element sets (Abaqus ELSETs): sets that hold some but not all of the tets,
    in file order; a tet in several takes the first, one in none gets 0."""
    sets = getattr(mesh, "cell_sets", None) or {}
    total = sum(len(mesh.cells[b].data) for b in volume_blocks)
    parts = [np.zeros(len(mesh.cells[b].data), dtype=np.int64) for b in volume_blocks]
    names: dict[int, str] = {}
    for name, per_block in sets.items():
        members = [np.asarray(per_block[b], dtype=np.int64) if b < len(per_block) else np.empty(0, np.int64) for b in volume_blocks]
        count = sum(len(np.unique(m)) for m in members)
        if count == 0 or count == total:
            continue
        rid = len(names) + 1
        names[rid] = name
        for part, m in zip(parts, members):
            fresh = m[part[m] == 0]
            part[fresh] = rid
    if not names:
        return None, {}
    return parts, names


def read_tets(path: str | os.PathLike[str], file_format: str | None = None) -> TetFile:
    """The tetrahedra of a mesh file (Tet4 or Tet10) with their regions; other volume cells
    are an error, surface, line and vertex cells are left out (and counted in ``ignored``)."""
    mesh = read(path, file_format)
    volume_blocks, ignored, kinds = [], {}, set()
    for b, block in enumerate(mesh.cells):
        name = block.type
        if name in ("tetra", "tetra10"):
            volume_blocks.append(b)
            kinds.add(name)
        elif name in _cells.BY_MESHIO_NAME or name in _cells.OTHER_VOLUME_NAMES:
            raise MeshFileError(
                f"{path}: unsupported cell type {name!r} ({len(block.data)} cells): hexmerge "
                "merges tetrahedral meshes (linear tetra or quadratic tetra10) only"
            )
        else:
            ignored[name] = ignored.get(name, 0) + len(block.data)
    if not volume_blocks:
        raise MeshFileError(f"{path}: the mesh has no tetrahedra")
    if len(kinds) > 1:
        raise MeshFileError(f"{path}: the mesh mixes linear (tetra) and quadratic (tetra10) tetrahedra")
    cells = np.concatenate([np.asarray(mesh.cells[b].data) for b in volume_blocks])
    key, regions = None, None
    parts = []
    for b in volume_blocks:
        k, r = _block_regions(mesh, b)
        if r is None or (key is not None and k != key):
            parts = []
            break
        key = k
        parts.append(r)
    names: dict[int, str] = {}
    if parts:
        regions = np.concatenate(parts)
        if key == "gmsh:physical" and not regions.any():
            # No physical groups in the file: the geometric volumes (solids) are the regions.
            _, geo = zip(*(_block_regions_key(mesh, b, "gmsh:geometrical") for b in volume_blocks))
            if all(g is not None for g in geo):
                key, regions = "gmsh:geometrical", np.concatenate(geo)
    else:
        key = None
        set_parts, names = _regions_from_sets(mesh, volume_blocks)
        if set_parts is not None:
            regions, key = np.concatenate(set_parts), "cell_sets"
    return TetFile(
        points=np.asarray(mesh.points, dtype=np.float64)[:, :3] if mesh.points.shape[1] >= 3 else mesh.points,
        cells=cells,
        regions=regions,
        region_key=key,
        region_names=names,
        ignored=ignored,
    )


def _block_regions_key(mesh: Any, b: int, key: str) -> tuple[str, np.ndarray | None]:
    data = mesh.cell_data.get(key)
    if data is None or b >= len(data):
        return key, None
    return key, np.asarray(data[b]).reshape(-1)


def read_mixed(path: str | os.PathLike[str], file_format: str | None = None) -> tuple[MixedMesh, Any]:
    """A mixed mesh (linear or quadratic tets, pyramids, prisms, hexes) from a file, with the
    raw meshio mesh. Lower-dimensional cells are left out."""
    mesh = read(path, file_format)
    blocks, region_parts = [], []
    have_regions = True
    for b, block in enumerate(mesh.cells):
        if block.type in _cells.BY_MESHIO_NAME:
            _, r = _block_regions(mesh, b)
            have_regions = have_regions and r is not None
            for name, rows in _uncollapsed_pyramids(block.type, np.asarray(block.data)):
                data = np.asarray(block.data)[rows]
                blocks.append((name, data[:, :5] if name != block.type else data))
                region_parts.append(None if r is None else r[rows])
        elif block.type in _cells.OTHER_VOLUME_NAMES:
            raise MeshFileError(f"{path}: unsupported cell type {block.type!r} ({len(block.data)} cells)")
    if not blocks:
        raise MeshFileError(f"{path}: the mesh has no volume cells")
    try:
        mixed = MixedMesh.from_blocks(mesh.points[:, :3], blocks, region_parts if have_regions else None)
    except ValueError as e:
        raise MeshFileError(f"{path}: {e}") from None
    return mixed, mesh


#: meshio formats that hold points, lines and surface cells only: a mixed volume mesh written
#: to them would lose every cell (meshio writes such files without a word).
SURFACE_ONLY_FORMATS = {"stl", "obj", "off", "ply", "wkt", "svg", "neuroglancer"}


def format_of(path: str | os.PathLike[str], file_format: str | None) -> str:
    """The meshio format name for writing `path`; surface-only formats are refused."""
    if file_format:
        fmt = file_format
    elif Path(path).suffix.lower() in PREFERRED_FORMAT:
        fmt = PREFERRED_FORMAT[Path(path).suffix.lower()]
    else:
        _meshio()
        from meshio._helpers import _filetypes_from_path  # meshio's own extension table

        try:
            types = _filetypes_from_path(Path(path))
        except Exception:
            types = []
        if not types:
            raise MeshFileError(f"{path}: unknown mesh file extension; give the format with --output-format")
        fmt = types[0]
    if fmt in SURFACE_ONLY_FORMATS:
        raise MeshFileError(
            f"{path}: the {fmt} format holds surfaces only and would lose every volume cell; "
            "write a volume format (.vtu, .msh, .inp, .mesh, .med)"
        )
    return fmt


def _identity(path: Path) -> tuple[int, int] | None:
    """(device, inode) of the file `path` names (through symlinks), None when there is none."""
    try:
        st = path.stat()
    except OSError:
        return None
    return st.st_dev, st.st_ino


def check_targets(targets: dict[str, str | os.PathLike[str] | None], inputs: list[str | os.PathLike[str]]) -> None:
    """Refuses, before any work, output paths (label -> path; None: not asked for) that are not
    regular files, that name an input, or that name each other (by inode for files that exist,
    by real path for files to be made): writing never overwrites an input, never replaces a
    device node, a FIFO or a symlink, and never writes two outputs over one another."""
    seen: dict[object, str] = {}
    for path in inputs:
        ident = _identity(Path(path))
        if ident is not None:
            seen[ident] = f"the input {path}"
        seen[os.path.realpath(path)] = f"the input {path}"
    for label, path in targets.items():
        if path is None:
            continue
        p = Path(path)
        folder = p.parent if str(p.parent) else Path(".")
        if not folder.is_dir():
            raise MeshFileError(f"{path} ({label}): the folder {folder} does not exist")
        try:
            st = p.lstat()
        except FileNotFoundError:
            st = None
        if st is not None:
            if stat.S_ISLNK(st.st_mode):
                raise MeshFileError(
                    f"{path} ({label}): is a symbolic link; hexmerge writes regular files only "
                    "(name the file it points to, or another path)"
                )
            if not stat.S_ISREG(st.st_mode):
                kind = _FILE_KINDS.get(stat.S_IFMT(st.st_mode), "not a regular file")
                raise MeshFileError(f"{path} ({label}): is {kind}; hexmerge writes regular files only")
        keys = [os.path.realpath(p)]
        ident = _identity(p)
        if ident is not None:
            keys.append(ident)
        for key in keys:
            if key in seen:
                raise MeshFileError(f"{path} ({label}): is also {seen[key]}; give another path")
        for key in keys:
            seen[key] = f"the {label} {path}"


_FILE_KINDS = {
    stat.S_IFDIR: "a folder",
    stat.S_IFCHR: "a character device",
    stat.S_IFBLK: "a block device",
    stat.S_IFIFO: "a FIFO (named pipe)",
    stat.S_IFSOCK: "a socket",
}


def _collapsed_pyramids(blocks: list[tuple[str, np.ndarray]]) -> list[tuple[str, np.ndarray]]:
    """Pyramids as degenerate hexahedra (base, then the apex four times): the form CalculiX
    and Abaqus accept where they have no pyramid element."""
    out = []
    for name, data in blocks:
        if name == "pyramid":
            name, data = "hexahedron", data[:, [0, 1, 2, 3, 4, 4, 4, 4]]
        out.append((name, data))
    return out


def _uncollapsed_pyramids(name: str, data: np.ndarray) -> list[tuple[str, np.ndarray]]:
    """The rows of a cell block by type: hexahedra written as pyramids (base, then the apex four
    times, as --collapse-pyramids writes them for CalculiX) are pyramids again; other rows keep
    their type."""
    if name != "hexahedron" or len(data) == 0:
        return [(name, np.arange(len(data)))]
    apex = (data[:, 4:8] == data[:, 4:5]).all(axis=1)
    out = []
    if (~apex).any():
        out.append((name, np.flatnonzero(~apex)))
    if apex.any():
        out.append(("pyramid", np.flatnonzero(apex)))
    return out


def _node_entities(nb_points: int, blocks: list[np.ndarray]) -> np.ndarray:
    """(dim 3, entity tag) per node for Gmsh 4.1: a node belongs to the first block (entity
    b + 1) that uses it, and every block keeps at least one node of its own."""
    owner = np.full(nb_points, -1, dtype=np.int64)
    for b, data in enumerate(blocks):
        nodes = np.unique(data)
        owner[nodes[owner[nodes] < 0]] = b
    for b, data in enumerate(blocks):
        if (owner == b).any():
            continue
        counts = np.bincount(owner[owner >= 0], minlength=len(blocks))
        for v in np.unique(data):
            if counts[owner[v]] > 1:
                owner[v] = b
                break
    owner[owner < 0] = 0
    return np.column_stack([np.full(nb_points, 3, dtype=np.int64), owner + 1])


def to_meshio(
    mesh: MixedMesh,
    fmt: str,
    *,
    region_key: str | None = None,
    region_names: dict[int, str] | None = None,
    collapse_pyramids: bool = False,
) -> Any:
    """A meshio.Mesh of the mixed mesh, with its regions stored the way `fmt` keeps them."""
    meshio = _meshio()

    blocks = mesh.cell_blocks(by_region=mesh.regions is not None)
    cells = [(b.type, b.data.astype(np.int64)) for b in blocks]
    if fmt == "abaqus" and not collapse_pyramids and any(b.type.startswith("pyramid") for b in blocks):
        raise MeshFileError(
            "the Abaqus/CalculiX format (.inp) has no pyramid element: add --collapse-pyramids "
            "(pyramids written as degenerate hexahedra; for CalculiX with --pyramid-placement "
            "no_boundary_node for recombined tets or no_curved_boundary_node for meshes from "
            "CAD: collapsed pyramids at the boundary overstate peak stresses), "
            "--no-make-pyramids, or write another format (.vtu, .msh, .mesh)"
        )
    if collapse_pyramids:
        if mesh.order == 2 and any(b.type == "pyramid13" for b in blocks):
            raise MeshFileError("--collapse-pyramids works on linear meshes only")
        cells = _collapsed_pyramids(cells)
    regions = [mesh.regions[b.cells] if mesh.regions is not None else np.zeros(len(b.cells), np.int64) for b in blocks]
    cell_data: dict[str, list[np.ndarray]] = {}
    cell_sets: dict[str, list[np.ndarray]] = {}
    point_data: dict[str, np.ndarray] = {}
    if fmt.startswith("gmsh"):
        # The physical tag is the region; the entity (geometrical) tag must be one per block
        # and unique (meshio's Gmsh 4.1 writer), and Gmsh 4.1 also wants every node in an entity.
        cell_data["gmsh:physical"] = [
            (r if mesh.regions is not None else np.ones_like(r)).astype(np.int64) for r in regions
        ]
        cell_data["gmsh:geometrical"] = [np.full(len(r), b + 1, dtype=np.int64) for b, r in enumerate(regions)]
        point_data["gmsh:dim_tags"] = _node_entities(len(mesh.points), [c[1] for c in cells])
    elif mesh.regions is not None:
        if fmt == "abaqus":
            names = region_names or {}
            for b, block in enumerate(blocks):
                rid = int(block.region) if block.region is not None else 0
                name = names.get(rid, f"Region{rid}")
                cell_sets.setdefault(name, [np.empty(0, np.int64) for _ in blocks])[b] = np.arange(len(block.cells))
        elif fmt == "medit":
            cell_data["medit:ref"] = regions
        else:
            key = region_key if region_key and not region_key.startswith(("gmsh:", "medit:")) and region_key != "cell_sets" else "region"
            cell_data[key] = regions
    return meshio.Mesh(
        mesh.points, cells, point_data=point_data, cell_data=cell_data, cell_sets=cell_sets or None
    )


def _temp_beside(path: Path) -> Path:
    """A new empty temporary file in `path`'s folder (so that renaming it over `path` is atomic)."""
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise MeshFileError(f"{path}: the folder {folder} does not exist")
    fd, tmp = tempfile.mkstemp(dir=folder, prefix=f".{path.stem}.", suffix=".tmp" + "".join(path.suffixes))
    os.close(fd)
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes it private; give it a normal file's mode
    return Path(tmp)


def write_atomic(
    path: str | os.PathLike[str],
    mesh: Any,
    fmt: str,
    *,
    text_files: dict[str | os.PathLike[str], str] | None = None,
    **kwargs: Any,
) -> None:
    """Writes the mesh and the text files (path -> text) through temporary files in their
    folders, renamed over their paths only once every one is written: a failed write leaves no
    output, partial or stale."""
    meshio = _meshio()

    path = Path(path)
    temps: list[tuple[Path, Path]] = []
    try:
        temps.append((_temp_beside(path), path))
        try:
            if fmt == "vtu" and kwargs.get("binary", True):
                _vtu.write(temps[0][0], mesh)  # raw binary: meshio's zlib was most of the write
            else:
                meshio.write(temps[0][0], mesh, file_format=fmt, **kwargs)
        except Exception as e:
            raise MeshFileError(f"{path}: cannot write the mesh as {fmt}: {type(e).__name__}: {e}") from None
        for target, text in (text_files or {}).items():
            target = Path(target)
            temps.append((_temp_beside(target), target))
            try:
                temps[-1][0].write_text(text)
            except OSError as e:
                raise MeshFileError(f"{target}: cannot write: {e.strerror or e}") from None
        while temps:
            tmp, target = temps[0]
            os.replace(tmp, target)
            temps.pop(0)
    except BaseException:
        for tmp, _ in temps:
            tmp.unlink(missing_ok=True)
        raise
