"""59 generated mechanical parts as BREP files, for bench/real_parts.py --extra (issue 13: parts
the mesher was not developed on, made the way a FreeCAD user makes them): booleans of boxes,
cylinders, cones, spheres and tori; fillets and chamfers (a 0.2 mm chamfer on a 100 mm part);
shells and thin walls (0.5 mm); revolved and extruded profiles with arcs; lofts and B-spline
faces; holes, counterbores, ribs, knurls, a helical spring, a variable-radius fillet, drafts,
tangent faces, rotated parts, compounds of touching solids. Every part is checked valid, closed
and read back unchanged; a fixed seed makes them the same each run.

Run it with FreeCAD's interpreter (Debian: freecad, freecad-common):

    freecadcmd bench/freecad_generated_parts.py [OUT_DIR]   # default /tmp/hexmerge-generated-parts

It writes OUT_DIR/<name>.brep and OUT_DIR/parts.json (name, description, volume, solids, faces,
bounding box; or the error of a part that could not be built). Then, with this repository's
module:

    PYTHONPATH=src/python:bench /usr/bin/python3.11 bench/real_parts.py --cad /nonexistent \
        --extra /tmp/hexmerge-generated-parts --no-generated --sizes 2k,20k,100k
"""
import json
import math
import os
import random
import sys
import time
import traceback

import FreeCAD  # noqa: F401  (freecadcmd's interpreter)
import Part
from FreeCAD import Vector as V

OUT = sys.argv[-1] if len(sys.argv) > 1 and not sys.argv[-1].endswith(".py") else "/tmp/hexmerge-generated-parts"
os.makedirs(OUT, exist_ok=True)
R = random.Random(20240917)  # fixed seed
PARTS = []  # (name, description, builder)


def part(name, desc):
    def deco(fn):
        PARTS.append((name, desc, fn))
        return fn
    return deco


def rnd(a, b):
    return round(R.uniform(a, b), 3)


def cyl(r, h, p=V(0, 0, 0), d=V(0, 0, 1)):
    return Part.makeCylinder(r, h, p, d)


def box(x, y, z, p=V(0, 0, 0)):
    return Part.makeBox(x, y, z, p)


def clean(s):
    try:
        return s.removeSplitter()
    except Exception:
        return s


def rotated(s, angle, axis, center=V(0, 0, 0)):
    s = s.copy()
    s.rotate(center, axis, angle)
    return s


def edges_where(shape, pred):
    return [e for e in shape.Edges if pred(e)]


def is_line(e):
    return isinstance(e.Curve, Part.Line) or e.Curve.TypeId == "Part::GeomLine"


def profile_face(points2d, z=0.0):
    pts = [V(x, y, z) for x, y in points2d]
    return Part.Face(Part.makePolygon(pts + [pts[0]]))


def revolve_profile(points_xz, angle=360):
    # profile in the XZ plane (x = radius), revolved about Z
    pts = [V(x, 0, z) for x, z in points_xz]
    f = Part.Face(Part.makePolygon(pts + [pts[0]]))
    return f.revolve(V(0, 0, 0), V(0, 0, 1), angle)


# ----------------------------------------------------------------------------- parts
@part("l_bracket_filleted", "L bracket (two boxes fused), inner edge fillet, two through holes in each leg")
def _():
    t = rnd(4, 6); L = rnd(50, 70); W = rnd(25, 35); H = rnd(40, 55)
    s = box(L, W, t).fuse(box(t, W, H))
    s = clean(s)
    inner = edges_where(s, lambda e: is_line(e) and abs(e.BoundBox.XMin - t) < 1e-6 and abs(e.BoundBox.XMax - t) < 1e-6
                        and abs(e.BoundBox.ZMin - t) < 1e-6 and abs(e.BoundBox.ZMax - t) < 1e-6)
    s = s.makeFillet(t * 0.8, inner)
    for x in (L * 0.45, L * 0.8):
        s = s.cut(cyl(3, t + 2, V(x, W / 2, -1)))
    for z in (H * 0.5, H * 0.8):
        s = s.cut(cyl(3, t + 2, V(-1, W / 2, z), V(1, 0, 0)))
    return s


