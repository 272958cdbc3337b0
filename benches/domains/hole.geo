// Unit square with a circular hole (centre (0.25, 0.25), radius 0.1, away from the
// contact zone of Test 3, which is around the centre) for the benchmark's
// "any domain" family (Test 3 data; a domain that is not simply connected); the outer
// boundary is physical line 1, the hole's boundary physical line 2 (both Dirichlet u = 0).
// The bench writes meshes with: gmsh -2 -nt 1 -setnumber lc LC hole.geo -o OUT.msh
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
Point(2) = {1, 0, 0, lc};
Point(3) = {1, 1, 0, lc};
Point(4) = {0, 1, 0, lc};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Point(5) = {0.25, 0.25, 0, lc};
Point(6) = {0.35, 0.25, 0, lc};
Point(7) = {0.25, 0.35, 0, lc};
Point(8) = {0.15, 0.25, 0, lc};
Point(9) = {0.25, 0.15, 0, lc};
Circle(5) = {6, 5, 7};
Circle(6) = {7, 5, 8};
Circle(7) = {8, 5, 9};
Circle(8) = {9, 5, 6};
Curve Loop(1) = {1, 2, 3, 4};
Curve Loop(2) = {5, 6, 7, 8};
Plane Surface(1) = {1, 2};
Physical Curve("outer", 1) = {1, 2, 3, 4};
Physical Curve("hole", 2) = {5, 6, 7, 8};
Physical Surface("Omega", 10) = {1};
