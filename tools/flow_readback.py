#!/usr/bin/env python3
"""Independent read-back of drape's flow-mesh exports (not drape's code).

Usage: python3 tools/flow_readback.py FORMAT FILE [FILE...]

  vtu FILE            meshio: points, cells in file order, cell data by name
  vtu-vtk FILE        VTK's vtkXMLUnstructuredGridReader: counts and cell data by name
  nastran FILE...     pyNastran (BDF, xref off; bulk data only, as drape writes it) per deck:
                      grids, elements with PID and THETA;
                      meshio on the same deck: its GRID points (meshio skips elements that carry
                      a THETA field, so only the points are compared)
  nastran-xref FILE   pyNastran read_bdf(FILE, xref=True), as a solver reads a deck: drape's
                      bulk data alone (punch=True) or a whole deck that INCLUDEs it: elements with
                      PID, the type of the property and material they cross-reference, THETA;
                      every property (type, thickness, material ids) and material (type and
                      constants) pyNastran cross-referenced
  optistruct-xref FILE  pyNastran read_bdf(FILE, xref=True) taught OptiStruct's PCOMPP (a property
                      that refers to no card, per the OptiStruct Reference Guide) for the parts
                      pyNastran knows (elements, PCOMPP/PSHELL/PCOMP, MAT8...); our parser for
                      PLY, STACK, SET and DRAPE and their references (to pyNastran's materials,
                      the sets, the drapes, the plies); "dangling" lists every reference that
                      does not resolve
  abaqus FILE         meshio for nodes and elements; our parser of *ELSET, *DISTRIBUTION TABLE,
                      *DISTRIBUTION and *ORIENTATION as the Abaqus Keywords Reference lays them out
  optistruct FILE     our parser of large-field fixed format (GRID*, CTRIA3*, CQUAD4*, SET*,
                      DRAPE*, PLY*) per the OptiStruct Reference Guide
  rtmsim MESH INPUT   our parser following RTMsim's read_nastran_mesh (8-character columns,
                      SETs numbered by order) and its 14-line input file; meshio on the mesh
  csv FILE            Python's csv module

Prints one JSON object to stdout. Exit status 2 on bad arguments.
"""
import csv
import json
import math
import os
import sys
import tempfile

# ---------------------------------------------------------------- helpers


def nastran_real(text):
    """A Nastran real: 1.5, .5, 1.5E-3, 1.5-3 (implicit exponent), -.5+2."""
    t = text.strip().lower().replace("d", "e")
    try:
        return float(t)
    except ValueError:
        pass
    for k in range(len(t) - 1, 0, -1):
        if t[k] in "+-" and t[k - 1] != "e":
            return float(t[:k] + "e" + t[k:])
    raise ValueError("not a Nastran real: %r" % text)


def large_entries(path):
    """Large-field fixed-format entries of a bulk section: [(name, [fields 2..])]."""
    entries = []
    with open(path) as f:
        text = f.read()
    # Bulk data alone (a file to INCLUDE) is all bulk.
    in_bulk = not any(l.strip().upper() == "BEGIN BULK" for l in text.splitlines())
    for raw in text.splitlines(True):
        line = raw.rstrip("\n")
        if line.startswith("$") or not line.strip():
            continue
        if line.strip().upper() == "BEGIN BULK":
            in_bulk = True
            continue
        if not in_bulk:
            continue
        if line.strip().upper() == "ENDDATA":
            break
        head = line[:8]
        fields = [line[8 + 16 * i: 24 + 16 * i].strip() for i in range(4)]
        if head.startswith("*"):
            if not entries:
                raise SystemExit("%s: continuation before any entry" % path)
            entries[-1][1].extend(fields)
        else:
            name = head.strip()
            if not name.endswith("*"):
                raise SystemExit("%s: not a large-field entry: %r" % (path, line))
            entries.append((name[:-1], fields))
    return entries


# ---------------------------------------------------------------- formats


def read_vtu_vtk(path):
    """VTK's own XML reader (the one ParaView is built on): cell data by name, per cell."""
    import vtk

    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(path)
    r.Update()
    if r.GetErrorCode() != 0:
        raise SystemExit("vtk could not read %s (error code %d)" % (path, r.GetErrorCode()))
    g = r.GetOutput()
    cd = g.GetCellData()
    data = {}
    for k in range(cd.GetNumberOfArrays()):
        a = cd.GetArray(k)
        data[a.GetName()] = [list(a.GetTuple(i)) for i in range(a.GetNumberOfTuples())]
    return {"points": g.GetNumberOfPoints(), "cells": g.GetNumberOfCells(), "cell_data": data}


