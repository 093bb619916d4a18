//! OptiStruct ply-based composite bulk data (large-field fixed format): GRID, CTRIA3/CQUAD4,
//! and per ply a SET of its elements, a DRAPE table and a PLY referencing both (OptiStruct
//! Reference Guide: PLY, SET, DRAPE bulk data entries).
//!
//! OptiStruct puts the fibre of ply k in element e at element x-axis (edge G1 -> G2 turned by
//! the element's THETA) + PLY THETA_k + DRAPE THETA_k,e. drape writes
//! * element THETA_e = nominal angle of the first ply covering e (its `theta - angle_change`)
//!   less that ply's PLY THETA; elements no ply covers get no THETA;
//! * PLY THETA_k = circular mean over shared elements of the ply's nominal angle relative to
//!   the first ply (0 for the first ply): the ply angle as the part sees it;
//! * DRAPE per covered element: `ELEM, eid, T, THETA` with the thinning factor
//!   T = thickness / nominal thickness and THETA = `angle_change` (degrees) plus the (normally
//!   zero) part of the nominal angle the two terms above do not carry, so the sum is exactly the
//!   map's `theta`;
//! * PLY: ID k, MID = the MAT8 of the ply's fabric, T = the ply's nominal thickness, DID k,
//!   ESID k (SET k, ELEM LIST); plies that cover no element get none;
//! * STACK 1 of the plies in stacking order (bottom first);
//! * PCOMPP with the PID of every element some ply covers (its own, [`DEFAULT_PID`] where the
//!   mesh gives none): the plies give its laminate. Elements no ply covers keep their PID and
//!   the mesh's card of it, or a fresh PID beside a PCOMPP (every element of a PCOMPP lies in a
//!   ply); the properties and materials follow [`super::nastran::cards`]: the mesh's own, carried
//!   through, else a PSHELL and MAT8 from a ply's material card, named in a comment and a note.
//!
//! Lengths are in the flow mesh's unit (its cards' unit). The deck is laid out as OptiStruct
//! reads one: a control section (empty but for comments: add your I/O options and subcases),
//! `CEND`, `BEGIN BULK`, the bulk data, `ENDDATA`. Card formats: OptiStruct Reference Guide,
//! bulk data entries PCOMPP, STACK, PLY, SET, DRAPE, MAT8, PSHELL.
use super::flow::{deg, wrap};
use super::nastran::cards::{self, OptiStructCards};
use super::nastran::write::{comment, write_cards, write_element, write_grids, DEFAULT_PID};
use super::nastran::{large, real};
use super::{write_atomic, ExportError};
use crate::mapping::{FlowMesh, LayupMap};
use std::io::{self, Write};
use std::path::Path;

/// Id of the STACK of the plies.
pub const STACK_ID: u64 = 1;

pub(crate) fn write_flow(mesh: &FlowMesh, map: &LayupMap, out: &Path) -> Result<(), ExportError> {
    let cards = plan(mesh, map)?;
    let angles = Angles::new(map);
    write_atomic(out, |w| write_to(mesh, map, &angles, &cards, w))
}

/// What [`write_flow`] checks before it writes: the notes on the cards drape writes in the
/// mesh's stead, or why the deck cannot be written.
pub(crate) fn check(mesh: &FlowMesh, map: &LayupMap) -> Result<Vec<String>, ExportError> {
    Ok(plan(mesh, map)?.cards.notes)
}

/// The deck's properties, materials and element PIDs, after the plies' thicknesses are checked.
fn plan(mesh: &FlowMesh, map: &LayupMap) -> Result<OptiStructCards, ExportError> {
    for ply in &map.plies {
        if let Some(f) = ply.elements.iter().flatten().find(|f| !(f.nominal_thickness > 0.0)) {
            return Err(ExportError::FlowInvalid {
                format: "optistruct",
                reason: format!(
                    "ply '{}' has nominal thickness {} (the thinning factor needs a positive one)",
                    ply.ply, f.nominal_thickness
                ),
            });
        }
    }
    cards::optistruct(mesh, map)
}

/// The split of each fibre angle between element, PLY and DRAPE (radians).
pub(crate) struct Angles {
    /// Element material angle, `None` where no ply covers the element.
    pub element: Vec<Option<f64>>,
    /// PLY THETA per ply.
    pub ply: Vec<f64>,
}

