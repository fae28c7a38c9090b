// Cylinder, radius 20 mm, height 100 mm, axis along z.
SetFactory("OpenCASCADE");
Cylinder(1) = {0, 0, 0, 0, 0, 100, 20};
Physical Volume("solid", 1) = {1};
