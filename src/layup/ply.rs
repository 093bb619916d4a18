//! The plies of a layup, ready to drape: what each ply is made of, how its warp is given and
//! whether it is refined mechanically. A scene file ([`crate::pipeline::scene`]) is one way to
//! make them.
use crate::geometry::smooth::SmoothSurface;
use crate::geometry::{Point, ToolSurface, Vector};
use crate::kinematic::provenance::WrinkleRecord;
use crate::kinematic::{wrinkle, DrapeNet, KinematicSettings};
use crate::material::MaterialCard;
use crate::mechanics::energy::bending_energy_density;
use crate::mechanics::forming::Forming;
use crate::mechanics::friction::PliesBelow;
use crate::mechanics::refine::{annotate, refine_draped, refine_from, RefineError, RefineSettings, Refined};
use crate::mechanics::sheet::SheetFeatures;
use crate::mechanics::{ContactMode, SolverSettings};
use std::path::PathBuf;
use std::time::Instant;

/// Locking angle used for reporting when neither the ply nor its material card gives one
/// (degrees; woven glass and carbon lock between about 40 and 60 degrees).
pub const DEFAULT_LOCKING_ANGLE_DEG: f64 = 45.0;

/// Where a ply's locking angle comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LockingSource {
    /// The ply's own `locking_angle_deg`.
    Ply,
    /// Its material card's shear law (a two-slope law's locking angle).
    Card,
    /// Neither gives one: [`DEFAULT_LOCKING_ANGLE_DEG`].
    Default,
}

impl LockingSource {
    /// One word for tables: `ply`, `card` or `default`.
    pub fn tag(self) -> &'static str {
        match self {
            LockingSource::Ply => "ply",
            LockingSource::Card => "card",
            LockingSource::Default => "default",
        }
    }
}

/// A ply's locking angle (degrees) and where it comes from: the ply's own value, else its card's
/// two-slope locking angle, else [`DEFAULT_LOCKING_ANGLE_DEG`].
pub fn locking_angle_deg(own: Option<f64>, card: Option<&MaterialCard>) -> (f64, LockingSource) {
    match (own, card.and_then(|c| c.shear.locking_angle_deg())) {
        (Some(a), _) => (a, LockingSource::Ply),
        (None, Some(a)) => (a, LockingSource::Card),
        (None, None) => (DEFAULT_LOCKING_ANGLE_DEG, LockingSource::Default),
    }
}

/// How a ply's warp direction is given.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Orientation {
    /// The warp direction itself (projected onto the tool at the seed).
    Warp(Vector),
    /// The scene's reference direction turned by this angle (radians) about the tool normal at
    /// the seed, counter-clockwise seen from the side the normal points to.
    Angle(f64),
}

/// A material card and the name the scene gives it.
#[derive(Debug, Clone)]
pub struct PlyMaterial {
    /// The name in `[materials]`, or the card's own name when the ply gives a file.
    pub name: String,
    /// The card.
    pub card: MaterialCard,
    /// Its file.
    pub path: PathBuf,
}

/// One ply of a scene, ready to drape (SI units).
#[derive(Debug, Clone)]
pub struct Ply {
    /// Kinematic settings; `settings.warp` is only final once [`Ply::orientation`] has been
    /// resolved on the (offset) tool by [`super::stack`].
    pub settings: KinematicSettings,
    /// How its warp is given.
    pub orientation: Orientation,
    /// Its material card, if any.
    pub material: Option<PlyMaterial>,
    /// Thickness as laid flat, metres: the ply's `thickness`, else its card's; `None` if neither.
    pub thickness: Option<f64>,
    /// Mechanical refinement after the kinematic drape, if the ply asks for it (with
    /// [`Ply::auto`], if the choice falls on mechanics).
    pub refinement: Option<Refinement>,
    /// `method = "auto"`: mechanics runs only where the kinematic net is not within the
    /// tolerance.
    pub auto: Option<AutoModel>,
    /// Locking angle for reporting, radians.
    pub locking_angle: f64,
    /// Where the locking angle comes from.
    pub locking_source: LockingSource,
    /// Line of the scene file where the ply starts.
    pub line: usize,
}

impl Ply {
    /// The ply angle in degrees for tables, `None` when the warp was given as a vector.
    pub fn angle_deg(&self) -> Option<f64> {
        match self.orientation {
            Orientation::Angle(a) => Some(a.to_degrees()),
            Orientation::Warp(_) => None,
        }
    }

