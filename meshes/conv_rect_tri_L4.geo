// dim: 2
// Mesh-convergence suite (issue 14), rectangle of gmsh default triangles, level 4 of 4:
// element size h = 0.003125 m (each level halves h). Geometry and groups: conv_rect.inc.
h = 0.003125;
Include "conv_rect.inc";
