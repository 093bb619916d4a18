//! The kinematic (pin-jointed net, "fishnet") drape: generators through a seed point, then every
//! other node as the intersection of the tool with a circle of points at distance d from two
//! placed neighbours.
pub mod coverage;
pub mod draw_in;
pub mod fabric_field;
pub mod fishnet;
pub mod generators;
pub mod net;
pub mod outline;
pub mod provenance;
pub mod sampler;
pub mod surface;
pub mod wrinkle;

pub use fishnet::{drape, drape_on, drape_smooth, DrapeError};
pub use net::{DrapeNet, Method, NodeStatus};
pub use provenance::{CellChanges, ChoiceIndicators, MethodChoice, Provenance, SolverRecord, UnbalancedRecord};
pub use surface::DrapeSurface;

use crate::geometry::{Point, Vector};

/// How the two fibre generators through the origin are laid.
#[derive(Debug, Clone, PartialEq)]
pub enum GeneratorKind {
    /// Straightest geodesics along the warp direction and its (pre-sheared) perpendicular.
    Geodesic,
    /// Each generator segment turned to minimise the shear of the cells beside it.
    MinShear,
    /// The warp generator follows this curve (projected onto the tool, resampled at d); the weft
    /// generator is a geodesic.
    Steer(Vec<Point>),
}

/// Which surface the fishnet lies on.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SurfaceKind {
    /// The tool's facets as given: every node exactly on the mesh.
    #[default]
    Facets,
    /// The smooth surface the facets stand for ([`crate::geometry::SmoothSurface`], the one the
    /// pressed contact slides on): a coarse tool drapes with the accuracy of a fine one.
    Smooth,
}

impl SurfaceKind {
    /// Every kind, in the order the choices are listed.
    pub const ALL: [SurfaceKind; 2] = [SurfaceKind::Facets, SurfaceKind::Smooth];

    /// Its name in files and on the command line: `facets` or `smooth`.
    pub fn name(self) -> &'static str {
        match self {
            SurfaceKind::Facets => "facets",
            SurfaceKind::Smooth => "smooth",
        }
    }
}

impl std::str::FromStr for SurfaceKind {
    type Err = String;

    /// `facets` or `smooth`; anything else is refused with a message naming the choices.
    fn from_str(s: &str) -> Result<Self, String> {
        SurfaceKind::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| format!("unknown surface '{s}': use \"facets\" (the tool's facets, the default) or \"smooth\" (the smooth surface over them)"))
    }
}

impl std::fmt::Display for SurfaceKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// How far the net extends.
#[derive(Debug, Clone, PartialEq)]
pub enum Extent {
    /// A grid of `nu x nv` nodes with the origin at node `origin_node` (default: the centre).
    Grid {
        /// Nodes along the warp.
        nu: usize,
        /// Nodes along the weft.
        nv: usize,
        /// The seed's node.
        origin_node: Option<(usize, usize)>,
    },
    /// A closed polyline on the tool: the grid is sized to cover it and nodes outside are dropped.
    Outline(Vec<Point>),
}

/// Everything the kinematic drape of one ply needs (SI units, radians).
#[derive(Debug, Clone)]
pub struct KinematicSettings {
    /// Ply name (file names derive from it).
    pub name: String,
    /// Seed point; projected onto the tool.
    pub origin: Point,
    /// Warp direction; projected onto the tangent plane at the origin.
    pub warp: Vector,
    /// Fibre segment length d.
    pub spacing: f64,
    /// How far the net extends.
    pub extent: Extent,
    /// Pre-shear: the generators meet at pi/2 - pre_shear.
    pub pre_shear: f64,
    /// How the generators through the seed are laid.
    pub generators: GeneratorKind,
    /// Nodes whose corner shear would reach this are not placed (radians, < pi/2).
    pub max_shear: f64,
    /// The surface the net lies on: the facets (default) or the smooth surface over them.
    pub surface: SurfaceKind,
}

/// Default shear at which a node is refused as a collapsing cell (degrees).
pub const DEFAULT_MAX_SHEAR_DEG: f64 = 75.0;

impl KinematicSettings {
    /// Settings for a geodesic-generator grid with the origin at the centre.
    pub fn grid(name: &str, origin: Point, warp: Vector, spacing: f64, nu: usize, nv: usize) -> Self {
        KinematicSettings {
            name: name.to_string(),
            origin,
            warp,
            spacing,
            extent: Extent::Grid { nu, nv, origin_node: None },
            pre_shear: 0.0,
            generators: GeneratorKind::Geodesic,
            max_shear: DEFAULT_MAX_SHEAR_DEG.to_radians(),
            surface: SurfaceKind::Facets,
        }
    }

    /// The same ply at fibre spacing `spacing`: a grid keeps its extent in fabric length on each
    /// side of its origin node (rounded to whole cells), an outline stays as it is. Only the
    /// spacing and the grid change.
    pub fn at_spacing(&self, spacing: f64) -> KinematicSettings {
        let mut s = self.clone();
        if let Extent::Grid { nu, nv, origin_node } = self.extent {
            let o = origin_node.unwrap_or((nu / 2, nv / 2));
            let r = self.spacing / spacing;
            let scaled = |n: usize| (n as f64 * r).round() as usize;
            let (i0, j0) = (scaled(o.0), scaled(o.1));
            s.extent = Extent::Grid {
                nu: i0 + scaled(nu - 1 - o.0) + 1,
                nv: j0 + scaled(nv - 1 - o.1) + 1,
                origin_node: Some((i0, j0)),
            };
        }
        s.spacing = spacing;
        s
    }
}
