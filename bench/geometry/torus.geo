// Torus, major radius 40 mm, minor radius 12 mm, axis along z.
SetFactory("OpenCASCADE");
Torus(1) = {0, 0, 0, 40, 12};
Physical Volume("solid", 1) = {1};
