// Test 1 (Signorini, Alnashri & Droniou Sec. 4), mesh 1 of 4.
// Omega = (0,1)^2; Gamma1 = top (y=1), Gamma2 = left and right, Gamma3 = bottom (y=0).
// Paper: h = 0.0625, 16 edges on Gamma3.
// Characteristic length lc = h = 1/16 everywhere; bottom curve transfinite with 16 edges.
Mesh.MshFileVersion = 4.1;
Mesh.Binary = 0;
General.NumThreads = 1;  // single thread: deterministic output
Mesh.Algorithm = 6;      // Frontal-Delaunay, fixed
Mesh.RandomSeed = 1;
Mesh.SaveAll = 0;        // only elements in physical groups are written

h = 0.0625;
N = 16;   // number of edges on Gamma3
Point(1) = {0, 0, 0, h};
Point(2) = {1, 0, 0, h};
Point(3) = {1, 1, 0, h};
Point(4) = {0, 1, 0, h};
Line(1) = {1, 2};  // bottom y=0: Gamma3
Line(2) = {2, 3};  // right  x=1: Gamma2
Line(3) = {3, 4};  // top    y=1: Gamma1
Line(4) = {4, 1};  // left   x=0: Gamma2
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Transfinite Curve{1} = N + 1 Using Progression 1;

Physical Curve("Gamma1", 1) = {3};
Physical Curve("Gamma2", 2) = {2, 4};
Physical Curve("Gamma3", 3) = {1};
Physical Surface("Omega", 10) = {1};
