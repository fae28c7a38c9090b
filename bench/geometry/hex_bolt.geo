// Bolt-like part (real-parts benchmark, bench/real_parts.py): an M16-size bolt without thread.
// A hexagonal head (24 mm across flats, 10 mm high, its top corners chamfered by a 30-degree
// cone) on a revolved body: washer face (diameter 23, 0.5 mm), a 1.5 mm fillet under the head,
// a plain shank (diameter 16, 60 mm long) and a 1 mm 45-degree chamfer at the tip. One solid
// along z.
SetFactory("OpenCASCADE");
s = 24; hh = 10; d = 16; ls = 60; rf = 1.5;
// The revolved body: its half profile in the xz plane, turned about z.
Point(1) = {0, 0, -ls};
Point(2) = {d / 2 - 1, 0, -ls};
Point(3) = {d / 2, 0, -ls + 1};
Point(4) = {d / 2, 0, -0.5 - rf};
Point(5) = {d / 2 + rf, 0, -0.5 - rf};  // centre of the fillet
Point(6) = {d / 2 + rf, 0, -0.5};
Point(7) = {11.5, 0, -0.5};
Point(8) = {11.5, 0, 0};
Point(9) = {0, 0, 0};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4};
Circle(4) = {4, 5, 6};
Line(5) = {6, 7}; Line(6) = {7, 8}; Line(7) = {8, 9}; Line(8) = {9, 1};
Curve Loop(1) = {1:8};
Plane Surface(1) = {1};
body() = Extrude {{0, 0, 1}, {0, 0, 0}, 2 * Pi} { Surface{1}; };
// The head: a hexagonal prism (circumradius s / sqrt(3)) meeting a cone that cuts its corners.
Rh = s / Sqrt(3);
For i In {0:5}
  Point(20 + i) = {Rh * Cos(i * Pi / 3), Rh * Sin(i * Pi / 3), 0};
EndFor
For i In {0:5}
  Line(20 + i) = {20 + i, 20 + (i + 1) % 6};
EndFor
Curve Loop(20) = {20:25};
Plane Surface(20) = {20};
prism() = Extrude {0, 0, hh} { Surface{20}; };
// Chamfer: the cone has radius s / 2 at the top face and widens downwards at 30 degrees.
Cone(30) = {0, 0, hh, 0, 0, -hh, s / 2, s / 2 + hh / Tan(Pi / 6)};
BooleanIntersection(31) = { Volume{prism(1)}; Delete; }{ Volume{30}; Delete; };
BooleanUnion(32) = { Volume{body(1)}; Delete; }{ Volume{31}; Delete; };
