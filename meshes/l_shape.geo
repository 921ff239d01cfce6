// dim: 2
// L-shaped plate with a re-entrant corner at (0.01, 0.01): the square [0, 0.02]² minus
// [0.01, 0.02]² (units: metres, z = 0), triangles of size 4e-4 m.
SetFactory("Built-in");
Mesh.Algorithm = 6;          // Frontal-Delaunay
General.NumThreads = 1;
Mesh.ElementOrder = 1;

h = 4e-4;

Point(1) = {0,    0,    0, h};
Point(2) = {0.02, 0,    0, h};
Point(3) = {0.02, 0.01, 0, h};
Point(4) = {0.01, 0.01, 0, h};   // re-entrant corner
Point(5) = {0.01, 0.02, 0, h};
Point(6) = {0,    0.02, 0, h};
Line(1) = {1, 2};   // y = 0
Line(2) = {2, 3};   // x = 0.02, y in [0, 0.01]
Line(3) = {3, 4};   // y = 0.01, x in [0.01, 0.02]
Line(4) = {4, 5};   // x = 0.01, y in [0.01, 0.02]
Line(5) = {5, 6};   // y = 0.02, x in [0, 0.01]
Line(6) = {6, 1};   // x = 0
Curve Loop(1) = {1, 2, 3, 4, 5, 6};
Plane Surface(1) = {1};

Physical Surface("plate") = {1};
Physical Curve("bottom") = {1};
Physical Curve("left") = {6};
Physical Curve("top") = {5, 3};
Physical Curve("right") = {2, 4};
