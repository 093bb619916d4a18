//! One ply from the options of `drape kinematic`, as library calls: the options checked before
//! the tool is read ([`PlyOptions::prepare`]), then the drape, kinematic or `auto`
//! ([`PreparedPly::drape`]). The command line and the Python package both come through here, so
//! they drape the same net and refuse the same input with the same message.
use super::failure::{compute, input, Failure};
use super::{parse_generators, unit_scale};
use crate::geometry::{Point, ToolSurface, Vector};
use crate::io::points::read_points;
use crate::kinematic::fishnet::check_settings;
use crate::kinematic::{drape, DrapeNet, Extent, KinematicSettings, SurfaceKind, DEFAULT_MAX_SHEAR_DEG};
use crate::layup::auto::{drape_auto, DEFAULT_TOLERANCE_DEG};
use crate::layup::ply::wrinkles_of;
use crate::layup::{locking_angle_deg, AutoModel, Refinement};
use crate::material::MaterialCard;
use std::path::{Path, PathBuf};

/// The options of `drape kinematic` as given (names where the command line takes names; lengths
/// in `units`). [`Default`] gives the command line's defaults.
#[derive(Debug, Clone)]
pub struct PlyOptions {
    /// Seed point, projected onto the tool.
    pub origin: [f64; 3],
    /// Warp direction, projected onto the tangent plane at the seed.
    pub warp: [f64; 3],
    /// Fibre segment length d.
    pub spacing: f64,
    /// Grid size (nodes along warp, weft); exactly one of `grid` and `outline`.
    pub grid: Option<[usize; 2]>,
    /// A ply outline file (a closed polyline on the tool, x,y,z per line) instead of a grid.
    pub outline: Option<PathBuf>,
    /// Grid indices of the seed node (default: the centre).
    pub origin_node: Option<[usize; 2]>,
    /// Pre-shear, degrees: the generators meet at 90 - pre-shear.
    pub pre_shear_deg: f64,
    /// `geodesic`, `min-shear` or `steer:FILE`.
    pub generators: String,
    /// Shear, degrees, at which a node is refused as a collapsing cell.
    pub max_shear_deg: f64,
    /// `facets` or `smooth`.
    pub surface: String,
    /// Locking angle, degrees (default: the card's two-slope locking angle, else 45).
    pub locking_angle_deg: Option<f64>,
    /// `kinematic` or `auto`.
    pub method: String,
    /// Material card (TOML): needed by `auto`; gives the locking angle.
    pub material: Option<PathBuf>,
    /// `auto`: the largest cell-shear error accepted, degrees.
    pub tolerance_deg: Option<f64>,
    /// `m` or `mm`: the tool's and these lengths' unit (nets are in metres).
    pub units: String,
    /// Ply name.
    pub name: String,
}

impl Default for PlyOptions {
    fn default() -> Self {
        PlyOptions {
            origin: [0.0; 3],
            warp: [1.0, 0.0, 0.0],
            spacing: 0.0,
            grid: None,
            outline: None,
            origin_node: None,
            pre_shear_deg: 0.0,
            generators: "geodesic".into(),
            max_shear_deg: DEFAULT_MAX_SHEAR_DEG,
            surface: "facets".into(),
            locking_angle_deg: None,
            method: "kinematic".into(),
            material: None,
            tolerance_deg: None,
            units: "m".into(),
            name: "ply".into(),
        }
    }
}

/// A ply whose options passed every check: ready to drape on a tool.
#[derive(Debug)]
pub struct PreparedPly {
    /// The drape's settings, lengths in metres.
    pub settings: KinematicSettings,
    /// Metres per unit of the tool file and the options' lengths.
    pub scale: f64,
    /// The material card, when one was given.
    pub card: Option<MaterialCard>,
    /// The locking angle, degrees.
    pub locking_angle_deg: f64,
    /// `auto`'s tolerance and the pressed refinement it may run.
    auto: Option<(AutoModel, Refinement)>,
}

