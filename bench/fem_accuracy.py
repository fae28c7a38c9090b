# SPDX-License-Identifier: LGPL-2.1-or-later
"""Accuracy of HexMerge meshes in CalculiX, solved through FreeCAD 0.20's FEM workbench (issue 15).

Three cases, each built in FreeCAD headless:
  cantilever  FreeCAD's ccx_cantilever_faceload (8000 x 1000 x 1000 mm, 9 MN end load): tip
              displacement; reference the converged 3D value 88.45 mm (beam theory 88.84 mm)
  plate       FreeCAD's material_nl_platewithhole made linear elastic (400 x 200 x 10 mm, 100 mm
              hole, 130 MPa tension): peak principal and von Mises stress at the hole
  cylinder    a thick-walled cylinder under internal pressure (a quarter, a = 50, b = 100,
              length 20 mm, 100 MPa, plane strain by symmetry): hoop stress at the bore against
              Lame's closed form
Meshes per case: Gmsh Tet4 and Tet10 at two sizes, each recombined by HexMerge (the engine's
defaults and the variants below), and meshes made from the shape (hexmerge.mesh_shape, first and
second order) at the same sizes. Every mesh is solved with CalculiX through FreeCAD's ccxtools.

Pyramids reach CalculiX as collapsed hexahedra (the add-on's PyramidsAsHexahedra); the .inp can
be post-processed here to hand them over as degenerate wedges instead (C3D6/C3D15, the collapsed
edge at the apex), and first-order hexahedra as C3D8I.

Run (5 to 10 min on 2 shared cores, depending on their other load):
    /usr/bin/python3.11 bench/fem_accuracy.py                      # every case, docs/fem-accuracy.md
    /usr/bin/python3.11 bench/fem_accuracy.py --cases plate --no-doc
It starts one freecadcmd per case and source mesh (the module and the add-on from this checkout,
a private HOME) and collects their rows; results also go to bench/results/fem-accuracy.json
(--output another file). --recombine-options adds engine options to every recombination variant,
e.g. the post-merge stage of issue 19:
    /usr/bin/python3.11 bench/fem_accuracy.py --cases cantilever,plate --kinds gmsh --no-doc \
        --recombine-options '{"same_nodes": false}' --paired \
        --output bench/results/fem-accuracy-post-merge.json
(--paired: each variant without and with those options, on the same Gmsh mesh.)
"""

import argparse
import atexit
import datetime
import json
import os
import platform
import re
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

REFERENCES = {
    # converged 3D solution (issue 15: a 266k-node Tet10 mesh refined at the hole and a 104k-node
    # Hexa20 mesh agree to 0.02 %); beam theory with shear beside it
    "cantilever": {"tip": 88.45, "beam theory": 88.84},
    # peak principal at the hole from the converged meshes of issue 15; von Mises from the same
    # run (measured here with --reference, see docs/fem-accuracy.md)
    "plate": {"P1": 570.6, "vM": None},
    # Lame: sigma_theta(a) = p (a^2 + b^2) / (b^2 - a^2)
    "cylinder": {"hoop": 100.0 * (50.0 ** 2 + 100.0 ** 2) / (100.0 ** 2 - 50.0 ** 2)},
}

# Errors closer than this (percentage points) are a tie: the references are known to about
# 0.05 % and Gmsh's meshes vary from run to run.
TIE = 0.1

# Sizes (mm): coarse, fine.
SIZES = {"cantilever": (300.0, 200.0), "plate": (12.0, 8.0), "cylinder": (8.0, 5.0)}

# Recombination variants: (label, engine options, .inp post-processing). The first is the engine's
# defaults; a variant whose options are the defaults is solved once (under the first label).
VARIANTS = [
    ("recombined, defaults", {}, None),
    ("pyramids anywhere (collapsed C3D8/C3D20)", {"pyramid_placement": "anywhere"}, None),
    ("pyramids anywhere, as wedges C3D6/C3D15", {"pyramid_placement": "anywhere"}, "wedge"),
    ("no pyramid with a boundary face", {"pyramid_placement": "no_boundary_face"}, None),
    ("no pyramid with a boundary node (the add-on's CalculiX default)",
     {"pyramid_placement": "no_boundary_node"}, None),
    ("no pyramid with a node on a curved face", {"pyramid_placement": "no_curved_boundary_node"},
     None),
    ("no pyramids", {"make_pyramids": False}, None),
]
LINEAR_ONLY_VARIANTS = [
    ("defaults, hexahedra as C3D8I", {}, {"C3D8": "C3D8I"}),
]
QUADRATIC_ONLY_VARIANTS = [
    ("pyramids anywhere, as two tied C3D10 (the add-on's QuadraticPyramid)",
     {"pyramid_placement": "anywhere"}, "split"),
    ("no pyramid with a boundary node, as two tied C3D10 (the add-on's default in second order)",
     {"pyramid_placement": "no_boundary_node"}, "split"),
    ("no pyramid with a node on a curved face, as two tied C3D10",
     {"pyramid_placement": "no_curved_boundary_node"}, "split"),
]


# ---- inside FreeCAD ----------------------------------------------------------------------------

