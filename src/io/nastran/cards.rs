//! The property and material cards of the Nastran and OptiStruct decks, so that a deck reads
//! alone: every PID its elements reference has a property card, and every material those cards
//! reference has a material card.
//!
//! * A PID the flow mesh gives a card for (PSHELL, PCOMP, PCOMPG, read by
//!   [`super::read`]) keeps it, as read, with the MAT1, MAT2 and MAT8 cards it refers to. A
//!   card that refers to a material the mesh does not give is refused, naming both (the deck
//!   would not read).
//! * A PID the flow mesh gives no card for (an OBJ, Abaqus or Gmsh mesh, or a Nastran mesh
//!   without its properties) gets a PSHELL drape can justify: membrane only (MID1), thickness
//!   t0 of the ply, and a MAT8 from the ply's material card ([`PlyFabric`]: E1 and E2 the
//!   families' tensile rigidities over t0, G12 the shear stiffness at zero shear over t0, NU12 =
//!   0, RHO the areal mass over t0: the dry fabric, not a cured laminate). A ply without a card
//!   has nothing to justify one: refused, saying what to give.
//!
//! Numbers are written in the flow mesh's own units (lengths in its unit, forces in newtons,
//! times in seconds: MPa and t/mm^3 for a mesh in millimetres), so that carried cards and drape's
//! agree. Fresh ids (drape's MAT8, the OptiStruct deck's PIDs for elements no ply covers) start
//! above every id the mesh uses.
use super::write::pid;
use super::{fit_real, real};
use crate::io::ExportError;
use crate::mapping::{FlowMesh, LayupMap, MeshCard, PlyFabric, PlyMap};
use std::collections::{BTreeMap, BTreeSet};

/// Element ids named in a message, at most.
const LISTED: usize = 10;

/// A card to write: its name and data fields, the id first, in small-field numbering.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Entry {
    /// `PSHELL`, `MAT8`, ...
    pub name: String,
    /// Fields 2, 3, ... as text (at most 15 characters each).
    pub fields: Vec<String>,
}

/// The property and material cards of a deck, and what the deck and the command line say of them.
#[derive(Debug, Clone, Default)]
pub(crate) struct Cards {
    /// Properties, then materials, in the order they are written.
    pub entries: Vec<Entry>,
    /// Comment lines (without the `$`) saying where each card comes from.
    pub comments: Vec<String>,
    /// What drape wrote in the flow mesh's stead, for the command line.
    pub notes: Vec<String>,
}

/// The cards of one ply's Nastran deck (every element keeps its PID).
pub(crate) fn nastran(mesh: &FlowMesh, ply: &PlyMap) -> Result<Cards, ExportError> {
    let mut d = Deck::new(mesh, "nastran");
    let mut missing: BTreeMap<u64, Vec<u64>> = BTreeMap::new();
    for el in &mesh.elements {
        let p = pid(el);
        if mesh.cards.property(p).is_none() {
            missing.entry(p).or_default().push(el.id);
        }
    }
    let pids: BTreeSet<u64> = mesh.elements.iter().map(pid).collect();
    for &p in &pids {
        if let Some(card) = mesh.cards.property(p) {
            d.carry_property(card, p, format!("PID {p}: the flow mesh's {} ({})", card.name, card.origin))?;
        }
    }
    if !missing.is_empty() {
        let fabric = ply.fabric.as_ref().ok_or_else(|| d.no_fabric(&missing, &ply.ply))?;
        let mid = d.fabric_material(fabric, &ply.ply)?;
        for (&p, ids) in &missing {
            let uncovered = ids.iter().filter(|&&id| !covers(mesh, ply, id)).count();
            let also = if uncovered > 0 {
                format!(", its {uncovered} element(s) the ply does not cover too (no THETA)")
            } else {
                String::new()
            };
            d.fabric_pshell(
                p,
                mid,
                fabric,
                format!(
                    "PID {p}: no property card in the flow mesh: PSHELL {p} of ply '{}''s fabric (MAT8 {mid}){also}",
                    ply.ply
                ),
            );
        }
    }
    Ok(d.finish())
}

/// Whether `ply` covers the element with id `id`.
fn covers(mesh: &FlowMesh, ply: &PlyMap, id: u64) -> bool {
    mesh.elements.iter().zip(&ply.elements).any(|(el, f)| el.id == id && f.is_some())
}

/// The cards of the OptiStruct deck and the PID each element takes in it.
pub(crate) struct OptiStructCards {
    /// Properties and materials.
    pub cards: Cards,
    /// The PID of each element of the mesh, in mesh order.
    pub element_pid: Vec<u64>,
    /// The MID of each ply's MAT8, `None` for a ply that covers no element (no PLY card).
    pub ply_mid: Vec<Option<u64>>,
}

