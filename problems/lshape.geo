// L-shaped domain for problems/lshape-obstacle.toml:
// Omega = (-1,1)^2 minus [0,1]x[-1,0]; the whole boundary is physical line 1.
// Regenerate: gmsh -2 -nt 1 -format msh41 -v 2 lshape.geo -o lshape.msh
Mesh.MshFileVersion = 4.1;
Mesh.Binary = 0;
General.NumThreads = 1;  // single thread: deterministic output
Mesh.Algorithm = 6;      // Frontal-Delaunay
Mesh.RandomSeed = 1;
Mesh.SaveAll = 0;        // only elements in physical groups are written

lc = 0.07;
Point(1) = {-1, -1, 0, lc};
Point(2) = {0, -1, 0, lc};
Point(3) = {0, 0, 0, lc / 3};   // refined at the re-entrant corner
Point(4) = {1, 0, 0, lc};
Point(5) = {1, 1, 0, lc};
Point(6) = {-1, 1, 0, lc};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 5};
Line(5) = {5, 6};
Line(6) = {6, 1};
Curve Loop(1) = {1, 2, 3, 4, 5, 6};
Plane Surface(1) = {1};

Physical Curve("boundary", 1) = {1, 2, 3, 4, 5, 6};
Physical Surface("Omega", 10) = {1};
