// dim: 3
// Property-test mesh: the box [0, 1] x [0, 0.8] x [0, 0.6] of gmsh's default tetrahedra
// (size 0.12), all faces in one group `wall` (tests/weights.rs).
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 0.8, 0.6};
MeshSize{ PointsOf{ Volume{1}; } } = 0.12;
Physical Surface("wall") = {1, 2, 3, 4, 5, 6};
Physical Volume("body") = {1};
