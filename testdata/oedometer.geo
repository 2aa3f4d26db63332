// Oedometer column 0.1 x 1.0 x 0.1 m, y up (bottom y = 0, drained top y = 1), structured:
// 3 x 19 x 3 cells of 6 tetrahedra = 1,026 tetrahedra, as the Anura3D reference run of the
// consolidation issue. Regenerate the mesh beside it with scripts/make-testdata.
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 0.1, 1.0, 0.1};
Transfinite Curve{:} = 4;
Transfinite Curve{2, 4, 6, 8} = 20;
Transfinite Surface{:};
Transfinite Volume{1};
Physical Volume("soil") = {1};
Physical Surface("x0") = {1};
Physical Surface("x1") = {2};
Physical Surface("bottom") = {3};
Physical Surface("top") = {4};
Physical Surface("z0") = {5};
Physical Surface("z1") = {6};