@part("flange_bolt_circle", "round flange with hub, central bore, 6 bolt holes on a circle, chamfered bore")
def _():
    R0 = rnd(40, 50); T = rnd(8, 12); rh = R0 * 0.45; Hh = rnd(20, 30); rb = rh * 0.6
    s = cyl(R0, T).fuse(cyl(rh, Hh))
    s = s.cut(cyl(rb, Hh + 2, V(0, 0, -1)))
    for k in range(6):
        a = 2 * math.pi * k / 6
        s = s.cut(cyl(3.5, T + 2, V(0.78 * R0 * math.cos(a), 0.78 * R0 * math.sin(a), -1)))
    s = clean(s)
    top = edges_where(s, lambda e: abs(e.BoundBox.ZMin - Hh) < 1e-6 and abs(e.BoundBox.ZMax - Hh) < 1e-6
                      and abs(e.BoundBox.XMax - rb) < 1e-4)
    return s.makeChamfer(1.0, top)


@part("counterbore_plate", "plate 80x50x12 with 4 counterbored holes and 2 countersunk holes")
def _():
    s = box(80, 50, 12)
    for x, y in ((12, 12), (68, 12), (12, 38), (68, 38)):
        s = s.cut(cyl(3.3, 14, V(x, y, -1)))
        s = s.cut(cyl(5.5, 6, V(x, y, 7)))
    for x in (32, 48):
        s = s.cut(cyl(2.5, 14, V(x, 25, -1)))
        s = s.cut(Part.makeCone(2.5, 6.5, 4.01, V(x, 25, 8)))
    return s


@part("stepped_shaft", "revolved stepped shaft 120 mm with chamfers at the steps and a keyway")
def _():
    prof = [(0, 0), (8, 0), (8, 30), (11, 30), (11, 70), (9, 70), (9, 100), (6, 100), (6, 120), (0, 120)]
    s = revolve_profile(prof)
    s = Part.Solid(Part.Shell(s.Faces)) if s.ShapeType != "Solid" else s
    s = clean(s)
    circ = edges_where(s, lambda e: not is_line(e) and abs(e.BoundBox.ZMin - e.BoundBox.ZMax) < 1e-6
                       and e.BoundBox.ZMin in (0.0, 120.0))
    s = s.makeChamfer(0.8, circ)
    s = s.cut(box(4, 4, 25, V(9.0, -2, 38)))  # keyway 2 mm deep on the d22 section
    return s


@part("v_pulley", "revolved V-belt pulley with two grooves, hub bore")
def _():
    prof = [(6, 0), (30, 0), (30, 3), (26, 7), (30, 11), (30, 14), (26, 18), (30, 22), (30, 25), (6, 25)]
    return revolve_profile(prof)


@part("box_all_fillets", "box 60x40x25 with every edge filleted r=4")
def _():
    s = box(60, 40, 25)
    return s.makeFillet(4, s.Edges)


@part("box_all_chamfers", "box 50x50x30 with every edge chamfered 3 mm")
def _():
    s = box(50, 50, 30)
    return s.makeChamfer(3, s.Edges)


@part("tiny_chamfer_block", "100x60x40 block, one 0.2 mm chamfer on a top edge, one 0.3 mm fillet on another")
def _():
    s = box(100, 60, 40)
    e1 = edges_where(s, lambda e: abs(e.BoundBox.ZMin - 40) < 1e-6 and abs(e.BoundBox.ZMax - 40) < 1e-6 and abs(e.BoundBox.YMin) < 1e-6 and abs(e.BoundBox.YMax) < 1e-6)
    s = s.makeChamfer(0.2, e1)
    e2 = edges_where(s, lambda e: is_line(e) and abs(e.BoundBox.ZMin) < 1e-6 and abs(e.BoundBox.ZMax - 40) < 1e-6 and abs(e.BoundBox.XMin - 100) < 1e-6 and abs(e.BoundBox.YMin - 60) < 1e-6)
    return s.makeFillet(0.3, e2)


@part("thin_shell_box", "50x40x30 open box shelled to 0.5 mm walls (makeThickness, top face removed)")
def _():
    s = box(50, 40, 30)
    top = [f for f in s.Faces if abs(f.BoundBox.ZMin - 30) < 1e-6 and abs(f.BoundBox.ZMax - 30) < 1e-6]
    return s.makeThickness(top, -0.5, 1e-3)