def read_vtu(path):
    import meshio
    import numpy as np

    m = meshio.read(path)
    cells = []
    for block in m.cells:
        for c in np.asarray(block.data):
            cells.append({"type": block.type, "nodes": [int(x) for x in c]})
    data = {}
    for name, arrays in m.cell_data.items():
        values = []
        for a in arrays:
            a = np.asarray(a, dtype=float)
            values.extend(a.reshape(len(a), -1).tolist())
        data[name] = values
    return {"points": np.asarray(m.points, dtype=float).tolist(), "cells": cells, "cell_data": data}


def read_nastran(paths):
    import meshio
    from pyNastran.bdf.bdf import BDF

    decks = []
    for path in paths:
        model = BDF(debug=None, log=None, mode="msc")
        model.read_bdf(path, xref=False, punch=True)
        grids = {int(nid): [float(x) for x in n.xyz] for nid, n in model.nodes.items()}
        # pyNastran reads a blank THETA as 0.0: whether the field is blank, from the text.
        blank = {}
        for name, fields in large_entries(path):
            if name in ("CTRIA3", "CQUAD4"):
                k = 5 if name == "CTRIA3" else 6
                blank[int(fields[0])] = len(fields) <= k or fields[k] == ""
        elements = {}
        for eid, e in model.elements.items():
            theta = e.theta_mcid
            elements[int(eid)] = {
                "type": e.type,
                "pid": int(e.pid),
                "nodes": [int(n) for n in e.node_ids],
                "theta": float(theta) if isinstance(theta, float) else None,
                "mcid": int(theta) if isinstance(theta, int) else None,
                "theta_blank": blank[int(eid)],
            }
        # meshio reads whole decks: the bulk data as a user's deck INCLUDEs it.
        with open(path) as f:
            bulk = f.read()
        with tempfile.NamedTemporaryFile("w", suffix=".bdf", delete=False) as whole:
            whole.write("CEND\nBEGIN BULK\n" + bulk + "ENDDATA\n")
        try:
            m = meshio.read(whole.name, file_format="nastran")
        finally:
            os.unlink(whole.name)
        decks.append(
            {
                "path": path,
                "grids": grids,
                "elements": elements,
                "meshio_points": [[float(x) for x in p] for p in m.points],
            }
        )
    return {"decks": decks}


def material_json(m):
    """The constants of a material pyNastran read."""
    out = {"type": m.type}
    if m.type == "MAT8":
        out.update(e1=m.e11, e2=m.e22, nu12=m.nu12, g12=m.g12, rho=m.rho)
    elif m.type == "MAT1":
        out.update(e=m.e, g=m.g, nu=m.nu, rho=m.rho)
    return out


def property_json(p):
    """A property pyNastran read and cross-referenced: its type, thickness and materials."""
    out = {"type": p.type}
    if p.type == "PSHELL":
        out.update(t=p.t, mids=[m for m in (p.mid1, p.mid2, p.mid3, p.mid4) if m is not None and m > 0],
                   materials=[m.type for m in (p.mid1_ref, p.mid2_ref, p.mid3_ref, p.mid4_ref)
                              if m is not None and not isinstance(m, int)])
    elif p.type in ("PCOMP", "PCOMPG"):
        out.update(thicknesses=[float(t) for t in p.thicknesses], mids=[int(m) for m in p.mids],
                   materials=[m.type for m in p.mids_ref])
    return out


def elements_json(model):
    elements = {}
    for eid, e in model.elements.items():
        theta = e.theta_mcid
        prop = e.pid_ref
        if prop.type == "PCOMPP":
            material = None
        else:
            material = (prop.mid_ref if hasattr(prop, "mid_ref") else prop.mids_ref[0]).type
        elements[int(eid)] = {
            "pid": int(e.pid),
            "property": prop.type,
            "material": material,
            "theta": float(theta) if isinstance(theta, float) else None,
        }
    return elements


def read_nastran_xref(path):
    from pyNastran.bdf.bdf import BDF

    with open(path) as f:
        whole = any(l.strip().upper() == "BEGIN BULK" for l in f)
    model = BDF(debug=None, log=None, mode="msc")
    # drape's deck is bulk data alone (punch=True); a user's deck INCLUDEs it after BEGIN BULK.
    model.read_bdf(path, xref=True, punch=not whole)
    return {
        "elements": elements_json(model),
        "properties": {int(k): property_json(p) for k, p in model.properties.items()},
        "materials": {int(k): material_json(m) for k, m in model.materials.items()},
        "rejected": sorted(model.reject_count),
    }


