// dim: 2
// Wang, Oterkus & Oterkus §4.1 two-region plate, mesh ratio k = Δ1/Δ2 = 0.5 (units: metres, z = 0).
// Square [-0.005, 0.005]² made of two SEPARATE rectangles that share no point or curve:
// the interface x = 0 is two coincident, distinct curves (no Coherence), in no physical group.
// Structured quadrilaterals: Region 1 (x < 0) spacing 1e-4 m (50 × 100 cells),
// Region 2 (x > 0) spacing 2e-4 m (25 × 50 cells).
// The horizon ratio m = δ1/δ2 is set in the case files (cases/dh_plate_k*_m*.toml).
SetFactory("Built-in");
Mesh.Algorithm = 6;
General.NumThreads = 1;
Mesh.ElementOrder = 1;

L = 0.005;
n1x = 50; n1y = 100;   // Region 1 cells
n2x = 25; n2y = 50;    // Region 2 cells

// Region 1: x in [-L, 0]
Point(1) = {-L, -L, 0};
Point(2) = { 0, -L, 0};
Point(3) = { 0,  L, 0};
Point(4) = {-L,  L, 0};
Line(1) = {1, 2};   // bottom
Line(2) = {2, 3};   // interface (region 1 side)
Line(3) = {3, 4};   // top
Line(4) = {4, 1};   // left
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};

// Region 2: x in [0, L], its own points and lines
Point(5) = { 0, -L, 0};
Point(6) = { L, -L, 0};
Point(7) = { L,  L, 0};
Point(8) = { 0,  L, 0};
Line(5) = {5, 6};   // bottom
Line(6) = {6, 7};   // right
Line(7) = {7, 8};   // top
Line(8) = {8, 5};   // interface (region 2 side)
Curve Loop(2) = {5, 6, 7, 8};
Plane Surface(2) = {2};

Transfinite Curve{1, 3} = n1x + 1;
Transfinite Curve{2, 4} = n1y + 1;
Transfinite Curve{5, 7} = n2x + 1;
Transfinite Curve{6, 8} = n2y + 1;
Transfinite Surface{1} = {1, 2, 3, 4};
Transfinite Surface{2} = {5, 6, 7, 8};
Recombine Surface{1, 2};

Physical Surface("region1") = {1};
Physical Surface("region2") = {2};
Physical Curve("left") = {4};
Physical Curve("right") = {6};
Physical Curve("bottom") = {1, 5};
Physical Curve("top") = {3, 7};
