#!/usr/bin/env python3
"""Open pfem output with VTK's own readers and print what VTK sees.

Usage: python3 docs/check_vtu.py FILE.vtu|FILE.pvd [...]

For a .vtu: point and cell counts, cell types, point/cell/field array names
with their component counts and value ranges. For a .pvd: the same for each
listed dataset, with its timestep. Exits non-zero when VTK reports an error or
a file has no points or an array of the wrong length. Needs the `vtk` Python
package (`pip install vtk`).

Sample files from the test suite (2D ASCII and base64 frames with every field
kind, a 3D series with its .pvd):

    PFEM_VTU_SAMPLE_DIR=/tmp/vtu cargo test -p pfem-io --test output_vtu write_samples -- --ignored
    python3 docs/check_vtu.py /tmp/vtu/*.vtu /tmp/vtu/series3d.pvd
"""

import os
import sys
import xml.etree.ElementTree as ET

import vtk  # noqa: E402  (imported after the docstring on purpose)
from vtk.util.numpy_support import vtk_to_numpy

CELL_NAMES = {1: "vertex", 5: "triangle", 10: "tetra"}


class ErrorObserver:
    """Collects VTK error messages instead of letting them scroll by."""

    def __init__(self):
        self.messages = []

    def __call__(self, obj, event):
        self.messages.append(event)


def arrays(data):
    out = []
    for i in range(data.GetNumberOfArrays()):
        a = data.GetAbstractArray(i)
        desc = f"{a.GetName()}[{a.GetNumberOfComponents()}] {a.GetDataTypeAsString()}"
        if hasattr(a, "GetRange") and a.GetNumberOfTuples() > 0:
            lo, hi = a.GetRange(-1) if a.GetNumberOfComponents() > 1 else a.GetRange()
            desc += f" range {lo:.6g}..{hi:.6g}"
        out.append(desc)
    return out


def check_vtu(path, indent=""):
    reader = vtk.vtkXMLUnstructuredGridReader()
    observer = ErrorObserver()
    reader.AddObserver("ErrorEvent", observer)
    reader.GetExecutive().AddObserver("ErrorEvent", observer)
    reader.SetFileName(path)
    reader.Update()
    grid = reader.GetOutput()
    n_points, n_cells = grid.GetNumberOfPoints(), grid.GetNumberOfCells()
    types = {}
    for k in range(n_cells):
        t = grid.GetCellType(k)
        types[CELL_NAMES.get(t, t)] = types.get(CELL_NAMES.get(t, t), 0) + 1
    print(f"{indent}{path}: {n_points} points, {n_cells} cells {types}")
    print(f"{indent}  point data: {arrays(grid.GetPointData())}")
    print(f"{indent}  cell data:  {arrays(grid.GetCellData())}")
    fd = grid.GetFieldData()
    if fd.GetNumberOfArrays():
        tv = fd.GetArray("TimeValue")
        extra = f" TimeValue = {tv.GetValue(0)}" if tv is not None else ""
        print(f"{indent}  field data: {arrays(fd)}{extra}")
    if n_points > 0:
        pts = vtk_to_numpy(grid.GetPoints().GetData())
        print(f"{indent}  bounds: {pts.min(axis=0)} .. {pts.max(axis=0)}")
    ok = not observer.messages and n_points > 0
    for where, data, n in (("point", grid.GetPointData(), n_points), ("cell", grid.GetCellData(), n_cells)):
        for i in range(data.GetNumberOfArrays()):
            a = data.GetAbstractArray(i)
            if a.GetNumberOfTuples() != n:
                print(f"{indent}  {where} array {a.GetName()} has {a.GetNumberOfTuples()} tuples, expected {n}")
                ok = False
    if observer.messages:
        print(f"{indent}  VTK reported errors: {observer.messages}")
    return ok


def check_pvd(path):
    ok = True
    base = os.path.dirname(os.path.abspath(path))
    root = ET.parse(path).getroot()
    sets = root.findall("./Collection/DataSet")
    print(f"{path}: collection of {len(sets)} datasets")
    for ds in sets:
        print(f"  timestep {ds.get('timestep')}:")
        ok &= check_vtu(os.path.join(base, ds.get("file")), indent="    ")
    # Also let VTK's own collection reader walk the time steps.
    reader = vtk.vtkPVDReader() if hasattr(vtk, "vtkPVDReader") else None
    if reader is not None:
        reader.SetFileName(path)
        reader.UpdateInformation()
        print(f"  vtkPVDReader time steps: {reader.GetNumberOfTimeSteps()}")
    return ok


def main(argv):
    if len(argv) < 2:
        print(__doc__)
        return 2
    print(f"VTK {vtk.vtkVersion.GetVTKVersion()}")
    ok = True
    for path in argv[1:]:
        ok &= check_pvd(path) if path.endswith(".pvd") else check_vtu(path)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
