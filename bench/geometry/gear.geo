// Shapes over sizes (bench/shapes_over_sizes.py): an 18-tooth gear 12 mm thick (trapezoidal
// teeth from radius 26 to 30) with a bore of radius 8: an extrusion along z.
SetFactory("OpenCASCADE");
n = 18; R = 30; r = 26; k = 1;
For i In {0:n-1}
  a = 2*Pi*i/n;
  Point(k) = {r*Cos(a), r*Sin(a), 0}; k += 1;
  Point(k) = {R*Cos(a + Pi/n*0.4), R*Sin(a + Pi/n*0.4), 0}; k += 1;
  Point(k) = {R*Cos(a + Pi/n*1.0), R*Sin(a + Pi/n*1.0), 0}; k += 1;
  Point(k) = {r*Cos(a + Pi/n*1.4), r*Sin(a + Pi/n*1.4), 0}; k += 1;
EndFor
For i In {1:k-2}
  Line(i) = {i, i + 1};
EndFor
Line(k-1) = {k-1, 1};
Curve Loop(1) = {1:k-1};
Circle(1000) = {0, 0, 0, 8};
Curve Loop(2) = {1000};
Plane Surface(1) = {1, 2};
Extrude{0, 0, 12}{ Surface{1}; }
