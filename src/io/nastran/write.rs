//! Writing Nastran bulk data (MSC / NX / pyNastran) with the material orientation angle THETA of each
//! element: GRID, CTRIA3 and CQUAD4 in large-field fixed format (16-character fields; reals
//! take at most 15 characters so a blank always separates neighbours, which keeps 10 or more
//! significant digits: THETA to better than 1e-8 degree).
//!
//! THETA is field 7 of CTRIA3 (EID PID G1 G2 G3 THETA) and field 8 of CQUAD4 (EID PID G1 G2 G3
//! G4 THETA), a real in degrees measured from the element's G1 -> G2 edge about its normal: the
//! map's `theta`. An element card carries one angle, so one deck carries one ply: for one net
//! the deck is `out`; for a layup each ply gets its own deck `STEM_<ply>.<ext>` beside `out`
//! (same GRIDs and element ids in all of them). This is a mesh + orientation deck to INCLUDE:
//! elements covered by the ply have PID 1, the others PID 2 and no THETA (the field is left
//! blank, and a comment lists them); define PSHELL/PCOMP 1 and 2 yourself. The executive and
//! case control sections are empty (`CEND`, `BEGIN BULK`, ..., `ENDDATA`).
use super::{large, real};
use crate::io::flow::{deg, file_tag, sibling};
use crate::io::{write_atomic, ExportError};
use crate::mapping::{ElementShape, FlowElement, FlowMesh, LayupMap, PlyMap};
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// Property id of the elements the ply covers.
pub(crate) const PID_COVERED: u64 = 1;
/// Property id of the elements the ply does not cover.
pub(crate) const PID_UNCOVERED: u64 = 2;

pub(crate) fn write_flow(mesh: &FlowMesh, map: &LayupMap, out: &Path) -> Result<Vec<PathBuf>, ExportError> {
    let ext = out.extension().map(|e| format!(".{}", e.to_string_lossy())).unwrap_or_default();
    let targets: Vec<(PathBuf, &PlyMap)> = if map.layup {
        let mut v = Vec::new();
        for ply in &map.plies {
            let tag = file_tag("nastran", &ply.ply)?;
            v.push((sibling(out, &format!("_{tag}{ext}")), ply));
        }
        v
    } else {
        vec![(out.to_path_buf(), &map.plies[0])]
    };
    for (path, ply) in &targets {
        write_atomic(path, |w| write_deck(mesh, ply, w))?;
    }
    Ok(targets.into_iter().map(|(p, _)| p).collect())
}

fn write_deck<W: Write>(mesh: &FlowMesh, ply: &PlyMap, w: &mut W) -> io::Result<()> {
    writeln!(w, "$ drape: material orientation of ply '{}' on flow mesh {}", ply.ply, mesh.path.display())?;
    writeln!(w, "$ THETA (deg) from edge G1->G2 to the warp; PID {PID_COVERED} = covered, PID {PID_UNCOVERED} = not covered by this ply.")?;
    let uncovered: Vec<u64> =
        mesh.elements.iter().zip(&ply.elements).filter(|(_, f)| f.is_none()).map(|(e, _)| e.id).collect();
    if !uncovered.is_empty() {
        writeln!(
            w,
            "$ {} element(s) not covered by ply '{}' (PID {PID_UNCOVERED}, no THETA):",
            uncovered.len(),
            ply.ply
        )?;
        for chunk in uncovered.chunks(10) {
            let ids: Vec<String> = chunk.iter().map(u64::to_string).collect();
            writeln!(w, "$   {}", ids.join(" "))?;
        }
    }
    // Empty executive and case control sections: a deck pyNastran and meshio read whole; add
    // SOL and case control above CEND to run it, or INCLUDE the bulk lines in your own deck.
    writeln!(w, "CEND")?;
    writeln!(w, "BEGIN BULK")?;
    write_grids(mesh, w)?;
    for (el, f) in mesh.elements.iter().zip(&ply.elements) {
        let theta = f.as_ref().map(|f| real(deg(f.theta)));
        write_element(mesh, el, f.as_ref().map_or(PID_UNCOVERED, |_| PID_COVERED), theta, w)?;
    }
    writeln!(w, "ENDDATA")
}

/// Every node as a large-field GRID*.
pub(crate) fn write_grids<W: Write>(mesh: &FlowMesh, w: &mut W) -> io::Result<()> {
    for (p, id) in mesh.nodes.iter().zip(&mesh.node_ids) {
        large(w, "GRID", &[id.to_string(), String::new(), real(p.x), real(p.y), real(p.z)])?;
    }
    Ok(())
}

/// One CTRIA3*/CQUAD4* with property `pid` and material angle `theta` (blank if `None`).
pub(crate) fn write_element<W: Write>(
    mesh: &FlowMesh,
    el: &FlowElement,
    pid: u64,
    theta: Option<String>,
    w: &mut W,
) -> io::Result<()> {
    let name = match el.shape {
        ElementShape::Tria3 => "CTRIA3",
        ElementShape::Quad4 => "CQUAD4",
    };
    let mut fields = vec![el.id.to_string(), pid.to_string()];
    fields.extend(el.nodes.iter().map(|&k| mesh.node_ids[k].to_string()));
    fields.push(theta.unwrap_or_default());
    large(w, name, &fields)
}
