// Thin-walled bracket with fillets (real-parts benchmark, bench/real_parts.py): a 3 mm sheet
// bent into an L (base 60 x 40 mm, upright 40 mm high) with a 4 mm inner bend radius, two
// triangular gussets (3 mm) inside the bend, a 10 mm slot in the base and two 8 mm holes in the
// upright; the base's outer corners rounded (radius 6). One solid, walls a few h thick.
SetFactory("OpenCASCADE");
t = 3; w = 40; lb = 60; hu = 40; ri = 4;
// The bent sheet: the L profile in the xz plane (inner bend radius ri), extruded along y.
Point(1) = {0, 0, 0};
Point(2) = {lb, 0, 0};
Point(3) = {lb, 0, t};
Point(4) = {t + ri, 0, t};
Point(5) = {t + ri, 0, t + ri};  // centre of both bend arcs
Point(6) = {t, 0, t + ri};
Point(7) = {t, 0, hu};
Point(8) = {0, 0, hu};
Point(9) = {0, 0, t + ri};
Point(10) = {t + ri, 0, 0};
Line(1) = {10, 2}; Line(2) = {2, 3}; Line(3) = {3, 4};
Circle(4) = {4, 5, 6};
Line(5) = {6, 7}; Line(6) = {7, 8}; Line(7) = {8, 9};
Circle(8) = {9, 5, 10};
Curve Loop(1) = {1:8};
Plane Surface(1) = {1};
sheet() = Extrude {0, w, 0} { Surface{1}; };
// Gussets: right triangles 20 x 20 mm in planes y = 5 and y = w - 8.
For k In {0:1}
  y0 = 5 + k * (w - 13);
  p0 = newp; Point(p0) = {t, y0, t};
  p1 = newp; Point(p1) = {t + 20, y0, t};
  p2 = newp; Point(p2) = {t, y0, t + 20};
  l0 = newl; Line(l0) = {p0, p1};
  l1 = newl; Line(l1) = {p1, p2};
  l2 = newl; Line(l2) = {p2, p0};
  c = newll; Curve Loop(c) = {l0, l1, l2};
  f = news; Plane Surface(f) = {c};
  g~{k}() = Extrude {0, t, 0} { Surface{f}; };
EndFor
BooleanUnion(40) = { Volume{sheet(1)}; Delete; }{ Volume{g~{0}(1), g~{1}(1)}; Delete; };
// Slot in the base (10 mm wide, 24 mm long, round ends), holes in the upright.
Cylinder(41) = {30, w / 2, -1, 0, 0, t + 2, 5};
Cylinder(42) = {48, w / 2, -1, 0, 0, t + 2, 5};
Box(43) = {30, w / 2 - 5, -1, 18, 10, t + 2};
Cylinder(44) = {-1, 12, 28, t + 2, 0, 0, 4};
Cylinder(45) = {-1, w - 12, 28, t + 2, 0, 0, 4};
BooleanDifference(46) = { Volume{40}; Delete; }{ Volume{41:45}; Delete; };
// Round the base's two far corners (vertical edges at x = lb).
e() = Curve In BoundingBox{lb - 0.1, -0.1, -0.1, lb + 0.1, 0.1, t + 0.1};
e() += Curve In BoundingBox{lb - 0.1, w - 0.1, -0.1, lb + 0.1, w + 0.1, t + 0.1};
Fillet{46}{ e() }{ 6 }
