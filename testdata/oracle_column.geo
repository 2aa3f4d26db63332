// Consolidation column for point-by-point comparisons with Anura3D (solver/tests/oracle.rs):
// 0.1 x 1.0 x 0.1 m, y up, structured, 2 x 20 x 2 cells of 6 tetrahedra = 480 tetrahedra.
// Regenerate the mesh beside it with scripts/make-testdata.
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 0.1, 1.0, 0.1};
Transfinite Curve{:} = 3;
Transfinite Curve{2, 4, 6, 8} = 21;
Transfinite Surface{:};
Transfinite Volume{1};
Physical Volume("soil") = {1};
Physical Surface("x0") = {1};
Physical Surface("x1") = {2};
Physical Surface("bottom") = {3};
Physical Surface("top") = {4};
Physical Surface("z0") = {5};
Physical Surface("z1") = {6};
