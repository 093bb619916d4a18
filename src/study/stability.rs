//! `drape study stability`: the ply draped under the conditions that break drape methods, each
//! case ending in a result or a named failure. Each parameter is swept alone about the scene's
//! ply, and the two `--axes` parameters over their whole product, for the outcome map.
use super::plan::{absolute, find_ply, study_tools, Case, Plan, StudyKind, StudyMethod, Variant};
use super::runner::CaseRecord;
use super::StudyError;
use crate::geometry::ToolSurface;
use crate::mechanics::ContactMode;
use crate::pipeline::Scene;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, HashMap};
use std::path::PathBuf;

/// The study's result file.
pub const FILE: &str = "stability.json";
/// The map's axes when none are given.
pub const DEFAULT_AXES: [&str; 2] = ["spacing", "angle"];
/// Facet pairs turning by more than this (radians) are a sharp edge, not curvature.
const SHARP_EDGE: f64 = 0.6;
/// The share of the tool's curvature estimates below the one taken as its largest (the largest
/// few are facet noise).
const CURVATURE_QUANTILE: f64 = 0.99;

/// A swept parameter: its name, its values and what it changes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Parameter {
    /// Fibre spacing, as a multiple of the ply's (the JSON also gives d and d / R).
    Spacing,
    /// Ply angle, degrees.
    Angle,
    /// Seed moved along the warp, as a fraction of the ply's half length.
    SeedU,
    /// Seed moved along the weft, as a fraction of the ply's half width.
    SeedV,
    /// Pre-shear between the generators, degrees.
    PreShear,
    /// The kinematic shear limit (locking angle), degrees.
    Locking,
    /// Tool resolution: the scene's tool (0) and the `--tools` files (1, 2, ...).
    Tool,
    /// Fibre tension rigidity over the card's, which scales the tension-to-shear stiffness ratio.
    StiffnessRatio,
    /// Load steps of the mechanical stage.
    LoadSteps,
    /// Coulomb's coefficient of friction between the ply and the tool (mechanical stage).
    Friction,
}

impl Parameter {
    /// Every parameter.
    pub const ALL: [Parameter; 10] = [
        Parameter::Spacing,
        Parameter::Angle,
        Parameter::SeedU,
        Parameter::SeedV,
        Parameter::PreShear,
        Parameter::Locking,
        Parameter::Tool,
        Parameter::StiffnessRatio,
        Parameter::LoadSteps,
        Parameter::Friction,
    ];
    /// Its name in the JSON and in `--axes`.
    pub fn name(self) -> &'static str {
        match self {
            Parameter::Spacing => "spacing",
            Parameter::Angle => "angle",
            Parameter::SeedU => "seed_u",
            Parameter::SeedV => "seed_v",
            Parameter::PreShear => "pre_shear",
            Parameter::Locking => "locking",
            Parameter::Tool => "tool",
            Parameter::StiffnessRatio => "stiffness_ratio",
            Parameter::LoadSteps => "load_steps",
            Parameter::Friction => "friction",
        }
    }
    /// The parameter called `name`.
    pub fn parse(name: &str) -> Result<Parameter, String> {
        Parameter::ALL.into_iter().find(|p| p.name() == name.trim()).ok_or_else(|| {
            let names: Vec<&str> = Parameter::ALL.iter().map(|p| p.name()).collect();
            format!("unknown parameter '{name}': use one of {}", names.join(", "))
        })
    }
    /// Whether it only acts on the mechanical stage.
    pub fn is_mechanical(self) -> bool {
        matches!(self, Parameter::StiffnessRatio | Parameter::LoadSteps | Parameter::Friction)
    }
    /// Its default values.
    pub fn values(self, tools: usize) -> Vec<f64> {
        match self {
            Parameter::Spacing => vec![0.5, 1.0, 2.0, 4.0, 8.0],
            Parameter::Angle => vec![0.0, 15.0, 30.0, 45.0, 60.0, 75.0, 90.0],
            Parameter::SeedU | Parameter::SeedV => vec![-0.3, -0.15, 0.0, 0.15, 0.3],
            Parameter::PreShear => vec![0.0, 10.0, 20.0, 30.0, 40.0],
            Parameter::Locking => vec![15.0, 25.0, 35.0, 45.0, 60.0, 75.0],
            Parameter::Tool => (0..tools).map(|k| k as f64).collect(),
            Parameter::StiffnessRatio => vec![0.01, 0.1, 1.0, 10.0, 100.0],
            Parameter::LoadSteps => vec![1.0, 2.0, 5.0, 10.0],
            Parameter::Friction => vec![0.0, 0.1, 0.2, 0.3, 0.5],
        }
    }
    /// Set the parameter to `value` in `v`.
    fn apply(self, value: f64, v: &mut Variant, d0: f64, tools: &[PathBuf]) {
        match self {
            Parameter::Spacing => v.spacing = value * d0,
            Parameter::Angle => v.angle_deg = Some(value),
            Parameter::SeedU => v.seed_shift[0] = value,
            Parameter::SeedV => v.seed_shift[1] = value,
            Parameter::PreShear => v.pre_shear_deg = Some(value),
            Parameter::Locking => v.max_shear_deg = Some(value),
            Parameter::Tool => v.tool = tools[value as usize].clone(),
            Parameter::StiffnessRatio => v.tension_factor = value,
            Parameter::LoadSteps => v.load_steps = Some(value as usize),
            Parameter::Friction => v.friction = Some(value),
        }
    }
}