@part("thin_tube", "tube 50 mm long, outer d 30, 0.5 mm wall")
def _():
    return cyl(15, 50).cut(cyl(14.5, 52, V(0, 0, -1)))


@part("rotated_bracket", "L bracket with holes and fillet rotated 17 deg about oblique axis (1,2,3)")
def _():
    s = box(60, 30, 5).fuse(box(5, 30, 45))
    s = clean(s)
    s = s.cut(cyl(4, 7, V(35, 15, -1)))
    s = s.cut(cyl(4, 7, V(-1, 15, 30), V(1, 0, 0)))
    return rotated(s, 17, V(1, 2, 3))


@part("rotated_flanged_cylinder", "cylinder with flange and cross hole, rotated 33 deg about (1,-1,0.5) and translated")
def _():
    s = cyl(10, 60).fuse(cyl(22, 6))
    s = s.cut(cyl(4, 70, V(0, 0, -5)))
    s = s.cut(cyl(2.5, 30, V(-15, 0, 40), V(1, 0, 0)))
    s = rotated(clean(s), 33, V(1, -1, 0.5))
    s.translate(V(123.4, -56.7, 8.9))
    return s


@part("flat_plate_holes", "very flat plate 200x100x1 with 5 holes")
def _():
    s = box(200, 100, 1)
    for k in range(5):
        s = s.cut(cyl(rnd(3, 8), 3, V(25 + 37 * k, rnd(30, 70), -1)))
    return s


@part("flat_disk", "very flat disk d=120, t=0.8 with a central hole and a slot")
def _():
    s = cyl(60, 0.8).cut(cyl(10, 3, V(0, 0, -1)))
    return s.cut(box(30, 4, 3, V(20, -2, -1)))


@part("long_rod_flats", "very long rod 400 mm, d=6, with two flats and end chamfers")
def _():
    s = cyl(3, 400, V(0, 0, 0), V(1, 0, 0))
    s = s.cut(box(60, 10, 5, V(20, -5, 2.2)))
    s = s.cut(box(60, 10, 5, V(320, -5, -7.2)))
    ends = edges_where(s, lambda e: abs(e.BoundBox.XMin - e.BoundBox.XMax) < 1e-6 and e.BoundBox.XMin in (0.0, 400.0))
    return s.makeChamfer(0.5, ends)


@part("long_bar_rotated", "long square bar 300x8x8 rotated 17 deg about (1,2,3)")
def _():
    return rotated(box(300, 8, 8), 17, V(1, 2, 3))


@part("bspline_top_block", "80x60x30 block whose top face is a B-spline surface (block cut by a B-spline sheet)")
def _():
    n = 6
    pts = [[V(-10 + 100 * i / (n - 1), -10 + 80 * j / (n - 1), 20 + R.uniform(-6, 6)) for j in range(n)] for i in range(n)]
    bs = Part.BSplineSurface()
    bs.interpolate(pts)
    f = bs.toShape()
    above = f.extrude(V(0, 0, 40))
    return box(80, 60, 40).cut(above)


@part("bspline_loft", "loft through three closed B-spline cross sections (smooth blob)")
def _():
    wires = []
    for k, z in enumerate((0, 25, 50)):
        pts = []
        for i in range(8):
            a = 2 * math.pi * i / 8
            r = (15 + 5 * k % 10) * (1 + 0.2 * R.uniform(-1, 1))
            pts.append(V(r * math.cos(a), 0.7 * r * math.sin(a), z))
        c = Part.BSplineCurve()
        c.interpolate(pts, PeriodicFlag=True)
        wires.append(Part.Wire([c.toShape()]))
    return Part.makeLoft(wires, True, False)


@part("loft_square_circle", "loft from a 40 mm square to a d=20 circle 50 mm up, with a bore")
def _():
    sq = Part.makePolygon([V(-20, -20, 0), V(20, -20, 0), V(20, 20, 0), V(-20, 20, 0), V(-20, -20, 0)])
    ci = Part.Wire([Part.makeCircle(10, V(0, 0, 50))])
    s = Part.makeLoft([sq, ci], True, False)
    return s.cut(cyl(5, 60, V(0, 0, -5)))


