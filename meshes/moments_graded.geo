// dim: 2
// Property-test mesh: the 1 x 0.6 rectangle of default triangles graded from 0.01 near the
// point (0.5, 0.3) to 0.04 beyond 0.25 from it (a 4x ratio), group `wall` (tests/weights.rs).
Point(1) = {0, 0, 0}; Point(2) = {1, 0, 0}; Point(3) = {1, 0.6, 0}; Point(4) = {0, 0.6, 0};
Point(5) = {0.5, 0.3, 0};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Field[1] = Distance; Field[1].PointsList = {5};
Field[2] = Threshold; Field[2].InField = 1; Field[2].SizeMin = 0.01; Field[2].SizeMax = 0.04;
Field[2].DistMin = 0.05; Field[2].DistMax = 0.25;
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0; Mesh.MeshSizeFromPoints = 0; Mesh.MeshSizeFromCurvature = 0;
Physical Curve("wall") = {1, 2, 3, 4};
Physical Surface("body") = {1};
