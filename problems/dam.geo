// Trapezoid in two materials for problems/signorini-layers.toml:
// Omega = the trapezoid (0,0), (2,0), (1.5,1), (0,1), split by the segment x = 1 into
// surface 1 (x < 1) and surface 2 (x > 1); the interface is a mesh line.
// Physical lines: 1 = top (y = 1), 2 = the sides (x = 0 and the slanted side),
// 3 = the bottom (y = 0), the Signorini part.
// Regenerate: gmsh -2 -nt 1 -format msh41 -v 2 dam.geo -o dam.msh
Mesh.MshFileVersion = 4.1;
Mesh.Binary = 0;
General.NumThreads = 1;
Mesh.Algorithm = 6;
Mesh.RandomSeed = 1;
Mesh.SaveAll = 0;

lc = 0.05;
Point(1) = {0, 0, 0, lc};
Point(2) = {1, 0, 0, lc};
Point(3) = {2, 0, 0, lc};
Point(4) = {1.5, 1, 0, lc};
Point(5) = {1, 1, 0, lc};
Point(6) = {0, 1, 0, lc};
Line(1) = {1, 2};   // bottom, left material
Line(2) = {2, 3};   // bottom, right material
Line(3) = {3, 4};   // slanted side
Line(4) = {4, 5};   // top, right
Line(5) = {5, 6};   // top, left
Line(6) = {6, 1};   // left side
Line(7) = {2, 5};   // interface x = 1
Curve Loop(1) = {1, 7, 5, 6};
Curve Loop(2) = {2, 3, 4, -7};
Plane Surface(1) = {1};
Plane Surface(2) = {2};

Physical Curve("top", 1) = {4, 5};
Physical Curve("sides", 2) = {3, 6};
Physical Curve("bottom", 3) = {1, 2};
Physical Surface("left", 1) = {1};
Physical Surface("right", 2) = {2};
