//! CalculiX input decks (`.inp`) carrying a ply's fibre orientation per element, for CalculiX's
//! `ccx` (the open solver that reads Abaqus-style input). CalculiX decks are read as meshes by
//! the Abaqus reader ([`super::abaqus`]): the syntax is the same.
//!
//! Why not the Abaqus deck: CalculiX reads each `*DISTRIBUTION` value as a 20-character field,
//! and its `*SHELL SECTION` gives every element of its set the one orientation the section names,
//! so distributions never reach an element. This deck gives each orientation its own element set
//! and shell section instead (CalculiX User's Manual: `*ORIENTATION`, `*SHELL SECTION`).
//!
//! Layout (one deck per ply; for a layup `STEM_<ply>.inp` beside `out`, as for Nastran):
//! ```text
//! *NODE, NSET=DRAPE_NODES                        id, x, y, z
//! *ELEMENT, TYPE=S3, ELSET=DRAPE_S3              id, n1, n2, n3
//! *ELEMENT, TYPE=S4, ELSET=DRAPE_S4              id, n1, n2, n3, n4
//! per orientation k (elements with the same warp, weft and thickness share one):
//! *ELSET, ELSET=DRAPE_E<k>                       its elements
//! *ORIENTATION, NAME=DRAPE_O<k>, SYSTEM=RECTANGULAR
//! a1, a2, a3, b1, b2, b3                         a = warp, b = weft, both in the element's plane
//! *SHELL SECTION, ELSET=DRAPE_E<k>, MATERIAL=<name>, ORIENTATION=DRAPE_O<k>
//! t                                              the ply's thickness there
//! *ELSET, ELSET=DRAPE_COVERED                    every element the ply covers
//! *ELSET, ELSET=DRAPE_UNCOVERED                  the others, with no section (only if any)
//! ```
//! CalculiX takes local 1 along a and local 2 in the plane of a and b, so local 1 is the warp
//! and local 3 the element's normal. The material is the user's: define `*MATERIAL, NAME=<name>`
//! (`--material-name`, default [`DEFAULT_MATERIAL`]) in the deck that includes this one, and give
//! the uncovered elements a section of your own. Every number fits CalculiX's 20-character
//! fields ([`short`]).
use super::flow::ply_files;
use super::{write_atomic, ExportError};
use crate::mapping::{ElementShape, FlowMesh, LayupMap, PlyMap};
use std::collections::BTreeMap;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// The material name sections refer to when none is given.
pub const DEFAULT_MATERIAL: &str = "PLY_MATERIAL";
/// CalculiX reads numbers in fields of this many characters.
pub const FIELD_WIDTH: usize = 20;
/// Elements per data line of `*ELSET` (CalculiX and Abaqus take at most 16).
const PER_LINE: usize = 16;

/// `x` in at most [`FIELD_WIDTH`] characters with 13 significant digits (`-1.234567890123E-5`).
pub fn short(x: f64) -> String {
    format!("{x:.12E}")
}

/// Whether `name` can name a CalculiX material: a letter, then letters, digits and `_`, at most
/// 80 characters.
pub fn check_material_name(name: &str) -> Result<(), String> {
    let ok = name.len() <= 80
        && name.chars().next().is_some_and(|c| c.is_ascii_alphabetic())
        && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
    if ok {
        Ok(())
    } else {
        Err(format!(
            "'{name}' cannot name a CalculiX material: give a letter then letters, digits or _ (at most 80 characters)"
        ))
    }
}

/// Write one deck per ply (see the module documentation); returns the files written.
pub(crate) fn write_flow(
    mesh: &FlowMesh,
    map: &LayupMap,
    out: &Path,
    material: &str,
) -> Result<Vec<PathBuf>, ExportError> {
    let targets = check(map, out, material)?;
    for (path, ply) in &targets {
        write_atomic(path, |w| write_deck(mesh, ply, material, w))?;
    }
    Ok(targets.into_iter().map(|(p, _)| p).collect())
}

/// What [`write_flow`] checks before it writes (the material name, ply names that become file
/// names): the deck of each ply, or why none can be written.
pub(crate) fn check<'a>(
    map: &'a LayupMap,
    out: &Path,
    material: &str,
) -> Result<Vec<(PathBuf, &'a PlyMap)>, ExportError> {
    check_material_name(material).map_err(|reason| ExportError::FlowInvalid { format: "calculix", reason })?;
    ply_files("calculix", map, out)
}

