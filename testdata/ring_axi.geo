// Axisymmetric section of a thick cylinder (x the radius, y the axis): the wall between radii
// 1 and 2 m, an empty ring out to 2.25 m for it to expand into, a slice 0.25 m high; 16 x 4
// (wall) and 2 x 4 (void) cells of 2 triangles. For the Lamé test of axisymmetric runs
// (solver/tests/two_d.rs). Regenerate with scripts/make-testdata.
SetFactory("OpenCASCADE");
Rectangle(1) = {1, 0, 0, 1, 0.25};
Rectangle(2) = {2, 0, 0, 0.25, 0.25};
BooleanFragments{ Surface{1, 2}; Delete; }{}
Transfinite Curve{:} = 5;
Transfinite Curve{1, 3} = 17;
Transfinite Curve{5, 7} = 3;
Transfinite Surface{:};
Physical Surface("wall") = {1};
Physical Surface("void") = {2};
Physical Curve("bottom") = {1, 5};
Physical Curve("top") = {3, 7};
Physical Curve("inner") = {4};
