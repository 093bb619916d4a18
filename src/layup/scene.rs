//! The scene file: a tool OBJ and the plies to drape on it.
//!
//! ```toml
//! units = "m"                 # "m" (default) or "mm": lengths here and in the OBJ
//! tool = "hemisphere-20k.obj" # relative to this file
//! [[ply]]
//! name = "p0"
//! origin = [0.0, 0.0, 0.1]
//! warp = [1.0, 0.0, 0.0]
//! spacing = 0.004
//! grid = [61, 61]             # or outline = [[x,y,z], ...] or outline_file = "outline.csv"
//! origin_node = [30, 30]      # optional (default: the centre)
//! pre_shear_deg = 0.0         # optional
//! generators = "geodesic"     # or "min-shear" or "steer:curve.csv"
//! locking_angle_deg = 45.0    # optional, for reporting
//! max_shear_deg = 75.0        # optional: nodes shearing past this are not placed
//! method = "kinematic"       # or "mechanical": kinematic, then refinement with
//! # material = "../../materials/glass-plain-weave.toml"   # card, relative to this file
//! # mode = "pressed"          # or "free" (gravity drape with one-sided contact)
//! ```
use super::{parse_generators, read_points, unit_scale};
use crate::geometry::{Point, Vector};
use crate::kinematic::{Extent, KinematicSettings, DEFAULT_MAX_SHEAR_DEG};
use crate::material::MaterialCard;
use crate::mechanics::ContactMode;
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// Locking angle used for reporting when a ply gives none (degrees; woven glass and carbon
/// lock between about 40 and 60 degrees).
pub const DEFAULT_LOCKING_ANGLE_DEG: f64 = 45.0;

/// Why a scene could not be read.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("cannot read scene {path}: {source}. Check the path.")]
    Io { path: PathBuf, source: std::io::Error },
    #[error("scene {path}: {message}")]
    Invalid { path: PathBuf, message: String },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    #[serde(default = "default_units")]
    units: String,
    tool: String,
    #[serde(default)]
    ply: Vec<toml::Spanned<PlyFile>>,
}

