// Oedometer column 0.1 x 1.0 m in plane strain, y up (bottom y = 0, drained top y = 1),
// structured: 3 x 19 cells of 2 triangles = 114 triangles, the 2D twin of oedometer.geo (the
// workshop's own 2D column, 1 x 10 cells, is Anura3D's Oedometer_tri_MP_2024 GOM).
// Regenerate the mesh beside it with scripts/make-testdata.
SetFactory("OpenCASCADE");
Rectangle(1) = {0, 0, 0, 0.1, 1.0};
Transfinite Curve{1, 3} = 4;
Transfinite Curve{2, 4} = 20;
Transfinite Surface{1};
Physical Surface("soil") = {1};
Physical Curve("bottom") = {1};
Physical Curve("x1") = {2};
Physical Curve("top") = {3};
Physical Curve("x0") = {4};
