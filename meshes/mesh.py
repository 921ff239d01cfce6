#!/usr/bin/env python3
"""Mesh one gmsh .geo file into an MSH 4.1 ASCII file (used by scripts/regenerate-meshes.sh).

Usage: python3 meshes/mesh.py IN.geo OUT.msh

The mesh dimension is read from a `// dim: N` comment line in the .geo (else the model's
dimension). Meshing is made deterministic: one thread, first-order elements, and the 2D/3D
algorithms fixed (a .geo may choose its own 2D algorithm; the driver only fills defaults).
Prints one line: the file name, the element count of the top dimension, and the count per
physical group.
"""
import re
import sys

import gmsh


def declared_dim(path):
    with open(path, encoding="utf-8") as f:
        for line in f:
            m = re.match(r"\s*//\s*dim:\s*([123])\s*$", line)
            if m:
                return int(m.group(1))
    return None


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: mesh.py IN.geo OUT.msh")
    geo, msh = sys.argv[1], sys.argv[2]
    gmsh.initialize(["gmsh", "-nopopup"], readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Verbosity", 2)
        gmsh.option.setNumber("General.NumThreads", 1)
        gmsh.option.setNumber("Mesh.MaxNumThreads1D", 1)
        gmsh.option.setNumber("Mesh.MaxNumThreads2D", 1)
        gmsh.option.setNumber("Mesh.MaxNumThreads3D", 1)
        gmsh.option.setNumber("Mesh.Algorithm", 6)     # Frontal-Delaunay (a .geo may override)
        gmsh.option.setNumber("Mesh.Algorithm3D", 1)   # Delaunay (serial, deterministic)
        gmsh.open(geo)
        # Enforced after the .geo is read, whatever it says:
        gmsh.option.setNumber("General.NumThreads", 1)
        gmsh.option.setNumber("Mesh.ElementOrder", 1)
        gmsh.option.setNumber("Mesh.SaveAll", 0)
        dim = declared_dim(geo) or gmsh.model.getDimension()
        gmsh.model.mesh.generate(dim)
        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        gmsh.option.setNumber("Mesh.Binary", 0)
        gmsh.write(msh)

        total = 0
        for tag in [t for d, t in gmsh.model.getEntities(dim)
                    if gmsh.model.getPhysicalGroupsForEntity(d, t)]:
            types, elems, _ = gmsh.model.mesh.getElements(dim, tag)
            total += sum(len(e) for e in elems)
        groups = []
        for d, p in gmsh.model.getPhysicalGroups():
            n = 0
            for tag in gmsh.model.getEntitiesForPhysicalGroup(d, p):
                _, elems, _ = gmsh.model.mesh.getElements(d, tag)
                n += sum(len(e) for e in elems)
            groups.append(f"{gmsh.model.getPhysicalName(d, p)}({d}D)={n}")
        print(f"{msh}: {total} elements of dimension {dim}; " + ", ".join(groups))
    finally:
        gmsh.finalize()


if __name__ == "__main__":
    main()
