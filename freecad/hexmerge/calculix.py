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

# How a second-order pyramid (stored as a collapsed C3D20 under PyramidsAsHexahedra) reaches
# CalculiX, first the default. Collapsed C3D20 on the boundary overstate the stress peaks there
# (the plate with a hole from its shape, unswept, 8 mm: +4.25 %; the cylinder's bore +22 to +31
# %); two C3D10 on the base's diagonal, whose middle node is tied by an *EQUATION to the 8-node
# face's centre value, are continuous with the hexahedron or prism behind the base for every
# quadratic field and give +0.38 % and +2.6 to +3.0 % (docs/fem-accuracy.md).
SPLIT_PYRAMID = "two C3D10, tied"
QUADRATIC_PYRAMID = (SPLIT_PYRAMID, "collapsed C3D20")
QUADRATIC_PYRAMID_DOC = (
    "How second-order pyramids reach CalculiX (it has no pyramid element). 'two C3D10, tied' "
    "splits each on its base's diagonal into two quadratic tets, the diagonal's middle node tied "
    "by an *EQUATION to the base face of the hexahedron or prism behind it (continuous for "
    "every quadratic field); 'collapsed C3D20' writes FreeCAD's collapsed hexahedron, whose "
    "stresses are poor where it touches the surface (peaks +4 to +31 %). Needs Pyramids as "
    "hexahedra; first-order pyramids stay collapsed C3D8.")

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


def read_element_block(lines, i, kind):
    """The elements of the *ELEMENT block whose header is lines[i] (type `kind`): (the line after
    the block, [(id, [node ids])])."""
    j = i + 1
    numbers = []
    while j < len(lines) and not lines[j].lstrip().startswith("*"):
        numbers += [int(x) for x in re.findall(r"-?\d+", lines[j])]
        j += 1
    n = NODES[kind] + 1
    if len(numbers) % n:
        raise ValueError("the .inp's {} block at line {} does not hold whole elements ({} "
                         "numbers for {} per element)".format(kind, i + 1, len(numbers), n))
    return j, [(numbers[k], numbers[k + 1:k + n]) for k in range(0, len(numbers), n)]


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
        j, items = read_element_block(lines, i, kind)
        elements = [[eid] + nodes for eid, nodes in items]
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


# C3D20 (and C3D8) corners of each face (0-based), and the corners of each of its 12 edges,
# the k-th edge's middle node at position 8 + k; C3D10's faces and edges likewise.
_HEX_FACES = ((0, 1, 2, 3), (4, 7, 6, 5), (0, 4, 5, 1), (1, 5, 6, 2), (2, 6, 7, 3), (3, 7, 4, 0))
_HEX_EDGES = ((0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4), (0, 4), (1, 5),
              (2, 6), (3, 7))
_TET_FACES = ((0, 1, 2), (0, 3, 1), (1, 3, 2), (2, 3, 0))
_TET_EDGES = ((0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3))
_INCLUDE = re.compile(r"\*INCLUDE\s*,\s*INPUT\s*=\s*(.+?)\s*$", re.I)
_FACE_ITEM = re.compile(r"^(\s*)(\d+)(\s*,\s*)([PSFR])(\d)\b(.*)$", re.I)


def collapsed_pyramid(nodes):
    """(base corners in the hexahedron's circulation, apex) of a C3D8/C3D20 written as a collapsed
    pyramid (one face all on one node; FreeCAD's writer puts the apex first), or None."""
    for apex_face, base_face in (((0, 1, 2, 3), (4, 5, 6, 7)), ((4, 5, 6, 7), (0, 1, 2, 3))):
        apex = {nodes[i] for i in apex_face}
        base = [nodes[i] for i in base_face]
        if len(apex) == 1 and len(set(base)) == 4:
            return base, apex.pop()
    return None