/// The flow mesh as Abaqus/CalculiX input: its nodes (set DRAPE_NODES) and shell elements (S3
/// in DRAPE_S3, S4 in DRAPE_S4), numbers in [`short`] form. Shared with the Abaqus writer.
pub(crate) fn write_mesh<W: Write>(mesh: &FlowMesh, w: &mut W) -> io::Result<()> {
    writeln!(w, "*NODE, NSET=DRAPE_NODES")?;
    for (p, id) in mesh.nodes.iter().zip(&mesh.node_ids) {
        writeln!(w, "{id}, {}, {}, {}", short(p.x), short(p.y), short(p.z))?;
    }
    for (shape, ty) in [(ElementShape::Tria3, "S3"), (ElementShape::Quad4, "S4")] {
        let els: Vec<_> = mesh.elements.iter().filter(|e| e.shape == shape).collect();
        if els.is_empty() {
            continue;
        }
        writeln!(w, "*ELEMENT, TYPE={ty}, ELSET=DRAPE_{ty}")?;
        for el in els {
            let nodes: Vec<String> = el.nodes.iter().map(|&k| mesh.node_ids[k].to_string()).collect();
            writeln!(w, "{}, {}", el.id, nodes.join(", "))?;
        }
    }
    Ok(())
}

fn write_deck<W: Write>(mesh: &FlowMesh, ply: &PlyMap, material: &str, w: &mut W) -> io::Result<()> {
    let name = ply.ply.replace(['\n', '\r'], " ");
    writeln!(w, "** drape: fibre orientation of ply '{name}' on flow mesh {}", mesh.path.display())?;
    writeln!(w, "** local 1 = warp, local 2 in the plane of warp and weft, local 3 = element normal.")?;
    writeln!(w, "** Define *MATERIAL, NAME={material} (orthotropic, 1 = warp) in the deck that includes this one.")?;
    write_mesh(mesh, w)?;
    // Elements whose orientation and thickness read the same in the file share a section.
    let mut groups: BTreeMap<(String, String), Vec<u64>> = BTreeMap::new();
    let mut order: Vec<(String, String)> = Vec::new();
    let (mut covered, mut uncovered) = (Vec::new(), Vec::new());
    for (el, f) in mesh.elements.iter().zip(&ply.elements) {
        let Some(f) = f else {
            uncovered.push(el.id);
            continue;
        };
        covered.push(el.id);
        let (a, b) = (f.warp, f.weft);
        let key = ([a.x, a.y, a.z, b.x, b.y, b.z].map(short).join(", "), short(f.thickness));
        let members = groups.entry(key.clone()).or_default();
        if members.is_empty() {
            order.push(key);
        }
        members.push(el.id);
    }
    for (k, key) in order.iter().enumerate() {
        let k = k + 1;
        elset(w, &format!("DRAPE_E{k}"), &groups[key])?;
        writeln!(w, "*ORIENTATION, NAME=DRAPE_O{k}, SYSTEM=RECTANGULAR")?;
        writeln!(w, "{}", key.0)?;
        writeln!(w, "*SHELL SECTION, ELSET=DRAPE_E{k}, MATERIAL={material}, ORIENTATION=DRAPE_O{k}")?;
        writeln!(w, "{}", key.1)?;
    }
    elset(w, "DRAPE_COVERED", &covered)?;
    if !uncovered.is_empty() {
        writeln!(
            w,
            "** {} element(s) not covered by ply '{name}': no section here, give them one of your own",
            uncovered.len()
        )?;
        elset(w, "DRAPE_UNCOVERED", &uncovered)?;
    }
    Ok(())
}

/// An `*ELSET` of the element ids, [`PER_LINE`] to a data line. Shared with the Abaqus writer.
pub(crate) fn elset<W: Write>(w: &mut W, name: &str, ids: &[u64]) -> io::Result<()> {
    writeln!(w, "*ELSET, ELSET={name}")?;
    for chunk in ids.chunks(PER_LINE) {
        let s: Vec<String> = chunk.iter().map(u64::to_string).collect();
        writeln!(w, "{}", s.join(", "))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_fit_the_field() {
        for x in [-1.0283190065843826E-5, -1.7976931348623157e308, 0.0, -0.0, 1.0, -123456.789e-300, f64::MIN_POSITIVE]
        {
            let s = short(x);
            assert!(s.len() <= FIELD_WIDTH, "{s}");
            let back: f64 = s.parse().unwrap();
            assert!((back - x).abs() <= 1e-12 * x.abs(), "{s}");
        }
        assert!(check_material_name("PLY_MATERIAL").is_ok());
        assert!(check_material_name("1X").is_err() && check_material_name("A B").is_err());
    }
}
