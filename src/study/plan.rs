//! What a study is: the scene, the ply, and the list of independent [`Case`]s it runs. A plan is
//! written to `DIR/study.json` before any case runs; shards and resumed runs read it back, so
//! every process of one study agrees on what case `k` is.
use super::speed_accuracy::ReferencePlan;
use super::StudyError;
use crate::kinematic::fabric_field::FabricImage;
use crate::kinematic::SurfaceKind;
use crate::layup::Ply;
use crate::pipeline::Scene;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The plan's file in a study folder.
pub const PLAN_FILE: &str = "study.json";

/// Which study.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum StudyKind {
    /// Error against time of every method at a range of spacings ([`super::speed_accuracy`]).
    SpeedAccuracy,
    /// Outcomes over the conditions that break drape methods ([`super::stability`]).
    Stability,
    /// The best seed and angle of a ply: a global search over candidate placements, refined
    /// locally when the cases are in ([`super::optimise`]).
    Optimise,
}

impl StudyKind {
    /// The subcommand's name: `speed-accuracy` or `stability`.
    pub fn name(self) -> &'static str {
        match self {
            StudyKind::SpeedAccuracy => "speed-accuracy",
            StudyKind::Stability => "stability",
            StudyKind::Optimise => "optimise",
        }
    }
}

/// A drape method a study runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum StudyMethod {
    /// The fishnet from straightest-geodesic generators.
    KinematicGeodesic,
    /// The fishnet from minimum-shear generators.
    KinematicMinShear,
    /// The fishnet with its warp generator along the ply's steering curve.
    KinematicSteered,
    /// The kinematic net refined mechanically, pressed onto the tool.
    MechanicalPressed,
    /// The ply's free (gravity) drape.
    MechanicalFree,
    /// `method = "auto"`: the kinematic net, or the pressed drape where it is not within the
    /// ply's tolerance (default [`crate::layup::auto::DEFAULT_TOLERANCE_DEG`]).
    Auto,
}

impl StudyMethod {
    /// The name in files and charts (`kinematic-geodesic`, ...).
    pub fn name(self) -> &'static str {
        match self {
            StudyMethod::KinematicGeodesic => "kinematic-geodesic",
            StudyMethod::KinematicMinShear => "kinematic-min-shear",
            StudyMethod::KinematicSteered => "kinematic-steered",
            StudyMethod::MechanicalPressed => "mechanical-pressed",
            StudyMethod::MechanicalFree => "mechanical-free",
            StudyMethod::Auto => "auto",
        }
    }
    /// Whether the method may run the mechanical stage, so it runs at the mechanical spacings
    /// and node limit.
    pub fn may_run_mechanics(self) -> bool {
        self.is_mechanical() || self == StudyMethod::Auto
    }
    /// Whether the method runs the mechanical stage.
    pub fn is_mechanical(self) -> bool {
        matches!(self, StudyMethod::MechanicalPressed | StudyMethod::MechanicalFree)
    }
}

/// The ply as one case drapes it: every knob a study turns, the rest as the scene gives it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Variant {
    /// The method.
    pub method: StudyMethod,
    /// The surface the kinematic drape steps on: the tool's facets or the smooth surface over them.
    pub surface: SurfaceKind,
    /// The tool file (the scene's, or one of the study's tool resolutions).
    pub tool: PathBuf,
    /// Fibre segment length d, m. The grid keeps the scene's extent in fabric length.
    pub spacing: f64,
    /// The ply angle, degrees, when the case sets it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub angle_deg: Option<f64>,
    /// The seed moved along the warp and weft at the seed, as fractions of the ply's half size.
    #[serde(default)]
    pub seed_shift: [f64; 2],
    /// The seed itself, m, when the case sets it (a point on the tool; an optimisation's
    /// candidate). The seed shift, if any, moves it further.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub origin: Option<[f64; 3]>,
    /// Pre-shear, degrees, when the case sets it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pre_shear_deg: Option<f64>,
    /// The kinematic shear limit (the locking angle the drape refuses cells past), degrees.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_shear_deg: Option<f64>,
    /// Factor on the card's fibre tension rigidity (the tension-to-shear stiffness ratio).
    pub tension_factor: f64,
    /// Load steps of the mechanical stage, when the case sets them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub load_steps: Option<usize>,
    /// Friction between the ply and the tool in the mechanical stage, when the case sets it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction: Option<f64>,
}

