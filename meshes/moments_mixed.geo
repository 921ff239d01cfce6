// dim: 2
// Property-test mesh: a 1 x 0.6 rectangle, left half quadrangles, right half triangles
// (conformal at x = 0.5), group `wall` on the outer sides (tests/weights.rs).
h = 0.04;
Point(1) = {0, 0, 0, h}; Point(2) = {0.5, 0, 0, h}; Point(3) = {1, 0, 0, h};
Point(4) = {1, 0.6, 0, h}; Point(5) = {0.5, 0.6, 0, h}; Point(6) = {0, 0.6, 0, h};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 5}; Line(5) = {5, 6};
Line(6) = {6, 1}; Line(7) = {2, 5};
Curve Loop(1) = {1, 7, 5, 6}; Plane Surface(1) = {1};
Curve Loop(2) = {2, 3, 4, -7}; Plane Surface(2) = {2};
Recombine Surface{1};
Physical Curve("wall") = {1, 2, 3, 4, 5, 6};
Physical Surface("body") = {1, 2};
