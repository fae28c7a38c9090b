# SPDX-License-Identifier: LGPL-2.1-or-later
"""Where the first-order error at the thick-walled cylinder's bore comes from (issue 15,
docs/fem-accuracy.md): the hoop stress CalculiX gives at the bore nodes of C3D8 meshes.

Two parts:
  polar   structured polar C3D8 meshes of the same quarter tube written here (no HexMerge, no
          FreeCAD; CalculiX alone): the bore's nodal hoop stress against the bore elements'
          radial depth, uniform layers of h or a first layer of a fraction of h
  shape   HexMerge's first-order meshes from the shape (bench/fem_accuracy.py's cylinder case,
          solved as FreeCAD writes them, C3D8), with the integration-point stresses printed:
          peak and mean over the bore nodes, the integration points' scatter around Lame, the
          elements at the peak node (depth, distortion), the peak's relation to distortion

Run (about 1 min per shape size on 2 shared cores):
    /usr/bin/python3.11 bench/cylinder_bore.py polar
    /usr/bin/python3.11 bench/cylinder_bore.py shape --sizes 8,5,3
    /usr/bin/python3.11 bench/cylinder_bore.py shape --sizes 5 --layer-thickness 0.15
"""

import argparse
import importlib.util
import json
import math
import os
import re
import subprocess
import sys
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
A, B, LENGTH, PRESSURE = 50.0, 100.0, 20.0, 100.0
YOUNG, POISSON = 210000.0, 0.3


def lame_hoop(r):
    return PRESSURE * A ** 2 / (B ** 2 - A ** 2) * (1 + B ** 2 / r ** 2)


EXACT = lame_hoop(A)
GAUSS = 1 / math.sqrt(3)


def hoop(x, y, s):
    """Hoop stress at (x, y) from (sxx, syy, szz, sxy, ...)."""
    t = math.atan2(y, x)
    c, si = math.cos(t), math.sin(t)
    return s[0] * si * si + s[1] * c * c - 2 * s[3] * si * c


def read_frd_stress(path):
    """{node: (sxx, syy, szz, sxy, syz, szx)} of a CalculiX .frd's STRESS block."""
    out, inside = {}, False
    with open(path) as f:
        for line in f:
            if line.startswith(" -4"):
                inside = line.split()[1] == "STRESS"
            elif inside and line.startswith(" -1"):
                out[int(line[3:13])] = tuple(float(line[13 + 12 * q:25 + 12 * q]) for q in range(6))
            elif line.startswith(" -3"):
                inside = False
    return out


