// The cube (−2,2)³ in tetrahedra of size h = 0.5, for the 3D cross-check against dolfinx
// (problems/ex9-3d.toml, the 3D radial obstacle; reference/solve.py case ex9_3d_1):
//   gmsh -3 -nt 1 -format msh41 -v 2 ex9_3d_1.geo -o ex9_3d_1.msh
// Physical volume 10 = the cube; physical surface 1 = its whole boundary (Dirichlet).
SetFactory("OpenCASCADE");
h = 0.5;
General.NumThreads = 1;
Mesh.Algorithm = 6;
Mesh.Algorithm3D = 1;
Mesh.RandomSeed = 1;
Mesh.MshFileVersion = 4.1;
Mesh.Binary = 0;
Mesh.SaveAll = 0;
Mesh.CharacteristicLengthMin = h;
Mesh.CharacteristicLengthMax = h;

Box(1) = {-2, -2, -2, 4, 4, 4};
Physical Volume(10) = {1};
Physical Surface(1) = Surface{:};
