#!/usr/bin/env python3
"""Read a .vtu with VTK's own reader (vtkXMLUnstructuredGridReader), not drape's code.

Usage: python3 tools/vtu_vtk_readback.py FILE.vtu OUTDIR

Writes every array as raw little-endian float64 to OUTDIR/<kind>.<name>.f64 (kind: points,
cells (connectivity, offsets, types), cell, point), integers converted exactly, NaN kept, and
prints one JSON object: {"points": n, "cells": n, "arrays": {"<kind>.<name>": [tuples,
components]}, "encoding": the VTKFile attributes VTK saw (compressor, header_type)}.
Exit status 2 on bad arguments or a file VTK cannot read.
"""
import json
import os
import re
import sys

import numpy as np
import vtk
from vtk.util.numpy_support import vtk_to_numpy


def main():
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    path, out = sys.argv[1], sys.argv[2]
    os.makedirs(out, exist_ok=True)
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(path)
    reader.Update()
    if reader.GetErrorCode() != 0:
        print("VTK could not read %s" % path, file=sys.stderr)
        sys.exit(2)
    grid = reader.GetOutput()
    arrays = {}

    def dump(key, a):
        a = np.asarray(a)
        tuples = a.shape[0] if a.ndim else 0
        comps = a.shape[1] if a.ndim > 1 else 1
        a.astype("<f8").tofile(os.path.join(out, key + ".f64"))
        arrays[key] = [tuples, comps]

    dump("points.Points", vtk_to_numpy(grid.GetPoints().GetData()))
    cells = grid.GetCells()
    dump("cells.connectivity", vtk_to_numpy(cells.GetConnectivityArray()))
    dump("cells.offsets", vtk_to_numpy(cells.GetOffsetsArray())[1:])
    dump("cells.types", vtk_to_numpy(grid.GetCellTypesArray()))
    for kind, data in (("cell", grid.GetCellData()), ("point", grid.GetPointData())):
        for k in range(data.GetNumberOfArrays()):
            a = data.GetArray(k)
            dump("%s.%s" % (kind, a.GetName()), vtk_to_numpy(a))
    with open(path, "rb") as f:
        head = f.read(400).decode("latin-1")
    m = re.search(r"<VTKFile[^>]*>", head)
    attrs = dict(re.findall(r'(\w+)="([^"]*)"', m.group(0))) if m else {}
    print(json.dumps({
        "points": grid.GetNumberOfPoints(),
        "cells": grid.GetNumberOfCells(),
        "arrays": arrays,
        "encoding": {k: attrs.get(k) for k in ("version", "compressor", "header_type")},
    }))


main()
