"""Random mechanical parts as BREP files, for bench/real_parts.py --extra (issue 13: parts no one
chose, to find what fails on parts the mesher was not developed on). Each part is a base (a box,
a cylinder, an extruded polygon or a revolved profile) with 2 to 6 features cut or fused at
random places and angles (holes, counterbores, bosses, pockets, slots, ribs, spheres, tori,
cones), then fillets or chamfers on a random few of its edges, now and then a shell (a thin
wall), and now and then a box on top touching it (a compound of solids sharing faces, as
FreeCAD's BooleanFragments makes them). A part whose booleans or fillets fail, or that comes
out invalid, open, in pieces or failing FreeCAD's BOP check, is drawn again; so is one FreeCAD
itself crashes on (each draw runs in a child process; the next then draws from the seed and the
draw's number). Every part is read back unchanged.
The seed makes them the same each run; another seed gives other parts.

Run it with FreeCAD's interpreter (Debian: freecad, freecad-common):

    freecadcmd bench/random_parts.py [OUT_DIR]    # default /tmp/hexmerge-random-parts
    HEXMERGE_RANDOM_PARTS=60 HEXMERGE_RANDOM_SEED=7 freecadcmd bench/random_parts.py OUT

It writes OUT_DIR/<name>.brep and OUT_DIR/parts.json (name, description, volume, solids, faces,
bounding box). Then, with this repository's module:

    PYTHONPATH=src/python:bench /usr/bin/python3.11 bench/real_parts.py --cad /nonexistent \
        --extra /tmp/hexmerge-random-parts --no-generated --sizes 3k,30k
"""
import json
import math
import os
import pickle
import random
import sys
import time

import Part
from FreeCAD import Vector as V

OUT = sys.argv[-1] if len(sys.argv) > 1 and not sys.argv[-1].endswith(".py") else "/tmp/hexmerge-random-parts"
COUNT = int(os.environ.get("HEXMERGE_RANDOM_PARTS", "40"))
SEED = int(os.environ.get("HEXMERGE_RANDOM_SEED", "20261204"))
os.makedirs(OUT, exist_ok=True)


def unit(r):
    """A random direction: an axis half the time, else any."""
    if r.random() < 0.5:
        return r.choice([V(1, 0, 0), V(0, 1, 0), V(0, 0, 1), V(-1, 0, 0), V(0, -1, 0), V(0, 0, -1)])
    while True:
        v = V(r.uniform(-1, 1), r.uniform(-1, 1), r.uniform(-1, 1))
        if 0.1 < v.Length <= 1:
            return v.normalize()


def base(r):
    """The part's body, about 100 mm across; its description."""
    kind = r.choice(["box", "cylinder", "polygon", "revolved"])
    a, b, c = r.uniform(40, 120), r.uniform(30, 100), r.uniform(8, 60)
    if kind == "box":
        return Part.makeBox(a, b, c), f"box {a:.0f} x {b:.0f} x {c:.0f}"
    if kind == "cylinder":
        return Part.makeCylinder(a / 2, c), f"cylinder r {a / 2:.0f} h {c:.0f}"
    if kind == "polygon":
        n = r.randint(3, 8)
        angles = sorted(r.uniform(0, 2 * math.pi) for _ in range(n))
        pts = [V(a / 2 * r.uniform(0.5, 1) * math.cos(t), b / 2 * r.uniform(0.5, 1) * math.sin(t), 0)
               for t in angles]
        face = Part.Face(Part.makePolygon(pts + [pts[0]]))
        return face.extrude(V(0, 0, c)), f"{n}-gon extruded {c:.0f}"
    # revolved: a stepped profile in the XZ plane about Z
    steps = r.randint(2, 5)
    zs = sorted(r.uniform(0, c * 2) for _ in range(steps - 1))
    zs = [0.0] + zs + [c * 2]
    inner = r.choice([0.0, r.uniform(3, 10)])
    pts = [V(inner, 0, 0)]
    for i in range(steps):
        rad = r.uniform(inner + 5, a / 2)
        pts += [V(rad, 0, zs[i]), V(rad, 0, zs[i + 1])]
    pts += [V(inner, 0, zs[-1])]
    clean = [pts[0]]
    for p in pts[1:]:
        if (p - clean[-1]).Length > 0.5:
            clean.append(p)
    face = Part.Face(Part.makePolygon(clean + [clean[0]]))
    return face.revolve(V(0, 0, 0), V(0, 0, 1), 360), f"revolved {steps} steps" + (" hollow" if inner else "")


