// dim: 2
// Ring between radii 0.005 and 0.01 m centred at the origin (units: metres, z = 0), curved
// boundaries (circle arcs), triangles of size 2.5e-4 m.
SetFactory("Built-in");
Mesh.Algorithm = 6;          // Frontal-Delaunay
General.NumThreads = 1;
Mesh.ElementOrder = 1;

ri = 0.005;
ro = 0.01;
h = 2.5e-4;

Point(1) = {0, 0, 0, h};     // centre (not meshed)
Point(2) = { ri, 0, 0, h};
Point(3) = { 0, ri, 0, h};
Point(4) = {-ri, 0, 0, h};
Point(5) = { 0, -ri, 0, h};
Point(6) = { ro, 0, 0, h};
Point(7) = { 0, ro, 0, h};
Point(8) = {-ro, 0, 0, h};
Point(9) = { 0, -ro, 0, h};
Circle(1) = {2, 1, 3};
Circle(2) = {3, 1, 4};
Circle(3) = {4, 1, 5};
Circle(4) = {5, 1, 2};
Circle(5) = {6, 1, 7};
Circle(6) = {7, 1, 8};
Circle(7) = {8, 1, 9};
Circle(8) = {9, 1, 6};
Curve Loop(1) = {5, 6, 7, 8};   // outer, counter-clockwise
Curve Loop(2) = {1, 2, 3, 4};   // inner (hole)
Plane Surface(1) = {1, 2};

Mesh.MeshSizeFromCurvature = 0;

Physical Surface("ring") = {1};
Physical Curve("inner") = {1, 2, 3, 4};
Physical Curve("outer") = {5, 6, 7, 8};