/// The cards of the OptiStruct ply-based deck. Elements some ply covers reference a PCOMPP with
/// their own PID (the plies, through PLY and STACK, give the laminate, so the mesh's card of that
/// PID is not written); elements no ply covers keep their PID and its card, or, when their PID
/// also has covered elements, take a fresh PID with that card renumbered (OptiStruct puts every
/// element of a PCOMPP in a ply). Each ply that covers an element gets a MAT8 of its fabric.
pub(crate) fn optistruct(mesh: &FlowMesh, map: &LayupMap) -> Result<OptiStructCards, ExportError> {
    let mut d = Deck::new(mesh, "optistruct");
    let n = mesh.elements.len();
    let covered: Vec<bool> = (0..n).map(|e| map.plies.iter().any(|p| p.elements[e].is_some())).collect();
    let pcompp: BTreeSet<u64> = (0..n).filter(|&e| covered[e]).map(|e| pid(&mesh.elements[e])).collect();
    let mut next_pid = mesh
        .elements
        .iter()
        .map(pid)
        .chain(mesh.cards.properties.iter().map(|c| c.id))
        .max()
        .unwrap_or(0)
        + 1;
    // Elements no ply covers: their PID, or a fresh one standing for it beside a PCOMPP.
    let mut fresh: BTreeMap<u64, u64> = BTreeMap::new();
    let mut element_pid = Vec::with_capacity(n);
    let mut others: BTreeMap<u64, (u64, Vec<u64>)> = BTreeMap::new(); // PID -> (source PID, elements)
    for (e, el) in mesh.elements.iter().enumerate() {
        let p = pid(el);
        let q = if covered[e] {
            p
        } else if pcompp.contains(&p) {
            *fresh.entry(p).or_insert_with(|| {
                next_pid += 1;
                next_pid - 1
            })
        } else {
            p
        };
        if !covered[e] {
            others.entry(q).or_insert((p, Vec::new())).1.push(el.id);
        }
        element_pid.push(q);
    }
    let mut ply_mid = Vec::with_capacity(map.plies.len());
    for ply in &map.plies {
        if ply.elements.iter().all(Option::is_none) {
            ply_mid.push(None);
            continue;
        }
        let fabric = ply.fabric.as_ref().ok_or_else(|| {
            d.invalid(format!(
                "ply '{}' has no material card: its PLY needs a material, which drape writes as a MAT8 from the ply's card; give the ply a material card (--material CARD, or material = ... in the scene)",
                ply.ply
            ))
        })?;
        ply_mid.push(Some(d.fabric_material(fabric, &ply.ply)?));
    }
    for &p in &pcompp {
        let replaced = match mesh.cards.property(p) {
            Some(card) => format!("; it replaces the flow mesh's {} {p} ({})", card.name, card.origin),
            None => String::new(),
        };
        d.entries.push(Entry { name: "PCOMPP".into(), fields: vec![p.to_string()] });
        d.comments.push(format!("PID {p}: PCOMPP, the plies (PLY, STACK) give its laminate{replaced}"));
    }
    // The bottom ply with a fabric gives the elements no ply covers a property when the mesh has none.
    let bottom = map.plies.iter().zip(&ply_mid).find_map(|(ply, mid)| Some((ply, (*mid)?)));
    for (&q, (p, ids)) in &others {
        let stands = if q == *p { String::new() } else { format!(" (PID {p} in the flow mesh)") };
        match mesh.cards.property(*p) {
            Some(card) => d.carry_property(
                card,
                q,
                format!("PID {q}{stands}: elements no ply covers, the flow mesh's {} {p} ({})", card.name, card.origin),
            )?,
            None => {
                let (ply, mid, fabric) = match bottom {
                    Some((ply, mid)) => (ply, mid, ply.fabric.as_ref().expect("a ply with a MAT8 has a fabric")),
                    None => {
                        let fabric = map.plies.iter().find_map(|p| p.fabric.as_ref().map(|f| (p, f)));
                        let Some((ply, fabric)) = fabric else {
                            return Err(d.no_fabric(&BTreeMap::from([(*p, ids.clone())]), &map.plies[0].ply));
                        };
                        (ply, d.fabric_material(fabric, &ply.ply)?, fabric)
                    }
                };
                d.fabric_pshell(
                    q,
                    mid,
                    fabric,
                    format!(
                        "PID {q}{stands}: {} element(s) no ply covers and no property card in the flow mesh: PSHELL {q} of ply '{}''s fabric (MAT8 {mid}) so that the deck reads alone; give them your own property",
                        ids.len(),
                        ply.ply
                    ),
                );
            }
        }
    }
    Ok(OptiStructCards { cards: d.finish(), element_pid, ply_mid })
}

