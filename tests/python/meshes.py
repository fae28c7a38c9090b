"""Small meshes built by the tests themselves, and geometric measures written independently of
the engine (from VTK's documented node orders)."""

from __future__ import annotations

import itertools

import numpy as np

# VTK corner frames: corner -> (v, a, b, c) with (a-v, b-v, c-v) right-handed in a valid cell.
CORNERS = {
    "tetra": [(0, 1, 2, 3)],
    "pyramid": [(0, 1, 3, 4), (1, 2, 0, 4), (2, 3, 1, 4), (3, 0, 2, 4)],
    "wedge": [(0, 1, 2, 3), (1, 2, 0, 4), (2, 0, 1, 5), (3, 5, 4, 0), (4, 3, 5, 1), (5, 4, 3, 2)],
    "hexahedron": [
        (0, 1, 3, 4), (1, 2, 0, 5), (2, 3, 1, 6), (3, 0, 2, 7),
        (4, 7, 5, 0), (5, 4, 6, 1), (6, 5, 7, 2), (7, 6, 4, 3),
    ],
}
# VTK faces, outward by the right-hand rule.
FACES = {
    "tetra": [(1, 2, 3), (0, 3, 2), (0, 1, 3), (0, 2, 1)],
    "pyramid": [(0, 3, 2, 1), (0, 1, 4), (1, 2, 4), (2, 3, 4), (3, 0, 4)],
    "wedge": [(0, 2, 1), (3, 4, 5), (0, 1, 4, 3), (1, 2, 5, 4), (2, 0, 3, 5)],
    "hexahedron": [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)],
}
# VTK quadratic cells: the k-th mid-edge node sits on edge k.
EDGES = {
    "tetra10": [(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)],
    "pyramid13": [(0, 1), (1, 2), (2, 3), (3, 0), (0, 4), (1, 4), (2, 4), (3, 4)],
    "wedge15": [(0, 1), (1, 2), (2, 0), (3, 4), (4, 5), (5, 3), (0, 3), (1, 4), (2, 5)],
    "hexahedron20": [
        (0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4),
        (0, 4), (1, 5), (2, 6), (3, 7),
    ],
}
LINEAR_OF = {"tetra10": "tetra", "pyramid13": "pyramid", "wedge15": "wedge", "hexahedron20": "hexahedron"}


def tet_volumes(points: np.ndarray, tets: np.ndarray) -> np.ndarray:
    p = points[tets[:, :4]]
    return np.einsum("ij,ij->i", np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), p[:, 3] - p[:, 0]) / 6.0


def orient(points: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """Tets with positive volume (swaps vertices 1 and 2 of the negative ones)."""
    tets = tets.copy()
    neg = tet_volumes(points, tets) < 0
    tets[neg, 1], tets[neg, 2] = tets[neg, 2].copy(), tets[neg, 1].copy()
    return tets


def min_corner_determinant(points: np.ndarray, name: str, cells: np.ndarray) -> np.ndarray:
    """Per cell, the smallest corner determinant of normalised edge vectors (> 0: valid)."""
    out = np.full(len(cells), np.inf)
    for v, a, b, c in CORNERS[name]:
        e = [points[cells[:, k]] - points[cells[:, v]] for k in (a, b, c)]
        e = [x / np.linalg.norm(x, axis=1)[:, None] for x in e]
        det = np.einsum("ij,ij->i", np.cross(e[0], e[1]), e[2])
        out = np.minimum(out, det)
    return out


def cell_volumes(points: np.ndarray, name: str, cells: np.ndarray) -> np.ndarray:
    """Volumes by the divergence theorem: every face fanned from its centroid to the cell's
    centroid (exact for planar faces)."""
    centre = points[cells].mean(axis=1)
    vol = np.zeros(len(cells))
    for face in FACES[name]:
        f = points[cells[:, list(face)]]
        fc = f.mean(axis=1)
        for i in range(len(face)):
            a, b = f[:, i], f[:, (i + 1) % len(face)]
            vol += np.einsum("ij,ij->i", np.cross(a - centre, b - centre), fc - centre) / 6.0
    return vol


def cube_points() -> np.ndarray:
    """The unit cube's corners, vertex x + 2y + 4z."""
    return np.array([[x, y, z] for z in (0, 1) for y in (0, 1) for x in (0, 1)], dtype=float)


def kuhn_tets(corner: list[int]) -> list[list[int]]:
    """Six tets around the diagonal 0-7 of a cube whose corners (x + 2y + 4z) are `corner`."""
    tets = []
    for perm in itertools.permutations(range(3)):
        path, cur = [0], 0
        for axis in perm:
            cur |= 1 << axis
            path.append(cur)
        tets.append([corner[i] for i in path])
    return tets


def five_tets(corner: list[int], parity: int) -> list[list[int]]:
    """Five tets: four corners cut off and the central tet; `parity` picks the diagonal set so
    that neighbouring cubes match."""
    if parity:
        centre = [1, 2, 4, 7]
        cuts = [[0, 1, 2, 4], [3, 1, 2, 7], [5, 1, 4, 7], [6, 2, 4, 7]]
    else:
        centre = [0, 3, 5, 6]
        cuts = [[1, 0, 3, 5], [2, 0, 3, 6], [4, 0, 5, 6], [7, 3, 5, 6]]
    return [[corner[i] for i in t] for t in [centre, *cuts]]


def grid(n: int, split: str = "kuhn", size: float = 1.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A structured n x n x n grid of cubes split into tets: (points, tets, cube id per tet)."""
    ticks = np.linspace(0.0, size, n + 1)
    points = np.array([[x, y, z] for z in ticks for y in ticks for x in ticks])
    vid = lambda i, j, k: i + (n + 1) * (j + (n + 1) * k)  # noqa: E731
    tets, cube = [], []
    for k, j, i in itertools.product(range(n), repeat=3):
        corner = [vid(i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2)) for c in range(8)]
        split_tets = kuhn_tets(corner) if split == "kuhn" else five_tets(corner, (i + j + k) % 2)
        tets += split_tets
        cube += [i + n * (j + n * k)] * len(split_tets)
    tets = np.array(tets)
    return points, orient(points, tets), np.array(cube)


def to_tet10(points: np.ndarray, tets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Tet10 mesh with straight edges: one new node at the midpoint of every edge."""
    edges = {}
    new_points = [p for p in points]
    cells = []
    for t in tets:
        mids = []
        for a, b in EDGES["tetra10"]:
            key = tuple(sorted((int(t[a]), int(t[b]))))
            if key not in edges:
                edges[key] = len(new_points)
                new_points.append(0.5 * (points[key[0]] + points[key[1]]))
            mids.append(edges[key])
        cells.append(list(t) + mids)
    return np.array(new_points), np.array(cells)
