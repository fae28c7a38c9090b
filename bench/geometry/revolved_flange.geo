// Shapes over sizes (bench/shapes_over_sizes.py): a flange turned about z, its profile stepped:
// a disc (radius 10 to 50, 8 mm thick), a hub (10 to 22, 30 mm high) with a groove (14 to 18,
// from z = 20 up); two bolt holes of radius 3 through the disc.
SetFactory("OpenCASCADE");
Point(1) = {10, 0, 0}; Point(2) = {50, 0, 0}; Point(3) = {50, 0, 8}; Point(4) = {22, 0, 8};
Point(5) = {22, 0, 30}; Point(6) = {18, 0, 30}; Point(7) = {18, 0, 20}; Point(8) = {14, 0, 20};
Point(9) = {14, 0, 30}; Point(10) = {10, 0, 30};
For i In {1:9}
  Line(i) = {i, i + 1};
EndFor
Line(10) = {10, 1};
Curve Loop(1) = {1:10}; Plane Surface(1) = {1};
Extrude{{0, 0, 1}, {0, 0, 0}, 2*Pi}{ Surface{1}; }
Cylinder(10) = {36, 0, -1, 0, 0, 10, 3};
Cylinder(11) = {-36, 0, -1, 0, 0, 10, 3};
BooleanDifference{ Volume{1}; Delete; }{ Volume{10, 11}; Delete; }