def build_case(case):
    """A new document with the case's geometry, analysis, solver, material and loads; returns
    (doc, mesh object)."""
    if case == "cantilever":
        from femexamples.ccx_cantilever_faceload import setup
        doc = setup()
    elif case == "plate":
        from femexamples.material_nl_platewithhole import setup
        doc = setup()
        for o in list(doc.Analysis.Group):
            if o.isDerivedFrom("Fem::MaterialMechanicalNonlinear") or "nonlin" in o.Name.lower():
                doc.removeObject(o.Name)
        solver = solver_of(doc)
        solver.GeometricalNonlinearity = "linear"
        solver.MaterialNonlinearity = "linear"
    elif case == "cylinder":
        doc = cylinder_doc()
    else:
        raise ValueError("unknown case " + case)
    doc.recompute()
    return doc, mesh_object(doc)


def cylinder_doc(a=50.0, b=100.0, length=20.0, pressure=100.0):
    """A quarter of a thick-walled cylinder, symmetry on x = 0 and y = 0, both ends held in z
    (plane strain), internal pressure."""
    import FreeCAD
    import ObjectsFem
    import Part
    doc = FreeCAD.newDocument("Cylinder")
    tube = Part.makeCylinder(b, length).cut(Part.makeCylinder(a, length))
    quarter = tube.common(Part.makeBox(2 * b, 2 * b, length))
    geom = doc.addObject("Part::Feature", "Tube")
    geom.Shape = quarter
    doc.recompute()
    analysis = ObjectsFem.makeAnalysis(doc, "Analysis")
    solver = ObjectsFem.makeSolverCalculixCcxTools(doc, "CalculiXccxTools")
    solver.WorkingDir = ""
    solver.SplitInputWriter = False
    solver.AnalysisType = "static"
    solver.GeometricalNonlinearity = "linear"
    analysis.addObject(solver)
    material = ObjectsFem.makeMaterialSolid(doc, "FemMaterial")
    mat = material.Material
    mat["Name"] = "CalculiX-Steel"
    mat["YoungsModulus"] = "210000 MPa"
    mat["PoissonRatio"] = "0.30"
    material.Material = mat
    analysis.addObject(material)

    def faces(test):
        return ["Face{}".format(i + 1) for i, f in enumerate(quarter.Faces) if test(f)]

    def planar(axis, value):
        return lambda f: (f.Surface.__class__.__name__ == "Plane"
                          and abs(f.BoundBox.getPoint(0)[axis] - value) < 1e-6
                          and abs([f.BoundBox.XLength, f.BoundBox.YLength,
                                   f.BoundBox.ZLength][axis]) < 1e-6)

    for axis, value, name in ((0, 0.0, "SymX"), (1, 0.0, "SymY"), (2, 0.0, "EndZ0"),
                              (2, length, "EndZ1")):
        con = ObjectsFem.makeConstraintDisplacement(doc, name)
        con.References = [(geom, faces(planar(axis, value)))]
        for k, c in enumerate("xyz"):
            setattr(con, c + "Free", k != axis)
            setattr(con, c + "Fix", k == axis)
        analysis.addObject(con)
    bore = faces(lambda f: f.Surface.__class__.__name__ == "Cylinder"
                 and abs(f.Surface.Radius - a) < 1e-6)
    con = ObjectsFem.makeConstraintPressure(doc, "Pressure")
    con.References = [(geom, bore)]
    con.Pressure = pressure
    con.Reversed = False
    analysis.addObject(con)
    mesh = ObjectsFem.makeMeshGmsh(doc, "FEMMeshGmsh")
    mesh.Part = geom
    analysis.addObject(mesh)
    doc.recompute()
    return doc


def solver_of(doc):
    return [o for o in doc.Analysis.Group if o.isDerivedFrom("Fem::FemSolverObjectPython")][0]


def mesh_object(doc):
    return [o for o in doc.Analysis.Group if o.isDerivedFrom("Fem::FemMeshObject")][0]


def gmsh(mesh_obj, size, order="1st"):
    """Meshes a MeshGmsh object with Gmsh through FreeCAD (first or second order tets of the
    given largest size); returns its FemMesh. The FreeCAD tests use it too (tests/freecad)."""
    from femmesh.gmshtools import GmshTools
    mesh_obj.CharacteristicLengthMax = size
    mesh_obj.CharacteristicLengthMin = 0
    mesh_obj.ElementOrder = order
    mesh_obj.SecondOrderLinear = False
    error = GmshTools(mesh_obj).create_mesh()
    if error:
        raise RuntimeError("Gmsh failed: {}".format(error))
    return mesh_obj.FemMesh


# CalculiX faces by corner positions (1-based in the manual, 0-based here).
CCX_FACES = {
    "C3D8": ((0, 1, 2, 3), (4, 7, 6, 5), (0, 4, 5, 1), (1, 5, 6, 2), (2, 6, 7, 3), (3, 7, 4, 0)),
    "C3D6": ((0, 1, 2), (3, 4, 5), (0, 1, 4, 3), (1, 2, 5, 4), (2, 0, 3, 5)),
}
CCX_FACES["C3D20"] = CCX_FACES["C3D8"]
CCX_FACES["C3D15"] = CCX_FACES["C3D6"]
def read_inp_elements(lines):
    """[(first line, last line + 1, type, [(id, nodes)])] of the .inp's volume element blocks."""
    from freecad.hexmerge import calculix
    blocks = []
    i = 0
    while i < len(lines):
        m = re.match(r"\*ELEMENT\s*,\s*TYPE\s*=\s*(\w+)", lines[i], re.I)
        if not m or m.group(1).upper() not in calculix.NODES:
            i += 1
            continue
        kind = m.group(1).upper()
        j, items = calculix.read_element_block(lines, i, kind)
        blocks.append((i, j, kind, items))
        i = j
    return blocks