@part("twisted_loft", "ruled loft between a rectangle and the same rectangle rotated 40 deg 60 mm higher")
def _():
    r1 = Part.makePolygon([V(-20, -10, 0), V(20, -10, 0), V(20, 10, 0), V(-20, 10, 0), V(-20, -10, 0)])
    r2 = r1.copy(); r2.rotate(V(0, 0, 0), V(0, 0, 1), 40); r2.translate(V(0, 0, 60))
    return Part.makeLoft([r1, r2], True, True)


@part("compound_two_boxes", "compound of two boxes sharing a full face (30x20x10 + 30x20x10 on top)")
def _():
    return Part.makeCompound([box(30, 20, 10), box(30, 20, 10, V(0, 0, 10))])


@part("compound_box_cylinder", "compound of a box and a cylinder standing on its top (touching on a disk)")
def _():
    return Part.makeCompound([box(40, 40, 10), cyl(10, 30, V(20, 20, 10))])


@part("compound_fragments_three", "three overlapping boxes split by generalFuse into touching solids (compsolid-like)")
def _():
    a = box(30, 30, 10); b = box(30, 30, 10, V(15, 10, 5)); c = cyl(8, 30, V(20, 20, -5))
    pieces, _ = a.generalFuse([b, c])
    return Part.makeCompound(pieces.Solids)


@part("hemisphere_holes", "hemisphere r=30 with a vertical bore and a radial side hole")
def _():
    s = Part.makeSphere(30).common(box(80, 80, 40, V(-40, -40, 0)))
    s = s.cut(cyl(6, 40, V(0, 0, -1)))
    return s.cut(cyl(3, 40, V(0, 0, 12), V(1, 0.3, 0)))


@part("torus_handle", "torus ring (R=25, r=5) fused to a cylinder hub through it, cross bar")
def _():
    s = Part.makeTorus(25, 5)
    s = s.fuse(cyl(8, 20, V(0, 0, -10)))
    s = s.fuse(cyl(3, 50, V(-25, 0, 0), V(1, 0, 0)))
    return clean(s)


@part("cone_frustum_bore", "cone frustum r 30->12, h 40, with a bore and a side flat")
def _():
    s = Part.makeCone(30, 12, 40)
    s = s.cut(cyl(6, 50, V(0, 0, -5)))
    return s.cut(box(20, 80, 50, V(22, -40, -5)))


@part("stadium_tangent", "stadium plate (box + two tangent half cylinders) with two holes: tangent faces")
def _():
    s = box(60, 20, 8).fuse(cyl(10, 8, V(0, 10, 0))).fuse(cyl(10, 8, V(60, 10, 0)))
    s = clean(s)
    s = s.cut(cyl(4, 10, V(0, 10, -1))).cut(cyl(4, 10, V(60, 10, -1)))
    return s


@part("tangent_boss_block", "block with a cylinder boss tangent to two side faces and a pocket tangent to its wall")
def _():
    s = box(40, 20, 15).fuse(cyl(10, 25, V(40, 10, 0)))
    s = clean(s)
    return s.cut(box(15, 10, 10, V(10, 0, 8))).cut(cyl(5, 10, V(25, 5, 8)))


@part("ribbed_bracket", "base plate + vertical wall + 3 triangular ribs (extruded triangles)")
def _():
    s = box(80, 40, 5).fuse(box(80, 5, 40))
    for x in (5, 38.5, 72):
        tri = Part.Face(Part.makePolygon([V(x, 5, 5), V(x, 35, 5), V(x, 5, 35), V(x, 5, 5)]))
        s = s.fuse(tri.extrude(V(3, 0, 0)))
    return clean(s)


@part("sketch_arcs_gasket", "extruded sketch with arcs (cam/gasket shape) and 3 holes, 6 mm thick")
def _():
    e = []
    e.append(Part.LineSegment(V(0, 0, 0), V(50, 0, 0)).toShape())
    e.append(Part.Arc(V(50, 0, 0), V(62, 12, 0), V(50, 24, 0)).toShape())
    e.append(Part.LineSegment(V(50, 24, 0), V(30, 24, 0)).toShape())
    e.append(Part.Arc(V(30, 24, 0), V(20, 30, 0), V(10, 24, 0)).toShape())
    e.append(Part.LineSegment(V(10, 24, 0), V(0, 24, 0)).toShape())
    e.append(Part.Arc(V(0, 24, 0), V(-12, 12, 0), V(0, 0, 0)).toShape())
    f = Part.Face(Part.Wire(e))
    s = f.extrude(V(0, 0, 6))
    for x, y in ((0, 12), (50, 12), (20, 24)):
        s = s.cut(cyl(3, 8, V(x, y, -1)))
    return s


