// Two boxes sharing a face (real-parts benchmark, bench/real_parts.py): a compound of two
// touching solids, 60 x 40 x 30 mm and 40 x 40 x 20 mm, the second on the first's x = 60 face
// and offset in z, so they share a 40 x 20 mm rectangle (not a whole face). BooleanFragments
// makes the shared face one face of both solids, as an assembly exported from CAD has.
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 60, 40, 30};
Box(2) = {60, 0, 5, 40, 40, 20};
BooleanFragments{ Volume{1}; Delete; }{ Volume{2}; Delete; }
