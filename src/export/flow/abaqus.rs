//! Abaqus input deck: the flow mesh as shell elements and, per ply, a local material
//! orientation per element (Abaqus Keywords Reference: *DISTRIBUTION TABLE, *DISTRIBUTION,
//! *ORIENTATION).
//!
//! Layout:
//! ```text
//! *NODE, NSET=DRAPE_NODES                        id, x, y, z
//! *ELEMENT, TYPE=S3, ELSET=DRAPE_S3              id, n1, n2, n3
//! *ELEMENT, TYPE=S4, ELSET=DRAPE_S4              id, n1, n2, n3, n4
//! *DISTRIBUTION TABLE, NAME=DRAPE_DIRECTIONS     COORD3D, COORD3D
//! per ply P (TAG = "P<k>_" + the ply name with characters other than A-Z, a-z, 0-9, _ as _):
//! *ELSET, ELSET=<TAG>                            the elements the ply covers (16 per line)
//! *ELSET, ELSET=<TAG>_UNCOVERED                  the others (only if any)
//! *DISTRIBUTION, NAME=<TAG>_DIR, LOCATION=ELEMENT, TABLE=DRAPE_DIRECTIONS
//! , 1., 0., 0., 0., 1., 0.                       default line (required; used by no element)
//! id, a1, a2, a3, b1, b2, b3                     a = warp, b = weft (covered elements only)
//! *ORIENTATION, NAME=<TAG>_ORI, SYSTEM=RECTANGULAR, DEFINITION=COORDINATES
//! <TAG>_DIR
//! 3, 0.
//! ```
//! Abaqus takes local 1 = a projected onto the shell and local 2 in the plane of a and b, so
//! local 1 is the warp; b = weft keeps the sheared weft in the file (angle a-b = 90 - shear).
//! Reference the orientation from your *SHELL SECTION / *SHELL SECTION, COMPOSITE on ELSET <TAG>.
use super::{write_atomic, ExportError, FlowMesh, LayupMap};
use crate::export::flowmesh::ElementShape;
use std::io::{self, Write};
use std::path::Path;

/// Name of the shared distribution table.
pub const TABLE: &str = "DRAPE_DIRECTIONS";
/// Abaqus allows at most 16 entries on a data line of *ELSET.
const PER_LINE: usize = 16;

pub(super) fn write(mesh: &FlowMesh, map: &LayupMap, out: &Path) -> Result<(), ExportError> {
    write_atomic(out, |w| write_to(mesh, map, w))
}

/// The Abaqus name of ply `k` (0-based): unique, starts with a letter, at most 80 characters.
pub fn ply_tag(k: usize, ply: &str) -> String {
    let clean: String = ply.chars().map(|c| if c.is_ascii_alphanumeric() || c == '_' { c } else { '_' }).collect();
    let mut tag = format!("P{}_{clean}", k + 1);
    tag.truncate(64); // room for the _UNCOVERED / _DIR / _ORI suffixes
    tag
}

fn write_to<W: Write>(mesh: &FlowMesh, map: &LayupMap, w: &mut W) -> io::Result<()> {
    writeln!(w, "** drape: fibre orientations on flow mesh {}", mesh.path.display())?;
    writeln!(w, "*HEADING")?;
    writeln!(w, "drape fibre orientations, {} ply(s)", map.plies.len())?;
    for (k, ply) in map.plies.iter().enumerate() {
        writeln!(w, "** ply {} '{}' -> {}", k + 1, ply.ply.replace(['\n', '\r'], " "), ply_tag(k, &ply.ply))?;
    }
    writeln!(w, "*NODE, NSET=DRAPE_NODES")?;
    for (p, id) in mesh.nodes.iter().zip(&mesh.node_ids) {
        writeln!(w, "{id}, {:?}, {:?}, {:?}", p.x, p.y, p.z)?;
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
    writeln!(w, "*DISTRIBUTION TABLE, NAME={TABLE}")?;
    writeln!(w, "COORD3D, COORD3D")?;
    for (k, ply) in map.plies.iter().enumerate() {
        let tag = ply_tag(k, &ply.ply);
        let ids = |covered: bool| -> Vec<u64> {
            mesh.elements.iter().zip(&ply.elements).filter(|(_, f)| f.is_some() == covered).map(|(e, _)| e.id).collect()
        };
        let (cov, unc) = (ids(true), ids(false));
        elset(w, &tag, &cov)?;
        if !unc.is_empty() {
            writeln!(
                w,
                "** {} element(s) not covered by ply '{}': no orientation",
                unc.len(),
                ply.ply.replace(['\n', '\r'], " ")
            )?;
            elset(w, &format!("{tag}_UNCOVERED"), &unc)?;
        }
        writeln!(w, "*DISTRIBUTION, NAME={tag}_DIR, LOCATION=ELEMENT, TABLE={TABLE}")?;
        writeln!(w, ", 1., 0., 0., 0., 1., 0.")?;
        for (el, f) in mesh.elements.iter().zip(&ply.elements) {
            if let Some(f) = f {
                let (a, b) = (f.warp, f.weft);
                writeln!(w, "{}, {:?}, {:?}, {:?}, {:?}, {:?}, {:?}", el.id, a.x, a.y, a.z, b.x, b.y, b.z)?;
            }
        }
        writeln!(w, "*ORIENTATION, NAME={tag}_ORI, SYSTEM=RECTANGULAR, DEFINITION=COORDINATES")?;
        writeln!(w, "{tag}_DIR")?;
        writeln!(w, "3, 0.")?;
    }
    Ok(())
}

fn elset<W: Write>(w: &mut W, name: &str, ids: &[u64]) -> io::Result<()> {
    writeln!(w, "*ELSET, ELSET={name}")?;
    for chunk in ids.chunks(PER_LINE) {
        let s: Vec<String> = chunk.iter().map(u64::to_string).collect();
        writeln!(w, "{}", s.join(", "))?;
    }
    Ok(())
}