@part("spline_revolve_bottle", "bottle: spline profile revolved 360 deg, hollowed to 1.5 mm walls")
def _():
    c = Part.BSplineCurve()
    c.interpolate([V(20, 0, 0), V(22, 0, 30), V(18, 0, 60), V(8, 0, 80), V(8, 0, 95)])
    prof = Part.Wire([Part.LineSegment(V(0, 0, 0), V(20, 0, 0)).toShape(), c.toShape(),
                      Part.LineSegment(V(8, 0, 95), V(0, 0, 95)).toShape(), Part.LineSegment(V(0, 0, 95), V(0, 0, 0)).toShape()])
    s = Part.Face(prof).revolve(V(0, 0, 0), V(0, 0, 1), 360)
    s = Part.Solid(s) if s.ShapeType != "Solid" else s
    top = [f for f in s.Faces if f.BoundBox.ZMin > 94.9]
    return s.makeThickness(top, -1.5, 1e-3)


@part("partial_revolve_270", "L-shaped profile revolved 270 deg about Z (open ring segment with sharp ends)")
def _():
    return revolve_profile([(10, 0), (30, 0), (30, 5), (15, 5), (15, 20), (10, 20)], 270)


@part("hex_nut_chamfered", "M16-like hex nut: hexagonal prism, bore, 30-deg conical chamfer on both sides")
def _():
    pts = [(12 * math.cos(math.pi / 3 * k), 12 * math.sin(math.pi / 3 * k)) for k in range(6)]
    s = profile_face(pts).extrude(V(0, 0, 13))
    s = s.cut(cyl(7, 15, V(0, 0, -1)))
    # 30-deg chamfer on both faces: common with a double cone
    up = Part.makeCone(10.0 + 8 / math.tan(math.radians(30)), 10.0, 8, V(0, 0, 5))
    down = Part.makeCone(10.0, 10.0 + 8 / math.tan(math.radians(30)), 8, V(0, 0, 0))
    return clean(s.common(up.fuse(down)))


@part("spur_gear_like", "extruded 18-tooth gear outline (polygon teeth), bore with keyway, 10 mm thick")
def _():
    pts = []
    n = 18
    for k in range(n):
        a = 2 * math.pi * k / n
        for da, r in ((0, 26), (0.25, 26), (0.4, 30), (0.6, 30), (0.75, 26)):
            b = a + da * 2 * math.pi / n
            pts.append((r * math.cos(b), r * math.sin(b)))
    s = profile_face(pts).extrude(V(0, 0, 10))
    s = s.cut(cyl(8, 12, V(0, 0, -1))).cut(box(4, 4, 12, V(6, -2, -1)))
    return clean(s)


@part("pipe_elbow", "90-deg pipe elbow: annulus swept along an arc (r=40), 2 mm wall, with straight legs")
def _():
    path = Part.Wire([Part.LineSegment(V(0, 0, -20), V(0, 0, 0)).toShape(),
                      Part.Arc(V(0, 0, 0), V(40 - 40 * math.cos(math.pi / 4), 0, 40 * math.sin(math.pi / 4)), V(40, 0, 40)).toShape(),
                      Part.LineSegment(V(40, 0, 40), V(60, 0, 40)).toShape()])
    prof = Part.Wire([Part.makeCircle(10, V(0, 0, -20), V(0, 0, 1))])
    outer = path.makePipeShell([prof], True, True)
    prof2 = Part.Wire([Part.makeCircle(8, V(0, 0, -20), V(0, 0, 1))])
    inner = path.makePipeShell([prof2], True, True)
    return outer.cut(inner)


@part("heat_sink_fins", "heat sink: 40x40x3 base with 9 fins 0.8 mm thick 20 mm tall")
def _():
    s = box(40, 40, 3)
    for k in range(9):
        s = s.fuse(box(0.8, 40, 20, V(1 + 4.65 * k, 0, 3)))
    return clean(s)


