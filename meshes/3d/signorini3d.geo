// The unit cube cut at y = 1/2 into two materials, for problems/signorini-3d.toml.
// Tetrahedra of size h (default 0.25; gmsh -setnumber h 0.125 ...):
//   gmsh -3 -nt 1 -format msh41 -v 2 -setnumber h 0.25 signorini3d.geo -o signorini3d.msh
// Physical volumes: 1 = the lower material (y < 1/2), 2 = the upper one (y > 1/2).
// Physical surfaces: 10 = {x = 0} (Signorini), 11 = {x = 1} (no flux), 12 = {y = 0} and
// {y = 1} (u = 0), 14 = {z = 0} (Neumann), 15 = {z = 1} (u = 0).
SetFactory("OpenCASCADE");
If (!Exists(h))
  h = 0.25;
EndIf
General.NumThreads = 1;
Mesh.Algorithm3D = 1;
Mesh.RandomSeed = 1;
Mesh.MshFileVersion = 4.1;
Mesh.Binary = 0;
Mesh.SaveAll = 0;
Mesh.CharacteristicLengthMin = h;
Mesh.CharacteristicLengthMax = h;

Box(1) = {0, 0, 0, 1, 0.5, 1};
Box(2) = {0, 0.5, 0, 1, 0.5, 1};
BooleanFragments{ Volume{1}; Delete; }{ Volume{2}; Delete; }

e = 1e-6;
Physical Volume(1) = Volume In BoundingBox{-e, -e, -e, 1 + e, 0.5 + e, 1 + e};
Physical Volume(2) = Volume In BoundingBox{-e, 0.5 - e, -e, 1 + e, 1 + e, 1 + e};
Physical Surface(10) = Surface In BoundingBox{-e, -e, -e, e, 1 + e, 1 + e};
Physical Surface(11) = Surface In BoundingBox{1 - e, -e, -e, 1 + e, 1 + e, 1 + e};
Physical Surface(12) = Surface In BoundingBox{-e, -e, -e, 1 + e, e, 1 + e};
Physical Surface(12) += Surface In BoundingBox{-e, 1 - e, -e, 1 + e, 1 + e, 1 + e};
Physical Surface(14) = Surface In BoundingBox{-e, -e, -e, 1 + e, 1 + e, e};
Physical Surface(15) = Surface In BoundingBox{-e, -e, 1 - e, 1 + e, 1 + e, 1 + e};
