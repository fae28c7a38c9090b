#!/usr/bin/python3.11
"""Writes the fuzzers' seed corpus (tests/fuzz/corpus), small meshes committed to the
repository so that every run starts from the same files:

  *.tets             for hexmerge_fuzz: "points N" + N lines "x y z", "tets M" + M lines
                     "a b c d [region]" (0-based ids, positively oriented tets)
  readers/*          for fuzz_readers.py: the same kinds of mesh in the file formats the CLI reads

Run again only to change the corpus: Gmsh's meshes depend on its version.
  /usr/bin/python3.11 tests/fuzz/make_corpus.py
"""
from __future__ import annotations

import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
sys.path.insert(0, str(ROOT / "tests" / "python"))
sys.path.insert(0, str(ROOT / "src" / "python"))
from meshes import grid, orient, to_tet10  # noqa: E402

import hexmerge  # noqa: E402
import meshio  # noqa: E402

CORPUS = HERE / "corpus"

GEO = """
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 2, 1, 1};
Cylinder(2) = {1, 0.5, -0.1, 0, 0, 1.2, 0.3};
BooleanFragments{ Volume{1}; Delete; }{ Volume{2}; Delete; }
Physical Volume(1) = {3};
Physical Volume(2) = {2};
Mesh.CharacteristicLengthMax = %g;
"""


def write_tets(path: Path, points: np.ndarray, tets: np.ndarray, regions: np.ndarray | None, note: str) -> None:
    hexmerge.validate(points, tets, regions)  # seeds are valid meshes: the fuzzers break them
    lines = [f"# {note}", f"points {len(points)}"]
    lines += [" ".join(repr(float(c)) for c in p) for p in points]
    lines.append(f"tets {len(tets)}")
    for t, q in enumerate(tets):
        lines.append(" ".join(str(int(v)) for v in q) + (f" {int(regions[t])}" if regions is not None else ""))
    path.write_text("\n".join(lines) + "\n")


def gmsh_two_regions(h: float) -> meshio.Mesh:
    with tempfile.TemporaryDirectory() as tmp:
        geo = Path(tmp) / "part.geo"
        geo.write_text(GEO % h)
        out = Path(tmp) / "part.msh"
        subprocess.run(["gmsh", "-3", "-format", "msh22", str(geo), "-o", str(out)], check=True, capture_output=True)
        return meshio.read(out)


def main() -> None:
    (CORPUS / "readers").mkdir(parents=True, exist_ok=True)
    for n, split in ((2, "kuhn"), (3, "five")):
        points, tets, _ = grid(n, split)
        write_tets(CORPUS / f"{split}_grid_{n}.tets", points, tets, None, f"{n}^3 cubes, {split} split")
    m = gmsh_two_regions(0.35)
    tets = np.concatenate([b.data for b in m.cells if b.type == "tetra"])
    regions = np.concatenate([r for b, r in zip(m.cells, m.cell_data["gmsh:physical"]) if b.type == "tetra"])
    used = np.unique(tets)
    remap = np.full(len(m.points), -1)
    remap[used] = np.arange(len(used))
    points = m.points[used]
    tets = orient(points, remap[tets])
    write_tets(CORPUS / "gmsh_box_cylinder.tets", points, tets, regions,
               "Gmsh 4.8 Delaunay mesh of a box with a cylinder inclusion, two regions")
    rng = np.random.default_rng(3)
    lp, lt, _ = grid(3, "kuhn")
    lp = lp + rng.uniform(-0.08, 0.08, lp.shape) * (lp > 0) * (lp < 3)  # jitter the interior only
    write_tets(CORPUS / "jittered_kuhn_3.tets", lp, orient(lp, lt), None, "3^3 Kuhn cubes, interior nodes jittered")

    # Reader corpus: one small mesh in each format the CLI reads (and one Tet10).
    points, tets, _ = grid(2, "five")
    r = (points[tets].mean(axis=1)[:, 0] > 1).astype(int) + 1
    mesh = meshio.Mesh(points, [("tetra", tets)], cell_data={"gmsh:physical": [r], "gmsh:geometrical": [r]})
    meshio.write(CORPUS / "readers" / "grid.msh", mesh, file_format="gmsh22", binary=False)
    meshio.write(CORPUS / "readers" / "grid.vtk", meshio.Mesh(points, [("tetra", tets)]), binary=False)
    meshio.write(CORPUS / "readers" / "grid.inp", meshio.Mesh(points, [("tetra", tets)]))
    meshio.write(CORPUS / "readers" / "grid.mesh", meshio.Mesh(points, [("tetra", tets)], cell_data={"medit:ref": [r]}))
    p10, t10 = to_tet10(points, tets)
    meshio.write(CORPUS / "readers" / "grid10.msh", meshio.Mesh(p10, [("tetra10", t10)]), file_format="gmsh22", binary=False)


if __name__ == "__main__":
    main()