# C3D8/C3D20 edges (0-based corners); the k-th is the mid-edge node at position 8 + k.
HEX_EDGES = ((0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4), (0, 4), (1, 5),
             (2, 6), (3, 7))


def collapsed_pyramid(nodes):
    """The add-on's calculix.collapsed_pyramid (FreeCAD's writer stores pyramids so)."""
    from freecad.hexmerge import calculix
    return calculix.collapsed_pyramid(nodes)


def as_wedge(kind, nodes, points):
    """A collapsed hexahedron as a wedge with a collapsed edge at the apex: triangles (b0, b3, a)
    and (b1, b2, a) of the base b0..b3 turned towards the apex; for C3D20 with the mid-edge
    nodes of the pyramid's edges."""
    import numpy as np
    base, a = collapsed_pyramid(nodes)
    p = [np.array(points[n]) for n in base]
    if np.dot(np.cross(p[1] - p[0], p[3] - p[0]), np.array(points[a]) - p[0]) < 0:
        base = base[::-1]
    b0, b1, b2, b3 = base
    if kind == "C3D8":
        return "C3D6", [b0, b3, a, b1, b2, a]
    mid = {frozenset((nodes[u], nodes[v])): nodes[8 + k] for k, (u, v) in enumerate(HEX_EDGES)
           if nodes[u] != nodes[v]}

    def m(u, v):
        return mid[frozenset((u, v))]

    # C3D15: 6:(1-2) 7:(2-3) 8:(3-1) 9:(4-5) 10:(5-6) 11:(6-4) 12:(1-4) 13:(2-5) 14:(3-6)
    return "C3D15", [b0, b3, a, b1, b2, a, m(b0, b3), m(b3, a), m(a, b0), m(b1, b2), m(b2, a),
                     m(a, b1), m(b0, b1), m(b3, b2), a]


def postprocess_inp(path, mode):
    """Rewrites the .inp: mode "wedge" writes collapsed pyramids as degenerate wedges (and moves
    their face loads to the wedge's faces); "split" second-order ones as two tied C3D10 (the
    add-on's calculix.split_pyramids_in_input, its default); a dict {written type: type}
    retypes the true (not collapsed) hexahedra as the add-on does for its own mesh objects
    (calculix.retype_file: {"C3D8": "C3D8I"}, {"C3D20": "C3D20R"}). Returns how many elements
    changed."""
    from freecad.hexmerge import calculix
    if isinstance(mode, dict):
        return sum(calculix.retype_file(path, mode).values())
    if mode == "split":
        return calculix.split_pyramids_in_input(path)
    with open(path) as f:
        lines = f.read().split("\n")
    blocks = read_inp_elements(lines)
    points = calculix.read_nodes(lines)
    changed = {}
    out = []
    last = 0
    for first, end, kind, elements in blocks:
        out += lines[last:first]
        last = end
        keep, moved = [], []
        new_kind = None
        for eid, nodes in elements:
            if mode == "wedge" and kind in ("C3D8", "C3D20") and collapsed_pyramid(nodes):
                new_kind, wedge = as_wedge(kind, nodes, points)
                moved.append((eid, wedge))
                changed[eid] = (kind, nodes, new_kind, wedge)
            else:
                keep.append((eid, nodes))
        header = lines[first]
        for k, items in ((kind, keep), (new_kind, moved)):
            if not items:
                continue
            out.append(re.sub(r"TYPE\s*=\s*\w+", "TYPE=" + k, header, flags=re.I))
            for eid, nodes in items:
                row = [eid] + list(nodes)
                for s in range(0, len(row), 16):  # at most 16 numbers per line
                    out.append(", ".join(str(x) for x in row[s:s + 16])
                               + ("," if s + 16 < len(row) else ""))
    out += lines[last:]
    if mode == "wedge":
        out = remap_face_loads(out, changed)
    with open(path, "w") as f:
        f.write("\n".join(out))
    return len(changed)


def remap_face_loads(lines, changed):
    """Face loads (*DLOAD / *FILM 'eid, Pk, value') on changed elements: face k of the old type
    -> the face of the new type on the same corners; a collapsed face (under 3 corners) drops."""
    out = []
    for line in lines:
        m = re.match(r"\s*(\d+)\s*,\s*P(\d)\s*,(.*)$", line)
        if m and int(m.group(1)) in changed:
            old, nodes, new, new_nodes = changed[int(m.group(1))]
            corners = {nodes[i] for i in CCX_FACES[old][int(m.group(2)) - 1]}
            if len(corners) < 3:
                continue
            k = [f for f, face in enumerate(CCX_FACES[new])
                 if {new_nodes[i] for i in face} == corners]
            if len(k) != 1:
                raise RuntimeError("no wedge face for the load on element " + m.group(1))
            line = "{},P{},{}".format(m.group(1), k[0] + 1, m.group(3))
        out.append(line)
    return out


