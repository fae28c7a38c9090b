# SPDX-License-Identifier: LGPL-2.1-or-later
"""CalculiX element technology for HexMerge meshes (issue 15, docs/fem-accuracy.md).

FreeCAD 0.20's CalculiX writer picks an element type by node count alone (FemMesh.writeABAQUS:
8 nodes -> C3D8, 20 -> C3D20), and has no setting for it. C3D8 is too stiff in bending (shear
locking): the cantilever made from its shape at 200 mm, 1,000 hexahedra, bends 2.4 % short, and
0.24 % short as C3D8I, CalculiX's incompatible-modes brick. So the add-on rewrites the element
type of its own meshes' hexahedra in the .inp, right after FreeCAD's writer has written the mesh
and before anything else reads the file: `install_writer_hook()` wraps
femsolver.calculix.write_mesh.write_mesh, the one function both of FreeCAD 0.20's CalculiX paths
(the ccxtools solver and the solver framework) write the mesh with. Only meshes of HexMerge
objects are touched, and only their true hexahedra: a pyramid stored as a collapsed hexahedron
stays C3D8 / C3D20 (as C3D8I it gave nonsense: 581 MPa for 167 at the cylinder's bore).
Prisms and tetrahedra have no alternative in CalculiX 2.20 (C3D6, C3D15, C3D4, C3D10; C3D5 is
"an unknown element type"). Element faces keep their numbers (C3D8I and C3D20R number faces as
C3D8 and C3D20), so the writer's face loads stay right.

Nothing here needs FreeCAD's GUI; the hook imports FreeCAD's FEM modules when installed.
"""

import os
import re

# The choices, first the default (docs/fem-accuracy.md gives the measurements behind them).
C3D8I_IF_PARALLELEPIPED = "C3D8I if parallelepiped"
LINEAR_HEXAHEDRON = (C3D8I_IF_PARALLELEPIPED, "C3D8I", "C3D8")
# CalculiX 2.20's C3D8I fails the patch test on hexahedra that are not parallelepipeds: 2 x 2 x 2
# elements under uniform tension, the middle node moved, give integration-point stresses off by
# about 0.66 x distortion() (0.36 % at 0.0055, 1.5 % at 0.022, 4 % at 0.057; C3D8: exact). Past
# this distortion a hexahedron stays C3D8 under C3D8I_IF_PARALLELEPIPED.
MAX_C3D8I_DISTORTION = 0.005
QUADRATIC_HEXAHEDRON = ("C3D20", "C3D20R")
LINEAR_HEXAHEDRON_DOC = (
    "CalculiX element for first-order hexahedra. C3D8 locks in bending (cantilever tip -2.4 %); "
    "C3D8I (incompatible modes) bends right (-0.24 %) but CalculiX's C3D8I is wrong on distorted "
    "hexahedra (it fails the patch test: plate-with-hole peak +24 % at 4 mm). 'C3D8I if "
    "parallelepiped' writes C3D8I where a hexahedron is a parallelepiped (distortion <= 0.005) "
    "and C3D8 elsewhere. FreeCAD 0.20's writer writes C3D8; the add-on rewrites its own meshes' "
    "hexahedra in the .inp (pyramids stored as collapsed hexahedra stay C3D8).")
QUADRATIC_HEXAHEDRON_DOC = (
    "CalculiX element for second-order hexahedra: C3D20 (full integration) or C3D20R (reduced "
    "integration). The add-on rewrites its own meshes' hexahedra in the .inp (pyramids stored as "
    "collapsed hexahedra stay C3D20).")

NODES = {"C3D4": 4, "C3D6": 6, "C3D8": 8, "C3D8I": 8, "C3D8R": 8, "C3D10": 10, "C3D15": 15,
         "C3D20": 20, "C3D20R": 20}
_ELEMENT = re.compile(r"\*ELEMENT\s*,(.*)$", re.I)
_TYPE = re.compile(r"(TYPE\s*=\s*)(\w+)", re.I)


def is_collapsed(nodes):
    """True for a hexahedron (8 or 20 nodes) with a face on one node: a pyramid stored as a
    collapsed hexahedron (the apex four times)."""
    return len(set(nodes[4:8])) == 1 or len(set(nodes[0:4])) == 1


# Corner signs of the C3D8 node order in the parent cube.
_CORNERS = ((-1, -1, -1), (1, -1, -1), (1, 1, -1), (-1, 1, -1), (-1, -1, 1), (1, -1, 1),
            (1, 1, 1), (-1, 1, 1))


def distortion(corners):
    """How far a hexahedron (8 corners in C3D8 order) is from a parallelepiped: the largest of
    its trilinear map's bilinear and trilinear coefficients over the smallest linear one (0 for a
    parallelepiped; one corner of a cube moved by 10 % of its edge gives 0.025)."""
    def coefficient(f):
        v = [sum(f(s) * c[k] for s, c in zip(_CORNERS, corners)) / 8.0 for k in range(3)]
        return (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) ** 0.5

    linear = [coefficient(lambda s, k=k: s[k]) for k in range(3)]
    higher = [coefficient(lambda s: s[0] * s[1]), coefficient(lambda s: s[1] * s[2]),
              coefficient(lambda s: s[0] * s[2]), coefficient(lambda s: s[0] * s[1] * s[2])]
    return max(higher) / min(linear) if min(linear) > 0 else float("inf")


