// Shapes over sizes (bench/shapes_over_sizes.py): four touching solids (a plate, a cylinder
// on it, a plate on that, a pin on top), meshed conformally with one region each.
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 60, 60, 10};
Cylinder(2) = {30, 30, 10, 0, 0, 25, 15};
Box(3) = {10, 10, 35, 40, 40, 6};
Cylinder(4) = {30, 30, 41, 0, 0, 10, 5};
