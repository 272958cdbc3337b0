// L-shaped domain for the benchmark's "any domain" family (Test 3 data):
// Omega = (0,1)^2 minus [0.5,1]x[0,0.5]; the whole boundary is physical line 1.
// The bench writes meshes with: gmsh -2 -nt 1 -setnumber lc LC lshape.geo -o OUT.msh
If (!Exists(lc))
  lc = 0.02;
EndIf
Mesh.MshFileVersion = 4.1;
Mesh.Binary = 0;
General.NumThreads = 1;
Mesh.Algorithm = 6;
Mesh.RandomSeed = 1;
Mesh.SaveAll = 0;
Point(1) = {0, 0, 0, lc};
Point(2) = {0.5, 0, 0, lc};
Point(3) = {0.5, 0.5, 0, lc};
Point(4) = {1, 0.5, 0, lc};
Point(5) = {1, 1, 0, lc};
Point(6) = {0, 1, 0, lc};
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
