// dim: 2
// Property-test mesh: the 1 x 0.6 rectangle of moments_tri.geo recombined into unstructured
// quadrangles (gmsh's default recombination), group `wall` (tests/weights.rs).
h = 0.04;
Point(1) = {0, 0, 0, h}; Point(2) = {1, 0, 0, h}; Point(3) = {1, 0.6, 0, h}; Point(4) = {0, 0.6, 0, h};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Recombine Surface{1};
Physical Curve("wall") = {1, 2, 3, 4};
Physical Surface("body") = {1};
