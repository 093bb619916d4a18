//! CSV, one row per element and ply (elements in mesh order, plies in stacking order).
//!
//! Columns: see [`FLOW_CSV_HEADER`]. `covered` is 1 or 0; for an uncovered element every
//! column after `covered` is empty, and `k11..k33` (permeability, row-major, m^2) are empty
//! when the map has no permeability. Angles in degrees, floats with `{:?}` (exact). Ply names
//! are quoted when they contain a comma, quote or line break (RFC 4180).
use super::{deg, write_atomic, ExportError, FlowMesh, LayupMap};
use std::io::{self, Write};
use std::path::Path;

/// Header line of the flow CSV.
pub const FLOW_CSV_HEADER: &str = "element_id,ply,covered,warp_x,warp_y,warp_z,weft_x,weft_y,weft_z,shear_deg,theta_deg,angle_change_deg,thickness,vf,k11,k12,k13,k21,k22,k23,k31,k32,k33";

pub(super) fn write(mesh: &FlowMesh, map: &LayupMap, out: &Path) -> Result<(), ExportError> {
    write_atomic(out, |w| write_to(mesh, map, w))
}

fn quote(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

fn write_to<W: Write>(mesh: &FlowMesh, map: &LayupMap, w: &mut W) -> io::Result<()> {
    writeln!(w, "{FLOW_CSV_HEADER}")?;
    for (e, el) in mesh.elements.iter().enumerate() {
        for ply in &map.plies {
            let name = quote(&ply.ply);
            let Some(f) = &ply.elements[e] else {
                writeln!(w, "{},{name},0{}", el.id, ",".repeat(20))?;
                continue;
            };
            write!(w, "{},{name},1", el.id)?;
            for v in [f.warp.x, f.warp.y, f.warp.z, f.weft.x, f.weft.y, f.weft.z] {
                write!(w, ",{v:?}")?;
            }
            for v in [f.shear.to_degrees(), deg(f.theta), deg(f.angle_change), f.thickness, f.vf] {
                write!(w, ",{v:?}")?;
            }
            match &f.permeability {
                Some(k) => {
                    for r in 0..3 {
                        for c in 0..3 {
                            write!(w, ",{:?}", k[(r, c)])?;
                        }
                    }
                }
                None => write!(w, "{}", ",".repeat(9))?,
            }
            writeln!(w)?;
        }
    }
    Ok(())
}
