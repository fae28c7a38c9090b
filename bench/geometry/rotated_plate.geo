// Shapes over sizes (bench/shapes_over_sizes.py): a 100 x 60 x 8 plate with four holes of
// radius 4 to 7, turned by pi/7 about (1, 1, 0): no face normal to x, y or z.
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 100, 60, 8};
For i In {0:3}
  Cylinder(10 + i) = {15 + 22*i, 30, -1, 0, 0, 10, 4 + i};
EndFor
BooleanDifference(2) = { Volume{1}; Delete; }{ Volume{10:13}; Delete; };
Rotate{{1, 1, 0}, {0, 0, 0}, Pi/7}{ Volume{2}; }