def inp_counts(path):
    with open(path) as f:
        blocks = read_inp_elements(f.read().split("\n"))
    counts = {}
    collapsed = 0
    for _, _, kind, elements in blocks:
        counts[kind] = counts.get(kind, 0) + len(elements)
        if kind in ("C3D8", "C3D20"):
            collapsed += sum(1 for _, nodes in elements if collapsed_pyramid(nodes))
    return counts, collapsed


_WORK = []  # this process's work directory while it has one


def work_directory(prefix):
    """A new empty directory for one CalculiX run, inside a directory of this process's that
    remove_work_directories() removes (called when the process exits normally; freecadcmd -t
    skips that, so the FreeCAD tests call it themselves)."""
    if not _WORK:
        _WORK.append(tempfile.mkdtemp(prefix="hexmerge_ccx_"))
        atexit.register(remove_work_directories)
    return tempfile.mkdtemp(prefix=prefix, dir=_WORK[0])


def remove_work_directories():
    """Removes the CalculiX runs' directories work_directory() made."""
    while _WORK:
        shutil.rmtree(_WORK.pop(), ignore_errors=True)


def solve(doc, post=None):
    """Writes the .inp (post-processed when asked), runs CalculiX; returns (result object, inp
    path, solve seconds)."""
    from femtools import ccxtools
    for o in list(doc.Analysis.Group):
        if o.isDerivedFrom("Fem::FemResultObject") or o.isDerivedFrom("Fem::FemMeshObjectPython") \
                and o.Name.startswith("ResultMesh"):
            doc.removeObject(o.Name)
    fea = ccxtools.FemToolsCcx(doc.Analysis, solver_of(doc))
    fea.update_objects()
    fea.setup_working_dir(work_directory("fem_"))
    fea.setup_ccx()
    message = fea.check_prerequisites()
    if message:
        raise RuntimeError("CalculiX prerequisites: " + message)
    fea.write_inp_file()
    if post:
        postprocess_inp(fea.inp_file_name, post)
    t = time.perf_counter()
    fea.ccx_run()
    seconds = time.perf_counter() - t
    fea.load_results()
    results = [o for o in doc.Analysis.Group if o.isDerivedFrom("Fem::FemResultObject")]
    if not results:
        raise RuntimeError("CalculiX gave no results for " + fea.inp_file_name)
    return results[-1], fea.inp_file_name, seconds


def measure(case, result, mesh):
    """The case's quantities from a result: {name: value}."""
    import numpy as np
    if case == "cantilever":
        return {"tip": max(result.DisplacementLengths)}
    nodes = mesh.Nodes
    # CalculiX may add nodes of its own (expanded degenerate elements): only the mesh's count.
    mine = np.array([n in nodes for n in result.NodeNumbers])
    ids = np.array(result.NodeNumbers)[mine]
    xyz = np.array([tuple(nodes[i]) for i in ids.tolist()])
    r = np.hypot(xyz[:, 0], xyz[:, 1])
    p1 = np.array(result.PrincipalMax)[mine]
    if case == "plate":
        hole = r < 50.0 + 1e-3
        vm = np.array(result.vonMises)[mine]
        return {"P1": float(p1[hole].max()), "vM": float(vm[hole].max()),
                "P1 anywhere": float(p1.max())}
    bore = r < 50.0 + 1e-3
    return {"hoop": float(p1[bore].max()), "hoop mean": float(p1[bore].mean())}


def row(case, mesh_label, femmesh, result, inp, seconds, extra=None):
    counts, collapsed = inp_counts(inp)
    out = {"case": case, "mesh": mesh_label, "nodes": femmesh.NodeCount,
           "elements": counts, "collapsed": collapsed, "solve s": round(seconds, 2),
           "values": measure(case, result, femmesh)}
    out.update(extra or {})
    return out


def volume_fractions(report):
    vf = report.get("volume_fraction") or {}
    if isinstance(vf, dict):
        return {k: round(100 * float(v), 1) for k, v in vf.items()}
    return {n: round(100 * float(v), 1) for n, v in zip(("tet", "pyramid", "prism", "hex"), vf)}


def post_merge_report(report):
    """What the engine's post-merge stage (same_nodes off) did, from its report."""
    keys = ("post_merge", "post_merge_closed", "post_merge_lifted", "node_moves", "contractions",
            "flips_23", "flips_32", "flips_44")
    return {k: report[k] for k in keys if k in report}