@part("knife_wedge", "wedge with a 6-degree knife edge and a hole (very sharp dihedral)")
def _():
    t = 40 * math.tan(math.radians(6))
    f = Part.Face(Part.makePolygon([V(0, 0, 0), V(40, 0, 0), V(40, 0, t), V(0, 0, 0)]))
    s = f.extrude(V(0, 30, 0))
    return s.cut(cyl(1.2, t + 2, V(30, 15, -1)))


@part("cross_drilled_cylinder", "solid cylinder d40 h60 with two equal crossing d10 bores (saddle intersections) and an axial bore")
def _():
    s = cyl(20, 60)
    s = s.cut(cyl(5, 50, V(-25, 0, 30), V(1, 0, 0))).cut(cyl(5, 50, V(0, -25, 30), V(0, 1, 0)))
    return s.cut(cyl(5, 40, V(0, 0, -1)))


@part("sphere_cross_bores", "sphere r=25 with three orthogonal bores of r=6 and one oblique bore")
def _():
    s = Part.makeSphere(25)
    for d in (V(1, 0, 0), V(0, 1, 0), V(0, 0, 1)):
        s = s.cut(cyl(6, 60, d * -30, d))
    d = V(1, 1, 1).normalize()
    return s.cut(cyl(2, 60, d * -30 + V(0, 10, 0), d))


@part("boss_on_cylinder", "horizontal cylinder d50 with a radial boss d16 and a drilled hole through both")
def _():
    s = cyl(25, 80, V(0, 0, 0), V(1, 0, 0))
    s = s.fuse(cyl(8, 35, V(40, 0, 0), V(0, 0, 1)))
    return s.cut(cyl(4, 50, V(40, 0, -10), V(0, 0, 1)))


@part("shelled_filleted_rotated", "filleted box shelled to 2 mm (open top), rotated 23 deg about (0.3,1,0.2)")
def _():
    s = box(60, 40, 30)
    s = s.makeFillet(5, edges_where(s, lambda e: abs(e.BoundBox.ZMin - e.BoundBox.ZMax) > 1))
    top = [f for f in s.Faces if abs(f.BoundBox.ZMin - 30) < 1e-6 and abs(f.BoundBox.ZMax - 30) < 1e-6]
    s = s.makeThickness(top, -2, 1e-3)
    return rotated(s, 23, V(0.3, 1, 0.2))


@part("small_hole_big_block", "100x80x50 block with one 1 mm hole and one 0.6 mm deep 20 mm wide shallow pocket")
def _():
    s = box(100, 80, 50)
    s = s.cut(cyl(0.5, 60, V(50, 40, -5)))
    return s.cut(box(20, 20, 1, V(10, 10, 49.4)))


@part("mixed_fillets_bracket", "T-bracket with fillets of 3 radii (1, 2.5, 4) on different edges and a slot")
def _():
    s = box(70, 30, 6).fuse(box(6, 30, 40, V(32, 0, 6)))
    s = clean(s)
    s = s.cut(box(16, 6, 8, V(6, 12, -1))).cut(cyl(3, 8, V(6, 15, -1))).cut(cyl(3, 8, V(22, 15, -1)))
    inner = edges_where(s, lambda e: is_line(e) and abs(e.BoundBox.ZMin - 6) < 1e-6 and abs(e.BoundBox.ZMax - 6) < 1e-6
                        and abs(e.BoundBox.YMax - e.BoundBox.YMin - 30) < 1e-6 and e.BoundBox.XMin in (32.0, 38.0))
    s = s.makeFillet(4, inner)
    corners = edges_where(s, lambda e: is_line(e) and abs(e.BoundBox.ZMax - e.BoundBox.ZMin - 6) < 1e-6
                          and e.BoundBox.XMin in (0.0, 70.0))
    s = s.makeFillet(2.5, corners)
    top = edges_where(s, lambda e: is_line(e) and abs(e.BoundBox.ZMin - 46) < 1e-6 and abs(e.BoundBox.ZMax - 46) < 1e-6)
    return s.makeFillet(1, top)


@part("fillet_chamfer_tangent_mix", "box with filleted vertical edges then chamfered top loop (tangent chain chamfer)")
def _():
    s = box(50, 30, 20)
    s = s.makeFillet(6, edges_where(s, lambda e: abs(e.BoundBox.ZMax - e.BoundBox.ZMin - 20) < 1e-6))
    top = edges_where(s, lambda e: abs(e.BoundBox.ZMin - 20) < 1e-6 and abs(e.BoundBox.ZMax - 20) < 1e-6)
    return s.makeChamfer(1.5, top)