def polar(h, first, ntheta=None, junction=False, workdir=None):
    """Bore hoop stress errors (%) of a structured polar C3D8 mesh: bore spacing about h, a first
    radial layer `first` mm deep (0: none), then layers of about h. junction: the first layer
    ends before the symmetry plane x = 0 as in HexMerge's meshes from the shape (no layer node on
    the plane: a wedge at the bore and a hexahedron two layers deep). Returns (max, mean, cells,
    [(theta in degrees, error %)] of the bore nodes at z = 0)."""
    nth = ntheta or max(1, round(math.pi / 2 * A / h))
    radii = [A] + ([A + first] if first else [])
    n = max(1, round((B - radii[-1]) / h))
    radii += [radii[-1] + (B - radii[-1]) * k / n for k in range(1, n + 1)]
    nz = max(1, round(LENGTH / h))
    thetas = [math.pi / 2 * j / nth for j in range(nth + 1)]
    zs = [LENGTH * k / nz for k in range(nz + 1)]
    junction = junction and bool(first)
    plane = {(i, j): (r * math.cos(t), r * math.sin(t)) for i, r in enumerate(radii)
             for j, t in enumerate(thetas) if not (junction and i == 1 and j == nth)}
    cells = []  # (corners in the r-theta plane, the bore edge or None)
    for i in range(len(radii) - 1):
        for j in range(nth):
            if junction and j == nth - 1 and i == 0:
                cells.append(([(0, j), (0, j + 1), (1, j)], {(0, j), (0, j + 1)}))
            elif junction and j == nth - 1 and i == 1:
                cells.append(([(0, j + 1), (1, j), (2, j), (2, j + 1)], None))
            else:
                cells.append(([(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)],
                              {(i, j), (i, j + 1)} if i == 0 else None))
    nid, lines = {}, ["*NODE, NSET=Nall"]
    for key, (x, y) in plane.items():
        for k, z in enumerate(zs):
            nid[key + (k,)] = len(nid) + 1
            lines.append("{}, {:.12g}, {:.12g}, {:.12g}".format(nid[key + (k,)], x, y, z))
    blocks, loads, e = {"C3D8": [], "C3D6": []}, [], 0
    for corners, bore in cells:
        xy = [plane[c] for c in corners]
        if sum(xy[m - 1][0] * xy[m][1] - xy[m][0] * xy[m - 1][1] for m in range(len(xy))) < 0:
            corners = corners[::-1]  # counter-clockwise seen from +z
        for k in range(nz):
            e += 1
            connectivity = [nid[c + (k,)] for c in corners] + [nid[c + (k + 1,)] for c in corners]
            blocks["C3D8" if len(corners) == 4 else "C3D6"].append(
                "{}, {}".format(e, ", ".join(map(str, connectivity))))
            for side in range(len(corners)) if bore else ():
                if {corners[side], corners[(side + 1) % len(corners)]} == bore:
                    loads.append("{}, P{}, {}".format(e, 3 + side, PRESSURE))
    for kind, block in blocks.items():
        if block:
            lines += ["*ELEMENT, TYPE={}, ELSET=Eall".format(kind)] + block
    for name, test in (("SYMX", lambda key: key[1] == nth), ("SYMY", lambda key: key[1] == 0),
                       ("ENDS", lambda key: key[2] in (0, nz))):
        ids = [v for key, v in nid.items() if test(key)]
        lines.append("*NSET, NSET=" + name)
        lines += [", ".join(map(str, ids[s:s + 10])) for s in range(0, len(ids), 10)]
    lines += ["*MATERIAL, NAME=Steel", "*ELASTIC", "{}, {}".format(YOUNG, POISSON),
              "*SOLID SECTION, ELSET=Eall, MATERIAL=Steel", "*BOUNDARY", "SYMX, 1, 1",
              "SYMY, 2, 2", "ENDS, 3, 3", "*STEP", "*STATIC", "*DLOAD"] + loads
    lines += ["*NODE FILE", "U", "*EL FILE", "S", "*END STEP"]
    workdir = workdir or tempfile.mkdtemp(prefix="hexmerge_polar_")
    with open(os.path.join(workdir, "polar.inp"), "w") as f:
        f.write("\n".join(lines) + "\n")
    subprocess.run(["ccx", "polar"], cwd=workdir, capture_output=True, check=True)
    stress = read_frd_stress(os.path.join(workdir, "polar.frd"))
    errors, first_section = [], []
    for (i, j, k), node in nid.items():
        if i == 0:
            t = thetas[j]
            errors.append(100 * (hoop(A * math.cos(t), A * math.sin(t), stress[node]) / EXACT - 1))
            if k == 0:
                first_section.append((math.degrees(t), errors[-1]))
    return max(errors), float(np.mean(errors)), (len(radii) - 1, nth, nz), sorted(first_section)


def polar_table():
    print("| structured polar C3D8 | bore spacing | first layer | cells (r x theta x z) "
          "| bore hoop, max | mean | last bore nodes before x = 0 (theta: error) |")
    print("|---|---|---|---|---|---|---|")
    rows = [(h, f, None, False) for h in (8.0, 5.0, 3.0) for f in (0.0, 0.3 * h)]
    rows += [(5.0, 0.15 * 5, None, False), (5.0, 0.5 * 5, None, False), (5.0, 1.6, 18, False)]
    rows += [(8.0, 2.4, None, True), (5.0, 1.6, 18, True), (3.0, 0.9, None, True)]
    for h, first, nth, junction in rows:
        top, mean, cells, section = polar(h, first, nth, junction)
        print("| h {:g} mm{} | {:.2f} deg | {} | {} | {:+.2f} % | {:+.2f} % | {} |".format(
            h, ", layer ends before x = 0" if junction else "", 90.0 / cells[1],
            "{:.2f} mm".format(first) if first else "none (h)", " x ".join(map(str, cells)),
            top, mean, ", ".join("{:.1f}: {:+.2f}".format(t, v) for t, v in section[-4:])),
            flush=True)
    for depth in (0.9, 1.6, 2.4, 5.0):
        print("Lame's exact hoop stress at the two Gauss radii of a bore element {:g} mm deep, "
              "extrapolated linearly to the bore: {:+.3f} %".format(
                  depth, 100 * (gauss_extrapolation(depth) / EXACT - 1)))


def gauss_extrapolation(depth):
    """Lame's hoop stress at the Gauss radii of an element [A, A + depth], extrapolated linearly
    to r = A (what a linear element's nodal value would be, were its Gauss values exact)."""
    r1, r2 = (A + depth * (1 + s * GAUSS) / 2 for s in (-1, 1))
    s1, s2 = lame_hoop(r1), lame_hoop(r2)
    return s1 + (s1 - s2) * (r1 - A) / (r2 - r1)