def worker(job):
    """One case and one source mesh (Gmsh tets, then every recombination) or one shape mesh."""
    import FreeCAD
    from freecad.hexmerge import calculix, engine, jobs
    case = job["case"]
    doc, mesh = build_case(case)
    rows = []
    if job["kind"] == "gmsh":
        gmsh(mesh, job["size"], job["order"])
        source = mesh.FemMesh.copy()  # the property hands out its live mesh
        label = "Gmsh {} {:g} mm".format("Tet4" if job["order"] == "1st" else "Tet10", job["size"])
        result, inp, seconds = solve(doc)
        rows.append(row(case, label, source, result, inp, seconds, {"source": label}))
        variants = VARIANTS + (LINEAR_ONLY_VARIANTS if job["order"] == "1st" else
                               QUADRATIC_ONLY_VARIANTS)
        defaults = {r["name"]: r["default"] for r in engine.parameter_table()}
        extra = job.get("recombine_options") or {}
        runs = []
        for name, options, post in variants:
            if extra and job.get("paired"):  # both, on the same source mesh
                runs.append((name, options, post, ""))
                runs.append((name, dict(options, **extra), post, " + " + ", ".join(
                    "{}={}".format(k, json.dumps(v)) for k, v in sorted(extra.items()))))
            else:
                runs.append((name, dict(options, **extra), post, ""))
        seen = set()
        for name, options, post, suffix in runs:
            effective = tuple(sorted(dict(defaults, **{k: str(v).lower() for k, v in
                                                       options.items()}).items())) \
                + (json.dumps(post, sort_keys=True),)
            if effective in seen:
                continue
            seen.add(effective)
            if "pyramid_placement" not in options and options.get("make_pyramids", True):
                name += " (pyramid_placement={})".format(defaults["pyramid_placement"])
            name += suffix
            femmesh, report = jobs.recombine_femmesh(source, regions="none", **options)
            mesh.FemMesh = femmesh
            result, inp, seconds = solve(doc, post)
            rows.append(row(case, name, femmesh, result, inp, seconds,
                            {"source": label, "volume %": volume_fractions(report),
                             "options": options, "post": post,
                             "post-merge": post_merge_report(report)}))
            mesh.FemMesh = source
    else:
        shape = doc.getObject(mesh.Part.Name).Shape if mesh.Part else None
        second = job["order"] == "2nd"
        extra = job.get("shape_options") or {}
        sj = jobs.ShapeJob.prepare(shape, dict(extra, size=job["size"], second_order=second))
        sj.run()
        femmesh, report = sj.finish()
        mesh.FemMesh = femmesh
        label = "from shape {:g} mm, {} order".format(job["size"], "second" if second else "first")
        if extra:
            label += " ({})".format(", ".join("{}={}".format(k, v) for k, v in sorted(extra.items())))
        # As FreeCAD's writer writes it (C3D8 / C3D20), then each other hexahedron type the
        # add-on offers, retyped as the add-on's writer hook does (freecad/hexmerge/calculix.py).
        written = "C3D20" if second else "C3D8"
        offered = calculix.QUADRATIC_HEXAHEDRON if second else calculix.LINEAR_HEXAHEDRON
        if written == offered[0]:
            label += " (the add-on's default)"
        # Second order with pyramids: also as the add-on writes them (two tied C3D10).
        pyramids = second and any(len(set(femmesh.getElementNodes(i))) == 13
                                  for i in femmesh.Volumes)
        for kind in [written] + [k for k in offered if k != written] + (["split"] if pyramids else []):
            post = None if kind == written else "split" if kind == "split" else {written: kind}
            name = label if kind == written else \
                "{}, pyramids as two tied C3D10 (the add-on's default)".format(label) \
                if kind == "split" else "{}, hexahedra as {}".format(
                    label, kind + (" (the add-on's default)" if kind == offered[0] else ""))
            result, inp, seconds = solve(doc, post)
            rows.append(row(case, name, femmesh, result, inp, seconds,
                            {"source": label, "volume %": volume_fractions(report),
                             "post": post}))
    FreeCAD.closeDocument(doc.Name)
    return rows


def patch_test(kind, shift, workdir=None):
    """CalculiX's patch test of a hexahedron type: 2 x 2 x 2 unit hexahedra under uniform tension
    (100 MPa on x = 2, rollers on x = 0, y = 0, z = 0), the middle node moved by shift x (0.3,
    0.2, 0.25). Returns (the largest calculix.distortion() of the eight, the largest error of
    the integration-point stresses in % of 100 MPa). A type that passes gives 0 whatever the
    shift."""
    import itertools
    from freecad.hexmerge import calculix
    workdir = workdir or work_directory("patch_")
    ids, points = {}, []
    for k, j, i in itertools.product(range(3), repeat=3):
        p = [float(i), float(j), float(k)]
        if (i, j, k) == (1, 1, 1):
            p = [p[0] + 0.3 * shift, p[1] + 0.2 * shift, p[2] + 0.25 * shift]
        ids[(i, j, k)] = len(points) + 1
        points.append(p)
    hexes = []
    for k, j, i in itertools.product(range(2), repeat=3):
        hexes.append([ids[c] for c in ((i, j, k), (i + 1, j, k), (i + 1, j + 1, k), (i, j + 1, k),
                                       (i, j, k + 1), (i + 1, j, k + 1), (i + 1, j + 1, k + 1),
                                       (i, j + 1, k + 1))])
    lines = ["*NODE"] + ["{},{!r},{!r},{!r}".format(n + 1, *p) for n, p in enumerate(points)]
    lines += ["*ELEMENT,TYPE={},ELSET=EALL".format(kind)]
    lines += [",".join(str(x) for x in [e + 1] + h) for e, h in enumerate(hexes)]
    for axis, name in enumerate("XYZ"):
        lines += ["*NSET,NSET={}0".format(name),
                  ",".join(str(n) for c, n in ids.items() if c[axis] == 0)]
    lines += ["*MATERIAL,NAME=STEEL", "*ELASTIC", "210000,0.3",
              "*SOLID SECTION,ELSET=EALL,MATERIAL=STEEL", "*STEP", "*STATIC", "*BOUNDARY",
              "X0,1,1", "Y0,2,2", "Z0,3,3", "*DLOAD"]
    # face 4 of a C3D8 (corners 2 3 7 6) is its +x face
    lines += ["{},P4,-100".format(e + 1) for e, h in enumerate(hexes) if points[h[1] - 1][0] == 2]
    lines += ["*EL PRINT,ELSET=EALL", "S", "*END STEP"]
    with open(os.path.join(workdir, "patch.inp"), "w") as f:
        f.write("\n".join(lines) + "\n")
    subprocess.run(["ccx", "patch"], cwd=workdir, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL, check=True)
    error = None
    with open(os.path.join(workdir, "patch.dat")) as f:
        for line in f:
            parts = line.split()
            if len(parts) == 8 and re.match(r"^-?\d", parts[2]):
                stress = [float(x) for x in parts[2:]]
                e = max([abs(stress[0] - 100.0)] + [abs(x) for x in stress[1:]])
                error = e if error is None else max(error, e)
    if error is None:
        raise RuntimeError("CalculiX wrote no stresses in " + workdir)
    worst = max(calculix.distortion([points[n - 1] for n in h]) for h in hexes)
    return worst, error