def optistruct_model():
    """A pyNastran BDF that reads OptiStruct's PCOMPP (PID Z0 NSM SB FT TREF GE; OptiStruct
    Reference Guide): a property that refers to no other card."""
    from pyNastran.bdf.bdf import BDF
    from pyNastran.bdf.bdf_interface.assign_type import double_or_blank, integer, string_or_blank
    from pyNastran.bdf.cards.base_card import Property

    class PCOMPP(Property):
        type = "PCOMPP"

        def __init__(self, pid, comment=""):
            Property.__init__(self)
            self.pid = pid
            self.comment = comment

        @classmethod
        def add_card(cls, card, comment=""):
            pid = integer(card, 1, "pid")
            for k, name in ((2, "z0"), (3, "nsm"), (4, "sb"), (6, "tref"), (7, "ge")):
                double_or_blank(card, k, name)
            string_or_blank(card, 5, "ft")
            return PCOMPP(pid, comment)

        def cross_reference(self, model):
            pass

        def safe_cross_reference(self, model, xref_errors):
            pass

        def uncross_reference(self):
            pass

        def raw_fields(self):
            return ["PCOMPP", self.pid]

    model = BDF(debug=None, log=None, mode="optistruct")
    model._card_parser["PCOMPP"] = (PCOMPP, model._add_methods._add_property_object)
    model.cards_to_read.add("PCOMPP")
    return model


def read_optistruct_xref(path):
    model = optistruct_model()
    model.read_bdf(path, xref=True)
    ours = read_optistruct(path)
    dangling = []
    plies = {}
    for pid_s, ply in ours["plies"].items():
        m = model.materials.get(ply["mid"])
        if m is None:
            dangling.append("PLY %s: MID %d is not a material" % (pid_s, ply["mid"]))
        if str(ply["did"]) not in ours["drapes"]:
            dangling.append("PLY %s: DRAPE %d is not defined" % (pid_s, ply["did"]))
        for esid in ply["esids"]:
            if str(esid) not in ours["sets"]:
                dangling.append("PLY %s: SET %d is not defined" % (pid_s, esid))
        plies[pid_s] = dict(ply, material=material_json(m) if m is not None else None)
    in_plies = {}
    for pid_s, ply in ours["plies"].items():
        for esid in ply["esids"]:
            for eid in ours["sets"].get(str(esid), []):
                in_plies.setdefault(eid, []).append(int(pid_s))
                if eid not in model.elements:
                    dangling.append("SET %d: element %d is not defined" % (esid, eid))
    stacked = [p for s in ours["stacks"].values() for p in s["plies"]]
    for p in stacked:
        if str(p) not in ours["plies"]:
            dangling.append("STACK: ply %d is not defined" % p)
    for pid_s in ours["plies"]:
        if stacked.count(int(pid_s)) != 1:
            dangling.append("PLY %s is in %d STACKs (one expected)" % (pid_s, stacked.count(int(pid_s))))
    for eid, e in model.elements.items():
        is_pcompp = e.pid_ref.type == "PCOMPP"
        if is_pcompp and eid not in in_plies:
            dangling.append("element %d: PCOMPP %d but in no PLY" % (eid, e.pid))
        if not is_pcompp and eid in in_plies:
            dangling.append("element %d: in PLY %s but its property is a %s" % (eid, in_plies[eid], e.pid_ref.type))
    return {
        "elements": elements_json(model),
        "properties": {int(k): property_json(p) for k, p in model.properties.items()},
        "materials": {int(k): material_json(m) for k, m in model.materials.items()},
        "plies": plies,
        "stacks": ours["stacks"],
        "in_plies": {str(k): v for k, v in in_plies.items()},
        "dangling": dangling,
    }


