#!/usr/bin/env python3
"""Independent read-back of drape's cutting-pattern drawings (not drape's own code).

DXF files are read with ezdxf, SVG files with Python's xml.etree.

Usage: python3 tools/pattern_readback.py FILE.dxf|FILE.svg ...

Prints one JSON object to stdout, {path: summary}, where a DXF summary has
  dxfversion, insunits, layers (sorted layer-table names)
  by_layer: {layer: {closed_polylines, open_polylines, lines, texts, text (list),
             signed_area_mm2, abs_area_mm2, vertices, bbox_mm [xmin, ymin, xmax, ymax] of the
             polylines, text_bbox_mm the same of the texts as ezdxf measures them,
             text_boxes_mm (one [xmin, ymin, xmax, ymax] a text, in the order of `text`),
             loops_mm (the closed polylines' vertices, [[x, y], ...] each),
             self_intersecting (loops that cross or repeat a vertex),
             loops_ccw, loops_cw, max_turn_deg (the largest turn between consecutive edges of
             the closed polylines, degrees), max_edge_mm (their longest edge)}}
and an SVG summary has
  width, height (attribute strings), viewbox [x, y, w, h]
  groups: {id: {data_ply, cut_paths, subpaths, signed_area_mm2 (with y flipped back up),
            abs_area_mm2, fill_rule, warp_paths, warp_segments, text, self_intersecting,
            bbox_mm}}
Exit status 2 on bad arguments or an unreadable file.
"""
import json
import math
import re
import sys
import xml.etree.ElementTree as ET

import ezdxf
import ezdxf.bbox

SVG_NS = "{http://www.w3.org/2000/svg}"


def signed_area(pts):
    """Shoelace area, positive counter-clockwise (y up)."""
    n = len(pts)
    return 0.5 * sum(pts[k][0] * pts[(k + 1) % n][1] - pts[(k + 1) % n][0] * pts[k][1] for k in range(n))


def segments_cross(a, b, c, d):
    """Whether closed segments ab and cd share a point."""
    def orient(p, q, r):
        v = (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])
        return (v > 0) - (v < 0)

    def on(p, q, r):
        return min(p[0], q[0]) <= r[0] <= max(p[0], q[0]) and min(p[1], q[1]) <= r[1] <= max(p[1], q[1])

    o1, o2, o3, o4 = orient(a, b, c), orient(a, b, d), orient(c, d, a), orient(c, d, b)
    if o1 != o2 and o3 != o4:
        return True
    return (o1 == 0 and on(a, b, c)) or (o2 == 0 and on(a, b, d)) or (o3 == 0 and on(c, d, a)) or (o4 == 0 and on(c, d, b))


def self_intersecting(pts):
    """A closed loop is simple when no vertex repeats and only neighbouring edges meet."""
    n = len(pts)
    if len({(round(p[0], 9), round(p[1], 9)) for p in pts}) != n:
        return True
    for i in range(n):
        for j in range(i + 1, n):
            if j == i + 1 or (i == 0 and j == n - 1):
                continue
            if segments_cross(pts[i], pts[(i + 1) % n], pts[j], pts[(j + 1) % n]):
                return True
    return False


def max_turn_deg(pts):
    """Largest turn between consecutive edges of a closed loop, degrees (0 to 180)."""
    n = len(pts)
    worst = 0.0
    for k in range(n):
        a, b, c = pts[k - 1], pts[k], pts[(k + 1) % n]
        u, w = (b[0] - a[0], b[1] - a[1]), (c[0] - b[0], c[1] - b[1])
        worst = max(worst, abs(math.degrees(math.atan2(u[0] * w[1] - u[1] * w[0], u[0] * w[0] + u[1] * w[1]))))
    return worst


def bbox_update(box, pts):
    for x, y in pts:
        box[0], box[1] = min(box[0], x), min(box[1], y)
        box[2], box[3] = max(box[2], x), max(box[3], y)