@part("thin_rib_plate", "50x50x4 plate with a 0.5 mm thick 15 mm tall rib and a 0.5 mm gap slot")
def _():
    s = box(50, 50, 4).fuse(box(0.5, 40, 15, V(24.75, 5, 4)))
    return clean(s).cut(box(30, 0.5, 6, V(10, 45, -1)))


@part("oblique_cylinder_intersection", "two cylinders of different radii fused at 60 deg, then a bore through the main one")
def _():
    s = cyl(10, 80, V(0, 0, 0), V(1, 0, 0))
    d = V(math.cos(math.radians(60)), 0, math.sin(math.radians(60)))
    s = s.fuse(cyl(6, 40, V(40, 0, 0), d))
    return clean(s).cut(cyl(4, 90, V(-5, 0, 0), V(1, 0, 0)))


@part("random_boolean_blocks", "seeded random union of 5 boxes and 2 cylinders minus 3 holes")
def _():
    s = box(40, 30, 10)
    for _ in range(5):
        s = s.fuse(box(rnd(8, 25), rnd(8, 20), rnd(5, 20), V(rnd(0, 30), rnd(0, 20), rnd(5, 15))))
    for _ in range(2):
        s = s.fuse(cyl(rnd(3, 7), rnd(10, 25), V(rnd(5, 35), rnd(5, 25), rnd(0, 10))))
    for _ in range(3):
        s = s.cut(cyl(rnd(1, 3), 60, V(rnd(3, 37), rnd(3, 27), -5)))
    return clean(s)



# ----------------------------------------------------------------------------- batch 2: harder geometry
@part("drill_point_cone_apex", "drill blank: cylinder d10 with a 118-deg conical tip ending in an apex (degenerate point)")
def _():
    tip = 5 / math.tan(math.radians(59))
    return cyl(5, 50).fuse(Part.makeCone(5, 0, tip, V(0, 0, 50))).removeSplitter()


@part("full_ball", "full sphere d40 (poles, seam), with a flat spot")
def _():
    return Part.makeSphere(20).cut(box(50, 50, 10, V(-25, -25, 17)))


@part("ellipsoid_bspline", "ellipsoid 60x30x20 (sphere scaled non-uniformly: B-spline surface) with a bore")
def _():
    m = FreeCAD.Matrix(); m.scale(1.5, 0.75, 0.5)
    s = Part.makeSphere(20).transformGeometry(m)
    return s.cut(cyl(3, 40, V(0, 0, -20)))


@part("helical_spring", "helical spring: circle d2 swept along a 5-turn helix (pitch 6, radius 10), ends flat")
def _():
    helix = Part.makeHelix(6, 30, 10)
    prof = Part.Wire([Part.makeCircle(1.0, V(10, 0, 0), V(0, 1, 0))])
    return Part.Wire(helix).makePipeShell([prof], True, True)


@part("variable_fillet_block", "block 40x30x20 with a variable-radius fillet (1 -> 6 mm) on one edge")
def _():
    s = box(40, 30, 20)
    e = [k for k, x in enumerate(s.Edges) if is_line(x) and abs(x.BoundBox.XLength - 40) < 1e-6
         and abs(x.BoundBox.ZMin - 20) < 1e-6 and abs(x.BoundBox.YMin - 30) < 1e-6][0]
    return s.makeFillet(1.0, 6.0, [s.Edges[e]])


@part("tapered_prism_draft", "40x25 rectangle extruded 20 mm with a 5-deg draft on all four sides (ruled loft)")
def _():
    d = 20 * math.tan(math.radians(5))
    bottom = Part.makePolygon([V(0, 0, 0), V(40, 0, 0), V(40, 25, 0), V(0, 25, 0), V(0, 0, 0)])
    top = Part.makePolygon([V(d, d, 20), V(40 - d, d, 20), V(40 - d, 25 - d, 20), V(d, 25 - d, 20), V(d, d, 20)])
    s = Part.makeLoft([bottom, top], True, True)
    return s.cut(cyl(4, 22, V(20, 12.5, -1)))