def feature(r, body):
    """A tool shape placed on the body, and whether it is cut (else fused); its description."""
    bb = body.BoundBox
    p = V(r.uniform(bb.XMin, bb.XMax), r.uniform(bb.YMin, bb.YMax), r.uniform(bb.ZMin, bb.ZMax))
    d = unit(r)
    size = min(bb.XLength, bb.YLength, bb.ZLength)
    kind = r.choice(["hole", "counterbore", "boss", "pocket", "slot", "rib", "sphere", "torus", "cone"])
    if kind == "hole":
        rad = r.uniform(1, size / 3)
        tool = Part.makeCylinder(rad, 3 * bb.DiagonalLength, p - d * 1.5 * bb.DiagonalLength, d)
        return tool, True, f"hole r {rad:.1f}"
    if kind == "counterbore":
        rad = r.uniform(2, size / 3)
        tool = Part.makeCylinder(rad, 3 * bb.DiagonalLength, p - d * 1.5 * bb.DiagonalLength, d)
        tool = tool.fuse(Part.makeCylinder(rad * 1.7, bb.DiagonalLength, p, d))
        return tool, True, f"counterbore r {rad:.1f}"
    if kind == "boss":
        rad = r.uniform(2, size / 2)
        return Part.makeCylinder(rad, r.uniform(3, size), p, d), False, f"boss r {rad:.1f}"
    if kind in ("pocket", "rib"):
        x, y, z = (r.uniform(2, size), r.uniform(2, size), r.uniform(1, size / 2)) if kind == "pocket" \
            else (r.uniform(1, 4), r.uniform(size / 2, 2 * size), r.uniform(3, size))
        tool = Part.makeBox(x, y, z, p - V(x / 2, y / 2, z / 2))
        tool.rotate(p, unit(r), r.uniform(0, 90))
        return tool, kind == "pocket", f"{kind} {x:.1f} x {y:.1f} x {z:.1f}"
    if kind == "slot":
        w, length = r.uniform(2, size / 3), r.uniform(5, size)
        face = Part.Face(Part.Wire(Part.makeCircle(w / 2, V(0, 0, 0))))
        tool = face.extrude(V(0, 0, 3 * bb.DiagonalLength))
        tool = tool.fuse(Part.makeBox(length, w, 3 * bb.DiagonalLength, V(0, -w / 2, 0)))
        tool = tool.fuse(Part.makeCylinder(w / 2, 3 * bb.DiagonalLength, V(length, 0, 0)))
        tool.translate(V(0, 0, -1.5 * bb.DiagonalLength))
        tool.rotate(V(0, 0, 0), unit(r), r.uniform(0, 180))
        tool.translate(p)
        return tool, True, f"slot {w:.1f} x {length:.1f}"
    if kind == "sphere":
        rad = r.uniform(2, size / 2)
        return Part.makeSphere(rad, p), r.random() < 0.5, f"sphere r {rad:.1f}"
    if kind == "torus":
        big = r.uniform(5, size)
        return Part.makeTorus(big, r.uniform(1, big / 2), p, d), r.random() < 0.5, f"torus R {big:.1f}"
    rad = r.uniform(2, size / 2)
    return Part.makeCone(rad, r.uniform(0, rad), r.uniform(3, size), p, d), r.random() < 0.5, f"cone r {rad:.1f}"


def finish(r, s):
    """Fillets or chamfers on a few edges, now and then a shell; what was done."""
    done = []
    edges = list(s.Edges)
    r.shuffle(edges)
    for _ in range(r.randint(0, 2)):
        pick = edges[:r.randint(1, 6)]
        edges = edges[len(pick):]
        rad = r.uniform(0.3, 4)
        try:
            t = s.makeFillet(rad, pick) if r.random() < 0.6 else s.makeChamfer(rad, pick)
            if t.isValid() and len(t.Solids) == 1:
                s = t
                done.append(f"{len(pick)} edges rounded {rad:.1f}")
                edges = list(s.Edges)
                r.shuffle(edges)
        except Exception:
            pass
    if r.random() < 0.15:
        face = max(s.Faces, key=lambda f: f.Area)
        thick = r.uniform(1, 4)
        try:
            t = s.makeThickness([face], -thick, 1e-3)
            if t.isValid() and len(t.Solids) == 1:
                s = t.Solids[0]
                done.append(f"shelled {thick:.1f}")
        except Exception:
            pass
    return s, done


