// dim: 3
// Property-test mesh: the box [0, 1] x [0, 0.8] x [0, 0.6] of hexahedra: unstructured
// quadrangles of size 0.1 in z = 0 extruded in 6 layers, all faces in one group `wall`
// (tests/weights.rs).
h = 0.1;
Point(1) = {0, 0, 0, h}; Point(2) = {1, 0, 0, h}; Point(3) = {1, 0.8, 0, h}; Point(4) = {0, 0.8, 0, h};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Recombine Surface{1};
out[] = Extrude {0, 0, 0.6} { Surface{1}; Layers{6}; Recombine; };
Physical Surface("wall") = {1, out[0], out[2], out[3], out[4], out[5]};
Physical Volume("body") = {out[1]};