impl PlyOptions {
    /// Check the options and turn them into settings, reading the card, outline and steering
    /// curve (relative paths from the working folder), before the (possibly slow) tool load.
    pub fn prepare(&self) -> Result<PreparedPly, Failure> {
        let bad = |m: String| input(anyhow::anyhow!(m));
        let scale = unit_scale(&self.units).map_err(|m| bad(format!("--units: {m}")))?;
        let card = match &self.material {
            Some(path) => Some(MaterialCard::load(path).map_err(|e| bad(format!("--material: {e}")))?),
            None => None,
        };
        let (locking_angle, _) = locking_angle_deg(self.locking_angle_deg, card.as_ref());
        if !(locking_angle > 0.0 && locking_angle < 90.0) {
            return Err(bad(format!(
                "--locking-angle must lie strictly between 0 and 90 degrees, got {locking_angle}"
            )));
        }
        let auto = match (self.method.as_str(), self.tolerance_deg) {
            ("kinematic", None) => None,
            ("kinematic", Some(_)) => return Err(bad("--tolerance is for --method auto".into())),
            ("auto", t) => {
                let t = t.unwrap_or(DEFAULT_TOLERANCE_DEG);
                if !(t.is_finite() && t > 0.0) {
                    return Err(bad(format!("--tolerance must be a positive angle in degrees, got {t}")));
                }
                let (Some(card), Some(path)) = (card.clone(), self.material.clone()) else {
                    return Err(bad(
                        "--method auto weighs the kinematic net under a material card: give --material CARD.toml"
                            .into(),
                    ));
                };
                Some((AutoModel { tolerance_deg: t }, Refinement::pressed(card, path)))
            }
            (other, _) => return Err(bad(format!("--method: unknown method '{other}': use kinematic or auto"))),
        };
        let base = std::env::current_dir().unwrap_or_default();
        let generators =
            parse_generators(&self.generators, &base, scale).map_err(|m| bad(format!("--generators: {m}")))?;
        let surface: SurfaceKind = self.surface.parse().map_err(|m| bad(format!("--surface: {m}")))?;
        let extent = match (&self.grid, &self.outline) {
            (Some(_), Some(_)) => return Err(bad("give either a grid or an outline, not both".into())),
            (Some([nu, nv]), None) => {
                Extent::Grid { nu: *nu, nv: *nv, origin_node: self.origin_node.map(|[i, j]| (i, j)) }
            }
            (None, Some(f)) => Extent::Outline(read_points(f, scale).map_err(|m| bad(format!("--outline: {m}")))?),
            (None, None) => return Err(bad("give --grid NU,NV or --outline FILE".into())),
        };
        let settings = KinematicSettings {
            name: self.name.clone(),
            origin: Point::from(Vector::from(self.origin) * scale),
            warp: Vector::from(self.warp),
            spacing: self.spacing * scale,
            extent,
            pre_shear: self.pre_shear_deg.to_radians(),
            generators,
            max_shear: self.max_shear_deg.to_radians(),
            surface,
        };
        check_settings(&settings).map_err(input)?;
        Ok(PreparedPly { settings, scale, card, locking_angle_deg: locking_angle, auto })
    }
}

impl PreparedPly {
    /// Drape the ply on `tool` (read at [`PreparedPly::scale`]): the kinematic net, or with
    /// `auto` the model it chose, its choice in `meta.method_choice`; its wrinkles in
    /// `meta.wrinkles`.
    pub fn drape(&self, tool: &ToolSurface) -> Result<DrapeNet, Failure> {
        match &self.auto {
            None => drape(tool, &self.settings).map_err(input),
            Some((model, refinement)) => {
                let chosen =
                    drape_auto(tool, tool, &self.settings, refinement, self.locking_angle_deg.to_radians(), *model)
                        .map_err(|e| input(anyhow::anyhow!("{e}")))?;
                let mut net = chosen.refined.map_or(chosen.kinematic, |(refined, _)| refined);
                net.meta.method_choice = Some(chosen.choice);
                Ok(net)
            }
        }
        .map(|mut net| {
            let card = self.card.as_ref();
            net.meta.wrinkles = Some(wrinkles_of(&net, tool, card.map(|c| c.thickness), card, None));
            net
        })
    }

    /// The warning that the ply shears past the range its card's law was calibrated to, given
    /// its largest |shear| in degrees.
    pub fn shear_range_warning(&self, max_abs_shear_deg: f64) -> Option<String> {
        self.card.as_ref().and_then(|c| c.shear_range_warning(max_abs_shear_deg))
    }
}

/// Read a tool file, lengths scaled by `scale`: a tool that cannot be read is bad input.
pub fn read_tool(path: &Path, scale: f64) -> Result<ToolSurface, Failure> {
    crate::io::read_tool(path, scale).map_err(|e| input(anyhow::anyhow!(e.to_string())))
}

/// A net whose mechanical solver (`auto`'s) stopped without equilibrium is a failed
/// computation, reported after the net was written.
pub fn check_converged(net: &DrapeNet) -> Result<(), Failure> {
    match &net.meta.solver {
        Some(s) if !s.converged => Err(compute(anyhow::anyhow!(
            "the mechanical solver stopped without equilibrium: {}; the last accepted state was written",
            s.reason.as_deref().unwrap_or(&s.outcome)
        ))),
        _ => Ok(()),
    }
}
