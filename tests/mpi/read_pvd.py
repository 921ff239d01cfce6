"""Opens a run's fields.pvd with VTK's own readers (vtkPVDReader is ParaView's; plain VTK
reads the .pvd's parallel files with vtkXMLPUnstructuredGridReader) and checks each output
against the run's field_<k>.csv: one dataset per output time, every body node exactly once,
the same positions and temperatures. Used by tests/mpi (needs `pip install vtk numpy`).

Usage: python3 read_pvd.py RUN_DIR
Prints one line per output time; exits non-zero on the first disagreement."""

import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import vtk
from vtk.util.numpy_support import vtk_to_numpy


def read(path: Path):
    """The dataset of a .pvtu or .vtu file, read by VTK's XML readers."""
    if path.suffix == ".pvtu":
        reader = vtk.vtkXMLPUnstructuredGridReader()
    else:
        reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(str(path))
    reader.Update()
    return reader.GetOutput()


def main(run: Path) -> int:
    series = ET.parse(run / "fields.pvd").getroot().find("Collection")
    entries = [(float(d.get("timestep")), d.get("file")) for d in series.findall("DataSet")]
    if not entries:
        print("fields.pvd lists no dataset")
        return 1
    for k, (t, name) in enumerate(entries, start=1):
        grid = read(run / name)
        points = vtk_to_numpy(grid.GetPoints().GetData())
        theta = vtk_to_numpy(grid.GetPointData().GetArray("temperature"))
        csv = np.loadtxt(run / f"field_{k}.csv", delimiter=",", skiprows=1, usecols=(0, 1, 2, 3))
        if grid.GetNumberOfPoints() != len(csv):
            print(f"{name}: {grid.GetNumberOfPoints()} points, the CSV has {len(csv)} nodes")
            return 1
        # every node once: the points, sorted, are the CSV's positions, sorted
        order_v = np.lexsort(points.T[::-1])
        order_c = np.lexsort(csv[:, :3].T[::-1])
        if not np.array_equal(points[order_v], csv[order_c, :3]):
            print(f"{name}: the points are not the CSV's nodes")
            return 1
        if len(np.unique(points, axis=0)) != len(points):
            print(f"{name}: a node appears twice")
            return 1
        if not np.array_equal(theta[order_v], csv[order_c, 3]):
            print(f"{name}: the temperatures differ from the CSV's")
            return 1
        print(f"{name}: t = {t:g} s, {len(points)} nodes, one dataset, as field_{k}.csv")
    return 0


if __name__ == "__main__":
    sys.exit(main(Path(sys.argv[1])))
