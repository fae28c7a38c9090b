// Plate with many small holes (real-parts benchmark, bench/real_parts.py): 120 x 80 x 6 mm,
// a 9 x 6 grid of 4 mm holes on a 12 mm pitch, and a 20 mm hole in one corner region. Small
// holes against the size h: at 50k tets h is about a hole's diameter.
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 120, 80, 6};
k = 2;
For i In {0:8}
  For j In {0:5}
    Cylinder(k) = {12 + 12 * i, 10 + 12 * j, -1, 0, 0, 8, 2}; k += 1;
  EndFor
EndFor
BooleanDifference(100) = { Volume{1}; Delete; }{ Volume{2:k - 1}; Delete; };
