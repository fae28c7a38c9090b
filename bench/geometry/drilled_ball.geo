// Shapes over sizes (bench/shapes_over_sizes.py): a ball of radius 25 cut flat at z = 18,
// drilled across by holes of radius 6 (along x) and 4 (along y, off the centre).
SetFactory("OpenCASCADE");
Sphere(1) = {0, 0, 0, 25};
Cylinder(2) = {-30, 0, 0, 60, 0, 0, 6};
Cylinder(3) = {0, -30, 5, 0, 60, 0, 4};
Box(4) = {-30, -30, 18, 60, 60, 20};
BooleanDifference{ Volume{1}; Delete; }{ Volume{2, 3, 4}; Delete; }
