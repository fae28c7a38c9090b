"""The command line's VTU writer: a VTK XML UnstructuredGrid whose arrays
are appended as raw binary, written from numpy.

The arrays are those meshio's own VTU writer makes (its cell type numbers and node orders), so
that meshio, ParaView and VTK read the same mesh; what this writer leaves out is meshio's zlib
compression and base64 encoding, which took 80 % of writing a 1M-tet recombination's output
(docs/benchmarks.md). Node ids are written as 32-bit integers when they fit; the file is
still about 1.3x as large as meshio's compressed one (box Delaunay 100k: 2.2 against 1.7 MB)."""
from __future__ import annotations

from typing import Any, BinaryIO
from xml.sax.saxutils import quoteattr

import numpy as np

_HEADER = np.dtype("<u8")  # header_type="UInt64": the byte count before each array
_VTU_TYPES = {
    np.dtype(np.int8): "Int8",
    np.dtype(np.uint8): "UInt8",
    np.dtype(np.int16): "Int16",
    np.dtype(np.uint16): "UInt16",
    np.dtype(np.int32): "Int32",
    np.dtype(np.uint32): "UInt32",
    np.dtype(np.int64): "Int64",
    np.dtype(np.uint64): "UInt64",
    np.dtype(np.float32): "Float32",
    np.dtype(np.float64): "Float64",
}


def _little_endian(a: np.ndarray) -> np.ndarray:
    a = np.asarray(a)
    if a.dtype.newbyteorder("=") not in _VTU_TYPES:
        raise ValueError(f"VTU has no type for arrays of {a.dtype}")
    return np.ascontiguousarray(a, dtype=a.dtype.newbyteorder("<"))


def _cell_arrays(cells: list[Any]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """connectivity, offsets (the end of each cell) and VTK types, in meshio's node orders."""
    from meshio._vtk_common import meshio_to_vtk_order, meshio_to_vtk_type

    connectivity, sizes, types = [], [], []
    for block in cells:
        if block.type.startswith("polyhedron") or block.type not in meshio_to_vtk_type:
            raise ValueError(f"no VTU cell type for {block.type} cells")
        data = np.asarray(block.data, dtype=np.int64)
        order = meshio_to_vtk_order(block.type)
        if order is not None:
            data = data[:, order]
        connectivity.append(data.reshape(-1))
        sizes.append(np.full(len(data), data.shape[1], dtype=np.int64))
        types.append(np.full(len(data), meshio_to_vtk_type[block.type], dtype=np.uint8))
    if not cells:
        return np.empty(0, np.int32), np.empty(0, np.int32), np.empty(0, np.uint8)
    connectivity_, offsets = np.concatenate(connectivity), np.cumsum(np.concatenate(sizes))
    # 32-bit ids when they fit (half the file's size; VTK and meshio read either)
    if offsets[-1] <= np.iinfo(np.int32).max and connectivity_.max(initial=0) <= np.iinfo(np.int32).max:
        return connectivity_.astype(np.int32), offsets.astype(np.int32), np.concatenate(types)
    return connectivity_, offsets, np.concatenate(types)


def write(path: Any, mesh: Any) -> None:
    """Writes a meshio.Mesh of points, cells, point data and cell data (no sets, no polyhedra)
    as .vtu with raw appended arrays."""
    if mesh.point_sets or mesh.cell_sets:
        raise ValueError("the VTU writer writes no point or cell sets: make them cell data first")
    points = np.asarray(mesh.points)
    if points.ndim != 2 or points.shape[1] != 3:
        raise ValueError("VTU needs 3D points")
    connectivity, offsets, types = _cell_arrays(list(mesh.cells))
    arrays: list[tuple[str, np.ndarray]] = []  # (section, array) in file order
    tags: list[str] = []
    offset = 0

    def add(section: str, name: str, data: np.ndarray) -> None:
        nonlocal offset
        data = _little_endian(data)
        components = f' NumberOfComponents="{data.shape[1]}"' if data.ndim == 2 else ""
        tags.append(
            f'{section}<DataArray type="{_VTU_TYPES[data.dtype.newbyteorder("=")]}" '
            f'Name={quoteattr(str(name))}{components} format="appended" offset="{offset}"/>\n'
        )
        arrays.append((section, data))
        offset += _HEADER.itemsize + data.nbytes

    add("P", "Points", points)
    add("C", "connectivity", connectivity)
    add("C", "offsets", offsets)
    add("C", "types", types)
    for name, data in mesh.point_data.items():
        add("D", name, np.asarray(data))
    for name, blocks in mesh.cell_data.items():
        add("E", name, np.concatenate([np.asarray(b) for b in blocks]) if blocks else np.empty(0))

    def section(tag: str, open_: str, close: str) -> str:
        inner = "".join("      " + t[1:] for t in tags if t[0] == tag)
        return f"    <{open_}>\n{inner}    </{close}>\n" if inner else ""

    head = (
        '<?xml version="1.0"?>\n'
        '<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="UInt64">\n'
        "  <UnstructuredGrid>\n"
        f'    <Piece NumberOfPoints="{len(points)}" NumberOfCells="{len(types)}">\n'
        + section("P", "Points", "Points")
        + section("C", "Cells", "Cells")
        + section("D", "PointData", "PointData")
        + section("E", "CellData", "CellData")
        + "    </Piece>\n  </UnstructuredGrid>\n"
        + '  <AppendedData encoding="raw">\n   _'
    )
    with open(path, "wb") as f:
        f.write(head.encode())
        for _, data in arrays:
            _write_array(f, data)
        f.write(b"\n  </AppendedData>\n</VTKFile>\n")


def _write_array(f: BinaryIO, data: np.ndarray) -> None:
    f.write(np.array([data.nbytes], dtype=_HEADER).tobytes())
    if data.nbytes:
        f.write(data.reshape(-1).view(np.uint8))

