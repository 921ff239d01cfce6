// dim: 2
// Bobaru & Duangpanya 2012 Example 3 with a refined zone: square plate [-0.01, 0.01]² (units:
// metres, z = 0) with a crack from (-0.005, 0) to (0.005, 0), a curve embedded in the surface so
// that mesh edges follow it. The zone |x| <= 0.0065, |y| <= 0.0015 (crack, tips and 1.5 mm around
// them) has triangles of size h = 1.25e-4 m, meshed exactly as in crack_plate_uniform.geo;
// the far field grows linearly over a 2 mm band to 4.5 h (Box field with Thickness).
SetFactory("Built-in");
Mesh.Algorithm = 6;          // Frontal-Delaunay
General.NumThreads = 1;
Mesh.ElementOrder = 1;

L = 0.01;
a = 0.005;                   // crack half-length
h = 1.25e-4;
zx = 0.0065;                 // the zone around the crack: |x| <= zx, |y| <= zy
zy = 0.0015;

Point(1) = {-L, -L, 0};
Point(2) = { L, -L, 0};
Point(3) = { L,  L, 0};
Point(4) = {-L,  L, 0};
Point(5) = {-a,  0, 0};
Point(6) = { a,  0, 0};
Point(7) = {-zx, -zy, 0};
Point(8) = { zx, -zy, 0};
Point(9) = { zx,  zy, 0};
Point(10) = {-zx, zy, 0};
Line(1) = {1, 2};   // bottom
Line(2) = {2, 3};   // right
Line(3) = {3, 4};   // top
Line(4) = {4, 1};   // left
Line(5) = {5, 6};   // crack
Line(6) = {7, 8};   // zone boundary
Line(7) = {8, 9};
Line(8) = {9, 10};
Line(9) = {10, 7};
// The zone's sides and the crack are divided into pieces of length h in both crack-plate
// meshes, so the zone (crack, tips and 1.5 mm around them) is meshed identically in both.
Transfinite Curve{6, 8} = 105;   // 104 segments of h over 0.013 m
Transfinite Curve{7, 9} = 25;    // 24 segments over 0.003 m
Transfinite Curve{5} = 81;       // 80 segments over the crack
Curve Loop(1) = {1, 2, 3, 4};
Curve Loop(2) = {6, 7, 8, 9};
Plane Surface(1) = {2};          // zone
Plane Surface(2) = {1, 2};       // far field
Curve{5} In Surface{1};

Field[1] = Box;
Field[1].VIn = h;
Field[1].VOut = 4.5 * h;
Field[1].XMin = -zx;
Field[1].XMax =  zx;
Field[1].YMin = -zy;
Field[1].YMax =  zy;
Field[1].ZMin = -1;
Field[1].ZMax =  1;
Field[1].Thickness = 0.002;
Background Field = 1;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;

Physical Surface("zone") = {1};
Physical Surface("far") = {2};
Physical Curve("bottom") = {1};
Physical Curve("right") = {2};
Physical Curve("top") = {3};
Physical Curve("left") = {4};
Physical Curve("crack") = {5};
