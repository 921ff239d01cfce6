// dim: 2
// The axisymmetric phase-change paper (doi:10.1007/s42102-022-00092-3) §3.4 (Fig. 8): the (r, z)
// section of a thick pipe heated on part of its outer surface, for the Fig. 11 study (Δ = 0.04 m).
// Units: metres; x = r, y = z (z = 0 plane of the file). The square r ∈ [0.4, 1.2] × z ∈ [0, 0.8]
// (0.8 × 0.8 m as in the paper; the inner radius
// 0.4 m is our choice: the paper does not give it, and mirrored layers one horizon thick at
// the inner surface must stay at r > 0 for the largest horizon of the study, δ = 8 × 0.04 m).
// The heated part of the outer surface r = 1.2 is z ∈ [0.32, 0.52] (L = 0.2 m as in Fig. 8;
// centred at z = 0.42, the cell centre nearest mid-height whose band edges lie on the grid
// lines of all three spacings of the study, 0.04, 0.02 and 0.01 m).
// Structured quadrangles of 0.04 m (20 × 20 = 400 cells; one PD node per cell).
SetFactory("Built-in");
General.NumThreads = 1;
Mesh.ElementOrder = 1;

Point(1) = {0.4, 0.0, 0};
Point(2) = {1.2, 0.0, 0};
Point(3) = {1.2, 0.32, 0};
Point(4) = {1.2, 0.52, 0};
Point(5) = {1.2, 0.8, 0};
Point(6) = {0.4, 0.8, 0};
Line(1) = {1, 2};   // bottom z = 0
Line(2) = {2, 3};   // outer, below the heated band
Line(3) = {3, 4};   // outer, heated band
Line(4) = {4, 5};   // outer, above the heated band
Line(5) = {5, 6};   // top z = 0.8
Line(6) = {6, 1};   // inner r = 0.4
Curve Loop(1) = {1, 2, 3, 4, 5, 6};
Plane Surface(1) = {1};

Transfinite Curve{1, 5, 6} = 21;
Transfinite Curve{2} = 9;
Transfinite Curve{3} = 6;
Transfinite Curve{4} = 8;
Transfinite Surface{1} = {1, 2, 5, 6};
Recombine Surface{1};

Physical Surface("pipe") = {1};
Physical Curve("heated") = {3};
Physical Curve("insulated") = {1, 2, 4, 5, 6};
