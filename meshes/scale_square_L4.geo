// dim: 2
// Set-up scaling family (issue 33), unit square of gmsh default triangles, level 4 of 4:
// element size h = 0.0015 m (each level halves h, four times the nodes). Geometry: scale_square.inc.
h = 0.0015;
Include "scale_square.inc";
