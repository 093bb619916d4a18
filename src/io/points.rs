//! Points files: one point a line (a ply outline, a steering curve).
use crate::geometry::Point;
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
