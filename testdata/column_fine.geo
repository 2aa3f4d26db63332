// Column 0.1 x 1.0 x 0.1 m, y up, finer (for the solver's validation tests).
// Regenerate the mesh beside it with scripts/make-testdata.
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 0.1, 1.0, 0.1};
Mesh.CharacteristicLengthMin = 0.025;
Mesh.CharacteristicLengthMax = 0.025;
Physical Volume("soil") = {1};
Physical Surface("x0") = {1};
Physical Surface("x1") = {2};
Physical Surface("bottom") = {3};
Physical Surface("top") = {4};
Physical Surface("z0") = {5};
Physical Surface("z1") = {6};
