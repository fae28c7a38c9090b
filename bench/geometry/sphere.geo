// Sphere, radius 25 mm.
SetFactory("OpenCASCADE");
Sphere(1) = {0, 0, 0, 25};
Physical Volume("solid", 1) = {1};