    /// The material card the ply's mechanics uses: its refinement's card, else its own.
    pub fn card(&self) -> Option<&MaterialCard> {
        self.refinement.as_ref().map(|r| &r.material).or(self.material.as_ref().map(|m| &m.card))
    }

    /// The wrinkles of `net`, this ply draped on `surface` (the tool or the tool offset by the
    /// plies below): waviness and tool gap per cell ([`crate::kinematic::wrinkle`]) against the
    /// ply's thickness, and with a card ([`Ply::card`]) the bending energy density of its
    /// bending term ([`bending_energy_density`], with the sheet's features the refinement used).
    pub fn wrinkles(&self, net: &DrapeNet, surface: &ToolSurface) -> WrinkleRecord {
        wrinkles_of(net, surface, self.thickness, self.card(), self.refinement.as_ref().map(|r| &r.sheet))
    }
}

/// The wrinkles of `net` draped on `surface`: waviness and tool gap per cell
/// ([`crate::kinematic::wrinkle`]) against `thickness` (m), and with a `card` the bending energy
/// density of its bending term ([`bending_energy_density`], with the `sheet`'s features where
/// they still fit the grid, else without them).
pub fn wrinkles_of(
    net: &DrapeNet,
    surface: &ToolSurface,
    thickness: Option<f64>,
    card: Option<&MaterialCard>,
    sheet: Option<&SheetFeatures>,
) -> WrinkleRecord {
    let bending = card.map(|card| {
        bending_energy_density(net, card, sheet)
            .unwrap_or_else(|_| bending_energy_density(net, card, None).expect("no sheet features: nothing to fit"))
    });
    wrinkle::measure(net, surface, thickness, bending)
}

/// Solver iterations per load step of a mechanical ply when the scene gives none.
pub const DEFAULT_SOLVER_ITERATIONS: usize = 500;
/// Most solver iterations per load step a scene may ask for (every run ends in bounded time).
pub const MAX_SOLVER_ITERATIONS: usize = 100_000;
/// Most load steps a scene may ask for.
pub const MAX_LOAD_STEPS: usize = 1000;

/// A ply's mechanical refinement: the material card, the contact mode, where it starts, and the
/// sheet's features.
#[derive(Debug, Clone)]
pub struct Refinement {
    /// The card.
    pub material: MaterialCard,
    /// Its file (recorded in the net).
    pub material_path: PathBuf,
    /// Pressed onto the tool or hanging free.
    pub mode: ContactMode,
    /// The state the solver starts from.
    pub start: Start,
    /// Gravity is applied in this many steps.
    pub load_steps: usize,
    /// Solver iterations per load step, at most.
    pub max_iterations: usize,
    /// Reinforcements, seam, fold, cuts.
    pub sheet: SheetFeatures,
    /// Free drape: nodes the tool holds up stay where they touch.
    pub stick: bool,
    /// Coulomb's coefficient between the ply and the tool.
    pub friction: f64,
    /// Coulomb's coefficient between the ply and the plies below it in a layup (`ply_friction`;
    /// None: the tool's `friction` there too).
    pub ply_friction: Option<f64>,
    /// Where the plies below lie, with `ply_friction` (set by the layup, [`super::stack`],
    /// for a ply on plies below that gives `ply_friction`).
    pub plies_below: Option<PliesBelow>,
    /// Fabric points held in place at the user's request (u, v from the origin node, m; see
    /// [`RefineSettings::holds`]).
    pub holds: Vec<[f64; 2]>,
    /// Move off saddles the solver's stability check finds ([`SolverSettings::escape_saddles`]).
    pub escape_saddles: bool,
    /// A flat blank formed by tools in motion (`start = "flat"` with `mode = "pressed"`).
    pub forming: Option<Forming>,
    /// A formed blank is formed first at 2^`coarse_levels` times the ply's spacing, then held
    /// by its tools where the stroke ended on each grid of half the spacing, down to the ply's
    /// ([`super::coarse`]); 0: formed at the ply's spacing.
    pub coarse_levels: usize,
}

impl Refinement {
    /// The default pressed refinement with a material card: from the kinematic net, one load
    /// step, [`DEFAULT_SOLVER_ITERATIONS`], no sheet features, the card's friction (else none).
    pub fn pressed(material: MaterialCard, material_path: PathBuf) -> Refinement {
        Refinement {
            friction: material.friction.unwrap_or(0.0),
            ply_friction: None,
            plies_below: None,
            holds: Vec::new(),
            material,
            material_path,
            mode: ContactMode::Pressed,
            start: Start::Kinematic,
            load_steps: 1,
            max_iterations: DEFAULT_SOLVER_ITERATIONS,
            sheet: SheetFeatures::default(),
            stick: false,
            escape_saddles: false,
            forming: None,
            coarse_levels: 0,
        }
    }

