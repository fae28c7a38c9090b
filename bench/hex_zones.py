#!/usr/bin/python3.11
"""Where the non-hexahedral volume of a mesh_shape mesh lies: volume per element type by the
distance of the element's centroid from the boundary, in units of h (issue 13, item 3).

Two more measures of what the next hexahedra would need:
- the non-hexahedral volume within h of the boundary, by the kind of boundary nearest to it: a
  plane normal to an axis of the mesher's frame, another plane (a triangle whose neighbours
  across its sides all lie within 1 degree of its plane), or a curved face;
- a bound on a buffer layer (Schneiders' grid-based method: the core's boundary quads projected
  onto the surface, each with its projection a hexahedron reaching the boundary): over the closing
  pyramids' bases (hexahedron faces shared with a pyramid), those whose four corners' nearest
  boundary points lie within 35 degrees of the base's outward normal and give a hexahedron of
  scaled Jacobian 0.3 or more; the volume between base and projection as a share of the part.
  Bases with a corner on the boundary already (within 0.05 h: the core reaching a lattice face)
  are not counted.
  It is a bound: it counts neither the surface that would have to be remeshed to hold the
  projected quads, nor the quads at the edge of a projected patch, which need closing.
- the buffer layer's own census (the mesher's report, `buffer_bases`): each closing pyramid's
  base at the first test it fails (apex shared at a concave step, no top for a corner and why,
  tops on two faces, height or tilt, quality, folds, dropped by the later steps) or kept.

For each part (real_parts.py's names; sizes from bench/results/real-parts-sizes.json) the tets
are made with hexmerge.mesh_shape(..., recombine=False) and the given mesher options, recombined
with the defaults (conforming), and the volume of each type is summed per distance band (0-0.5 h,
0.5-1 h, ...). The distance is to the tet mesh's boundary triangles (sampled at their corners,
edge middles and centroids: accurate to about h / 4, enough for bands of h / 2). Also printed:
the mesher's counts (core cells, lattice and layer points, lattice faces, sweep axis).

Usage:
  PYTHONPATH=src/python /usr/bin/python3.11 bench/hex_zones.py --parts gmsh_t20_data,holed_plate
  ... --option lattice_margin=0.2 --option layer_thickness=0.25
"""
import argparse
import json
import os
import sys
import tempfile
import time

import numpy as np

import benchlib
import real_parts

TET_SPLIT = {  # each type split into tets (its volume: the sum of their absolute volumes)
    0: [(0, 1, 2, 3)],
    1: [(0, 1, 2, 4), (0, 2, 3, 4)],
    2: [(0, 1, 2, 5), (0, 1, 5, 4), (0, 4, 5, 3)],
    3: [(0, 1, 3, 4), (1, 2, 3, 6), (1, 4, 5, 6), (3, 6, 7, 4), (1, 3, 4, 6)],
}
NAMES = ("tet", "pyramid", "prism", "hex")
BANDS = [0, 0.5, 1.0, 1.5, 2.0, 3.0, 1e9]


def cell_volumes_and_centroids(mesh):
    vol = np.zeros(mesh.nb_cells)
    cen = np.zeros((mesh.nb_cells, 3))
    for t in range(4):
        cells = np.flatnonzero(mesh.types == t)
        if len(cells) == 0:
            continue
        n = real_parts.NB_VERTICES[t]
        p = mesh.points[mesh.cell_vertices[mesh.offsets[cells][:, None] + np.arange(n)]]
        cen[cells] = p.mean(axis=1)
        for a, b, c, d in TET_SPLIT[t]:
            e1, e2, e3 = p[:, b] - p[:, a], p[:, c] - p[:, a], p[:, d] - p[:, a]
            vol[cells] += np.abs(np.einsum("ij,ij->i", e1, np.cross(e2, e3))) / 6
    return vol, cen


def boundary_samples(points, tets):
    p = points[boundary_triangles(tets)]
    samples = [p[:, 0], p[:, 1], p[:, 2], p.mean(axis=1), (p[:, 0] + p[:, 1]) / 2, (p[:, 1] + p[:, 2]) / 2,
               (p[:, 2] + p[:, 0]) / 2]
    return np.concatenate(samples)


def boundary_triangles(tets):
    faces = np.concatenate([tets[:, [1, 2, 3]], tets[:, [0, 2, 3]], tets[:, [0, 1, 3]], tets[:, [0, 1, 2]]])
    key = np.sort(faces, axis=1)
    _, inverse, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    return key[counts[inverse.ravel()] == 1]