def read_nodes(lines):
    """{node id: (x, y, z)} of the .inp's *NODE blocks."""
    points = {}
    inside = False
    for line in lines:
        if line.lstrip().startswith("*"):
            inside = re.match(r"\*NODE\b", line.strip(), re.I) is not None \
                and not re.match(r"\*NODE\s+(FILE|PRINT|OUTPUT)", line.strip(), re.I)
            continue
        if inside:
            parts = line.split(",")
            if len(parts) >= 4:
                points[int(parts[0])] = (float(parts[1]), float(parts[2]), float(parts[3]))
    return points


def retype_lines(lines, types, max_distortion=MAX_C3D8I_DISTORTION):
    """The .inp's lines with its true hexahedra's element type changed: `types` maps a type the
    writer wrote (C3D8, C3D20) to the one wanted; C3D8I_IF_PARALLELEPIPED asks for C3D8I on the
    hexahedra whose distortion() is at most max_distortion (the others keep the written type).
    A block that mixes types is split, each header kept otherwise as written (so ELSET= names
    the same set). Returns (new lines, {new type: number of elements retyped})."""
    points = read_nodes(lines) if C3D8I_IF_PARALLELEPIPED in types.values() else None
    out, counts = [], {}
    i = 0
    while i < len(lines):
        m = _ELEMENT.match(lines[i])
        kind = _TYPE.search(m.group(1)).group(2).upper() if m and _TYPE.search(m.group(1)) else None
        if kind not in types or types[kind] == kind:
            out.append(lines[i])
            i += 1
            continue
        header = lines[i]
        j = i + 1
        numbers = []
        while j < len(lines) and not lines[j].lstrip().startswith("*"):
            numbers += [int(x) for x in re.findall(r"-?\d+", lines[j])]
            j += 1
        n = NODES[kind] + 1
        if len(numbers) % n:
            raise ValueError("the .inp's {} block at line {} does not hold whole elements ({} "
                             "numbers for {} per element)".format(kind, i + 1, len(numbers), n))
        elements = [numbers[k:k + n] for k in range(0, len(numbers), n)]
        new = types[kind]
        if new == C3D8I_IF_PARALLELEPIPED:
            new = "C3D8I"
            moved = []
            for e in elements:
                if is_collapsed(e[1:]):
                    continue
                missing = [p for p in e[1:9] if p not in points]
                if missing:
                    raise ValueError("the .inp's element {} names node {}, which has no *NODE "
                                     "line".format(e[0], missing[0]))
                if distortion([points[p] for p in e[1:9]]) <= max_distortion:
                    moved.append(e)
        else:
            moved = [e for e in elements if not is_collapsed(e[1:])]
        ids = {e[0] for e in moved}
        kept = [e for e in elements if e[0] not in ids]
        for new_kind, items in ((kind, kept), (new, moved)):
            if not items:
                continue
            out.append(_TYPE.sub(lambda t: t.group(1) + new_kind, header, count=1))
            for e in items:
                for s in range(0, len(e), 16):  # at most 16 numbers on a line
                    out.append(", ".join(str(x) for x in e[s:s + 16])
                               + ("," if s + 16 < len(e) else ""))
        if moved:
            counts[new] = counts.get(new, 0) + len(moved)
        i = j
    return out, counts


def retype_file(path, types, max_distortion=MAX_C3D8I_DISTORTION):
    """retype_lines() on a file, replaced whole (never half-written); returns the counts."""
    with open(path) as f:
        text = f.read()
    lines, counts = retype_lines(text.split("\n"), types, max_distortion)
    if counts:
        tmp = path + ".hexmerge-tmp"
        with open(tmp, "w") as f:
            f.write("\n".join(lines))
        os.replace(tmp, path)
    return counts


def element_types(mesh_obj):
    """{written type: wanted type} for a mesh object, from a HexMerge object's properties;
    None for any other mesh object."""
    proxy = getattr(mesh_obj, "Proxy", None)
    if getattr(proxy, "Type", None) != "HexMerge::MeshHexDominant":
        return None
    types = {}
    if "LinearHexahedron" in mesh_obj.PropertiesList:
        types["C3D8"] = str(mesh_obj.LinearHexahedron)
    if "QuadraticHexahedron" in mesh_obj.PropertiesList:
        types["C3D20"] = str(mesh_obj.QuadraticHexahedron)
    return types


class _RetypingMesh:
    """Stands for the writer's FemMesh while write_mesh runs: writeABAQUS writes, then retypes."""

    def __init__(self, femmesh, types, label):
        self._femmesh = femmesh
        self._types = types
        self._label = label

    def writeABAQUS(self, path, *args):
        self._femmesh.writeABAQUS(path, *args)
        counts = retype_file(path, self._types)
        if counts:
            import FreeCAD
            FreeCAD.Console.PrintMessage("HexMerge: {}: {} in {}\n".format(
                self._label, ", ".join("{} hexahedra written as {}".format(n, k)
                                       for k, n in sorted(counts.items())), path))

    def __getattr__(self, name):
        return getattr(self._femmesh, name)


def install_writer_hook():
    """Wraps FreeCAD's femsolver.calculix.write_mesh.write_mesh once (idempotent). Returns True
    when the hook is in place."""
    from femsolver.calculix import write_mesh as module
    original = module.write_mesh
    if getattr(original, "hexmerge_hook", False):
        return True

    def write_mesh(ccxwriter):
        types = element_types(ccxwriter.mesh_object)
        if not types:
            return original(ccxwriter)
        femmesh = ccxwriter.femmesh
        ccxwriter.femmesh = _RetypingMesh(femmesh, types, ccxwriter.mesh_object.Label)
        try:
            return original(ccxwriter)
        finally:
            ccxwriter.femmesh = femmesh

    write_mesh.hexmerge_hook = True
    write_mesh.__doc__ = original.__doc__
    module.write_mesh = write_mesh
    return True
