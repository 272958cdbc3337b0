// Test 3 (obstacle problem, Alnashri & Droniou Sec. 4), mesh 1 of 4.
// Omega = (0,1)^2; the whole boundary is Gamma1 (homogeneous Dirichlet).
// Paper: h = 0.062 (MATLAB initmesh), #cells = 872.  The gmsh characteristic length
// lc = 0.05348 was calibrated with calibrate_test3.py so that the triangle count is
// within 3% of the paper's (see README.md).
Mesh.MshFileVersion = 4.1;
Mesh.Binary = 0;
General.NumThreads = 1;  // single thread: deterministic output
Mesh.Algorithm = 6;      // Frontal-Delaunay, fixed
Mesh.RandomSeed = 1;
Mesh.SaveAll = 0;        // only elements in physical groups are written

lc = 0.05348;
Point(1) = {0, 0, 0, lc};
Point(2) = {1, 0, 0, lc};
Point(3) = {1, 1, 0, lc};
Point(4) = {0, 1, 0, lc};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};

Physical Curve("Gamma1", 1) = {1, 2, 3, 4};
Physical Surface("Omega", 10) = {1};