def pyramid_patch_test(split, workdir=None):
    """A quadratic patch test of second-order pyramids: a unit cube as one C3D20 beside a unit
    cube of six pyramids (collapsed C3D20, apex at its centre); every node on the outside held at
    pure bending's exact displacement (curvature 1e-3 about y: u = (k x z, -nu k y z, -k (x^2 +
    nu (z^2 - y^2)) / 2), stress sxx = E k z), the rest free. Quadratic elements that are
    continuous reproduce it exactly. split: the pyramids as calculix.split_pyramids_in_input()
    writes them (their split diagonals tied, not held); else collapsed C3D20. Returns the
    largest error of the nodal displacements, in % of the largest exact one, and of the
    integration-point stresses, in % of the largest exact one."""
    from freecad.hexmerge import calculix
    workdir = workdir or work_directory("pyramid_patch_")
    young, nu, k = 210000.0, 0.3, 1e-3
    points, ids = [], {}

    def node(p):
        key = tuple(round(x, 9) for x in p)
        if key not in ids:
            ids[key] = len(points) + 1
            points.append(key)
        return ids[key]

    def cube(x0):
        return [(x0 + i, j, kk) for i, j, kk in ((0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0),
                                                 (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1))]

    def c3d20(corners):
        ends = [node(c) for c in corners]
        middles = [node([(corners[u][c] + corners[v][c]) / 2 for c in range(3)])
                   for u, v in HEX_EDGES]
        return ends + middles

    elements = [c3d20(cube(0.0))]
    b = cube(1.0)
    centre = (1.5, 0.5, 0.5)
    # each face of the second cube (CalculiX's C3D8 faces, which run counterclockwise seen from
    # inside: from the apex) as the bottom of a hexahedron whose top is the apex
    for face in CCX_FACES["C3D8"]:
        base = [b[i] for i in face]
        elements.append(c3d20(base + [centre] * 4))
    outside = [n for p, n in ids.items()
               if min(p) < 1e-9 or p[0] > 2 - 1e-9 or p[1] > 1 - 1e-9 or p[2] > 1 - 1e-9]

    def exact(p):
        x, y, z = p
        return (k * x * z, -nu * k * y * z, -k * (x * x + nu * (z * z - y * y)) / 2)

    lines = ["*NODE,NSET=NALL"] + ["{},{!r},{!r},{!r}".format(n + 1, *p)
                                   for n, p in enumerate(points)]
    lines += ["*ELEMENT,TYPE=C3D20,ELSET=EALL"]
    for e, nodes in enumerate(elements):
        row = [e + 1] + nodes
        lines += [",".join(str(x) for x in row[:16]) + ",", ",".join(str(x) for x in row[16:])]
    lines += ["*MATERIAL,NAME=STEEL", "*ELASTIC", "{!r},{!r}".format(young, nu),
              "*SOLID SECTION,ELSET=EALL,MATERIAL=STEEL", "*STEP", "*STATIC", "*BOUNDARY"]
    for n in outside:
        for dof, value in enumerate(exact(points[n - 1])):
            lines.append("{},{},{},{:.12g}".format(n, dof + 1, dof + 1, value))
    lines += ["*NODE PRINT,NSET=NALL", "U", "*EL PRINT,ELSET=EALL", "S", "*END STEP"]
    path = os.path.join(workdir, "patch.inp")
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")
    if split and calculix.split_pyramids_in_input(path) != 6:
        raise RuntimeError("split_pyramids_in_input did not split the six pyramids")
    subprocess.run(["ccx", "patch"], cwd=workdir, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL, check=True)
    with open(path) as f:
        where = calculix.read_nodes(f.read().split("\n"))
    scale = max(max(abs(x) for x in exact(p)) for p in where.values())
    displacement = stress = None
    with open(os.path.join(workdir, "patch.dat")) as f:
        for line in f:
            parts = line.split()
            if len(parts) == 4 and parts[0].isdigit():  # node, ux, uy, uz
                u = exact(where[int(parts[0])])
                e = max(abs(float(x) - v) for x, v in zip(parts[1:], u)) / scale
                displacement = e if displacement is None else max(displacement, e)
            elif len(parts) == 8 and re.match(r"^-?\d", parts[2]):
                # sxx = E k z in [0, E k] at every integration point; the others 0
                s = [float(x) for x in parts[2:]]
                e = max([max(0.0, -s[0], s[0] - young * k)] + [abs(x) for x in s[1:]]) / (young * k)
                stress = e if stress is None else max(stress, e)
    if displacement is None or stress is None:
        raise RuntimeError("CalculiX wrote no displacements or stresses in " + workdir)
    return 100.0 * displacement, 100.0 * stress


