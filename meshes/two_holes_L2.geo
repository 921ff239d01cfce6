// dim: 2
// Plate with two holes and refined rings of mesh ratio 8 (issues 33 and 34), level 2 of 3:
// element size h = 0.0003 m in the rings, 8 h in the far field (each level halves h). Geometry and
// groups: two_holes.inc.
h = 0.0003;
Include "two_holes.inc";