impl Angles {
    pub(crate) fn new(map: &LayupMap) -> Angles {
        let n = map.thickness.len();
        let nominal = |k: usize, e: usize| map.plies[k].elements[e].as_ref().map(|f| wrap(f.theta - f.angle_change));
        // Reference ply: the first that covers anything.
        let r = (0..map.plies.len()).find(|&k| (0..n).any(|e| nominal(k, e).is_some()));
        let ply: Vec<f64> = (0..map.plies.len())
            .map(|k| {
                let Some(r) = r else { return 0.0 };
                let (mut s, mut c) = (0.0, 0.0);
                for e in 0..n {
                    if let (Some(a), Some(b)) = (nominal(k, e), nominal(r, e)) {
                        let d = wrap(a - b);
                        s += d.sin();
                        c += d.cos();
                    }
                }
                if s == 0.0 && c == 0.0 {
                    0.0
                } else {
                    s.atan2(c)
                }
            })
            .collect();
        let element =
            (0..n).map(|e| (0..map.plies.len()).find_map(|k| nominal(k, e).map(|a| wrap(a - ply[k])))).collect();
        Angles { element, ply }
    }

    /// DRAPE THETA of ply k in element e (radians), so that element + ply + drape = theta.
    pub(crate) fn drape(&self, k: usize, e: usize, theta: f64) -> f64 {
        wrap(theta - self.element[e].unwrap_or(0.0) - self.ply[k])
    }
}

fn pad8(fields: &mut Vec<String>) {
    while !fields.len().is_multiple_of(8) {
        fields.push(String::new());
    }
}

fn write_to<W: Write>(
    mesh: &FlowMesh,
    map: &LayupMap,
    angles: &Angles,
    cards: &OptiStructCards,
    w: &mut W,
) -> io::Result<()> {
    comment(w, &format!("drape: ply-based composite data on flow mesh {}", mesh.path.display()))?;
    comment(w, "fibre angle = element THETA + PLY THETA + DRAPE THETA (deg, from edge G1->G2).")?;
    comment(
        w,
        &format!(
            "Lengths in the flow mesh's unit ({} m). Elements some ply covers: PCOMPP of their PID ({DEFAULT_PID} where the mesh had none), plies in STACK {STACK_ID}.",
            mesh.scale
        ),
    )?;
    for c in &cards.cards.comments {
        comment(w, c)?;
    }
    comment(w, "Control section: add your I/O options and SUBCASEs here.")?;
    writeln!(w, "CEND")?;
    writeln!(w, "BEGIN BULK")?;
    write_grids(mesh, w)?;
    for (e, el) in mesh.elements.iter().enumerate() {
        let theta = angles.element[e].map(|a| real(deg(a)));
        write_element(mesh, el, cards.element_pid[e], theta, w)?;
    }
    write_cards(&cards.cards, w)?;
    let mut stack = vec![STACK_ID.to_string(), String::new()];
    for (k, ply) in map.plies.iter().enumerate() {
        let id = (k + 1) as u64;
        let covered: Vec<usize> = (0..mesh.elements.len()).filter(|&e| ply.elements[e].is_some()).collect();
        writeln!(w, "$ ply {id} '{}': {} element(s) covered", ply.ply.replace(['\n', '\r'], " "), covered.len())?;
        let (Some(&first), Some(mid)) = (covered.first(), cards.ply_mid[k]) else {
            writeln!(w, "$ ply {id} covers no element of this mesh: no PLY written")?;
            continue;
        };
        stack.push(id.to_string());
        let t0 = ply.elements[first].as_ref().expect("covered").nominal_thickness;
        let mut set = vec![id.to_string(), "ELEM".into(), "LIST".into()];
        pad8(&mut set);
        set.extend(covered.iter().map(|&e| mesh.elements[e].id.to_string()));
        pad8(&mut set);
        large(w, "SET", &set)?;
        let mut drape = vec![id.to_string()];
        pad8(&mut drape);
        for &e in &covered {
            let f = ply.elements[e].as_ref().expect("covered");
            let thinning = f.thickness / t0;
            drape.extend([
                "ELEM".to_string(),
                mesh.elements[e].id.to_string(),
                real(thinning),
                real(deg(angles.drape(k, e, f.theta))),
            ]);
            pad8(&mut drape);
        }
        large(w, "DRAPE", &drape)?;
        let mut card = vec![
            id.to_string(),
            mid.to_string(),
            real(t0 / mesh.scale),
            real(deg(angles.ply[k])),
            String::new(),
            String::new(),
            id.to_string(),
        ];
        pad8(&mut card);
        card.push(id.to_string());
        large(w, "PLY", &card)?;
    }
    if stack.len() > 2 {
        large(w, "STACK", &stack)?;
    }
    writeln!(w, "ENDDATA")
}