# ---- the driver ------------------------------------------------------------------------------

def jobs_for(cases, kinds=("gmsh", "shape"), orders=("1st", "2nd")):
    jobs = []
    for case in cases:
        for size in SIZES[case]:
            for kind in kinds:
                for order in orders:
                    jobs.append({"case": case, "kind": kind, "size": size, "order": order})
    return jobs


def run_job(job, timeout):
    home = os.path.join(tempfile.gettempdir(), "hexmerge-fem-home")
    os.makedirs(home, exist_ok=True)
    out = tempfile.mktemp(suffix=".json")
    env = dict(os.environ, HOME=home, QT_QPA_PLATFORM="offscreen",
               HEXMERGE_FEM_JOB=json.dumps(job), HEXMERGE_FEM_OUT=out,
               PYTHONPATH=os.path.join(ROOT, "src", "python"))
    t = time.perf_counter()
    proc = subprocess.run(["freecadcmd", os.path.abspath(__file__), "-M", ROOT], env=env,
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                          timeout=timeout)
    if not os.path.exists(out):
        sys.stderr.write(proc.stdout[-1500:])
        raise RuntimeError("job {} failed (exit {})".format(job, proc.returncode))
    with open(out) as f:
        rows = json.load(f)
    os.unlink(out)
    print("  {} {} {:g} {}: {} rows, {:.0f} s".format(job["case"], job["kind"], job["size"],
                                                      job["order"], len(rows),
                                                      time.perf_counter() - t), flush=True)
    return rows


def error_percent(case, values):
    ref = REFERENCES[case]
    errs = {}
    for key, value in values.items():
        if ref.get(key):
            errs[key] = 100.0 * (value / ref[key] - 1.0)
    return errs


def elements_text(r):
    parts = ["{} {:,}".format(k, v) for k, v in sorted(r["elements"].items())]
    if r["collapsed"]:
        parts.append("({:,} collapsed)".format(r["collapsed"]))
    return ", ".join(parts)


def markdown(rows, header):
    lines = [header, ""]
    for case in ("cantilever", "plate", "cylinder"):
        case_rows = [r for r in rows if r["case"] == case]
        if not case_rows:
            continue
        ref = REFERENCES[case]
        if case == "cantilever":
            title = ("### Cantilever: tip displacement (reference {} mm, converged 3D; beam theory "
                     "{} mm)".format(ref["tip"], ref["beam theory"]))
            cols = ["tip mm", "error %"]
        elif case == "plate":
            title = ("### Plate with a hole: peak stress at the hole (reference principal {} MPa"
                     "{})".format(ref["P1"], ", von Mises {} MPa".format(ref["vM"])
                                  if ref["vM"] else ""))
            cols = ["P1 MPa", "error %", "vM MPa"] + (["vM error %"] if ref["vM"] else []) + \
                   ["P1 anywhere MPa"]
        else:
            title = ("### Thick-walled cylinder: hoop stress at the bore (Lame {:.2f} MPa)"
                     .format(ref["hoop"]))
            cols = ["peak MPa", "error %", "mean MPa", "mean error %"]
        lines += [title, "",
                  "| mesh | nodes | elements (.inp) | hex/prism/pyr/tet vol % | solve s | "
                  + " | ".join(cols) + " | vs source |",
                  "|---|---|---|---|---|" + "---|" * len(cols) + "---|"]
        source_error = {}
        for r in case_rows:
            v = r["values"]
            e = error_percent(case, v)
            if case == "cantilever":
                cells = ["{:.2f}".format(v["tip"]), "{:+.2f}".format(e["tip"])]
                main = abs(e["tip"])
            elif case == "plate":
                cells = ["{:.1f}".format(v["P1"]), "{:+.2f}".format(e["P1"]), "{:.1f}".format(v["vM"])]
                if ref["vM"]:
                    cells.append("{:+.2f}".format(e["vM"]))
                cells.append("{:.1f}".format(v["P1 anywhere"]))
                main = abs(e["P1"])
            else:
                mean_err = 100.0 * (v["hoop mean"] / ref["hoop"] - 1.0)
                cells = ["{:.2f}".format(v["hoop"]), "{:+.2f}".format(e["hoop"]),
                         "{:.2f}".format(v["hoop mean"]), "{:+.2f}".format(mean_err)]
                main = abs(e["hoop"])
            if r["mesh"] == r["source"]:
                source_error[r["source"]] = main
                verdict = ""
            else:
                verdict = "ok" if main <= source_error.get(r["source"], float("inf")) + TIE \
                    else "**worse**"
            vf = r.get("volume %") or {}
            vol = "/".join(str(vf.get(k, "")) for k in ("hex", "prism", "pyramid", "tet")) if vf \
                else ""
            label = r["mesh"] if r["mesh"] == r["source"] else "&nbsp;&nbsp;" + r["mesh"]
            lines.append("| {} | {:,} | {} | {} | {} | {} | {} |".format(
                label, r["nodes"], elements_text(r), vol, r["solve s"], " | ".join(cells),
                verdict))
        lines.append("")
    return "\n".join(lines)


