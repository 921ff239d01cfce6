// dim: 2
// Seed 003 Example 3: square plate [-0.01, 0.01]² (units: metres, z = 0) with a crack
// from (-0.005, 0) to (0.005, 0), a curve embedded in the surface so that mesh edges follow
// it. Uniform triangles of size h = 1.25e-4 m everywhere (80 edges along the crack).
SetFactory("Built-in");
Mesh.Algorithm = 6;          // Frontal-Delaunay
General.NumThreads = 1;
Mesh.ElementOrder = 1;

L = 0.01;
a = 0.005;                   // crack half-length
h = 1.25e-4;

Point(1) = {-L, -L, 0, h};
Point(2) = { L, -L, 0, h};
Point(3) = { L,  L, 0, h};
Point(4) = {-L,  L, 0, h};
Point(5) = {-a,  0, 0, h};
Point(6) = { a,  0, 0, h};
Line(1) = {1, 2};   // bottom
Line(2) = {2, 3};   // right
Line(3) = {3, 4};   // top
Line(4) = {4, 1};   // left
Line(5) = {5, 6};   // crack
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Curve{5} In Surface{1};

// Size h everywhere, from a constant field only.
Field[1] = MathEval;
Field[1].F = Sprintf("%g", h);
Background Field = 1;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;

Physical Surface("plate") = {1};
Physical Curve("bottom") = {1};
Physical Curve("right") = {2};
Physical Curve("top") = {3};
Physical Curve("left") = {4};
Physical Curve("crack") = {5};
