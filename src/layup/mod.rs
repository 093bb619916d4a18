//! Scenes: the tool and the plies to drape on it, read from TOML.
pub mod flat;
pub mod nest;
pub mod scene;
pub mod stack;

pub use scene::{Ply, Scene, SceneError};

use crate::geometry::{ObjError, Point, ToolSurface};
use crate::kinematic::GeneratorKind;
use std::path::Path;

/// Read a points file: one point a line as `x,y,z` (commas and/or spaces), `#` comments and
/// blank lines ignored, an optional header line of non-numbers skipped. Lengths scaled by `scale`.
pub fn read_points(path: &Path, scale: f64) -> Result<Vec<Point>, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read points file {}: {e}. Check the path.", path.display()))?;
    let mut points = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let fields: Vec<&str> = line.split(|c: char| c == ',' || c.is_whitespace()).filter(|f| !f.is_empty()).collect();
        let numbers: Result<Vec<f64>, _> = fields.iter().map(|f| f.parse::<f64>()).collect();
        match numbers {
            Ok(v) if v.len() == 3 && v.iter().all(|x| x.is_finite()) => {
                points.push(Point::new(v[0], v[1], v[2]) * scale)
            }
            Err(_) if points.is_empty() && n == 0 => continue, // header
            _ => {
                return Err(format!(
                    "{} line {}: expected three finite numbers x,y,z, found '{line}'",
                    path.display(),
                    n + 1
                ))
            }
        }
    }
    Ok(points)
}

/// Parse a generator choice: `geodesic`, `min-shear`, or `steer:FILE` (FILE relative to `base`).
pub fn parse_generators(s: &str, base: &Path, scale: f64) -> Result<GeneratorKind, String> {
    match s.trim() {
        "geodesic" => Ok(GeneratorKind::Geodesic),
        "min-shear" => Ok(GeneratorKind::MinShear),
        other => match other.strip_prefix("steer:") {
            Some(file) if !file.trim().is_empty() => {
                Ok(GeneratorKind::Steer(read_points(&base.join(file.trim()), scale)?))
            }
            _ => Err(format!(
                "unknown generators '{other}': use geodesic, min-shear or steer:FILE (a curve, x,y,z per line)"
            )),
        },
    }
}

/// Length scale of a unit name: `m` (1) or `mm` (0.001).
pub fn unit_scale(units: &str) -> Result<f64, String> {
    match units.trim() {
        "m" => Ok(1.0),
        "mm" => Ok(1e-3),
        other => Err(format!("unknown units '{other}': use \"m\" or \"mm\"")),
    }
}

/// Read a tool surface: an OBJ, or any shell mesh the flow-mesh readers take (an Abaqus mould
/// deck, a Nastran or Gmsh mesh), its quads split into triangles. Lengths scaled by `scale`.
pub fn load_tool(path: &Path, scale: f64) -> Result<ToolSurface, String> {
    let is_obj = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("obj"));
    if is_obj {
        return ToolSurface::from_obj_scaled(path, scale).map_err(|e: ObjError| e.to_string());
    }
    let mesh = crate::io::read_flow_mesh(path, scale).map_err(|e| e.to_string())?;
    // Only the nodes the elements use: decks carry reference nodes (rigid bodies) that are not
    // part of the surface.
    let mut index = vec![u32::MAX; mesh.nodes.len()];
    let mut vertices = Vec::new();
    let mut triangles = Vec::new();
    for el in &mesh.elements {
        let ids: Vec<u32> = el
            .nodes
            .iter()
            .map(|&n| {
                if index[n] == u32::MAX {
                    index[n] = vertices.len() as u32;
                    vertices.push(mesh.nodes[n]);
                }
                index[n]
            })
            .collect();
        triangles.push([ids[0], ids[1], ids[2]]);
        if ids.len() == 4 {
            triangles.push([ids[0], ids[2], ids[3]]);
        }
    }
    ToolSurface::from_triangles(vertices, triangles).map_err(|e| format!("tool {}: {e}", path.display()))
}
