// dim: 2
// Mesh-convergence suite (issue 14), disc of gmsh default triangles, level 2 of 4: element
// size h = 0.0125 m on the disc of radius 0.5 m (each level halves h). Geometry: conv_disc.inc.
h = 0.0125;
Include "conv_disc.inc";
