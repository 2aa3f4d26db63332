// Unit square in the x-y plane (2D plane strain), for triangle tests.
// Regenerate the meshes beside it with scripts/make-testdata.
SetFactory("OpenCASCADE");
Rectangle(1) = {0, 0, 0, 1, 1};
Mesh.CharacteristicLengthMin = 0.2;
Mesh.CharacteristicLengthMax = 0.2;
Physical Surface("soil") = {1};
Physical Curve("bottom") = {1};
