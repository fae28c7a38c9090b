// Shapes over sizes (bench/shapes_over_sizes.py): a 60 x 40 x 25 block, every edge filleted
// (radius 4), a hole of radius 8 through it along z. Fillets meet at its corners.
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 60, 40, 25};
f() = Fillet{1}{Curve{:}}{4};
Cylinder(3) = {30, 20, -5, 0, 0, 35, 8};
BooleanDifference{ Volume{f()}; Delete; }{ Volume{3}; Delete; }