def split_pyramid(nodes, points, new_node):
    """A collapsed C3D20 (20 node ids) as two C3D10 on the base's diagonal through its smallest
    node (a pyramid on the other side of the base splits it the same way). new_node(position)
    gives the id of the diagonal's middle node, placed at the 8-node face's centre. Returns the
    two tets (10 ids each, positively oriented) and the equation that ties that node to the
    8-node face on the base: [(node, coefficient)], sum = 0 (the node's value = -1/4 corners +
    1/2 middles of the base). Tied also where the base is on the boundary (its node then follows
    the constraints of the face's nodes) or on another pyramid (both ties give the same value):
    with the diagonal's node free there and put in the node sets that hold the whole base, the
    plate and the cylinder of docs/fem-accuracy.md read the same to 0.2 points."""
    base, apex = collapsed_pyramid(nodes)
    k = base.index(min(base))
    base = base[k:] + base[:k]
    middle = {frozenset((nodes[u], nodes[v])): nodes[8 + e] for e, (u, v) in enumerate(_HEX_EDGES)
              if nodes[u] != nodes[v]}
    sides = [middle[frozenset(pair)] for pair in zip(base, base[1:] + base[:1])]
    centre = [sum(0.5 * points[n][c] for n in sides) - sum(0.25 * points[n][c] for n in base)
              for c in range(3)]
    middle[frozenset((base[0], base[2]))] = new_node(centre)
    tets = []
    for corners in ((base[0], base[1], base[2], apex), (base[0], base[2], base[3], apex)):
        p = [points[n] for n in corners]
        d = [[p[i][c] - p[0][c] for c in range(3)] for i in (1, 2, 3)]
        volume = (d[0][1] * d[1][2] - d[0][2] * d[1][1]) * d[2][0] \
            + (d[0][2] * d[1][0] - d[0][0] * d[1][2]) * d[2][1] \
            + (d[0][0] * d[1][1] - d[0][1] * d[1][0]) * d[2][2]
        if volume < 0:
            corners = (corners[0], corners[2], corners[1], corners[3])
        tets.append(list(corners) + [middle[frozenset((corners[u], corners[v]))]
                                     for u, v in _TET_EDGES])
    equation = [(middle[frozenset((base[0], base[2]))], 1.0)] + [(n, 0.25) for n in base] \
        + [(n, -0.5) for n in sides]
    return tets, equation


def _input_files(path):
    """The .inp at path and the files it includes (recursively, relative to its folder):
    {path: lines}, in reading order."""
    files = {}

    def read(p):
        if p in files:
            return
        with open(p) as f:
            files[p] = f.read().split("\n")
        for line in files[p]:
            m = _INCLUDE.match(line.strip())
            if m:
                read(os.path.join(os.path.dirname(path), m.group(1).strip().strip('"')))
    read(path)
    return files


