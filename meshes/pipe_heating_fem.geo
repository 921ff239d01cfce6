// dim: 2
// The axisymmetric phase-change paper (doi:10.1007/s42102-022-00092-3) §3.4: the FEM reference mesh
// of cases/pipe_heating_2d.toml and of the Fig. 11 study (scripts/pipe-heating-study.sh): the same
// (r, z) section and physical groups as pipe_heating_d*.geo (r ∈ [0.4, 1.2] m, z ∈ [0, 0.8] m,
// heated band r = 1.2 m, z ∈ [0.32, 0.52] m), in triangles graded towards the two ends of the
// heated band. Why graded: where the held band meets the insulated surface the temperature goes as
// s^½ (s the distance to the end), and on uniform elements the FEM converges at first order
// only (measured: ε of quads of 0.04, 0.02, 0.01 m against this mesh's solution 4.6e-3,
// 2.3e-3, 1.1e-3). With elements of 2.5e-4 m at the band ends growing linearly to 5e-3 m
// at 0.1 m from them, halving every size changes the field by ε = 2.7e-5 at 5 h.
SetFactory("Built-in");
General.NumThreads = 1;
Mesh.ElementOrder = 1;
Mesh.Algorithm = 6;

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

// element size: 2.5e-4 m within 2.5e-4 m of a band end, growing linearly to 5e-3 m at 0.1 m
Field[1] = Distance;
Field[1].PointsList = {3, 4};
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = 0.00025;
Field[2].SizeMax = 0.005;
Field[2].DistMin = 0.00025;
Field[2].DistMax = 0.1;
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;

Physical Surface("pipe") = {1};
Physical Curve("heated") = {3};
Physical Curve("insulated") = {1, 2, 4, 5, 6};