def read_abaqus(path):
    import meshio
    import numpy as np

    m = meshio.read(path, file_format="abaqus")
    cells = []
    for block in m.cells:
        for c in np.asarray(block.data):
            cells.append({"type": block.type, "nodes": [int(x) for x in c]})

    # Our parser: keyword lines start with '*', '**' are comments, parameters NAME=VALUE.
    elsets, tables, dists, oris = {}, {}, {}, {}
    node_ids, element_ids = [], []
    current = None
    with open(path) as f:
        for raw in f:
            line = raw.strip()
            if not line or line.startswith("**"):
                continue
            if line.startswith("*"):
                parts = [p.strip() for p in line[1:].split(",")]
                kw = parts[0].upper()
                params = {}
                for p in parts[1:]:
                    if "=" in p:
                        k, v = p.split("=", 1)
                        params[k.strip().upper()] = v.strip()
                    elif p:
                        params[p.upper()] = True
                current = (kw, params)
                if kw == "ELSET":
                    elsets[params["ELSET"]] = []
                elif kw == "DISTRIBUTION TABLE":
                    tables[params["NAME"]] = None
                elif kw == "DISTRIBUTION":
                    dists[params["NAME"]] = {
                        "location": params.get("LOCATION"),
                        "table": params.get("TABLE"),
                        "default": None,
                        "rows": {},
                    }
                elif kw == "ORIENTATION":
                    oris[params["NAME"]] = {"params": params, "lines": []}
                continue
            if current is None:
                continue
            kw, params = current
            fields = [x.strip() for x in line.split(",")]
            if kw == "NODE":
                node_ids.append(int(fields[0]))
            elif kw == "ELEMENT":
                element_ids.append(int(fields[0]))
            elif kw == "ELSET":
                elsets[params["ELSET"]].extend(int(x) for x in fields if x)
            elif kw == "DISTRIBUTION TABLE":
                tables[params["NAME"]] = [x.upper() for x in fields if x]
            elif kw == "DISTRIBUTION":
                d = dists[params["NAME"]]
                if fields[0] == "":
                    if d["default"] is not None or d["rows"]:
                        raise SystemExit("%s: default line of %s is not first" % (path, params["NAME"]))
                    d["default"] = [float(x) for x in fields[1:]]
                else:
                    if d["default"] is None:
                        raise SystemExit("%s: distribution %s has no default line first" % (path, params["NAME"]))
                    d["rows"][int(fields[0])] = [float(x) for x in fields[1:]]
            elif kw == "ORIENTATION":
                oris[params["NAME"]]["lines"].append(fields)
    return {
        "meshio_points": np.asarray(m.points, dtype=float).tolist(),
        "meshio_cells": cells,
        "node_ids": node_ids,
        "element_ids": element_ids,
        "elsets": elsets,
        "tables": tables,
        "distributions": {k: dict(v, rows={str(e): r for e, r in v["rows"].items()}) for k, v in dists.items()},
        "orientations": oris,
    }


def read_optistruct(path):
    grids, elements, sets, drapes, plies, stacks = {}, {}, {}, {}, {}, {}
    for name, fields in large_entries(path):
        if name == "GRID":
            grids[int(fields[0])] = [nastran_real(x) for x in fields[2:5]]
        elif name in ("CTRIA3", "CQUAD4"):
            nn = 3 if name == "CTRIA3" else 4
            theta = fields[2 + nn] if len(fields) > 2 + nn else ""
            elements[int(fields[0])] = {
                "type": name,
                "pid": int(fields[1]),
                "nodes": [int(x) for x in fields[2: 2 + nn]],
                "theta": nastran_real(theta) if theta else None,
            }
        elif name == "SET":
            if fields[1] != "ELEM" or fields[2] != "LIST":
                raise SystemExit("%s: SET %s is not ELEM LIST" % (path, fields[0]))
            sets[int(fields[0])] = [int(x) for x in fields[8:] if x]
        elif name == "DRAPE":
            rows = {}
            for k in range(8, len(fields), 8):
                line = fields[k: k + 4]
                if not any(line):
                    continue
                if line[0] != "ELEM":
                    raise SystemExit("%s: DRAPE %s: entity type %r" % (path, fields[0], line[0]))
                rows[line[1]] = [nastran_real(line[2]), nastran_real(line[3])]
            drapes[int(fields[0])] = rows
        elif name == "PLY":
            plies[int(fields[0])] = {
                "mid": int(fields[1]),
                "t": nastran_real(fields[2]),
                "theta": nastran_real(fields[3]) if fields[3] else 0.0,
                "did": int(fields[6]),
                "esids": [int(x) for x in fields[8:] if x],
            }
        elif name == "STACK":
            stacks[int(fields[0])] = {"lam": fields[1], "plies": [int(x) for x in fields[2:] if x]}
    return {
        "grids": {str(k): v for k, v in grids.items()},
        "elements": {str(k): v for k, v in elements.items()},
        "sets": {str(k): v for k, v in sets.items()},
        "drapes": {str(k): v for k, v in drapes.items()},
        "plies": {str(k): v for k, v in plies.items()},
        "stacks": {str(k): v for k, v in stacks.items()},
    }