/// The cards of a deck as they are gathered.
struct Deck<'a> {
    mesh: &'a FlowMesh,
    format: &'static str,
    entries: Vec<Entry>,
    materials: Vec<Entry>,
    comments: Vec<String>,
    notes: Vec<String>,
    /// Carried materials already written.
    carried: BTreeSet<u64>,
    /// The MAT8 of each ply's fabric already written (by ply name).
    fabrics: BTreeMap<String, u64>,
    next_mid: u64,
}

impl<'a> Deck<'a> {
    fn new(mesh: &'a FlowMesh, format: &'static str) -> Deck<'a> {
        let next_mid = mesh.cards.materials.iter().map(|c| c.id).max().unwrap_or(0) + 1;
        Deck {
            mesh,
            format,
            entries: Vec::new(),
            materials: Vec::new(),
            comments: Vec::new(),
            notes: Vec::new(),
            carried: BTreeSet::new(),
            fabrics: BTreeMap::new(),
            next_mid,
        }
    }

    fn invalid(&self, reason: String) -> ExportError {
        ExportError::FlowInvalid { format: self.format, reason }
    }

    /// The error for PIDs without a card when there is no fabric to write one from.
    fn no_fabric(&self, missing: &BTreeMap<u64, Vec<u64>>, ply: &str) -> ExportError {
        let (p, ids) = missing.iter().next().expect("a PID without a card");
        let mut listed: Vec<String> = ids.iter().take(LISTED).map(u64::to_string).collect();
        if ids.len() > LISTED {
            listed.push(format!("and {} more", ids.len() - LISTED));
        }
        let others = if missing.len() > 1 { format!(" (and {} other PIDs)", missing.len() - 1) } else { String::new() };
        self.invalid(format!(
            "PID {p}{others} of flow mesh {} (elements {}) has no PSHELL, PCOMP or PCOMPG in the mesh, and ply '{ply}' has no material card to write one from, so the deck would not read alone: give the ply a material card (--material CARD, or material = ... in the scene), or a Nastran flow mesh with the property and material cards of its PIDs",
            self.mesh.path.display(),
            listed.join(", ")
        ))
    }

    /// Write the mesh's property `card` as PID `id` (renumbered when it differs) and the
    /// materials it refers to.
    fn carry_property(&mut self, card: &MeshCard, id: u64, comment: String) -> Result<(), ExportError> {
        for mid in material_ids(card).map_err(|m| self.invalid(m))? {
            if self.carried.contains(&mid) {
                continue;
            }
            let Some(mat) = self.mesh.cards.material(mid) else {
                let not_carried = &self.mesh.cards.not_carried;
                let also = if not_carried.is_empty() {
                    String::new()
                } else {
                    format!(" (cards drape does not carry: {})", not_carried.join(", "))
                };
                return Err(self.invalid(format!(
                    "the flow mesh's {} {} ({}) refers to material {mid}, which the mesh does not give as MAT1, MAT2 or MAT8{also}, so the deck would not read alone: add the material card to the flow mesh",
                    card.name, card.id, card.origin
                )));
            };
            self.carried.insert(mid);
            self.materials.push(Entry { name: mat.name.clone(), fields: mat.fields.clone() });
            self.comments.push(format!("MID {mid}: the flow mesh's {} ({})", mat.name, mat.origin));
        }
        let mut fields = card.fields.clone();
        fields[0] = id.to_string();
        self.entries.push(Entry { name: card.name.clone(), fields });
        self.comments.push(comment);
        Ok(())
    }

    /// The MAT8 of `ply`'s fabric (written once), its MID.
    fn fabric_material(&mut self, fabric: &PlyFabric, ply: &str) -> Result<u64, ExportError> {
        if let Some(&mid) = self.fabrics.get(ply) {
            return Ok(mid);
        }
        let m = fabric.moduli();
        for (what, v) in [("E1", m.e1), ("E2", m.e2), ("G12", m.g12), ("RHO", m.density)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(self.invalid(format!(
                    "ply '{ply}': its material card '{}' gives {what} = {v} for the MAT8 (from rigidities {} and {} N/m, shear stiffness {} N/m per rad at zero shear, areal mass {} kg/m^2, thickness {} m): a MAT8 needs it positive; give the card a shear law with stiffness at zero shear",
                    fabric.card, fabric.tension_warp, fabric.tension_weft, fabric.shear, fabric.areal_mass, fabric.thickness
                )));
            }
        }
        let mid = self.next_mid;
        self.next_mid += 1;
        let s = self.mesh.scale;
        // N, s and the mesh's length unit L (m): stress in N / L^2, density in (N s^2 / L) / L^3.
        let (stress, density) = (s * s, s.powi(4));
        let fields = vec![
            mid.to_string(),
            real(m.e1 * stress),
            real(m.e2 * stress),
            real(m.nu12),
            real(m.g12 * stress),
            String::new(),
            String::new(),
            real(m.density * density),
        ];
        self.materials.push(Entry { name: "MAT8".into(), fields });
        self.comments.push(format!(
            "MID {mid}: MAT8 of ply '{ply}''s material card '{}', the dry fabric: E1, E2 = tensile rigidities / t0, G12 = shear stiffness at zero shear / t0, NU12 = 0 (a pin-jointed net), RHO = areal mass / t0, t0 = {} m; in N, s and the mesh's length unit. Not a cured laminate: give your own for a structural analysis",
            fabric.card, fabric.thickness
        ));
        self.fabrics.insert(ply.to_string(), mid);
        Ok(mid)
    }

    /// A membrane PSHELL `pid` of material `mid`, thickness t0 of `fabric`, with a note.
    fn fabric_pshell(&mut self, pid: u64, mid: u64, fabric: &PlyFabric, comment: String) {
        let t = fit_real(fabric.thickness / self.mesh.scale, super::LARGE - 1).expect("a finite thickness");
        self.entries.push(Entry { name: "PSHELL".into(), fields: vec![pid.to_string(), mid.to_string(), t] });
        self.notes.push(format!("{}: {comment}", self.format));
        self.comments.push(comment);
    }

    fn finish(mut self) -> Cards {
        self.entries.append(&mut self.materials);
        if !self.mesh.cards.not_carried.is_empty() {
            self.comments.push(format!("not carried from the flow mesh: {}", self.mesh.cards.not_carried.join(", ")));
        }
        Cards { entries: self.entries, comments: self.comments, notes: self.notes }
    }
}