    /// The mechanical stage's settings for this refinement.
    pub fn settings(&self) -> RefineSettings {
        RefineSettings {
            mode: self.mode,
            load_steps: self.load_steps,
            solver: SolverSettings::default().max_iterations(self.max_iterations).escape_saddles(self.escape_saddles),
            sheet: self.sheet.clone(),
            stick: self.stick,
            friction: self.friction,
            plies_below: self.plies_below.clone(),
            holds: self.holds.clone(),
            forming: self.forming.clone(),
            ..RefineSettings::default()
        }
    }

    /// Refine a ply's kinematic `net` on `surface` as this refinement says (on `smooth`, the
    /// surface's smooth surface, when the caller has built it): the refined net, annotated with
    /// the solver's record and the change from the kinematic net, and the solver's result.
    pub fn run(
        &self,
        net: &DrapeNet,
        surface: &ToolSurface,
        smooth: Option<&SmoothSurface>,
    ) -> Result<(DrapeNet, Refined), RefineError> {
        self.run_from(net, &net.positions, surface, smooth)
    }

    /// Refine the kinematic `net` draped on `surface` with `draped`, as a scene's ply is: as
    /// [`Refinement::run`], but a pressed refinement on the smooth patches of a net draped on
    /// the facets starts from the ply draped on the smooth surface ([`refine_draped`]; `smooth`
    /// as in [`Refinement::run`]).
    pub fn run_draped(
        &self,
        net: &DrapeNet,
        surface: &ToolSurface,
        smooth: Option<&SmoothSurface>,
        draped: &KinematicSettings,
    ) -> Result<(DrapeNet, Refined), RefineError> {
        let t = Instant::now();
        let result = refine_draped(net, draped, surface, smooth, &self.material, &self.settings())?;
        Ok(self.annotated(net, result, t))
    }

    /// [`Refinement::run`] with the solver starting from `start` (a position per node of `net`,
    /// e.g. where a probe towards equilibrium stopped); `net` stays the kinematic reference.
    pub fn run_from(
        &self,
        net: &DrapeNet,
        start: &[Point],
        surface: &ToolSurface,
        smooth: Option<&SmoothSurface>,
    ) -> Result<(DrapeNet, Refined), RefineError> {
        let t = Instant::now();
        let result = refine_from(net, start, surface, smooth, &self.material, &self.settings())?;
        Ok(self.annotated(net, result, t))
    }

    /// The refined net of `result` annotated against the kinematic `net`, the refinement's time
    /// (since `t`) its fill.
    fn annotated(&self, net: &DrapeNet, result: Refined, t: Instant) -> (DrapeNet, Refined) {
        let mut out = result.net.clone();
        annotate(&mut out, net, &result, &self.material_path);
        out.timing.load_ms = net.timing.load_ms;
        out.timing.generators_ms = 0.0;
        out.timing.fill_ms = t.elapsed().as_secs_f64() * 1e3;
        // The whole drape: the kinematic net's, then the refinement.
        out.timing.total_ms = net.timing.total_ms + out.timing.fill_ms;
        (out, result)
    }
}

/// `method = "auto"`: the ply runs the least model that keeps its cell shear within the
/// tolerance (see [`super::auto`]); its `refinement` is what runs if mechanics is needed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AutoModel {
    /// The largest cell-shear error accepted, degrees.
    pub tolerance_deg: f64,
}

/// Where a mechanical ply starts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Start {
    /// From its kinematic drape.
    Kinematic,
    /// From a flat sheet with this unit normal laid over the tool, just touching it (seed
    /// 000's drapes).
    Flat {
        /// The sheet plane's normal.
        normal: Vector,
    },
}

pub use crate::kinematic::provenance::StackSide;

/// The plies to drape, in stacking order (the first lies on the tool, each next one on the plies
/// below it), and how their angles and stacking side are measured.
#[derive(Debug, Clone)]
pub struct Layup {
    /// The 0 deg direction of ply angles (unit).
    pub reference: Vector,
    /// Which side of the tool the plies stack on.
    pub stack_side: StackSide,
    /// The plies in stacking order.
    pub plies: Vec<Ply>,
    /// Measure each ply's wrinkles ([`Ply::wrinkles`], the net's `meta.wrinkles`): `drape run`
    /// does; the studies, which need only the table's shear and coverage figures and time the
    /// drape, do not.
    pub wrinkles: bool,
}
