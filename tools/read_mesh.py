#!/usr/bin/env python3
"""Independent reader of flow-mesh fixtures (meshio, not drape's code), for tests/flowmesh_readers.rs.

Usage: python3 tools/read_mesh.py MESH_FILE

Prints one JSON object to stdout:
  ok            true when meshio read the file; false with "error" (meshio's message) if not
  points        number of points
  coords        [[x, y, z], ...] in meshio's point order (file units)
  cells         {meshio cell type: count}
  triangle, quad   connectivity of the 3- and 4-node cells, 0-based point indices, in file order
Exit status 2 on bad arguments; a file meshio cannot read is reported with ok=false, status 0,
so that the test can say which reader failed.
"""
import json
import sys

import meshio


def main():
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    path = sys.argv[1]
    try:
        # meshio cannot tell .bdf from other formats by itself for every extension.
        fmt = None
        low = path.lower()
        if low.endswith((".bdf", ".nas", ".fem", ".blk", ".dat")):
            fmt = "nastran"
        mesh = meshio.read(path, file_format=fmt)
    except Exception as e:  # meshio raises many kinds; the test only needs the message
        print(json.dumps({"ok": False, "error": f"{type(e).__name__}: {e}"}))
        return
    out = {
        "ok": True,
        "points": int(len(mesh.points)),
        "coords": [[float(v) for v in p] + [0.0] * (3 - len(p)) for p in mesh.points],
        "cells": {},
        "triangle": [],
        "quad": [],
    }
    for block in mesh.cells:
        out["cells"][block.type] = out["cells"].get(block.type, 0) + int(len(block.data))
        if block.type in ("triangle", "quad"):
            out[block.type].extend([[int(i) for i in c] for c in block.data])
    print(json.dumps(out))


if __name__ == "__main__":
    main()
