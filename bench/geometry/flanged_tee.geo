// Flanged pipe tee (real-parts benchmark, bench/real_parts.py): a run pipe along x (outer
// diameter 60, wall 6, length 200 mm) and a branch pipe along z (same section, 100 mm from the
// run's axis), each of its three ends with a flange (diameter 120, 12 mm thick) drilled with
// four 14 mm bolt holes on a 90 mm circle. One solid: curved faces meeting at a saddle, planar
// flanges, small holes.
SetFactory("OpenCASCADE");
R = 30; r = 24; L = 100; Rf = 60; t = 12; Rb = 45; rb = 7;
Cylinder(1) = {-L, 0, 0, 2 * L, 0, 0, R};
Cylinder(2) = {0, 0, 0, 0, 0, L, R};
Cylinder(3) = {-L, 0, 0, t, 0, 0, Rf};
Cylinder(4) = {L - t, 0, 0, t, 0, 0, Rf};
Cylinder(5) = {0, 0, L - t, 0, 0, t, Rf};
outer() = BooleanUnion{ Volume{1}; Delete; }{ Volume{2:5}; Delete; };
Cylinder(10) = {-L - 1, 0, 0, 2 * L + 2, 0, 0, r};
Cylinder(11) = {0, 0, 0, 0, 0, L + 1, r};
k = 12;
For i In {0:3}
  a = Pi / 4 + i * Pi / 2;
  Cylinder(k) = {-L - 1, Rb * Cos(a), Rb * Sin(a), t + 2, 0, 0, rb}; k += 1;
  Cylinder(k) = {L - t - 1, Rb * Cos(a), Rb * Sin(a), t + 2, 0, 0, rb}; k += 1;
  Cylinder(k) = {Rb * Cos(a), Rb * Sin(a), L - t - 1, 0, 0, t + 2, rb}; k += 1;
EndFor
BooleanDifference(100) = { Volume{outer()}; Delete; }{ Volume{10:k - 1}; Delete; };
