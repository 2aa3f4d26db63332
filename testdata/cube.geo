// Unit cube, y up. Regenerate the meshes beside it with scripts/make-testdata.
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 1};
Mesh.CharacteristicLengthMin = 0.25;
Mesh.CharacteristicLengthMax = 0.25;
Physical Volume("soil") = {1};
Physical Surface("x0") = {1};
Physical Surface("x1") = {2};
Physical Surface("bottom") = {3};
Physical Surface("top") = {4};
Physical Surface("z0") = {5};
Physical Surface("z1") = {6};
