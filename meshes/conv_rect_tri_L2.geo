// dim: 2
// Mesh-convergence suite (issue 14), rectangle of gmsh default triangles, level 2 of 4:
// element size h = 0.0125 m (each level halves h). Geometry and groups: conv_rect.inc.
h = 0.0125;
Include "conv_rect.inc";
