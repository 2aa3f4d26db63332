// Two-layer column for the K0 comparison with Anura3D (solver/tests/oracle.rs): 0.1 x 1.0 x
// 0.1 m, y up, "lower" below y = 0.5 and "upper" above, structured, 2 x 10 x 2 cells of 6
// tetrahedra per layer = 480 tetrahedra. Regenerate the mesh beside it with
// scripts/make-testdata.
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 0.1, 0.5, 0.1};
Box(2) = {0, 0.5, 0, 0.1, 0.5, 0.1};
BooleanFragments{ Volume{1}; Delete; }{ Volume{2}; Delete; }
cs() = Curve{:};
For i In {0:#cs()-1}
  bb() = BoundingBox Curve{cs(i)};
  If (bb(4) - bb(1) > 0.2)
    Transfinite Curve{cs(i)} = 11;
  Else
    Transfinite Curve{cs(i)} = 3;
  EndIf
EndFor
Transfinite Surface{:};
Transfinite Volume{:};
Physical Volume("lower") = {1};
Physical Volume("upper") = {2};