def read_dxf(path):
    doc = ezdxf.readfile(path)
    out = {
        "dxfversion": doc.dxfversion,
        "insunits": doc.header.get("$INSUNITS", None),
        "layers": sorted(layer.dxf.name for layer in doc.layers),
        "by_layer": {},
    }
    inf = float("inf")
    for e in doc.modelspace():
        s = out["by_layer"].setdefault(e.dxf.layer, {
            "closed_polylines": 0, "open_polylines": 0, "lines": 0, "texts": 0, "text": [],
            "signed_area_mm2": 0.0, "abs_area_mm2": 0.0, "vertices": 0,
            "bbox_mm": [inf, inf, -inf, -inf], "text_bbox_mm": [inf, inf, -inf, -inf], "text_boxes_mm": [],
            "loops_mm": [], "self_intersecting": 0, "loops_ccw": 0, "loops_cw": 0,
            "max_turn_deg": 0.0, "max_edge_mm": 0.0,
        })
        kind = e.dxftype()
        if kind in ("POLYLINE", "LWPOLYLINE"):
            if kind == "POLYLINE":
                pts = [(v.dxf.location[0], v.dxf.location[1]) for v in e.vertices]
            else:
                pts = [(p[0], p[1]) for p in e.get_points("xy")]
            if not e.is_closed:
                s["open_polylines"] += 1
                continue
            s["closed_polylines"] += 1
            s["loops_mm"].append([list(p) for p in pts])
            a = signed_area(pts)
            s["signed_area_mm2"] += a
            s["abs_area_mm2"] += abs(a)
            s["loops_ccw" if a > 0 else "loops_cw"] += 1
            s["vertices"] += len(pts)
            s["self_intersecting"] += int(self_intersecting(pts))
            s["max_turn_deg"] = max(s["max_turn_deg"], max_turn_deg(pts))
            s["max_edge_mm"] = max(s["max_edge_mm"], max(math.dist(pts[k - 1], pts[k]) for k in range(len(pts))))
            bbox_update(s["bbox_mm"], pts)
        elif kind == "LINE":
            s["lines"] += 1
        elif kind == "TEXT":
            s["texts"] += 1
            s["text"].append(e.dxf.text)
            box = ezdxf.bbox.extents([e])
            bbox_update(s["text_bbox_mm"], [(box.extmin[0], box.extmin[1]), (box.extmax[0], box.extmax[1])])
            s["text_boxes_mm"].append([box.extmin[0], box.extmin[1], box.extmax[0], box.extmax[1]])
    return out


def parse_path(d):
    """Subpaths of an SVG path made of M, L and Z commands with absolute coordinates."""
    tokens = re.findall(r"[MLZmlz]|-?[0-9.]+(?:[eE][-+]?[0-9]+)?", d)
    subpaths, cur, cmd, nums = [], None, None, []
    for t in tokens:
        if t in "MLZmlz":
            if t.islower():
                raise ValueError("relative path commands are not expected: " + t)
            cmd = t
            if t == "Z":
                subpaths.append((cur, True))
                cur = None
            continue
        nums.append(float(t))
        if len(nums) == 2:
            if cmd == "M":
                if cur:
                    subpaths.append((cur, False))
                cur = [tuple(nums)]
                cmd = "L"
            else:
                cur.append(tuple(nums))
            nums = []
    if cur:
        subpaths.append((cur, False))
    return subpaths


def read_svg(path):
    root = ET.parse(path).getroot()
    out = {
        "width": root.get("width"),
        "height": root.get("height"),
        "viewbox": [float(v) for v in root.get("viewBox").replace(",", " ").split()],
        "groups": {},
    }
    inf = float("inf")
    for g in root.iter(SVG_NS + "g"):
        s = {"data_ply": g.get("data-ply"), "cut_paths": 0, "subpaths": 0, "open_subpaths": 0,
             "signed_area_mm2": 0.0, "abs_area_mm2": 0.0, "fill_rule": None, "warp_paths": 0,
             "warp_segments": 0, "text": [], "self_intersecting": 0, "bbox_mm": [inf, inf, -inf, -inf]}
        for p in g.iter(SVG_NS + "path"):
            sub = parse_path(p.get("d"))
            if p.get("class") == "cut":
                s["cut_paths"] += 1
                s["fill_rule"] = p.get("fill-rule")
                for pts, closed in sub:
                    if not closed:
                        s["open_subpaths"] += 1
                        continue
                    up = [(x, -y) for x, y in pts]  # SVG y points down
                    a = signed_area(up)
                    s["subpaths"] += 1
                    s["signed_area_mm2"] += a
                    s["abs_area_mm2"] += abs(a)
                    s["self_intersecting"] += int(self_intersecting(up))
                    bbox_update(s["bbox_mm"], up)
            elif p.get("class") == "warp":
                s["warp_paths"] += 1
                s["warp_segments"] += len(sub)
        for t in g.iter(SVG_NS + "text"):
            s["text"].append(t.text)
        out["groups"][g.get("id")] = s
    return out


def finite_or_none(v):
    """Infinite or NaN floats (an empty bounding box) as null, so the output stays strict JSON."""
    if isinstance(v, float) and (v != v or v in (float("inf"), float("-inf"))):
        return None
    if isinstance(v, dict):
        return {k: finite_or_none(x) for k, x in v.items()}
    if isinstance(v, list):
        return [finite_or_none(x) for x in v]
    return v


def main(argv):
    if not argv or any(not a.lower().endswith((".dxf", ".svg")) for a in argv):
        print(__doc__, file=sys.stderr)
        return 2
    result = {}
    for a in argv:
        try:
            result[a] = read_dxf(a) if a.lower().endswith(".dxf") else read_svg(a)
        except (OSError, ezdxf.DXFError) as e:
            print(f"{a}: {e}", file=sys.stderr)
            return 2
    print(json.dumps(finite_or_none(result), allow_nan=False))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
