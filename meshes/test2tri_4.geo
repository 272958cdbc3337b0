// Test 2 on triangles (heterogeneous Signorini, Alnashri & Droniou Sec. 4), mesh 4 of 4.
// Omega = (0,1)^2 split at y = 1/2 into two surfaces (both physical surface 10) so that
// the line y = 1/2 (jump of A) is made of mesh edges and no triangle straddles it.
// Gamma1 = bottom (y=0) and top (y=1), Gamma2 = right (x=1), Gamma3 = left (x=0).
// n = 160 edges on x=0 (n/2 below and n/2 above y=1/2); uniform boundary subdivision
// (all boundary curves and the interface transfinite), lc = 1/n.
Mesh.MshFileVersion = 4.1;
Mesh.Binary = 0;
General.NumThreads = 1;  // single thread: deterministic output
Mesh.Algorithm = 6;      // Frontal-Delaunay, fixed
Mesh.RandomSeed = 1;
Mesh.SaveAll = 0;        // only elements in physical groups are written

n = 160;
lc = 1 / n;
Point(1) = {0, 0, 0, lc};
Point(2) = {1, 0, 0, lc};
Point(3) = {1, 0.5, 0, lc};
Point(4) = {0, 0.5, 0, lc};
Point(5) = {1, 1, 0, lc};
Point(6) = {0, 1, 0, lc};
Line(1) = {1, 2};  // bottom y=0:    Gamma1
Line(2) = {2, 3};  // right, lower:  Gamma2
Line(3) = {3, 4};  // interface y=1/2 (interior, no physical tag)
Line(4) = {4, 1};  // left, lower:   Gamma3
Line(5) = {3, 5};  // right, upper:  Gamma2
Line(6) = {5, 6};  // top y=1:       Gamma1
Line(7) = {6, 4};  // left, upper:   Gamma3
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Curve Loop(2) = {-3, 5, 6, 7};
Plane Surface(2) = {2};
Transfinite Curve{1, 3, 6} = n + 1 Using Progression 1;
Transfinite Curve{2, 4, 5, 7} = n / 2 + 1 Using Progression 1;

Physical Curve("Gamma1", 1) = {1, 6};
Physical Curve("Gamma2", 2) = {2, 5};
Physical Curve("Gamma3", 3) = {4, 7};
Physical Surface("Omega", 10) = {1, 2};
