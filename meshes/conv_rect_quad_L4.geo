// dim: 2
// Mesh-convergence suite (issue 14), rectangle of quadrangles, level 4 of 4: gmsh's default
// triangulation of size h = 0.003125 m recombined into quadrangles (each level halves h).
// Geometry and groups: conv_rect.inc.
h = 0.003125;
Include "conv_rect.inc";
Recombine Surface{1};     // quadrangles: gmsh's default recombination of the triangles