def one_solid(r):
    body, desc = base(r)
    what = [desc]
    for _ in range(r.randint(2, 6)):
        tool, cut, d = feature(r, body)
        t = body.cut(tool) if cut else body.fuse(tool)
        t = t.removeSplitter()
        if t.isValid() and len(t.Solids) == 1 and t.Volume > 0.05 * body.Volume:
            body = t.Solids[0]
            what.append(("cut " if cut else "fused ") + d)
    body, done = finish(r, body)
    return body, what + done


def touching(r, s):
    """A box touching s on a face of its bounding box, fragments of both: a compound."""
    bb = s.BoundBox
    x, y, z = r.uniform(10, 60), r.uniform(10, 60), r.uniform(5, 40)
    other = Part.makeBox(x, y, z, V(r.uniform(bb.XMin - x / 2, bb.XMax - x / 2),
                                    r.uniform(bb.YMin - y / 2, bb.YMax - y / 2), bb.ZMax))
    pieces = s.generalFuse([other])[0]
    return Part.makeCompound(pieces.Solids)


def build(r):
    s, what = one_solid(r)
    if r.random() < 0.2:
        s = touching(r, s)
        what.append(f"with a box on top ({len(s.Solids)} solids)")
    return s, "; ".join(what)


def draw(r, name):
    """One draw of a part named `name` with generator r: its row, written to OUT, or None when it
    is no valid closed solid, fails the BOP check or does not read back the same."""
    try:
        s, desc = build(r)
    except Exception:
        return None
    solids = s.Solids
    if not solids or not s.isValid() or not all(x.isValid() for x in solids):
        return None
    if not all(x.Shells and all(sh.isClosed() for sh in x.Shells) for x in solids):
        return None
    try:  # FreeCAD's Part > Check geometry with its BOP check (edges off their faces, ...)
        s.check(True)
    except ValueError:
        return None
    if s.ShapeType != "Compound" and len(solids) == 1:
        s = solids[0]
    path = os.path.join(OUT, name + ".brep")
    s.exportBrep(path)
    back = Part.Shape()
    back.read(path)
    if not back.isValid() or abs(back.Volume - s.Volume) > 1e-6 * abs(s.Volume):
        return None
    bb = s.BoundBox
    print(f"{name}: {desc}; V={s.Volume:.0f} faces={len(s.Faces)}", flush=True)
    return {"name": name, "description": desc, "ok": True, "path": path, "volume": s.Volume,
            "solids": len(solids), "faces": len(s.Faces), "edges": len(s.Edges),
            "bbox": [bb.XMin, bb.YMin, bb.ZMin, bb.XMax, bb.YMax, bb.ZMax],
            "face_types": sorted({f.Surface.TypeId.split("::")[-1] for f in s.Faces})}


def draw_apart(r, name):
    """draw() in a child process: FreeCAD itself can crash on a boolean or a fillet (a
    segmentation fault on seed 20261210's 13th part and 20261212's 37th ended their corpora).
    The child draws with the parent's generator and sends back its row and the generator's state,
    so the parts are those one process would draw. (row, False) where the child died."""
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:
        os.close(read)
        try:
            payload = pickle.dumps((draw(r, name), r.getstate()))
        except BaseException:
            payload = pickle.dumps((None, r.getstate()))
        with os.fdopen(write, "wb") as f:
            f.write(payload)
        os._exit(0)
    os.close(write)
    with os.fdopen(read, "rb") as f:
        data = f.read()
    os.waitpid(pid, 0)
    if not data:
        return None, False
    row, state = pickle.loads(data)
    r.setstate(state)
    return row, True


def main():
    t0 = time.time()
    r = random.Random(SEED)
    rows = []
    drawn = crashed = 0
    while len(rows) < COUNT:
        drawn += 1
        name = f"random_{SEED}_{len(rows):03d}"
        row, survived = draw_apart(r, name)
        if not survived:  # FreeCAD crashed: the next draws from the seed and this draw's number
            crashed += 1
            print(f"{name}: FreeCAD crashed on draw {drawn}; drawn again", flush=True)
            r = random.Random(f"{SEED}-{drawn}")
            continue
        if row is not None:
            rows.append(row)
    with open(os.path.join(OUT, "parts.json"), "w") as f:
        json.dump(rows, f, indent=1)
    print(f"{len(rows)} parts ({drawn} drawn, FreeCAD crashed on {crashed}) in {time.time() - t0:.1f} s")

main()