def boundary_classes(points, triangles, frame):
    """Per boundary triangle: 0 a plane normal to a frame axis, 1 another plane (every neighbour
    across a side within 1 degree of its plane), 2 curved; and the unit normals."""
    a, b, c = (points[triangles[:, k]] for k in range(3))
    normal = np.cross(b - a, c - a)
    normal /= np.maximum(np.linalg.norm(normal, axis=1), 1e-300)[:, None]
    flat = np.ones(len(triangles), dtype=bool)
    sides = np.concatenate([np.sort(triangles[:, [i, j]], axis=1) for i, j in ((0, 1), (1, 2), (2, 0))])
    owner = np.tile(np.arange(len(triangles)), 3)
    order = np.lexsort((sides[:, 1], sides[:, 0]))
    sides, owner = sides[order], owner[order]
    pair = np.flatnonzero((sides[1:] == sides[:-1]).all(axis=1))
    t0, t1 = owner[pair], owner[pair + 1]
    bent = np.abs(np.einsum("ij,ij->i", normal[t0], normal[t1])) < np.cos(np.radians(1.0))
    flat[t0[bent]] = False
    flat[t1[bent]] = False
    axis_normal = np.abs(normal @ np.asarray(frame).T).max(axis=1) > 0.999
    return np.where(flat & axis_normal, 0, np.where(flat, 1, 2)), normal


def hex_scaled_jacobian(p):
    """Verdict's scaled Jacobian of one hexahedron (8 x 3 coordinates, VTK order)."""
    corners, scale = real_parts.CORNERS[3]
    return float(real_parts.corner_scaled_jacobians(p[None], corners, scale)[0])


def buffer_bound(mesh, points, samples, h):
    """The buffer layer's bound (module docstring): (bases, projectable bases, their volume)."""
    from scipy.spatial import cKDTree

    tree = cKDTree(samples)
    offsets, vertices, pmap = mesh.offsets, mesh.cell_vertices, mesh.point_map
    hex_faces = {}
    for e in np.flatnonzero(mesh.types == 3):
        v = pmap[vertices[offsets[e]:offsets[e + 1]]]
        for f in ((0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)):
            hex_faces.setdefault(tuple(sorted(v[list(f)])), []).append([v[i] for i in f])
    bases = kept = 0
    volume = 0.0
    for e in np.flatnonzero(mesh.types == 1):
        v = pmap[vertices[offsets[e]:offsets[e + 1]]]
        quads = hex_faces.get(tuple(sorted(v[:4])), [])
        if len(quads) != 1:
            continue
        bases += 1
        q = points[quads[0]]
        n = np.cross(q[2] - q[0], q[3] - q[1])
        n /= np.linalg.norm(n)
        if np.dot(points[v[4]] - q.mean(axis=0), n) < 0:
            n = -n  # towards the pyramid's apex: out of the core
        _, nearest = tree.query(q)
        reach = samples[nearest] - q
        length = np.linalg.norm(reach, axis=1)
        if (length < 0.05 * h).any() or (reach @ n < np.cos(np.radians(35)) * length).any():
            continue
        p = np.concatenate([q, samples[nearest]])
        sj = hex_scaled_jacobian(p)
        if sj < 0:
            sj = hex_scaled_jacobian(np.concatenate([q[::-1], samples[nearest][::-1]]))
        if sj < 0.3:
            continue
        kept += 1
        volume += 0.5 * np.linalg.norm(np.cross(q[2] - q[0], q[3] - q[1])) * float(np.mean(reach @ n))
    return bases, kept, volume


