// Disk of centre (0.5, 0.5) and radius 0.5 for the benchmark's "any domain" family
// (Test 3 data; a curved boundary); the whole boundary is physical line 1.
// The bench writes meshes with: gmsh -2 -nt 1 -setnumber lc LC disk.geo -o OUT.msh
If (!Exists(lc))
  lc = 0.02;
EndIf
Mesh.MshFileVersion = 4.1;
Mesh.Binary = 0;
General.NumThreads = 1;
Mesh.Algorithm = 6;
Mesh.RandomSeed = 1;
Mesh.SaveAll = 0;
Point(1) = {0.5, 0.5, 0, lc};
Point(2) = {1, 0.5, 0, lc};
Point(3) = {0.5, 1, 0, lc};
Point(4) = {0, 0.5, 0, lc};
Point(5) = {0.5, 0, 0, lc};
Circle(1) = {2, 1, 3};
Circle(2) = {3, 1, 4};
Circle(3) = {4, 1, 5};
Circle(4) = {5, 1, 2};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Physical Curve("boundary", 1) = {1, 2, 3, 4};
Physical Surface("Omega", 10) = {1};