impl Variant {
    /// The ply as the scene gives it, drawn by `method` on the facets of `tool` at `spacing`.
    pub fn baseline(method: StudyMethod, tool: PathBuf, spacing: f64) -> Variant {
        Variant {
            method,
            surface: SurfaceKind::Facets,
            tool,
            spacing,
            angle_deg: None,
            seed_shift: [0.0, 0.0],
            origin: None,
            pre_shear_deg: None,
            max_shear_deg: None,
            tension_factor: 1.0,
            load_steps: None,
            friction: None,
        }
    }
}

/// `path` made absolute, so every process of a study (shards, Slurm tasks) finds it.
pub fn absolute(path: &Path) -> Result<PathBuf, StudyError> {
    std::path::absolute(path).map_err(|e| StudyError::Input(format!("{}: {e}", path.display())))
}

/// The tools a study runs on: the scene's, then the further resolutions given (`--tools`).
pub fn study_tools(scene: &Scene, extra: &[PathBuf]) -> Result<Vec<PathBuf>, StudyError> {
    let mut tools = vec![absolute(&scene.tool)?];
    for t in extra {
        if !t.is_file() {
            return Err(StudyError::Input(format!("--tools: {} is not a file", t.display())));
        }
        tools.push(absolute(t)?);
    }
    Ok(tools)
}

/// The ply of `scene` named `name`, or its first.
pub fn find_ply<'a>(scene: &'a Scene, name: Option<&str>) -> Result<&'a Ply, StudyError> {
    let plies = &scene.layup.plies;
    match name {
        None => plies.first().ok_or_else(|| StudyError::Input("the scene has no ply".into())),
        Some(n) => plies.iter().find(|p| p.settings.name == n).ok_or_else(|| {
            let names: Vec<&str> = plies.iter().map(|p| p.settings.name.as_str()).collect();
            StudyError::Input(format!("the scene has no ply '{n}': its plies are {}", names.join(", ")))
        }),
    }
}

/// One independent case of a study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Case {
    /// Its number in the plan, from 0.
    pub index: usize,
    /// What it drapes.
    pub variant: Variant,
    /// The swept parameters and their values, named as the study's JSON and `--axes` name them.
    pub params: BTreeMap<String, f64>,
    /// Runs whose median time is reported.
    pub repeats: usize,
    /// Whether the case keeps its cell-shear field (the speed-accuracy study compares fields).
    pub keep_field: bool,
}

/// A study: its kind, scene, ply and cases.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    /// Which study.
    pub kind: StudyKind,
    /// The scene file (absolute).
    pub scene: PathBuf,
    /// The ply studied.
    pub ply: String,
    /// The two swept parameters of the stability map.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axes: Option<[String; 2]>,
    /// The symmetries of the ply's drape problem on the scene's tool, the identity left out
    /// ([`super::symmetry`]): a mechanical reference is compared in each of its images.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub symmetries: Vec<FabricImage>,
    /// The speed-accuracy study's one reference: its tool and the models the ply allows.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference: Option<ReferencePlan>,
    /// An optimisation's search: its objective, region and refinement.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub search: Option<super::optimise::Search>,
    /// The cases, in order.
    pub cases: Vec<Case>,
}

impl Plan {
    /// The plan's scene, read again, and its ply's place in the layup.
    pub fn scene_and_ply(&self) -> Result<(Scene, usize), StudyError> {
        let scene = Scene::load(&self.scene).map_err(|e| StudyError::Input(e.to_string()))?;
        let k = scene
            .layup
            .plies
            .iter()
            .position(|p| p.settings.name == self.ply)
            .ok_or_else(|| StudyError::Input(format!("the scene has no ply '{}'", self.ply)))?;
        Ok((scene, k))
    }
}

/// The part of a study one process runs: shard `k` (from 1) of `n` takes the cases whose index
/// is `k - 1` modulo `n`, so the shards are disjoint and together hold every case.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// This shard, 1..=n.
    pub k: usize,
    /// Shards in all.
    pub n: usize,
}

impl Shard {
    /// The whole study.
    pub const ALL: Shard = Shard { k: 1, n: 1 };

    /// Parse `K/N` (1 <= K <= N).
    pub fn parse(s: &str) -> Result<Shard, String> {
        let bad = || format!("'{s}' is not a shard: give K/N with 1 <= K <= N, like 2/8");
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let (k, n): (usize, usize) = (k.trim().parse().map_err(|_| bad())?, n.trim().parse().map_err(|_| bad())?);
        if k == 0 || n == 0 || k > n {
            return Err(bad());
        }
        Ok(Shard { k, n })
    }

    /// Whether case `index` belongs to this shard.
    pub fn holds(&self, index: usize) -> bool {
        index % self.n == self.k - 1
    }
}