def analyse(path: str, h: float, options: dict) -> dict:
    import hexmerge
    from hexmerge import _core
    from scipy.spatial import cKDTree

    brep = _core.read_shape_file(path)
    start = time.perf_counter()
    tets, rep = hexmerge.mesh_shape(brep, h, recombine=False, **options)
    meshing = rep["meshing"]
    points = tets.points
    cells = tets.cell_vertices.reshape(-1, 4).astype(np.int64)
    mesh, report = hexmerge.recombine(points, cells, tets.regions)
    seconds = time.perf_counter() - start
    check = hexmerge.check(mesh, points, cells, tets.regions)
    sj = real_parts.scaled_jacobians(mesh)
    vol, cen = cell_volumes_and_centroids(mesh)
    dist, _ = cKDTree(boundary_samples(points, cells)).query(cen)
    dist /= h
    total = vol.sum()
    table = []
    for lo, hi in zip(BANDS[:-1], BANDS[1:]):
        inband = (dist >= lo) & (dist < hi)
        table.append([float(vol[inband & (mesh.types == t)].sum() / total) for t in range(4)])
    # The non-hexahedral volume within h of the boundary, by the kind of boundary nearest.
    triangles = boundary_triangles(cells)
    kind, _ = boundary_classes(points, triangles, np.asarray(meshing["frame"]).reshape(3, 3))
    centroids = points[triangles].mean(axis=1)
    near, nearest = cKDTree(centroids).query(cen)
    area = 0.5 * np.linalg.norm(np.cross(points[triangles[:, 1]] - points[triangles[:, 0]],
                                         points[triangles[:, 2]] - points[triangles[:, 0]]), axis=1)
    by_kind = {}
    for k, name in enumerate(("axis plane", "other plane", "curved")):
        band = (near < h) & (kind[nearest] == k) & (mesh.types != 3)
        by_kind[name] = {"area": float(area[kind == k].sum() / area.sum()),
                         "non_hex_within_h": float(vol[band].sum() / total)}
    bases, projectable, buffer_volume = buffer_bound(mesh, points, boundary_samples(points, cells), h)
    return {
        "seconds": seconds, "tets": len(cells), "valid": check["valid"],
        "nonconforming_quads": check["nonconforming_quads"], "cracks": check["cracks"],
        "min_sj": check["min_scaled_jacobian"], "below_0.2": int((sj < 0.2).sum()),
        "boundary_distance_h": meshing["max_boundary_distance"] / h, "strategy": meshing["strategy"],
        "volume_fraction": report["volume_fraction"], "bands": table, "by_boundary": by_kind,
        "buffer": {"pyramid_bases": bases, "projectable": projectable,
                   "volume": float(buffer_volume / total)},
        "counts": {k: meshing[k] for k in ("nb_core_cells", "nb_lattice_points", "nb_apex_points",
                                           "nb_layer_points", "nb_lattice_faces", "nb_faces", "sweep_axis",
                                           "nb_surface_nodes")},
        "buffer_bases": meshing["buffer_bases"],
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--parts", required=True, help="comma-separated part names")
    ap.add_argument("--size", default="50k")
    ap.add_argument("--option", action="append", default=[], help="NAME=VALUE, a mesh_shape option")
    ap.add_argument("--cad", default=real_parts.DEFAULT_CAD)
    ap.add_argument("--json", help="write the rows there")
    args = ap.parse_args()
    options = {}
    for o in args.option:
        k, v = o.split("=", 1)
        options[k] = int(v) if v.isdigit() else (float(v) if v.replace(".", "", 1).isdigit() else v)
    sizes = json.load(open(real_parts.SIZES_FILE))["parts"]
    rows = {}
    with tempfile.TemporaryDirectory() as work:
        for name in args.parts.split(","):
            if name in real_parts.GENERATED:
                path = benchlib.geo_to_cad(os.path.join(benchlib.ROOT, "bench", "geometry", name + ".geo"),
                                           os.path.join(work, name + ".step"))
            else:
                path = next(os.path.join(args.cad, f) for f in sorted(os.listdir(args.cad))
                            if os.path.splitext(f)[0] == name)
            h = sizes[name][args.size]["h"]
            try:
                row = analyse(path, h, options)
            except Exception as e:  # the failure is the row
                row = {"error": str(e).splitlines()[0][:300]}
            rows[name] = row
            if "error" in row:
                print(f"{name} h {h:.4g}: error: {row['error']}")
                continue
            vf = row["volume_fraction"]
            print(f"{name} h {h:.4g}: {row['tets']} tets {row['seconds']:.1f} s hex {100 * vf['hex']:.1f} % "
                  f"prism {100 * vf['prism']:.1f} pyr {100 * vf['pyramid']:.1f} tet {100 * vf['tet']:.1f}; "
                  f"min SJ {row['min_sj']:.2g} (<0.2: {row['below_0.2']}) valid {row['valid']} "
                  f"nc {row['nonconforming_quads']} cracks {row['cracks']} bd/h {row['boundary_distance_h']:.1e} "
                  f"{row['strategy']}")
            print("   ", row["counts"])
            for (lo, hi), band in zip(zip(BANDS[:-1], BANDS[1:]), row["bands"]):
                print(f"    d/h {lo:>3}-{hi if hi < 1e8 else 'inf':<4}: vol {100 * sum(band):5.1f} %  " +
                      "  ".join(f"{NAMES[t]} {100 * band[t]:5.1f}" for t in range(4)))
            print("    within h of the boundary, not hexahedra: " + ", ".join(
                f"{name} {100 * k['non_hex_within_h']:.1f} % (its area {100 * k['area']:.1f} %)"
                for name, k in row["by_boundary"].items()))
            b = row["buffer"]
            print(f"    buffer layer bound: {b['projectable']} of {b['pyramid_bases']} closing pyramids' bases "
                  f"project, +{100 * b['volume']:.1f} % of the volume")
            print("    buffer layer's census of the bases: " +
                  ", ".join(f"{k} {v}" for k, v in row["buffer_bases"].items()))
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"options": options, "size": args.size, "rows": rows}, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