@part("offset_shape_bracket", "L bracket grown by makeOffsetShape 1.5 mm (rounded offset faces, arc join)")
def _():
    s = clean(box(40, 20, 5).fuse(box(5, 20, 30)))
    return s.makeOffsetShape(1.5, 1e-4, join=0)


@part("compound_shaft_in_bore", "compound: shaft d20 in a bored block, touching along a cylindrical face (press fit)")
def _():
    blk = box(40, 40, 30, V(-20, -20, 0)).cut(cyl(10, 32, V(0, 0, -1)))
    return Part.makeCompound([blk, cyl(10, 30)])


@part("compound_offset_boxes", "compound: small box on a big box, contact face a part of the big top face (not fragmented)")
def _():
    return Part.makeCompound([box(50, 40, 10), box(20, 15, 8, V(12.3, 9.7, 10))])


@part("hole_across_seam", "cylinder d40 with radial holes crossing the cylinder's seam line and tangent-ish shallow flat")
def _():
    s = cyl(20, 40)
    s = s.cut(cyl(3, 30, V(0, 0, 20), V(1, 0, 0)))
    return s.cut(box(10, 40, 40, V(19.6, -20, -1)))


@part("near_tangent_bores", "block with two parallel bores 0.3 mm apart (thin web between holes)")
def _():
    return box(40, 30, 20).cut(cyl(5, 22, V(14.85, 15, -1))).cut(cyl(5, 22, V(25.15, 15, -1)))


@part("knurled_ring", "ring with 36 small V-grooves on its outside (many narrow faces)")
def _():
    s = cyl(20, 10).cut(cyl(12, 12, V(0, 0, -1)))
    for k in range(36):
        a = 2 * math.pi * k / 36
        tri = Part.Face(Part.makePolygon([V(21, -0.6, -1), V(19.2, 0, -1), V(21, 0.6, -1), V(21, -0.6, -1)])).extrude(V(0, 0, 12))
        tri.rotate(V(0, 0, 0), V(0, 0, 1), math.degrees(a))
        s = s.cut(tri)
    return s


# ----------------------------------------------------------------------------- main
def main():
    t0 = time.time()
    rows = []
    for name, desc, fn in PARTS:
        row = {"name": name, "description": desc}
        try:
            s = fn()
            if s is None:
                raise RuntimeError("builder returned None")
            # single solid or a compound of touching solids
            solids = s.Solids
            if not solids:
                raise RuntimeError(f"no solid ({s.ShapeType})")
            if s.ShapeType != "Compound" and len(solids) == 1:
                s = solids[0]
            ok = s.isValid() and all(x.isValid() for x in solids)
            closed = all(x.Shells and all(sh.isClosed() for sh in x.Shells) for x in solids)
            if not ok:
                raise RuntimeError("shape not valid")
            if not closed:
                raise RuntimeError("a shell is open")
            if not name.startswith("compound") and len(solids) != 1:
                raise RuntimeError(f"{len(solids)} solids")
            path = os.path.join(OUT, name + ".brep")
            s.exportBrep(path)
            back = Part.Shape(); back.read(path)
            if not back.isValid() or abs(back.Volume - s.Volume) > 1e-6 * abs(s.Volume):
                raise RuntimeError("re-read shape differs")
            bb = s.BoundBox
            row.update(ok=True, path=path, volume=s.Volume, solids=len(solids), faces=len(s.Faces),
                       edges=len(s.Edges), bbox=[bb.XMin, bb.YMin, bb.ZMin, bb.XMax, bb.YMax, bb.ZMax],
                       face_types=sorted({f.Surface.TypeId.split("::")[-1] for f in s.Faces}))
        except Exception as e:
            row.update(ok=False, error=f"{type(e).__name__}: {e}", trace=traceback.format_exc()[-800:])
        rows.append(row)
        print(f"{name}: {'ok' if row['ok'] else row['error']}" + (f" V={row['volume']:.1f} faces={row['faces']}" if row["ok"] else ""), flush=True)
    with open(os.path.join(OUT, "parts.json"), "w") as f:
        json.dump(rows, f, indent=1)
    print(f"{sum(r['ok'] for r in rows)}/{len(rows)} parts in {time.time() - t0:.1f} s")


main()