/// What the stability study sweeps.
#[derive(Debug, Clone, Default)]
pub struct Options {
    /// The ply (default: the scene's first).
    pub ply: Option<String>,
    /// The parameters swept (default: every one that applies).
    pub parameters: Option<Vec<Parameter>>,
    /// The two parameters of the map (default [`DEFAULT_AXES`]).
    pub axes: Option<[Parameter; 2]>,
    /// Further resolutions of the tool.
    pub tools: Vec<PathBuf>,
}

/// The tool's smallest radius of curvature, m (infinite on a flat or developable-only tool is
/// not promised: a cylinder gives its radius). From the turn of the normal between neighbouring
/// facets over the distance of their centroids, at [`CURVATURE_QUANTILE`], sharp edges left out.
pub fn smallest_radius(tool: &ToolSurface) -> f64 {
    let tris = tool.triangles();
    let verts = tool.vertices();
    let centroid = |t: usize| {
        let [a, b, c] = tris[t].map(|v| verts[v as usize].coords);
        (a + b + c) / 3.0
    };
    let mut edges: HashMap<(u32, u32), usize> = HashMap::new();
    let mut kappa = Vec::new();
    for (t, tri) in tris.iter().enumerate() {
        for e in 0..3 {
            let (a, b) = (tri[e], tri[(e + 1) % 3]);
            let key = (a.min(b), a.max(b));
            if let Some(&o) = edges.get(&key) {
                let turn = tool.normal(t as u32).angle(&tool.normal(o as u32));
                let dist = (centroid(t) - centroid(o)).norm();
                if turn < SHARP_EDGE && dist > 0.0 {
                    kappa.push(turn / dist);
                }
            } else {
                edges.insert(key, t);
            }
        }
    }
    if kappa.is_empty() {
        return f64::INFINITY;
    }
    kappa.sort_by(f64::total_cmp);
    let k = kappa[((kappa.len() - 1) as f64 * CURVATURE_QUANTILE) as usize];
    if k > 0.0 {
        1.0 / k
    } else {
        f64::INFINITY
    }
}

