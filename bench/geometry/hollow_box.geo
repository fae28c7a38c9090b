// Shapes over sizes (bench/shapes_over_sizes.py): an 80 x 50 x 30 box, open on top, walls
// 4 mm thick, and a 4 mm rib across it: thin walls at planes no one spacing fits.
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 80, 50, 30};
Box(2) = {4, 4, 4, 72, 42, 30};
BooleanDifference(3) = { Volume{1}; Delete; }{ Volume{2}; Delete; };
Box(4) = {38, 4, 4, 4, 42, 20};
BooleanUnion{ Volume{3}; Delete; }{ Volume{4}; Delete; }
