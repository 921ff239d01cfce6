// dim: 3
// Cube [0, 0.01]³ (units: metres) with a refined sub-block [0, 0.004]³ at the origin corner.
// Tetrahedra of size 4e-4 m in the sub-block ("fine") and 1e-3 m elsewhere ("coarse").
// OpenCASCADE: the two boxes are fragmented so the mesh is conformal across their interface.
// Boundary groups are the cube's outer faces (both volumes' faces on each plane; the interior
// faces x, y or z = 0.004 are in no group).
SetFactory("OpenCASCADE");
Mesh.Algorithm = 6;          // Frontal-Delaunay (surfaces)
Mesh.Algorithm3D = 1;        // Delaunay (serial, deterministic)
General.NumThreads = 1;
Mesh.ElementOrder = 1;

L = 0.01;
s = 0.004;
hf = 4e-4;
hc = 1e-3;
e = 1e-6;                    // bounding-box tolerance

Box(1) = {0, 0, 0, L, L, L};
Box(2) = {0, 0, 0, s, s, s};
BooleanFragments{ Volume{1}; Delete; }{ Volume{2}; Delete; }

fine() = Volume In BoundingBox{-e, -e, -e, s + e, s + e, s + e};
all() = Volume{:};
coarse() = all();
coarse() -= fine();

// Sizes: hf in (and on the boundary of) the sub-block, hc elsewhere.
Field[1] = Constant;
Field[1].VIn = hf;
Field[1].VOut = hc;
Field[1].VolumesList = {fine()};
Field[1].IncludeBoundary = 1;
Background Field = 1;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;

Physical Volume("fine") = {fine()};
Physical Volume("coarse") = {coarse()};
Physical Surface("x_min") = Surface In BoundingBox{-e, -e, -e, e, L + e, L + e};
Physical Surface("x_max") = Surface In BoundingBox{L - e, -e, -e, L + e, L + e, L + e};
Physical Surface("y_min") = Surface In BoundingBox{-e, -e, -e, L + e, e, L + e};
Physical Surface("y_max") = Surface In BoundingBox{-e, L - e, -e, L + e, L + e, L + e};
Physical Surface("z_min") = Surface In BoundingBox{-e, -e, -e, L + e, L + e, e};
Physical Surface("z_max") = Surface In BoundingBox{-e, -e, L - e, L + e, L + e, L + e};