# -- meshes from the shape, in freecadcmd ------------------------------------------------------
CORNERS = [(-1, -1, -1), (1, -1, -1), (1, 1, -1), (-1, 1, -1), (-1, -1, 1), (1, -1, 1),
           (1, 1, 1), (-1, 1, 1)]
# CalculiX's integration points of C3D8: xi fastest, then eta, then zeta
POINTS = [(a * GAUSS, b * GAUSS, c * GAUSS) for c in (-1, 1) for b in (-1, 1) for a in (-1, 1)]


def at(corners, xi):
    w = np.array([(1 + a * xi[0]) * (1 + b * xi[1]) * (1 + c * xi[2]) / 8 for a, b, c in CORNERS])
    return w @ corners


def shape_worker(job):
    """One size: mesh from the shape (first order), CalculiX with integration-point stresses."""
    from femtools import ccxtools
    from freecad.hexmerge import calculix, jobs
    spec = importlib.util.spec_from_file_location(
        "fem_accuracy", os.path.join(ROOT, "bench", "fem_accuracy.py"))
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    doc, mesh = bench.build_case("cylinder")
    mesher = {"size": job["size"], "second_order": False}
    if job.get("layer_thickness") is not None:
        mesher["layer_thickness"] = job["layer_thickness"]
    if job.get("boundary_layers") is not None:
        mesher["boundary_layers"] = job["boundary_layers"]
    sj = jobs.ShapeJob.prepare(mesh.Part.Shape, mesher)
    sj.run()
    femmesh, report = sj.finish()
    mesh.FemMesh = femmesh
    fea = ccxtools.FemToolsCcx(doc.Analysis, bench.solver_of(doc))
    fea.update_objects()
    fea.setup_working_dir(tempfile.mkdtemp(prefix="hexmerge_bore_"))
    fea.setup_ccx()
    fea.write_inp_file()
    with open(fea.inp_file_name) as f:
        text = f.read()
    with open(fea.inp_file_name, "w") as f:
        f.write(re.sub(r"\*END STEP", "*EL PRINT, ELSET=Eall\nS\n*END STEP", text, count=1,
                       flags=re.I))
    fea.ccx_run()
    stress = read_frd_stress(os.path.splitext(fea.inp_file_name)[0] + ".frd")
    ip = {}
    with open(os.path.splitext(fea.inp_file_name)[0] + ".dat") as f:
        for line in f:
            parts = line.split()
            if len(parts) == 8 and parts[0].isdigit() and parts[1].isdigit():
                ip.setdefault(int(parts[0]), {})[int(parts[1])] = [float(x) for x in parts[2:]]
    nodes = femmesh.Nodes
    # the connectivity as written (CalculiX's corner order, which the integration points follow)
    with open(fea.inp_file_name) as f:
        blocks = bench.read_inp_elements(f.read().splitlines())
    elements = {e: ns for _, _, _, block in blocks for e, ns in block}
    around = {}
    for e, ns in elements.items():
        for n in ns:
            around.setdefault(n, []).append(e)

    def xyz(e):
        return np.array([tuple(nodes[n]) for n in elements[e]])

    def is_hexahedron(e):
        return len(elements[e]) == 8 and len(set(elements[e])) == 8

    bore = [n for n in nodes if math.hypot(nodes[n].x, nodes[n].y) < A + 1e-3]
    error = {n: 100 * (hoop(nodes[n].x, nodes[n].y, stress[n]) / EXACT - 1) for n in bore}
    scatter = []
    for e in {e for n in bore for e in around[n] if is_hexahedron(e)}:
        c = xyz(e)
        for k, xi in enumerate(POINTS):
            q = at(c, xi)
            scatter.append(hoop(q[0], q[1], ip[e][k + 1]) - lame_hoop(math.hypot(q[0], q[1])))
    distortion = {n: max([calculix.distortion([tuple(p) for p in xyz(e)])
                          for e in around[n] if is_hexahedron(e)] or [float("nan")])
                  for n in bore}
    peak = max(bore, key=lambda n: error[n])
    depth = [float(np.hypot(xyz(e)[:, 0], xyz(e)[:, 1]).max() - A) for e in around[peak]]
    with_d = [n for n in bore if not math.isnan(distortion[n])]
    d_values = [distortion[n] for n in with_d]
    return {"size": job["size"], "mesher": mesher, "counts": report.get("output_counts"),
            "bore nodes": len(bore), "max %": error[peak],
            "mean %": float(np.mean(list(error.values()))),
            "ip scatter MPa": float(np.std(scatter)), "ip mean MPa": float(np.mean(scatter)),
            "peak theta": math.degrees(math.atan2(nodes[peak].y, nodes[peak].x)),
            "peak elements": ["{}-node, {:.2f} mm deep".format(len(set(elements[e])), d)
                              for e, d in zip(around[peak], depth)],
            "peak distortion": distortion[peak],
            "bore distortion": [min(d_values), max(d_values)],
            "corr error distortion": float(np.corrcoef([error[n] for n in with_d], d_values)[0, 1]),
            "section": sorted((math.degrees(math.atan2(nodes[n].y, nodes[n].x)), error[n])
                              for n in bore if abs(nodes[n].z) < 1e-6),
            "plane layer nodes": plane_layer_nodes(nodes, bore, job["size"])}


