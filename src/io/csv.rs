//! CSV files: the cells of a draped net and the fibres of a layup on a flow mesh.
//!
//! `<ply>.cells.csv`: one row per complete cell (all four corners placed), in cell order, with its
//! centre, shear (degrees) and unit fibre frame, and for a net that records its wrinkles their
//! measures ([`CSV_WRINKLE_COLUMNS`]). Floats are written with `{:?}` (shortest exact round trip, exponent when needed).
//!
//! The flow CSV (`drape export --format csv`, `flow.csv`): one row per element and ply (elements in mesh order, plies in stacking order).
//!
//! Columns: see [`FLOW_CSV_HEADER`]. `covered` is 1 or 0; for an uncovered element every
//! column after `covered` is empty, and `k11..k33` (permeability, row-major, m^2) are empty
//! when the map has no permeability. Angles in degrees, floats with `{:?}` (exact). Ply names
//! are quoted when they contain a comma, quote or line break (RFC 4180).
use super::check::{cells, check_net};
use super::flow::deg;
use super::{write_atomic, ExportError};
use crate::kinematic::DrapeNet;
use crate::mapping::{FlowMesh, LayupMap};
use std::io::{self, Write};
use std::path::Path;
/// The header line of the cell CSV (its first columns, all a net without wrinkles has).
pub const CSV_HEADER: &str =
    "i,j,cx,cy,cz,shear_deg,warp_x,warp_y,warp_z,weft_x,weft_y,weft_z,normal_x,normal_y,normal_z";
/// The columns after [`CSV_HEADER`] of a net that records its wrinkles (`meta.wrinkles`):
/// waviness (m), wrinkled (1 where the waviness exceeds the record's threshold and the ply
/// undulates, `WrinkleRecord::wrinkled`, else 0) and the
/// tool gap (m); then `bending_energy_density_j_m2` when the record has it.
pub const CSV_WRINKLE_COLUMNS: &str = "waviness_m,wrinkled,tool_gap_m";

/// Write the complete cells of `net` to `path` (normally `DIR/<ply>.cells.csv`) atomically.
/// Fails, writing nothing, if a value would not be finite or a complete cell is degenerate.
pub fn write_csv(net: &DrapeNet, path: &Path) -> Result<(), ExportError> {
    check_net(net, true)?;
    write_atomic(path, |w| write_csv_to(net, w))
}

fn write_csv_to<W: Write>(net: &DrapeNet, w: &mut W) -> io::Result<()> {
    let wrinkles = net.meta.wrinkles.as_ref();
    let bending = wrinkles.is_some_and(|wr| !wr.bending_energy_density_j_m2.is_empty());
    let mut header = CSV_HEADER.to_string();
    if wrinkles.is_some() {
        header += &format!(",{CSV_WRINKLE_COLUMNS}");
    }
    if bending {
        header += ",bending_energy_density_j_m2";
    }
    writeln!(w, "{header}")?;
    let cv = net.nv.saturating_sub(1);
    for (i, j) in cells(net) {
        let (Some(g), Some(f)) = (net.cell_shear(i, j), net.cell_frame(i, j)) else { continue };
        let (c, a, b, n) = (f.centre, f.warp, f.weft, f.normal);
        // The net check made sure every complete cell has each measure the record holds.
        let mut extra = String::new();
        if let Some(wr) = wrinkles {
            let at = |list: &[Option<f64>]| list[i * cv + j].expect("checked: complete cell");
            let waviness = at(&wr.waviness_m);
            let wrinkled = wr.wrinkled(i * cv + j).expect("checked: complete cell") as u8;
            extra += &format!(",{waviness:?},{wrinkled},{:?}", at(&wr.tool_gap_m));
            if bending {
                extra += &format!(",{:?}", at(&wr.bending_energy_density_j_m2));
            }
        }
        writeln!(
            w,
            "{i},{j},{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?},{:?}{extra}",
            c.x,
            c.y,
            c.z,
            g.to_degrees(),
            a.x,
            a.y,
            a.z,
            b.x,
            b.y,
            b.z,
            n.x,
            n.y,
            n.z
        )?;
    }
    Ok(())
}

// ---- the flow CSV ---------------------------------------------------------------------------

/// Header line of the flow CSV.
pub const FLOW_CSV_HEADER: &str = "element_id,ply,covered,warp_x,warp_y,warp_z,weft_x,weft_y,weft_z,shear_deg,theta_deg,angle_change_deg,thickness,vf,k11,k12,k13,k21,k22,k23,k31,k32,k33";

pub(crate) fn write_flow(mesh: &FlowMesh, map: &LayupMap, out: &Path) -> Result<(), ExportError> {
    write_atomic(out, |w| write_flow_to(mesh, map, w))
}

fn quote(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

fn write_flow_to<W: Write>(mesh: &FlowMesh, map: &LayupMap, w: &mut W) -> io::Result<()> {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Point;
    use crate::kinematic::NodeStatus;

    #[test]
    fn rows_for_complete_cells_only() {
        let mut net = DrapeNet::new("p", 0.5, 3, 2, (0, 0));
        for i in 0..3 {
            for j in 0..2 {
                let k = net.index(i, j);
                net.positions[k] = Point::new(0.5 * i as f64, 0.5 * j as f64, 1.0);
                net.status[k] = NodeStatus::Placed;
            }
        }
        let k = net.index(2, 1);
        net.status[k] = NodeStatus::OffTool;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.cells.csv");
        write_csv(&net, &path).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert_eq!(text, format!("{CSV_HEADER}\n0,0,0.25,0.25,1.0,0.0,1.0,0.0,0.0,0.0,1.0,0.0,0.0,0.0,1.0\n"));
    }
}
