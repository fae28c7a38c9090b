"""The public Python API: recombine(), check(), parameters() and the MixedMesh result."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Iterator, NamedTuple, Sequence

import numpy as np

from . import _cells, _core, _validate


class CellBlock(NamedTuple):
    """The cells of one type (and, when asked, one region), meshio style."""

    type: str  #: meshio name: "tetra", "pyramid", "wedge", "hexahedron" or a quadratic name
    data: np.ndarray  #: (k, nodes per cell) node ids, VTK order
    cells: np.ndarray  #: (k,) ids of these cells in the MixedMesh
    region: int | None  #: the region of every cell of the block, when blocks are split by region


@dataclass(eq=False)
class MixedMesh:
    """A mesh of tets, pyramids, prisms and hexes (linear or quadratic), as flat arrays.

    Cell ``c`` has type ``types[c]`` (0 tet, 1 pyramid, 2 prism, 3 hex) and corners
    ``cell_vertices[offsets[c]:offsets[c + 1]]`` in VTK's local order. A quadratic mesh also
    has ``quadratic_nodes[quadratic_offsets[c]:quadratic_offsets[c + 1]]``: the corners, then
    one mid-edge node per edge in VTK's quadratic order. Node ids index ``points``.
    ``point_map[i]`` is the input's node id of node ``i`` (past the input's for a node it added; None
    when the mesh was not made
    by recombine()); ``source_offsets``/``source_tets`` list the input tets each cell is the
    union of. ``changed_nodes`` (sorted ids, None or empty when none) are the nodes recombine()
    moved, removed (used by no cell) or added (ids past the input's): only the post-merge stage
    (same_nodes=False) changes nodes, and check() then verifies the boundary and the volumes.
    """

    points: np.ndarray
    types: np.ndarray
    offsets: np.ndarray
    cell_vertices: np.ndarray
    regions: np.ndarray | None = None
    source_offsets: np.ndarray | None = None
    source_tets: np.ndarray | None = None
    quadratic_offsets: np.ndarray | None = None
    quadratic_nodes: np.ndarray | None = None
    point_map: np.ndarray | None = None
    changed_nodes: np.ndarray | None = None

    @property
    def order(self) -> int:
        """1 for linear cells, 2 for quadratic cells."""
        return 1 if self.quadratic_nodes is None else 2

    @property
    def nb_cells(self) -> int:
        return int(self.types.shape[0])

    @property
    def nb_points(self) -> int:
        return int(self.points.shape[0])

    def counts(self) -> dict[str, int]:
        """Number of cells per type, by meshio name of the linear type."""
        n = np.bincount(self.types, minlength=len(_cells.LINEAR_NAMES))
        return {name: int(n[t]) for t, name in enumerate(_cells.LINEAR_NAMES)}

    def cell_blocks(self, *, quadratic: bool | None = None, by_region: bool = False) -> list[CellBlock]:
        """Per-type blocks in meshio / VTK order (tetra, pyramid, wedge, hexahedron), empty
        types left out; quadratic blocks (tetra10, ...) for a quadratic mesh unless
        ``quadratic=False``. With ``by_region``, one block per type and region."""
        order2 = self.order == 2 if quadratic is None else quadratic
        if order2 and self.order != 2:
            raise ValueError("this mesh has no quadratic nodes")
        offsets, nodes = (
            (self.quadratic_offsets, self.quadratic_nodes) if order2 else (self.offsets, self.cell_vertices)
        )
        order = 2 if order2 else 1
        blocks = []
        for t in range(len(_cells.LINEAR_NAMES)):
            ids = np.flatnonzero(self.types == t)
            if ids.size == 0:
                continue
            n = _cells.nodes_per_cell(t, order)
            data = nodes[offsets[ids].astype(np.int64)[:, None] + np.arange(n)]
            if by_region and self.regions is not None:
                regions = self.regions[ids]
                for r in np.unique(regions):
                    keep = regions == r
                    blocks.append(CellBlock(_cells.meshio_name(t, order), data[keep], ids[keep], int(r)))
            else:
                blocks.append(CellBlock(_cells.meshio_name(t, order), data, ids, None))
        return blocks

    def cells(self, type_name: str) -> np.ndarray:
        """The (k, n) node ids of every cell of one meshio type ("hexahedron", "wedge20", ...)."""
        for block in self.cell_blocks(quadratic=_cells.BY_MESHIO_NAME[type_name][1] == 2):
            if block.type == type_name:
                return block.data
        return np.empty((0, _cells.nodes_per_cell(*_cells.BY_MESHIO_NAME[type_name])), dtype=np.uint32)

    def __iter__(self) -> Iterator[CellBlock]:
        return iter(self.cell_blocks())

    @classmethod
    def from_blocks(
        cls,
        points: Any,
        blocks: Sequence[tuple[str, Any]],
        regions: Sequence[Any] | None = None,
    ) -> "MixedMesh":
        """A mesh from meshio-style blocks [(type name, (k, n) node ids)], linear or
        quadratic (not both), with optional per-block region arrays."""
        points = _validate.points_array(points)
        orders = {_cells.BY_MESHIO_NAME[name][1] for name, _ in blocks}
        if len(orders) > 1:
            raise ValueError("the mesh mixes linear and quadratic cells")
        order = orders.pop() if orders else 1
        types, corners, full, region_parts = [], [], [], []
        for b, (name, data) in enumerate(blocks):
            t, _ = _cells.BY_MESHIO_NAME[name]
            data = np.asarray(data)
            n = _cells.NB_VERTICES[t]
            types.append(np.full(len(data), t, dtype=np.uint8))
            corners.append(data[:, :n].reshape(-1))
            full.append(data.reshape(-1))
            if regions is not None:
                region_parts.append(np.asarray(regions[b]).reshape(-1))
        types_a = np.concatenate(types) if types else np.empty(0, np.uint8)
        sizes = np.asarray(_cells.NB_VERTICES, dtype=np.int64)[types_a]
        offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.uint32)
        mesh = cls(
            points=points,
            types=types_a,
            offsets=offsets,
            cell_vertices=np.concatenate(corners).astype(np.uint32) if corners else np.empty(0, np.uint32),
            regions=np.concatenate(region_parts).astype(np.int32) if region_parts else None,
        )
        if order == 2:
            qsizes = sizes + np.asarray(_cells.NB_EDGES, dtype=np.int64)[types_a]
            mesh.quadratic_offsets = np.concatenate([[0], np.cumsum(qsizes)]).astype(np.uint32)
            mesh.quadratic_nodes = np.concatenate(full).astype(np.uint32)
        if mesh.cell_vertices.size and int(mesh.cell_vertices.max()) >= len(points):
            raise ValueError("a cell refers to a node that does not exist")
        return mesh

    def to_meshio(self, region_key: str = "region") -> Any:
        """A meshio.Mesh with one block per type (and region), regions as cell data."""
        from ._meshio import meshio as _meshio

        meshio = _meshio()

        blocks = self.cell_blocks(by_region=self.regions is not None)
        cell_data = {}
        if self.regions is not None:
            cell_data[region_key] = [self.regions[b.cells] for b in blocks]
        return meshio.Mesh(self.points, [(b.type, b.data.astype(np.int64)) for b in blocks], cell_data=cell_data)


def _tet_input(points: Any, cells: Any, regions: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    p = _validate.points_array(points)
    c = _validate.cells_array(cells, len(p))
    r = _validate.regions_array(regions, len(c))
    return p, c, r


def _drop_unused_mid_nodes(mesh: MixedMesh, tets10: np.ndarray) -> None:
    """Removes the input's mid-edge nodes that no output cell uses, renumbering in place.
    Nodes that are no mid-edge node of the input (corners, isolated nodes) are kept."""
    n = mesh.nb_points
    keep = np.ones(n, dtype=bool)
    keep[tets10[:, 4:].reshape(-1)] = False
    keep[mesh.quadratic_nodes] = True
    new_id = np.cumsum(keep, dtype=np.int64) - 1
    mesh.point_map = np.flatnonzero(keep)
    mesh.points = mesh.points[keep]
    mesh.cell_vertices = new_id[mesh.cell_vertices].astype(np.uint32)
    mesh.quadratic_nodes = new_id[mesh.quadratic_nodes].astype(np.uint32)


def recombine(
    points: Any,
    cells: Any,
    regions: Any = None,
    progress: Callable[[str, float], Any] | None = None,
    **options: Any,
) -> tuple[MixedMesh, dict[str, Any]]:
    """Merges the tetrahedra of a mesh into hexahedra, prisms and pyramids.

    Parameters
    ----------
    points : (N, 3) array of float
        Node coordinates.
    cells : (M, 4) or (M, 10) array of int
        Tetrahedra in VTK node order (0-based ids): linear (Tet4) or quadratic (Tet10: corners,
        then the mid-edge nodes of edges 01, 12, 20, 03, 13, 23).
    regions : (M,) array of int, optional
        Region (material, solid) of every tet; tets of different regions never merge.
    progress : callable(phase: str, fraction: float) -> bool | None, optional
        Called now and then from the calling thread; returning False cancels the run
        (raises hexmerge.Cancelled).
    **options
        Engine parameters by name; see parameters() (e.g. ``min_dihedral_angle=150``).

    Returns
    -------
    (MixedMesh, dict)
        The mixed mesh (quadratic for Tet10 input, reusing its mid-edge nodes; the mid-edge
        nodes no cell uses are dropped) and the run's report.

    Raises
    ------
    ValueError
        Bad input or option, naming the node or element at fault (hexmerge.InputError for what
        the engine finds: inverted, flat or duplicate tets, overshared faces...).
    """
    p, c, r = _tet_input(points, cells, regions)
    opts = _validate.options_text(options)
    fn = _validate.progress_function(progress)
    raw, report = _core.recombine(p, c, r, opts, fn)
    mesh = MixedMesh(
        points=raw["points"],
        types=raw["types"],
        offsets=raw["offsets"],
        cell_vertices=raw["cell_vertices"],
        regions=raw["regions"],
        source_offsets=raw["source_offsets"],
        source_tets=raw["source_tets"],
        # Nodes past the input's (vertex splits, same_nodes=False) keep ids past it.
        point_map=np.arange(len(raw["points"])),
        changed_nodes=raw["changed_nodes"] if len(raw["changed_nodes"]) else None,
    )
    if c.shape[1] == 10:
        mesh.quadratic_offsets = raw["quadratic_offsets"]
        mesh.quadratic_nodes = raw["quadratic_nodes"]
        _drop_unused_mid_nodes(mesh, c)
    return mesh, report


def _align_points(mesh: MixedMesh, source: np.ndarray) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """The mesh's corners renumbered onto the source's nodes: (points, cell_vertices,
    problems). Nodes are matched through point_map when known, else by exact coordinates;
    a node found nowhere in the source is appended (the core then counts it) and named."""
    if mesh.point_map is not None:
        pm = np.asarray(mesh.point_map, dtype=np.int64)
        if pm.size and len(pm) == len(mesh.points):
            # Nodes the mesh added (ids past the source's) are appended after its nodes.
            pts = np.vstack([source, np.zeros((max(0, int(pm.max()) + 1 - len(source)), 3))])
            pts[pm] = mesh.points
            return pts, pm[mesh.cell_vertices].astype(np.uint32), []
    if mesh.points.shape == source.shape and np.array_equal(mesh.points, source):
        return source, mesh.cell_vertices, []
    key = lambda row: (row + 0.0).tobytes()  # noqa: E731  (+0.0 turns -0.0 into 0.0)
    where = {key(row): i for i, row in enumerate(source)}
    used = np.unique(mesh.cell_vertices)
    new_id = np.full(mesh.nb_points, -1, dtype=np.int64)
    extra, problems = [], []
    for v in used:
        i = where.get(key(mesh.points[v]))
        if i is None:
            new_id[v] = len(source) + len(extra)
            extra.append(mesh.points[v])
            if len(problems) < 5:
                x, y, z = mesh.points[v]
                problems.append(f"node {v} at ({x}, {y}, {z}) is not a node of the source mesh")
        else:
            new_id[v] = i
    pts = np.vstack([source, np.asarray(extra).reshape(-1, 3)]) if extra else source
    return pts, new_id[mesh.cell_vertices].astype(np.uint32), problems


def check(mesh: MixedMesh, points: Any, cells: Any, regions: Any = None) -> dict[str, Any]:
    """Checks a mixed mesh against the tet mesh it came from (an independent checker).

    ``mesh`` is a MixedMesh (from recombine() or MixedMesh.from_blocks()); ``points``,
    ``cells`` (Tet4 or Tet10: only the corners count) and ``regions`` describe the source
    tet mesh. Returns the report as a dict; ``report["valid"]`` says whether the mesh passes:
    every cell positively oriented, no crack or overshared face, every input corner used at
    its exact coordinates, regions preserved. Volumes and non-conforming quads are reported.
    Nodes in ``mesh.changed_nodes`` may be moved or unused; then every such node on the
    boundary must lie on the source's boundary triangles and every region's volume must be kept
    to 1e-6 (``off_boundary_nodes``, ``volume_not_kept``).
    """
    p, c, r = _tet_input(points, cells, regions)
    corners = np.ascontiguousarray(c[:, :4])
    pts, cell_vertices, problems = _align_points(mesh, p)
    changed = None
    if mesh.changed_nodes is not None and len(mesh.changed_nodes):
        changed = np.asarray(mesh.changed_nodes, dtype=np.int64)
        if mesh.point_map is not None:
            changed = np.sort(np.asarray(mesh.point_map, dtype=np.int64)[changed])
        changed = changed.astype(np.uint32)
    report = _core.check_mesh(
        pts,
        np.ascontiguousarray(mesh.types, dtype=np.uint8),
        np.ascontiguousarray(mesh.offsets, dtype=np.uint32),
        cell_vertices,
        None if mesh.regions is None else np.ascontiguousarray(mesh.regions, dtype=np.int32),
        mesh.source_offsets,
        mesh.source_tets,
        p,
        corners,
        r,
        changed,
    )
    if problems:
        report["problems"] = problems + list(report["problems"])
        report["valid"] = False
    return report


def _typed_default(row: dict[str, Any]) -> Any:
    text = row["default"]
    kind = row["type"]
    if kind == "bool":
        return text == "true"
    if kind == "int":
        return int(float(text))
    if kind == "float":
        return float(text)
    return text


def typed_row(row: dict[str, Any]) -> dict[str, Any]:
    """A row of a compiled parameter table with its default typed (``default``) and as text
    (``default_text``)."""
    row = dict(row)
    row["default_text"] = row["default"]
    row["default"] = _typed_default(row)
    return row


def parameters() -> list[dict[str, Any]]:
    """The engine's parameter table, in display order: one dict per parameter with ``name``
    (the keyword of recombine()), ``type`` ("float", "int", "bool", "choice"), ``default``
    (typed), ``default_text``, ``unit`` ("deg" or ""), ``min``, ``max``, ``min_exclusive``
    (the range is (min, max]), ``choices``, ``label`` (for GUIs), ``doc``, ``cli_flag`` (the
    command-line option) and ``freecad_property`` (the FreeCAD add-on's property)."""
    return [typed_row(row) for row in _core.parameter_table()]


def cell_types() -> list[dict[str, Any]]:
    """The cell descriptors by type value: name, nb_vertices, nb_edges, nb_faces, faces
    (outward, VTK order), edges (VTK's quadratic order), vtk_id, plus the meshio names
    ``meshio_name`` and ``meshio_quadratic_name``."""
    rows = []
    for row in _core.cell_types():
        row = dict(row)
        row["meshio_name"] = _cells.LINEAR_NAMES[row["value"]]
        row["meshio_quadratic_name"] = _cells.QUADRATIC_NAMES[row["value"]]
        rows.append(row)
    return rows


def validate(points: Any, cells: Any, regions: Any = None) -> None:
    """Raises ValueError naming the first node or element the engine cannot process."""
    p, c, r = _tet_input(points, cells, regions)
    _core.validate_tet_mesh(p, np.ascontiguousarray(c[:, :4]), r)
