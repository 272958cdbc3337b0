// The cube (-2,2)^3 in unstructured gmsh tetrahedra for the benchmark's 3D "any domain"
// family (problems/ex9-3d.toml on its own domain, but not on the Kuhn cubes of the dolfinx
// comparison). Physical volume 10 = the cube, physical surface 1 = its six sides (Dirichlet
// u = 1/(2r)). Unstructured tetrahedra of size lc:
//   gmsh -3 -nt 1 -format msh41 -v 2 -setnumber lc LC cube.geo -o OUT.msh
SetFactory("OpenCASCADE");
If (!Exists(lc))
  lc = 0.3;
EndIf
General.NumThreads = 1;
Mesh.Algorithm = 6;
Mesh.Algorithm3D = 1;
Mesh.RandomSeed = 1;
Mesh.MshFileVersion = 4.1;
Mesh.Binary = 0;
Mesh.SaveAll = 0;
Mesh.CharacteristicLengthMin = lc;
Mesh.CharacteristicLengthMax = lc;

Box(1) = {-2, -2, -2, 4, 4, 4};
Physical Volume(10) = {1};
Physical Surface(1) = Surface{:};