/// The material ids a property card refers to, in order: PSHELL's MID1 to MID4, each ply's MID
/// of PCOMP (four fields a ply) and PCOMPG (a line a ply); blanks (the ply above's) skipped.
fn material_ids(card: &MeshCard) -> Result<Vec<u64>, String> {
    let at: Vec<usize> = match card.name.as_str() {
        "PSHELL" => vec![1, 3, 5, 10],
        "PCOMP" => (8..card.fields.len()).step_by(4).collect(),
        "PCOMPG" => (9..card.fields.len()).step_by(8).collect(),
        _ => Vec::new(),
    };
    let mut ids = Vec::new();
    for k in at {
        let f = card.fields.get(k).map_or("", |f| f.trim());
        if f.is_empty() {
            continue;
        }
        match f.parse::<i64>() {
            // PSHELL's MID2 = -1 (plane strain) names no card.
            Ok(m) if m < 0 && card.name == "PSHELL" => {}
            Ok(m) if m > 0 && !ids.contains(&(m as u64)) => ids.push(m as u64),
            Ok(m) if m > 0 => {}
            _ => {
                return Err(format!(
                    "the flow mesh's {} {} ({}) field {} '{f}' is not a material id: drape carries cards with numeric ids only",
                    card.name,
                    card.id,
                    card.origin,
                    k + 2
                ))
            }
        }
    }
    Ok(ids)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn card(name: &str, fields: &[&str]) -> MeshCard {
        MeshCard {
            name: name.into(),
            id: fields[0].parse().unwrap(),
            fields: fields.iter().map(|f| f.to_string()).collect(),
            origin: "x.bdf line 1".into(),
        }
    }

    #[test]
    fn material_ids_of_each_property_layout() {
        let pshell = card("PSHELL", &["5", "100", ".002", "101", "", "100", "", "", "", "", "102"]);
        assert_eq!(material_ids(&pshell).unwrap(), [100, 101, 102]);
        assert_eq!(material_ids(&card("PSHELL", &["5", "100", ".002", "-1"])).unwrap(), [100]);
        // PCOMP: header line, then MID T THETA SOUT per ply; a blank MID is the ply above's.
        let pcomp = card("PCOMP", &["6", "", "", "", "", "", "", "", "200", ".1", "0.", "", "", ".1", "45.", "", "201", ".1"]);
        assert_eq!(material_ids(&pcomp).unwrap(), [200, 201]);
        // PCOMPG: a line a ply, GPLYID MID T THETA SOUT.
        let mut f = vec!["7", "", "", "", "", "", "", ""];
        f.extend(["1", "300", ".1", "0.", "", "", "", "", "2", "301", ".1", "90."]);
        assert_eq!(material_ids(&card("PCOMPG", &f)).unwrap(), [300, 301]);
        let e = material_ids(&card("PSHELL", &["5", "STEEL"])).unwrap_err();
        assert!(e.contains("field 3 'STEEL'") && e.contains("x.bdf line 1"), "{e}");
    }
}
