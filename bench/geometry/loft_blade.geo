// Shapes over sizes (bench/shapes_over_sizes.py): a loft (B-spline faces) through an ellipse
// 20 x 6, a turned ellipse 14 x 4 at z = 40 and a circle of radius 6 at z = 80.
SetFactory("OpenCASCADE");
Ellipse(1) = {0, 0, 0, 20, 6};
Curve Loop(1) = {1};
Ellipse(2) = {3, 2, 40, 14, 4};
Rotate{{0, 0, 1}, {3, 2, 40}, Pi/5}{ Curve{2}; }
Curve Loop(2) = {2};
Circle(3) = {0, 0, 80, 6};
Curve Loop(3) = {3};
ThruSections(1) = {1, 2, 3};