def plane_layer_nodes(nodes, bore, h):
    """The bore nodes on the planes x = 0 and y = 0, and the radial depth of the nearest node
    on the same plane and at the same z (within 0.7 h of the bore; None: none)."""
    out = []
    for n in bore:
        p = nodes[n]
        if abs(p.x) > 1e-6 and abs(p.y) > 1e-6:
            continue
        on_x = abs(p.x) <= 1e-6
        depths = [math.hypot(q.x, q.y) - A for q in nodes.values()
                  if abs(q.z - p.z) < 1e-6 and abs(q.x if on_x else q.y) <= 1e-6
                  and 1e-6 < math.hypot(q.x, q.y) - A < 0.7 * h]
        out.append(min(depths) if depths else None)
    return out


def shape_table(sizes, layer_thickness, boundary_layers, timeout, nodes=False):
    home = os.path.join(tempfile.gettempdir(), "hexmerge-fem-home")
    os.makedirs(home, exist_ok=True)
    for size in sizes:
        out = tempfile.mktemp(suffix=".json")
        job = {"size": size, "layer_thickness": layer_thickness,
               "boundary_layers": boundary_layers}
        env = dict(os.environ, HOME=home, QT_QPA_PLATFORM="offscreen",
                   HEXMERGE_BORE_JOB=json.dumps(job), HEXMERGE_BORE_OUT=out,
                   PYTHONPATH=os.path.join(ROOT, "src", "python"))
        proc = subprocess.run(["freecadcmd", os.path.abspath(__file__), "-M", ROOT], env=env,
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                              timeout=timeout)
        if not os.path.exists(out):
            sys.exit("size {:g} failed (exit {}):\n{}".format(size, proc.returncode,
                                                              proc.stdout[-1500:]))
        with open(out) as f:
            r = json.load(f)
        os.unlink(out)
        print("h {size:g} mm {mesher}: {bore nodes} bore nodes, hoop max {max %:+.2f} %, mean "
              "{mean %:+.2f} %; integration points of the bore hexahedra minus Lame: mean "
              "{ip mean MPa:+.2f} MPa, std {ip scatter MPa:.2f} MPa; peak at theta "
              "{peak theta:.1f} deg in {peak elements}, distortion {peak distortion:.3f} "
              "(bore hexahedra {bore distortion}); corr(node error, distortion) "
              "{corr error distortion:+.2f}".format(**r), flush=True)
        layer = r["plane layer nodes"]
        print("  bore nodes on the planes x = 0 and y = 0: {}, with a layer node on the plane: {} "
              "(depth {})".format(len(layer), sum(d is not None for d in layer),
                                  ", ".join("{:.2f}".format(d) for d in sorted(
                                      {round(d, 2) for d in layer if d is not None})) or "-"))
        if nodes:
            print("  bore nodes at z = 0 (theta: error %): " + ", ".join(
                "{:.1f}: {:+.2f}".format(t, e) for t, e in r["section"]), flush=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("part", choices=("polar", "shape"))
    parser.add_argument("--sizes", default="8,5,3")
    parser.add_argument("--layer-thickness", type=float)
    parser.add_argument("--boundary-layers", type=int)
    parser.add_argument("--timeout", type=float, default=900.0, help="seconds per size")
    parser.add_argument("--nodes", action="store_true",
                        help="shape: print every bore node's error at z = 0")
    args = parser.parse_args()
    if args.part == "polar":
        polar_table()
    else:
        shape_table([float(s) for s in args.sizes.split(",")], args.layer_thickness,
                    args.boundary_layers, args.timeout, args.nodes)


if os.environ.get("HEXMERGE_BORE_JOB"):
    sys.path[:0] = [ROOT, os.path.join(ROOT, "src", "python")]
    _result = shape_worker(json.loads(os.environ["HEXMERGE_BORE_JOB"]))
    with open(os.environ["HEXMERGE_BORE_OUT"], "w") as _f:
        json.dump(_result, _f)
    os._exit(0)
elif __name__ == "__main__":
    main()
