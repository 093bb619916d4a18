#!/usr/bin/env python3
"""Independent read-back of drape's exports (not drape's own code: meshio, csv and json).

Usage: python3 tools/readback.py PLY.vtu PLY.cells.csv PLY.drape.json [--cells]

Prints one JSON object to stdout:
  points, quads, other_cells        counts in the .vtu (other_cells: cells that are not quads)
  cell_data_shapes, point_data_shapes   {name: shape} of the .vtu arrays
  shear_deg_min, shear_deg_max      over the .vtu cells
  max_warp_norm_err, max_weft_norm_err, max_normal_norm_err   max |norm(v) - 1|
  max_warp_dot_normal, max_weft_dot_normal                    max |v . normal|
  connectivity_errors               quads whose corners are not (i,j),(i+1,j),(i+1,j+1),(i,j+1)
                                    by the points' node_i/node_j
  json_grid, json_placed, json_nodes_non_null
  max_point_vs_json_node            max |point - json node| over the .vtu points
  json_cell_shear_non_null          non-null entries of cell_shear_deg
  json_cells_not_in_vtu, vtu_cells_not_in_json   set differences of the non-null cells
  max_json_vs_vtu_shear_deg         max |cell_shear_deg - shear_deg(vtu)| matched by (i, j)
  csv_rows, csv_cells_not_in_vtu, vtu_cells_not_in_csv
  max_csv_vs_vtu_shear_deg          max |shear_deg(csv) - shear_deg(vtu)| matched by (i, j)
  max_csv_vs_vtu_direction          max abs difference of warp/weft/normal components
  cells                             (with --cells) sorted [i, j] of the .vtu quads
Non-finite numbers are printed as the strings "nan", "inf", "-inf".
Exit status 2 on a missing file or bad arguments.
"""
import csv
import json
import math
import sys

import meshio
import numpy as np


def fmax(values):
    """Max of an iterable of floats, 0.0 when empty; NaN propagates."""
    m = 0.0
    for v in values:
        v = float(v)
        if math.isnan(v):
            return float("nan")
        m = max(m, v)
    return m


def finite_or_text(v):
    """Non-finite floats as the strings "nan", "inf", "-inf" so the output stays strict JSON."""
    if isinstance(v, float) and not math.isfinite(v):
        return str(v)
    if isinstance(v, dict):
        return {k: finite_or_text(x) for k, x in v.items()}
    if isinstance(v, list):
        return [finite_or_text(x) for x in v]
    return v


def main(argv):
    args = [a for a in argv if not a.startswith("--")]
    if len(args) != 3 or any(a not in ("--cells",) for a in argv if a.startswith("--")):
        print(__doc__, file=sys.stderr)
        return 2
    vtu_path, csv_path, json_path = args
    out = {}

    mesh = meshio.read(vtu_path)
    points = np.asarray(mesh.points, dtype=float)
    out["points"] = int(points.shape[0])
    quads = None
    other = 0
    cell_data = {}
    for b, block in enumerate(mesh.cells):
        if block.type == "quad":
            if quads is not None:
                raise SystemExit("more than one quad block in " + vtu_path)
            quads = np.asarray(block.data)
            cell_data = {name: np.asarray(arrays[b]) for name, arrays in mesh.cell_data.items()}
        else:
            other += len(block.data)
    if quads is None:
        quads = np.zeros((0, 4), dtype=int)
    out["quads"] = int(quads.shape[0])
    out["other_cells"] = other
    out["cell_data_shapes"] = {k: list(v.shape) for k, v in sorted(cell_data.items())}
    out["point_data_shapes"] = {k: list(np.asarray(v).shape) for k, v in sorted(mesh.point_data.items())}

    shear = cell_data.get("shear_deg", np.zeros(0))
    out["shear_deg_min"] = float(shear.min()) if shear.size else None
    out["shear_deg_max"] = float(shear.max()) if shear.size else None
    vec = {k: cell_data.get(k, np.zeros((0, 3))) for k in ("warp", "weft", "normal")}
    for k, v in vec.items():
        out[f"max_{k}_norm_err"] = fmax(np.abs(np.linalg.norm(v, axis=1) - 1.0)) if len(v) else 0.0
    for k in ("warp", "weft"):
        n = min(len(vec[k]), len(vec["normal"]))
        out[f"max_{k}_dot_normal"] = fmax(np.abs(np.sum(vec[k][:n] * vec["normal"][:n], axis=1)))

    ci = cell_data.get("cell_i", np.zeros(0, dtype=int)).astype(int)
    cj = cell_data.get("cell_j", np.zeros(0, dtype=int)).astype(int)
    vtu_cells = {(int(i), int(j)): c for c, (i, j) in enumerate(zip(ci, cj))}
    ni = np.asarray(mesh.point_data.get("node_i", np.zeros(0)), dtype=int)
    nj = np.asarray(mesh.point_data.get("node_j", np.zeros(0)), dtype=int)
    bad = 0
    for c, (i, j) in enumerate(zip(ci, cj)):
        want = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)]
        got = [(int(ni[p]), int(nj[p])) for p in quads[c]]
        bad += got != want
    out["connectivity_errors"] = bad

    with open(json_path, encoding="utf-8") as f:
        net = json.load(f)
    nu, nv = net["grid"]
    out["json_grid"] = [nu, nv]
    out["json_placed"] = net["status"]["placed"]
    out["json_nodes_non_null"] = sum(n is not None for n in net["nodes"])
    node_err = 0.0
    for p in range(len(points)):
        node = net["nodes"][int(ni[p]) * nv + int(nj[p])]
        node_err = max(node_err, float("inf") if node is None else float(np.max(np.abs(points[p] - node))))
    out["max_point_vs_json_node"] = node_err
    shears = net["cell_shear_deg"]
    json_cells = {(k // (nv - 1), k % (nv - 1)): s for k, s in enumerate(shears) if s is not None}
    out["json_cell_shear_non_null"] = len(json_cells)
    out["json_cells_not_in_vtu"] = len(set(json_cells) - set(vtu_cells))
    out["vtu_cells_not_in_json"] = len(set(vtu_cells) - set(json_cells))
    out["max_json_vs_vtu_shear_deg"] = fmax(abs(s - shear[vtu_cells[ij]]) for ij, s in json_cells.items() if ij in vtu_cells)

    with open(csv_path, newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    out["csv_rows"] = len(rows)
    csv_cells = {(int(r["i"]), int(r["j"])): r for r in rows}
    out["csv_cells_not_in_vtu"] = len(set(csv_cells) - set(vtu_cells))
    out["vtu_cells_not_in_csv"] = len(set(vtu_cells) - set(csv_cells))
    both = [(r, vtu_cells[ij]) for ij, r in csv_cells.items() if ij in vtu_cells]
    out["max_csv_vs_vtu_shear_deg"] = fmax(abs(float(r["shear_deg"]) - shear[c]) for r, c in both)
    out["max_csv_vs_vtu_direction"] = fmax(
        abs(float(r[f"{k}_{x}"]) - vec[k][c][a]) for r, c in both for k in vec for a, x in enumerate("xyz")
    )
    if "--cells" in argv:
        out["cells"] = sorted([i, j] for i, j in vtu_cells)
    json.dump(finite_or_text(out), sys.stdout, indent=1, allow_nan=False)
    print()
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main(sys.argv[1:]))
    except FileNotFoundError as e:
        print(f"readback: {e}", file=sys.stderr)
        sys.exit(2)
