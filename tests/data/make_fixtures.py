#!/usr/bin/env python3
"""Regenerates the gmsh fixtures of tests/properties/gmsh.rs (needs `pip install gmsh`; tested with 4.15).

Run from anywhere: `python3 tests/data/make_fixtures.py`. The .msh files are committed, so the
tests never need gmsh.
"""
import os

import gmsh

HERE = os.path.dirname(os.path.abspath(__file__))
SIDES = ["bottom", "right", "top", "left"]


def start(name):
    gmsh.clear()
    gmsh.model.add(name)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.option.setNumber("Mesh.Binary", 0)
    gmsh.option.setNumber("Mesh.SaveAll", 0)
    gmsh.option.setNumber("Mesh.ElementOrder", 1)
    gmsh.option.setNumber("Mesh.RecombineAll", 0)


def write(name):
    gmsh.write(os.path.join(HERE, name))


def square(h, groups=True):
    """Unit square [0,1]² (geo kernel); returns (surface, [bottom, right, top, left] curves)."""
    geo = gmsh.model.geo
    p = [geo.addPoint(x, y, 0, h) for x, y in [(0, 0), (1, 0), (1, 1), (0, 1)]]
    c = [geo.addLine(p[i], p[(i + 1) % 4]) for i in range(4)]
    s = geo.addPlaneSurface([geo.addCurveLoop(c)])
    geo.synchronize()
    if groups:
        gmsh.model.addPhysicalGroup(2, [s], name="plate")
        for curve, side in zip(c, SIDES):
            gmsh.model.addPhysicalGroup(1, [curve], name=side)
    return s, c


def square_tri():
    start("square_tri")
    square(0.08)
    gmsh.model.mesh.generate(2)
    write("square_tri_ascii.msh")
    gmsh.option.setNumber("Mesh.MshFileVersion", 2.2)
    write("msh22.msh")
    # ASCII keeps 16 significant digits, which does not round-trip every double: the binary
    # twin is written from the ASCII file as read back, so both hold the very same numbers.
    gmsh.clear()
    gmsh.open(os.path.join(HERE, "square_tri_ascii.msh"))
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.option.setNumber("Mesh.Binary", 1)
    write("square_tri_binary.msh")
    gmsh.option.setNumber("Mesh.Binary", 0)


def square_quad():
    start("square_quad")
    s, c = square(1.0)
    for curve in c:
        gmsh.model.mesh.setTransfiniteCurve(curve, 9)
    gmsh.model.mesh.setTransfiniteSurface(s)
    gmsh.model.mesh.setRecombine(2, s)
    gmsh.model.mesh.generate(2)
    write("square_quad.msh")


def line():
    start("line")
    geo = gmsh.model.geo
    a, b = geo.addPoint(0, 0, 0), geo.addPoint(1, 0, 0)
    bar = geo.addLine(a, b)
    geo.synchronize()
    gmsh.model.mesh.setTransfiniteCurve(bar, 11)
    gmsh.model.addPhysicalGroup(1, [bar], name="bar")
    gmsh.model.addPhysicalGroup(0, [a], name="left")
    gmsh.model.addPhysicalGroup(0, [b], name="right")
    gmsh.model.mesh.generate(1)
    write("line.msh")


def cube_hex():
    start("cube_hex")
    s, c = square(1.0, groups=False)
    for curve in c:
        gmsh.model.geo.mesh.setTransfiniteCurve(curve, 3)
    gmsh.model.geo.mesh.setTransfiniteSurface(s)
    gmsh.model.geo.mesh.setRecombine(2, s)
    out = gmsh.model.geo.extrude([(2, s)], 0, 0, 1, numElements=[2], recombine=True)
    gmsh.model.geo.synchronize()
    volume = [tag for dim, tag in out if dim == 3]
    gmsh.model.addPhysicalGroup(3, volume, name="block")
    gmsh.model.addPhysicalGroup(2, [s], name="bottom")
    gmsh.model.mesh.generate(3)
    write("cube_hex.msh")


def cube_hex_faces():
    """Unit cube of 5 × 5 × 5 hexahedra with all six faces named x_min ... z_max."""
    start("cube_hex_faces")
    box = gmsh.model.occ.addBox(0, 0, 0, 1, 1, 1)
    gmsh.model.occ.synchronize()
    for dim, tag in gmsh.model.getEntities(1):
        gmsh.model.mesh.setTransfiniteCurve(tag, 6)
    for dim, tag in gmsh.model.getEntities(2):
        gmsh.model.mesh.setTransfiniteSurface(tag)
        gmsh.model.mesh.setRecombine(2, tag)
    gmsh.model.mesh.setTransfiniteVolume(box)
    gmsh.model.addPhysicalGroup(3, [box], name="block")
    eps = 1e-3  # OpenCASCADE pads bounding boxes, so the search box must be wider
    for name, (axis, value) in {"x_min": (0, 0.0), "x_max": (0, 1.0), "y_min": (1, 0.0),
                                "y_max": (1, 1.0), "z_min": (2, 0.0), "z_max": (2, 1.0)}.items():
        lo = [-eps] * 3
        hi = [1 + eps] * 3
        lo[axis] = value - eps
        hi[axis] = value + eps
        faces = gmsh.model.getEntitiesInBoundingBox(*lo, *hi, dim=2)
        gmsh.model.addPhysicalGroup(2, [t for _, t in faces], name=name)
    gmsh.model.mesh.generate(3)
    write("cube_hex_faces.msh")


def cube_tet():
    start("cube_tet")
    box = gmsh.model.occ.addBox(0, 0, 0, 1, 1, 1)
    gmsh.model.occ.synchronize()
    gmsh.model.mesh.setSize(gmsh.model.getEntities(0), 0.5)
    gmsh.model.addPhysicalGroup(3, [box], name="block")
    gmsh.model.mesh.generate(3)
    write("cube_tet.msh")


def no_groups():
    start("no_groups")
    square(0.25, groups=False)
    gmsh.option.setNumber("Mesh.SaveAll", 1)
    gmsh.model.mesh.generate(2)
    write("no_groups.msh")


def unmeshed():
    start("unmeshed")
    square(0.25)
    write("unmeshed.msh")


def second_order():
    start("second_order")
    square(0.25)
    gmsh.option.setNumber("Mesh.ElementOrder", 2)
    gmsh.model.mesh.generate(2)
    write("second_order.msh")


if __name__ == "__main__":
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    for make in [square_tri, square_quad, line, cube_hex, cube_hex_faces, cube_tet, no_groups, second_order,
                 unmeshed]:
        make()
    gmsh.finalize()
