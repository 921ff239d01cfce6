// dim: 3
// Mesh-convergence suite (issue 14), unit cube of gmsh default tetrahedra, level 2 of 4:
// element size h = 0.1 m (each level halves h). Geometry and groups: conv_cube.inc.
h = 0.1;
Include "conv_cube.inc";
