//! What `drape run` does, as library calls: a scene file ([`scene`]) read, every ply draped on
//! the tool offset by the plies below it and refined where it asks, the nets, flat patterns,
//! nesting, layup table and flow-mesh fields written ([`run`]). The command line only prints what
//! [`run::run`] reports.
pub mod export;
pub mod failure;
pub mod folder;
pub mod ply;
pub mod refine;
pub mod run;
pub mod scene;

pub use scene::{Scene, SceneError};

use crate::io::points::read_points;
use crate::kinematic::GeneratorKind;
use std::path::Path;

/// Parse `X,Y,Z` into three finite numbers.
pub fn parse_vec3(s: &str) -> Result<[f64; 3], String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let nums: Result<Vec<f64>, _> = parts.iter().map(|p| p.parse::<f64>()).collect();
    match nums {
        Ok(v) if v.len() == 3 && v.iter().all(|x| x.is_finite()) => Ok([v[0], v[1], v[2]]),
        _ => Err(format!("'{s}' is not a vector: give three finite numbers separated by commas, like 0,0,1.5")),
    }
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
