// Ball of centre 0 and radius 2 for the benchmark's 3D "any domain" family
// (problems/ex9-3d.toml: the radial obstacle, whose contact ball r <= 1/sqrt(2) it contains;
// a curved boundary). Physical volume 10 = the ball, physical surface 1 = its sphere
// (Dirichlet u = 1/(2r)). Unstructured tetrahedra of size lc:
//   gmsh -3 -nt 1 -format msh41 -v 2 -setnumber lc LC ball.geo -o OUT.msh
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

Sphere(1) = {0, 0, 0, 2};
Physical Volume(10) = {1};
Physical Surface(1) = Surface{:};