fn default_units() -> String {
    "m".into()
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PlyFile {
    name: String,
    origin: [f64; 3],
    warp: [f64; 3],
    spacing: f64,
    grid: Option<[usize; 2]>,
    outline: Option<Vec<[f64; 3]>>,
    outline_file: Option<String>,
    origin_node: Option<[usize; 2]>,
    #[serde(default)]
    pre_shear_deg: f64,
    #[serde(default = "default_generators")]
    generators: String,
    locking_angle_deg: Option<f64>,
    max_shear_deg: Option<f64>,
    #[serde(default = "default_method")]
    method: String,
    material: Option<String>,
    mode: Option<String>,
}

fn default_generators() -> String {
    "geodesic".into()
}
fn default_method() -> String {
    "kinematic".into()
}

/// One ply of a scene, ready to drape (SI units).
#[derive(Debug, Clone)]
pub struct Ply {
    pub settings: KinematicSettings,
    /// Mechanical refinement after the kinematic drape, if the ply asks for it.
    pub refinement: Option<Refinement>,
    /// Locking angle for reporting, radians.
    pub locking_angle: f64,
    /// Line of the scene file where the ply starts.
    pub line: usize,
}

/// A ply's mechanical refinement: the material card and the contact mode.
#[derive(Debug, Clone)]
pub struct Refinement {
    pub material: MaterialCard,
    pub material_path: PathBuf,
    pub mode: ContactMode,
}

/// A scene: the tool and its plies in stacking order.
#[derive(Debug, Clone)]
pub struct Scene {
    pub path: PathBuf,
    /// Metres per unit of the scene and OBJ.
    pub scale: f64,
    pub tool: PathBuf,
    pub plies: Vec<Ply>,
}

impl Scene {
    /// Read and check a scene file.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io { path: path.into(), source })?;
        let invalid = |message: String| SceneError::Invalid { path: path.into(), message };
        let file: SceneFile = toml::from_str(&text).map_err(|e| invalid(e.to_string().trim_end().to_string()))?;
        let scale = unit_scale(&file.units).map_err(|m| invalid(format!("field `units`: {m}")))?;
        let base = path.parent().unwrap_or(Path::new("."));
        if file.ply.is_empty() {
            return Err(invalid("no [[ply]] table: add at least one ply (name, origin, warp, spacing, grid)".into()));
        }
        let mut plies = Vec::new();
        for spanned in &file.ply {
            let line = 1 + text[..spanned.span().start].matches('\n').count();
            let p = spanned.get_ref();
            let at = |field: &str, m: String| invalid(format!("ply '{}' (line {line}), field `{field}`: {m}", p.name));
            if plies.iter().any(|q: &Ply| q.settings.name == p.name) {
                return Err(at("name", "two plies have this name; give each ply its own name".into()));
            }
            let v = |a: [f64; 3]| Vector::new(a[0], a[1], a[2]);
            for (field, a) in [("origin", p.origin), ("warp", p.warp)] {
                if !a.iter().all(|x| x.is_finite()) {
                    return Err(at(field, "must be three finite numbers".into()));
                }
            }
            if !(p.spacing.is_finite() && p.spacing > 0.0) {
                return Err(at("spacing", format!("must be a positive length, got {}", p.spacing)));
            }
            if v(p.warp).norm() == 0.0 {
                return Err(at("warp", "must not be the zero vector".into()));
            }
            let extent = match (p.grid, &p.outline, &p.outline_file) {
                (Some([nu, nv]), None, None) => {
                    if nu < 2 || nv < 2 {
                        return Err(at("grid", format!("needs at least 2 x 2 nodes, got {nu} x {nv}")));
                    }
                    Extent::Grid { nu, nv, origin_node: p.origin_node.map(|[i, j]| (i, j)) }
                }
                (None, Some(points), None) => {
                    Extent::Outline(points.iter().map(|a| Point::new(a[0], a[1], a[2]) * scale).collect())
                }
                (None, None, Some(f)) => Extent::Outline(read_points(&base.join(f), scale).map_err(|m| at("outline_file", m))?),
                _ => return Err(at("grid", "give exactly one of grid, outline or outline_file".into())),
            };
            let generators = parse_generators(&p.generators, base, scale).map_err(|m| at("generators", m))?;
            let refinement = match p.method.as_str() {
                "kinematic" => {
                    for (field, given) in [("material", p.material.is_some()), ("mode", p.mode.is_some())] {
                        if given {
                            return Err(at(field, "only a ply with method = \"mechanical\" uses it".into()));
                        }
                    }
                    None
                }
                "mechanical" => {
                    let file = p.material.as_ref().ok_or_else(|| {
                        at("material", "a mechanical ply needs a material card: material = \"card.toml\"".into())
                    })?;
                    let material_path = base.join(file);
                    let material = MaterialCard::load(&material_path).map_err(|e| at("material", e.to_string()))?;
                    let mode = match p.mode.as_deref().unwrap_or("pressed") {
                        "pressed" => ContactMode::Pressed,
                        "free" => ContactMode::Free,
                        other => return Err(at("mode", format!("unknown mode '{other}': use \"pressed\" or \"free\""))),
                    };
                    Some(Refinement { material, material_path, mode })
                }
                other => return Err(at("method", format!("unknown method '{other}': use \"kinematic\" or \"mechanical\""))),
            };
            let max_shear = p.max_shear_deg.unwrap_or(DEFAULT_MAX_SHEAR_DEG);
            if !(max_shear > 0.0 && max_shear < 90.0) {
                return Err(at("max_shear_deg", format!("must lie strictly between 0 and 90, got {max_shear}")));
            }
            if !(p.pre_shear_deg.abs() < 90.0) {
                return Err(at("pre_shear_deg", format!("must lie strictly between -90 and 90, got {}", p.pre_shear_deg)));
            }
            let locking = p.locking_angle_deg.unwrap_or(DEFAULT_LOCKING_ANGLE_DEG);
            if !(locking > 0.0 && locking < 90.0) {
                return Err(at("locking_angle_deg", format!("must lie strictly between 0 and 90, got {locking}")));
            }
            let settings = KinematicSettings {
                name: p.name.clone(),
                origin: Point::from(v(p.origin) * scale),
                warp: v(p.warp),
                spacing: p.spacing * scale,
                extent,
                pre_shear: p.pre_shear_deg.to_radians(),
                generators,
                max_shear: max_shear.to_radians(),
            };
            plies.push(Ply { settings, refinement, locking_angle: locking.to_radians(), line });
        }
        Ok(Scene { path: path.into(), scale, tool: base.join(&file.tool), plies })
    }
}
