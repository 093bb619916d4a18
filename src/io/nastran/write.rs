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
//! The deck is bulk data only, the flow mesh's model without executive or case control: it
//! reads alone (pyNastran `read_bdf(deck, xref=True, punch=True)` cross-references every element
//! to its property and material) and takes the place of the mesh's file in your deck (`INCLUDE`
//! it after BEGIN BULK). Every element keeps the property id (PID) it has in the flow mesh
//! (elements of a mesh without PIDs, like OBJ, get [`DEFAULT_PID`]); the properties and
//! materials are the mesh's own, carried through, or, for a PID the mesh gives none for, a
//! PSHELL and MAT8 from the ply's material card ([`super::cards`]). Lengths are in the flow
//! mesh's unit, as its cards are. Elements the ply does not cover keep their PID and get no
//! THETA (the field is left blank, and a comment lists them).
use super::cards::{self, Cards};
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
    let decks = plan(mesh, map, out)?;
    for (path, ply, cards) in &decks {
        write_atomic(path, |w| write_deck(mesh, ply, cards, w))?;
    }
    Ok(decks.into_iter().map(|(p, _, _)| p).collect())
}

/// What [`write_flow`] checks before it writes (ply names become file names; every PID gets its
/// property and materials): the notes on the cards drape writes in the mesh's stead, or why no
/// deck can be written.
pub(crate) fn check(mesh: &FlowMesh, map: &LayupMap, out: &Path) -> Result<Vec<String>, ExportError> {
    Ok(plan(mesh, map, out)?.into_iter().flat_map(|(_, _, c)| c.notes).collect())
}

/// Each ply's deck: its file, the ply and its property and material cards.
fn plan<'a>(mesh: &FlowMesh, map: &'a LayupMap, out: &Path) -> Result<Vec<(PathBuf, &'a PlyMap, Cards)>, ExportError> {
    ply_files("nastran", map, out)?
        .into_iter()
        .map(|(path, ply)| Ok((path, ply, cards::nastran(mesh, ply)?)))
        .collect()
}

fn write_deck<W: Write>(mesh: &FlowMesh, ply: &PlyMap, cards: &Cards, w: &mut W) -> io::Result<()> {
    comment(w, &format!("drape: material orientation of ply '{}' on flow mesh {}", ply.ply, mesh.path.display()))?;
    comment(
        w,
        &format!(
            "THETA (deg) from edge G1->G2 to the warp. The mesh's model as bulk data (lengths in its unit, {} m), with the properties and materials of its PIDs ({DEFAULT_PID} where it had none): it reads alone, and takes the mesh file's place after BEGIN BULK in your deck.",
            mesh.scale
        ),
    )?;
    for c in &cards.comments {
        comment(w, c)?;
    }
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
    write_cards(cards, w)
}

/// Comment lines per [`COMMENT_WIDTH`]: `$ ` and the text, broken at blanks.
pub(crate) fn comment<W: Write>(w: &mut W, text: &str) -> io::Result<()> {
    let mut line = String::from("$");
    for word in text.split_whitespace() {
        if line.len() > 2 && line.len() + 1 + word.len() > COMMENT_WIDTH {
            writeln!(w, "{line}")?;
            line = String::from("$  ");
        }
        line.push(' ');
        line.push_str(word);
    }
    writeln!(w, "{line}")
}

/// Width comment lines are broken at (a word longer than that goes on a line of its own).
const COMMENT_WIDTH: usize = 80;

/// The property and material cards, large fields.
pub(crate) fn write_cards<W: Write>(cards: &Cards, w: &mut W) -> io::Result<()> {
    for e in &cards.entries {
        large(w, &e.name, &e.fields)?;
    }
    Ok(())
}

/// Every node as a large-field GRID*, in the mesh's own length unit.
pub(crate) fn write_grids<W: Write>(mesh: &FlowMesh, w: &mut W) -> io::Result<()> {
    let s = mesh.scale;
    for (p, id) in mesh.nodes.iter().zip(&mesh.node_ids) {
        large(w, "GRID", &[id.to_string(), String::new(), real(p.x / s), real(p.y / s), real(p.z / s)])?;
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