def split_pyramids_in_input(path):
    """Rewrites the CalculiX input at path (and the files it includes) with every collapsed
    C3D20 as split_pyramid()'s two C3D10: the first keeps the element's id, the second takes a
    new one (added to every *ELSET that lists the first); the diagonals' middle nodes go after
    the mesh's nodes and the *EQUATION cards that tie them after its elements; face loads and element surfaces (Pk, Sk, Fk, Rk) move to
    the tet faces on the same corners (a base face to both). Each file is replaced whole.
    Returns the number of pyramids split."""
    files = _input_files(path)
    points, elements = {}, {}
    node_end = None  # (file, line) after the last *NODE block
    blocks = []  # (file, header line, end line, type, [(id, nodes)])
    for name, lines in files.items():
        points.update(read_nodes(lines))
        i = 0
        while i < len(lines):
            stripped = lines[i].strip()
            if re.match(r"\*NODE\s*(,|$)", stripped, re.I):
                j = i + 1
                while j < len(lines) and not lines[j].lstrip().startswith("*"):
                    j += 1
                node_end = (name, j)
                i = j
                continue
            m = _ELEMENT.match(stripped)
            kind = _TYPE.search(m.group(1)).group(2).upper() if m and _TYPE.search(m.group(1)) else None
            if kind in NODES:
                j, items = read_element_block(lines, i, kind)
                blocks.append((name, i, j, kind, items))
                elements.update(items)
                i = j
                continue
            i += 1
    pyramids = [(b, eid) for b, block in enumerate(blocks) if block[3] in ("C3D20", "C3D20R")
                for eid, nodes in block[4] if collapsed_pyramid(nodes)]
    if not pyramids:
        return 0
    next_node = [max(points) + 1]
    new_nodes = []

    def new_node(position):
        new_nodes.append((next_node[0], position))
        next_node[0] += 1
        return new_nodes[-1][0]

    next_element = max(elements) + 1
    split = {}  # id -> (old nodes, [(id, tet nodes), (id, tet nodes)])
    equations = []
    for _, eid in pyramids:
        tets, equation = split_pyramid(elements[eid], points, new_node)
        split[eid] = (elements[eid], [(eid, tets[0]), (next_element, tets[1])])
        next_element += 1
        equations.append(equation)

    def element_lines(items):
        out = []
        for eid, nodes in items:
            row = [eid] + list(nodes)
            for k in range(0, len(row), 16):  # at most 16 numbers on a line
                out.append(", ".join(str(x) for x in row[k:k + 16])
                           + ("," if k + 16 < len(row) else ""))
        return out

    # Per file, edits as (line, end, new lines), applied from the bottom up.
    edits = {name: [] for name in files}
    for name, first, end, kind, items in blocks:
        if not any(eid in split for eid, _ in items):
            continue
        header = files[name][first]
        kept = [(eid, nodes) for eid, nodes in items if eid not in split]
        tets = [t for eid, _ in items if eid in split for t in split[eid][1]]
        text = ([header] + element_lines(kept) if kept else []) \
            + [_TYPE.sub(lambda t: t.group(1) + "C3D10", header, count=1)] + element_lines(tets)
        edits[name].append((first, end, text))
    mesh_file = blocks[pyramids[0][0]][0]
    last_block_end = max(end for name, _, end, _, _ in blocks if name == mesh_file)
    ties = []
    for equation in equations:
        for dof in (1, 2, 3):
            terms = ["{},{},{:.6g}".format(n, dof, c) for n, c in equation]
            ties += ["*EQUATION", str(len(terms))] \
                + [",".join(terms[k:k + 4]) for k in range(0, len(terms), 4)]
    if ties:
        edits[mesh_file].append((last_block_end, last_block_end,
                                 ["** HexMerge: the pyramids' split diagonals tied to the faces "
                                  "behind them"] + ties))
    edits[node_end[0]].append((node_end[1], node_end[1], [
        "{}, {:.12g}, {:.12g}, {:.12g}".format(n, *p) for n, p in new_nodes]))
    # Face loads, surfaces and element sets that name a split pyramid.
    second = {eid: tets[1][0] for eid, (_, tets) in split.items()}
    for name, lines in files.items():
        keyword = ""
        for i, line in enumerate(lines):
            stripped = line.strip()
            if stripped.startswith("*"):
                keyword = stripped.split(",")[0].upper() if not stripped.startswith("**") else keyword
                continue
            m = _FACE_ITEM.match(line)
            if m and keyword in ("*DLOAD", "*SURFACE", "*FILM", "*RADIATE", "*DFLUX") \
                    and int(m.group(2)) in split:
                nodes, tets = split[int(m.group(2))]
                corners = {nodes[k] for k in _HEX_FACES[int(m.group(5)) - 1]}
                if len(corners) < 3:  # a collapsed face: nothing there
                    edits[name].append((i, i + 1, []))
                    continue
                found = [(tid, f) for tid, t in tets for f, face in enumerate(_TET_FACES)
                         if {t[k] for k in face} <= corners]
                edits[name].append((i, i + 1, [
                    "{}{}{}{}{}{}".format(m.group(1), tid, m.group(3), m.group(4), f + 1,
                                          m.group(6)) for tid, f in found]))
            elif keyword == "*ELSET" and re.fullmatch(r"[\d,\s]+", stripped):
                extra = [second[int(x)] for x in re.findall(r"\d+", stripped) if int(x) in second]
                if extra:
                    edits[name].append((i + 1, i + 1, [", ".join(str(x) for x in extra)]))
    for name, lines in files.items():
        if not edits[name]:
            continue
        for first, end, text in sorted(edits[name], key=lambda e: (e[0], e[1]), reverse=True):
            lines[first:end] = text
        tmp = name + ".hexmerge-tmp"
        with open(tmp, "w") as f:
            f.write("\n".join(lines))
        os.replace(tmp, name)
    return len(split)


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


def splits_pyramids(mesh_obj):
    """True for a HexMerge mesh object whose second-order pyramids go to CalculiX as two tied
    C3D10 (QuadraticPyramid; they are written as collapsed C3D20 only under
    PyramidsAsHexahedra)."""
    proxy = getattr(mesh_obj, "Proxy", None)
    return getattr(proxy, "Type", None) == "HexMerge::MeshHexDominant" \
        and "QuadraticPyramid" in mesh_obj.PropertiesList \
        and str(mesh_obj.QuadraticPyramid) == SPLIT_PYRAMID


def install_writer_hook():
    """Wraps FreeCAD's femsolver.calculix.write_mesh.write_mesh (element types) and
    FemInputWriterCcx.write_solver_input (pyramids split once the whole input, loads included,
    is written) once (idempotent). Returns True when the hooks are in place."""
    from femsolver.calculix import writer
    solver_input = writer.FemInputWriterCcx.write_solver_input
    if not getattr(solver_input, "hexmerge_hook", False):
        def write_solver_input(ccxwriter):
            path = solver_input(ccxwriter)
            if path and splits_pyramids(ccxwriter.mesh_object):
                count = split_pyramids_in_input(path)
                if count:
                    import FreeCAD
                    FreeCAD.Console.PrintMessage(
                        "HexMerge: {}: {} pyramids written as two tied C3D10 each in {}\n"
                        .format(ccxwriter.mesh_object.Label, count, path))
            return path

        write_solver_input.hexmerge_hook = True
        write_solver_input.__doc__ = solver_input.__doc__
        writer.FemInputWriterCcx.write_solver_input = write_solver_input
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
