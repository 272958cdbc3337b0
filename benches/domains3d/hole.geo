// The cube (-2,2)^3 with a spherical hole of centre (1.1, 1.1, 1.1) and radius 0.4 for the
// benchmark's 3D "any domain" family (problems/ex9-3d.toml: the hole is 1.1*sqrt(3) - 0.4
// = 1.51 from the centre, away from the contact ball r <= 1/sqrt(2) = 0.71; a domain that is
// not simply connected in the sense of its boundary: two boundary components). Physical
// volume 10 = the domain, physical surface 1 = the cube's sides and the hole's sphere (both
// Dirichlet u = 1/(2r)). Unstructured tetrahedra of size lc:
//   gmsh -3 -nt 1 -format msh41 -v 2 -setnumber lc LC hole.geo -o OUT.msh
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
Sphere(2) = {1.1, 1.1, 1.1, 0.4};
BooleanDifference(3) = { Volume{1}; Delete; }{ Volume{2}; Delete; };
Physical Volume(10) = {3};
Physical Surface(1) = Surface{:};
