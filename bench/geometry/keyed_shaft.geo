// Shapes over sizes (bench/shapes_over_sizes.py): a stepped shaft (radius 12 over 100 mm,
// 8 over 30 mm) with a keyway 6 mm wide, every edge filleted (0.8 mm): small fillets on
// curved faces.
SetFactory("OpenCASCADE");
Cylinder(1) = {0, 0, 0, 0, 0, 100, 12};
Cylinder(2) = {0, 0, 100, 0, 0, 30, 8};
BooleanUnion(3) = { Volume{1}; Delete; }{ Volume{2}; Delete; };
Box(4) = {-3, 9, 20, 6, 5, 50};
BooleanDifference(5) = { Volume{3}; Delete; }{ Volume{4}; Delete; };
Fillet{5}{Curve{:}}{0.8}
