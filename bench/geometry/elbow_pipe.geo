// Shapes over sizes (bench/shapes_over_sizes.py): a quarter torus tube (bend radius 40,
// outer radius 10, inner 7): a thin curved wall.
SetFactory("OpenCASCADE");
Torus(1) = {0, 0, 0, 40, 10, Pi/2};
Torus(2) = {0, 0, 0, 40, 7, Pi/2};
BooleanDifference(3) = { Volume{1}; Delete; }{ Volume{2}; Delete; };
