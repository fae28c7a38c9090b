// L-bracket with a hole: base plate 80 x 40 x 10 mm, upright flange 10 x 40 x 60 mm
// at one end, a 16 mm diameter through hole in the base plate.
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 80, 40, 10};
Box(2) = {0, 0, 0, 10, 40, 60};
Cylinder(3) = {50, 20, -1, 0, 0, 12, 8};
BooleanDifference(4) = { Volume{1}; Delete; }{ Volume{3}; Delete; };
BooleanUnion(5) = { Volume{4}; Delete; }{ Volume{2}; Delete; };
Physical Volume("solid", 1) = {5};