def rtmsim_number(text):
    """RTMsim's own conversion of a GRID coordinate field (pre.jl)."""
    t = text.replace(" ", "").replace("E", "").replace("e", "")
    t = t.replace("-", "e-").replace("+", "e+")
    if t.startswith("e"):
        t = t[1:]
    return float(t)


def read_rtmsim(mesh_path, input_path):
    import meshio

    grids, tris, sets, splits, uncovered = {}, {}, [[], [], [], []], [], []
    set_index = 0
    in_set = False
    with open(mesh_path) as f:
        for raw in f:
            line = raw.rstrip("\n")
            if line.startswith("$$ SPLIT"):
                splits.append([int(x) for x in line.split()[2:]])
            if line.startswith("$$ UNCOVERED"):
                uncovered.extend(int(x) for x in line.split()[2:])
            if len(line) < 8:
                continue
            if in_set and line[:8] != " " * 8:
                in_set = False
                set_index += 1
            card = line[:8]
            if card == "GRID    ":
                grids[int(line[8:16])] = [rtmsim_number(line[24 + 8 * i: 32 + 8 * i]) for i in range(3)]
            elif card == "CTRIA3  ":
                tris[int(line[8:16])] = [int(line[24 + 8 * i: 32 + 8 * i]) for i in range(3)]
            elif card[:3] == "SET" or in_set:
                in_set = True
                for x in line[8:].replace(" ", "").split(","):
                    if x:
                        if set_index >= 4:
                            raise SystemExit("%s: more than four SETs" % mesh_path)
                        sets[set_index].append(int(x))
    with open(input_path) as f:
        rows = [line.rstrip("\n").split(" ") for line in f]
    if len(rows) < 14:
        raise SystemExit("%s: %d lines, RTMsim reads 14" % (input_path, len(rows)))
    params = [[float(x) for x in rows[5 + k][:7]] for k in range(5)]
    m = meshio.read(mesh_path, file_format="nastran")
    n_tri = sum(len(b.data) for b in m.cells if b.type == "triangle")
    return {
        "grids": {str(k): v for k, v in grids.items()},
        "tris": {str(k): v for k, v in tris.items()},
        "sets": sets,
        "splits": splits,
        "uncovered": uncovered,
        "meshfilename": rows[1][0],
        "params": params,
        "patchtypes": [int(x) for x in rows[10][:4]],
        "i_interactive": int(rows[12][0]),
        "meshio_points": len(m.points),
        "meshio_triangles": n_tri,
    }


def read_csv(path):
    with open(path, newline="") as f:
        r = csv.reader(f)
        header = next(r)
        rows = [dict(zip(header, row)) for row in r]
        widths = sorted({len(row) for row in rows})
    return {"header": header, "rows": rows, "widths": widths}


def main(argv):
    if len(argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    fmt, files = argv[0], argv[1:]
    if fmt == "vtu" and len(files) == 1:
        out = read_vtu(files[0])
    elif fmt == "vtu-vtk" and len(files) == 1:
        out = read_vtu_vtk(files[0])
    elif fmt == "nastran":
        out = read_nastran(files)
    elif fmt == "nastran-xref" and len(files) == 1:
        out = read_nastran_xref(files[0])
    elif fmt == "abaqus" and len(files) == 1:
        out = read_abaqus(files[0])
    elif fmt == "optistruct" and len(files) == 1:
        out = read_optistruct(files[0])
    elif fmt == "optistruct-xref" and len(files) == 1:
        out = read_optistruct_xref(files[0])
    elif fmt == "rtmsim" and len(files) == 2:
        out = read_rtmsim(files[0], files[1])
    elif fmt == "csv" and len(files) == 1:
        out = read_csv(files[0])
    else:
        print(__doc__, file=sys.stderr)
        return 2

    def clean(v):
        if isinstance(v, float) and not math.isfinite(v):
            return str(v)
        if isinstance(v, dict):
            return {str(k): clean(x) for k, x in v.items()}
        if isinstance(v, list):
            return [clean(x) for x in v]
        return v

    json.dump(clean(out), sys.stdout)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
