// Box 100 x 40 x 30 mm. Mesh size is set from the command line (gmsh -3 -clmax h).
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 100, 40, 30};
Physical Volume("solid", 1) = {1};
