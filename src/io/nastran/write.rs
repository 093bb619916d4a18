//! Writing Nastran bulk data (MSC / NX / pyNastran) with the material orientation angle THETA of each
//! element: GRID, CTRIA3 and CQUAD4 in large-field fixed format (16-character fields; reals
//! take at most 15 characters so a blank always separates neighbours, which keeps 10 or more
//! significant digits: THETA to better than 1e-8 degree).
//!
//! THETA is field 7 of CTRIA3 (EID PID G1 G2 G3 THETA) and field 8 of CQUAD4 (EID PID G1 G2 G3
//! G4 THETA), a real in degrees measured from the element's G1 -> G2 edge about its normal: the
//! map's `theta`. An element card carries one angle, so one deck carries one ply: for one net
//! the deck is `out`; for a layup each ply gets its own deck `STEM_<ply>.<ext>` beside `out`
//! (same GRIDs and element ids in all of them).
//!
//! The deck is bulk data only, to `INCLUDE` in the bulk section of your own deck, which defines
//! the properties and materials: every element keeps the property id (PID) it has in the flow
//! mesh (elements of a mesh without PIDs, like OBJ, get [`DEFAULT_PID`]), so a solver, or
//! pyNastran with cross-referencing, finds the user's PSHELL/PCOMP and MAT cards. Elements the
//! ply does not cover keep their PID and get no THETA (the field is left blank, and a comment
//! lists them).
use super::{large, real};
use crate::io::flow::{deg, ply_files};
use crate::io::{write_atomic, ExportError};
use crate::mapping::{ElementShape, FlowElement, FlowMesh, LayupMap, PlyMap};
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// Property id of elements the flow mesh gives none (an OBJ mesh, say).
pub const DEFAULT_PID: u64 = 1;

/// The PID an element keeps: its own, else [`DEFAULT_PID`].
pub(crate) fn pid(el: &FlowElement) -> u64 {
    if el.property > 0 {
        el.property
    } else {
        DEFAULT_PID
    }
}

pub(crate) fn write_flow(mesh: &FlowMesh, map: &LayupMap, out: &Path) -> Result<Vec<PathBuf>, ExportError> {
    let targets = check(map, out)?;
    for (path, ply) in &targets {
        write_atomic(path, |w| write_deck(mesh, ply, w))?;
    }
    Ok(targets.into_iter().map(|(p, _)| p).collect())
}

/// What [`write_flow`] checks before it writes: the deck of each ply (ply names become file
/// names), or why none can be written.
pub(crate) fn check<'a>(map: &'a LayupMap, out: &Path) -> Result<Vec<(PathBuf, &'a PlyMap)>, ExportError> {
    ply_files("nastran", map, out)
}

fn write_deck<W: Write>(mesh: &FlowMesh, ply: &PlyMap, w: &mut W) -> io::Result<()> {
    writeln!(w, "$ drape: material orientation of ply '{}' on flow mesh {}", ply.ply, mesh.path.display())?;
    writeln!(w, "$ THETA (deg) from edge G1->G2 to the warp. Bulk data to INCLUDE after BEGIN BULK in your deck,")?;
    writeln!(w, "$ which defines the properties (PIDs as in the flow mesh, {DEFAULT_PID} where it had none) and materials.")?;
    let uncovered: Vec<u64> =
        mesh.elements.iter().zip(&ply.elements).filter(|(_, f)| f.is_none()).map(|(e, _)| e.id).collect();
    if !uncovered.is_empty() {
        writeln!(
            w,
            "$ {} element(s) not covered by ply '{}' (their own PID, no THETA):",
            uncovered.len(),
            ply.ply
        )?;
        for chunk in uncovered.chunks(10) {
            let ids: Vec<String> = chunk.iter().map(u64::to_string).collect();
            writeln!(w, "$   {}", ids.join(" "))?;
        }
    }
    write_grids(mesh, w)?;
    for (el, f) in mesh.elements.iter().zip(&ply.elements) {
        let theta = f.as_ref().map(|f| real(deg(f.theta)));
        write_element(mesh, el, pid(el), theta, w)?;
    }
    Ok(())
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