def header_text():
    commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"],
                            stdout=subprocess.PIPE, text=True).stdout.strip()
    dirty = subprocess.run(["git", "-C", ROOT, "status", "--porcelain", "--untracked-files=no"],
                           stdout=subprocess.PIPE, text=True).stdout.strip()
    ccx = subprocess.run(["sh", "-c", "ccx -v 2>&1 | head -3"], stdout=subprocess.PIPE,
                         text=True).stdout
    version = re.search(r"[Vv]ersion\s+([\d.]+)", ccx)
    return ("Commit {}{}, machine {} ({} cores, {}), {} UTC; FreeCAD 0.20 ccxtools, CalculiX {}."
            .format(commit, " (with uncommitted changes)" if dirty else "", platform.node(),
                    os.cpu_count(), platform.platform(),
                    datetime.datetime.utcnow().strftime("%Y-%m-%d %H:%M"),
                    version.group(1) if version else "?"))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cases", default="cantilever,plate,cylinder")
    parser.add_argument("--sizes", help="case:size[,size] overrides, e.g. plate:10")
    parser.add_argument("--kinds", default="gmsh,shape",
                        help="source meshes: gmsh (Gmsh tets and their recombinations), shape")
    parser.add_argument("--orders", default="1st,2nd")
    parser.add_argument("--timeout", type=float, default=900.0, help="seconds per job")
    parser.add_argument("--no-doc", action="store_true", help="do not write docs/fem-accuracy.md")
    parser.add_argument("--table", help="print the table of an earlier JSON run")
    parser.add_argument("--recombine-options", default="{}",
                        help='JSON: engine options added to every recombination variant of the '
                        'Gmsh meshes, e.g. \'{"same_nodes": false}\' (the post-merge stage)')
    parser.add_argument("--paired", action="store_true",
                        help="with --recombine-options: solve each variant without and with "
                        "them, on the same Gmsh mesh (Gmsh's meshes differ from run to run)")
    parser.add_argument("--output", default=os.path.join(ROOT, "bench", "results",
                                                         "fem-accuracy.json"),
                        help="the JSON results file (default bench/results/fem-accuracy.json)")
    parser.add_argument("--shape-options", default="{}",
                        help='JSON: more mesher parameters for the meshes from the shape, e.g. '
                        '\'{"layer_thickness": 0.15}\'')
    args = parser.parse_args()
    if args.table:
        with open(args.table) as f:
            data = json.load(f)
        print(markdown(data["rows"], data["header"]))
        return
    cases = args.cases.split(",")
    if args.sizes:
        for item in args.sizes.split(";"):
            case, sizes = item.split(":")
            SIZES[case] = tuple(float(s) for s in sizes.split(","))
    rows = []
    t = time.perf_counter()
    os.makedirs(os.path.dirname(os.path.abspath(args.output)), exist_ok=True)
    recombine_options = json.loads(args.recombine_options)
    for job in jobs_for(cases, args.kinds.split(","), args.orders.split(",")):
        if job.get("kind", "shape") == "shape":
            job["shape_options"] = json.loads(args.shape_options)
        else:
            job["recombine_options"] = recombine_options
            job["paired"] = args.paired
        try:
            rows += run_job(job, args.timeout)
        except (RuntimeError, subprocess.TimeoutExpired) as e:
            print("  FAILED: {}".format(e), flush=True)
        header = header_text() + " Whole run {:.0f} s.".format(time.perf_counter() - t)
        if recombine_options:
            header += " Recombination options {}: {}.".format(
                "beside every variant (rows ' + ...')" if args.paired else "on every variant",
                json.dumps(recombine_options, sort_keys=True))
        with open(args.output, "w") as f:
            json.dump({"header": header, "rows": rows}, f, indent=1)  # after every job
    table = markdown(rows, header)
    print(table)
    if not args.no_doc:
        path = os.path.join(ROOT, "docs", "fem-accuracy.md")
        text = open(path).read() if os.path.exists(path) else ""
        begin, end = "<!-- table: bench/fem_accuracy.py -->", "<!-- end table -->"
        if begin in text and end in text:
            text = text[:text.index(begin) + len(begin)] + "\n" + table + "\n" + text[text.index(end):]
        else:
            text += "\n" + begin + "\n" + table + "\n" + end + "\n"
        with open(path, "w") as f:
            f.write(text)


if os.environ.get("HEXMERGE_FEM_JOB"):
    _rows = worker(json.loads(os.environ["HEXMERGE_FEM_JOB"]))
    with open(os.environ["HEXMERGE_FEM_OUT"], "w") as _f:
        json.dump(_rows, _f)
    os._exit(0)
elif __name__ == "__main__":
    main()
