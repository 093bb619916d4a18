//! OptiStruct ply-based composite bulk data (large-field fixed format): GRID, CTRIA3/CQUAD4,
//! and per ply a SET of its elements, a DRAPE table and a PLY referencing both (OptiStruct
//! Reference Guide: PLY, SET, DRAPE bulk data entries).
//!
//! OptiStruct puts the fibre of ply k in element e at element x-axis (edge G1 -> G2 turned by
//! the element's THETA) + PLY THETA_k + DRAPE THETA_k,e. drape writes
//! * element THETA_e = nominal angle of the first ply covering e (its `theta - angle_change`)
//!   less that ply's PLY THETA; elements no ply covers get no THETA; every element keeps the
//!   PID it has in the flow mesh ([`DEFAULT_PID`] where it has none);
//! * PLY THETA_k = circular mean over shared elements of the ply's nominal angle relative to
//!   the first ply (0 for the first ply): the ply angle as the part sees it;
//! * DRAPE per covered element: `ELEM, eid, T, THETA` with the thinning factor
//!   T = thickness / nominal thickness and THETA = `angle_change` (degrees) plus the (normally
//!   zero) part of the nominal angle the two terms above do not carry, so the sum is exactly the
//!   map's `theta`;
//! * PLY: ID k, MID 1, T = the ply's nominal thickness, DID k, ESID k (SET k, ELEM LIST).
//!
//! The deck is laid out as OptiStruct reads one: a control section (empty but for comments: add
//! your I/O options and subcases), `CEND`, `BEGIN BULK`, the bulk data, `ENDDATA`.
//! Not written (yours to add): MAT8 1, the PCOMPP properties of the flow mesh's PIDs and the
//! STACK ordering the plies.
use super::flow::{deg, wrap};
use super::nastran::write::{pid, write_element, write_grids, DEFAULT_PID};
use super::nastran::{large, real};
use super::{write_atomic, ExportError};
use crate::mapping::{FlowMesh, LayupMap};
use std::io::{self, Write};
use std::path::Path;

/// Material id the PLY entries reference.
pub const MID: u64 = 1;

pub(crate) fn write_flow(mesh: &FlowMesh, map: &LayupMap, out: &Path) -> Result<(), ExportError> {
    check(map)?;
    let angles = Angles::new(map);
    write_atomic(out, |w| write_to(mesh, map, &angles, w))
}

/// What [`write_flow`] checks before it writes.
pub(crate) fn check(map: &LayupMap) -> Result<(), ExportError> {
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
    Ok(())
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

fn write_to<W: Write>(mesh: &FlowMesh, map: &LayupMap, angles: &Angles, w: &mut W) -> io::Result<()> {
    writeln!(w, "$ drape: ply-based composite data on flow mesh {}", mesh.path.display())?;
    writeln!(w, "$ fibre angle = element THETA + PLY THETA + DRAPE THETA (deg, from edge G1->G2).")?;
    writeln!(
        w,
        "$ Add MAT8 {MID}, a PCOMPP for each PID of the flow mesh ({DEFAULT_PID} where it had none) and a STACK of the plies."
    )?;
    writeln!(w, "$ Control section: add your I/O options and SUBCASEs here.")?;
    writeln!(w, "CEND")?;
    writeln!(w, "BEGIN BULK")?;
    write_grids(mesh, w)?;
    for (e, el) in mesh.elements.iter().enumerate() {
        let theta = angles.element[e].map(|a| real(deg(a)));
        write_element(mesh, el, pid(el), theta, w)?;
    }
    for (k, ply) in map.plies.iter().enumerate() {
        let id = (k + 1) as u64;
        let covered: Vec<usize> = (0..mesh.elements.len()).filter(|&e| ply.elements[e].is_some()).collect();
        writeln!(w, "$ ply {id} '{}': {} element(s) covered", ply.ply.replace(['\n', '\r'], " "), covered.len())?;
        let Some(&first) = covered.first() else {
            writeln!(w, "$ ply {id} covers no element of this mesh: no PLY written")?;
            continue;
        };
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
            MID.to_string(),
            real(t0),
            real(deg(angles.ply[k])),
            String::new(),
            String::new(),
            id.to_string(),
        ];
        pad8(&mut card);
        card.push(id.to_string());
        large(w, "PLY", &card)?;
    }
    writeln!(w, "ENDDATA")
}
