// Square with a circular hole for problems/hole-obstacle.toml:
// Omega = (-1,1)^2 minus the disc of radius 0.3 centred at (0.2, 0).
// Physical lines: 1 = the outer square, 2 = the hole's circle.
// Regenerate: gmsh -2 -nt 1 -format msh41 -v 2 hole.geo -o hole.msh
Mesh.MshFileVersion = 4.1;
Mesh.Binary = 0;
General.NumThreads = 1;
Mesh.Algorithm = 6;
Mesh.RandomSeed = 1;
Mesh.SaveAll = 0;

lc = 0.08;
Point(1) = {-1, -1, 0, lc};
Point(2) = {1, -1, 0, lc};
Point(3) = {1, 1, 0, lc};
Point(4) = {-1, 1, 0, lc};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4};

r = 0.3;
Point(10) = {0.2, 0, 0, lc / 2};
Point(11) = {0.2 + r, 0, 0, lc / 2};
Point(12) = {0.2, r, 0, lc / 2};
Point(13) = {0.2 - r, 0, 0, lc / 2};
Point(14) = {0.2, -r, 0, lc / 2};
Circle(11) = {11, 10, 12};
Circle(12) = {12, 10, 13};
Circle(13) = {13, 10, 14};
Circle(14) = {14, 10, 11};
Curve Loop(2) = {11, 12, 13, 14};
Plane Surface(1) = {1, 2};

Physical Curve("outer", 1) = {1, 2, 3, 4};
Physical Curve("hole", 2) = {11, 12, 13, 14};
Physical Surface("Omega", 10) = {1};
