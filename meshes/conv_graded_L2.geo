// dim: 2
// Mesh-convergence suite (issue 14), graded rectangle of gmsh default triangles, level 2 of 4:
// far-field size h = 0.025 m, a refined zone of size h/4 (each level halves both).
// Geometry and groups: conv_rect.inc.
h = 0.025;
Include "conv_rect.inc";
// The refined zone: size h/4 inside the box [0.45, 0.55] × [0.25, 0.35], growing to h over a
// transition of 0.05 m around it (ratio 4 between the zone and the far field).
Field[1] = Box;
Field[1].VIn = h / 4;
Field[1].VOut = h;
Field[1].XMin = 0.45;
Field[1].XMax = 0.55;
Field[1].YMin = 0.25;
Field[1].YMax = 0.35;
Field[1].Thickness = 0.05;
Background Field = 1;