/// The cases of the study of `scene`; `radius` is the tool's smallest radius of curvature (for
/// d / R).
pub fn plan(scene: &Scene, opts: &Options, radius: f64) -> Result<Plan, StudyError> {
    let ply = find_ply(scene, opts.ply.as_deref())?;
    let d0 = ply.settings.spacing;
    let tools = study_tools(scene, &opts.tools)?;
    let free = ply.refinement.as_ref().is_some_and(|r| r.mode == ContactMode::Free);
    let mechanical = ply.material.is_some() || ply.refinement.is_some();
    let applies = |p: Parameter| match p {
        Parameter::Tool => tools.len() > 1,
        Parameter::StiffnessRatio | Parameter::LoadSteps | Parameter::Friction => mechanical,
        Parameter::Spacing | Parameter::Angle => true,
        // A free drape starts from a flat sheet: no seed, generators or shear limit to turn.
        _ => !free,
    };
    let params: Vec<Parameter> = match &opts.parameters {
        Some(p) => p.clone(),
        None => Parameter::ALL.into_iter().filter(|p| applies(*p)).collect(),
    };
    let axes = opts.axes.unwrap_or([Parameter::Spacing, Parameter::Angle]);
    for p in params.iter().chain(axes.iter()) {
        if !applies(*p) {
            return Err(StudyError::Input(format!(
                "parameter '{}' does not apply to ply '{}' ({})",
                p.name(),
                ply.settings.name,
                match p {
                    Parameter::Tool => "give further tool resolutions with --tools",
                    _ if p.is_mechanical() => "the ply has no material card",
                    _ => "a free drape starts from a flat sheet",
                }
            )));
        }
    }
    if axes[0] == axes[1] {
        return Err(StudyError::Input("--axes: give two different parameters".into()));
    }
    // The kinematic method unless the ply drapes only mechanically, or a mechanical parameter
    // is swept.
    let method_for = |ps: &[Parameter]| {
        if free {
            StudyMethod::MechanicalFree
        } else if ps.iter().any(|p| p.is_mechanical()) {
            StudyMethod::MechanicalPressed
        } else {
            StudyMethod::KinematicGeodesic
        }
    };
    let mut settings: Vec<Vec<(Parameter, f64)>> = Vec::new();
    for a in axes[0].values(tools.len()) {
        for b in axes[1].values(tools.len()) {
            settings.push(vec![(axes[0], a), (axes[1], b)]);
        }
    }
    for p in params.iter().filter(|p| !axes.contains(p)) {
        for x in p.values(tools.len()) {
            settings.push(vec![(*p, x)]);
        }
    }
    let mut cases = Vec::new();
    for s in settings {
        let ps: Vec<Parameter> = s.iter().map(|(p, _)| *p).collect();
        let mut v = Variant::baseline(method_for(&ps), tools[0].clone(), d0);
        let mut named = BTreeMap::new();
        for (p, x) in &s {
            p.apply(*x, &mut v, d0, &tools);
            named.insert(p.name().to_string(), *x);
        }
        named.insert("d".into(), v.spacing);
        named.insert("d_over_r".into(), if radius.is_finite() { v.spacing / radius } else { 0.0 });
        cases.push(Case { index: cases.len(), variant: v, params: named, repeats: 1, keep_field: false });
    }
    Ok(Plan {
        kind: StudyKind::Stability,
        scene: absolute(&scene.path)?,
        ply: ply.settings.name.clone(),
        axes: Some(axes.map(|a| a.name().to_string())),
        symmetries: Vec::new(),
        reference: None,
        search: None,
        cases,
    })
}

/// One case of `stability.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StabilityCase {
    /// The swept parameters' values (and d, d / R).
    pub params: BTreeMap<String, f64>,
    /// The method.
    pub method: String,
    /// `ok` or the reason it failed.
    pub outcome: String,
    /// Placed nodes over the grid's nodes.
    pub placed_fraction: f64,
    /// Largest |cell shear|, degrees.
    pub max_shear_deg: Option<f64>,
    /// Nodes not placed, by reason.
    pub failures: BTreeMap<String, usize>,
    /// Where each failure happened on the part, m.
    #[serde(rename = "where")]
    pub where_: BTreeMap<String, [f64; 3]>,
    /// Time, s.
    pub time_s: f64,
}

/// `stability.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Stability {
    /// The ply.
    pub ply: String,
    /// The map's two parameters.
    pub axes: [String; 2],
    /// Every case.
    pub cases: Vec<StabilityCase>,
}

/// The study's result from every case's record.
pub fn evaluate(plan: &Plan, records: &[CaseRecord]) -> Stability {
    let axes = plan.axes.clone().unwrap_or(DEFAULT_AXES.map(str::to_string));
    let cases = records
        .iter()
        .map(|r| StabilityCase {
            params: r.case.params.clone(),
            method: r.case.variant.method.name().into(),
            outcome: r.result.outcome.clone(),
            placed_fraction: r.result.placed_fraction,
            max_shear_deg: r.result.max_shear_deg,
            failures: r.result.failures.clone(),
            where_: r.result.where_.clone(),
            time_s: r.result.time_s,
        })
        .collect();
    Stability { ply: plan.ply.clone(), axes, cases }
}

/// [`plan`], with the radius measured on the scene's tool.
pub fn plan_for(scene: &Scene, opts: &Options) -> Result<Plan, StudyError> {
    let tool = crate::io::read_tool(&scene.tool, scene.scale).map_err(|e| StudyError::Input(e.to_string()))?;
    plan(scene, opts, smallest_radius(&tool))
}
