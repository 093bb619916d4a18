//! `drape study speed-accuracy`: every method that applies to a ply, at a range of spacings (and
//! tool resolutions), timed and measured against ONE reference for the ply, at the same fabric
//! coordinates.
//!
//! The reference is the most complete model the ply allows ([`reference_models`]): the
//! mechanical drape where the ply has a material card (pressed; free for a free drape), else the
//! kinematic net of the ply's own generators on the smooth surface. It is drawn on the finest
//! tool given (the most triangles, the scene's or one of `--tools`), at the finest spacing the
//! study ran it at, and carried to its limit in the spacing where the order of convergence
//! allows ([`limit`]): with the shear `s_m` of the second-finest spacing and `s_f` of the finest
//! (ratio r), `s* = s_f + (s_f - s_m) / (r^p - 1)`, p the order observed from three spacings
//! (capped at the formal 2), else the model's formal order (the fishnet's 2; the mechanical
//! drape has none that two spacings could trust, so it is then taken as drawn). So the error of
//! a run is its distance from that reference, whatever its source: its spacing, the facets of a
//! coarser tool, or a simpler model. Each method's distance from its own limit (its own
//! convergence, blind to the tool's facets and to what its model leaves out) is reported beside
//! it and labelled as such.
//!
//! Errors are measured at every complete cell of the run, its cell shear as drawn against the
//! reference there. The reference lives on its finest run's cells (the coarser run it is
//! extrapolated with read off at them) and is read off between its cells by the cubic through
//! the 4 x 4 cells around ([`ShearField::interpolate`]): a bilinear reading would add an error
//! of the order of a fine run's own, and averaging a fine run's cells would hide the cell-to-cell
//! error a coarse tool's facets give it.
use super::plan::{absolute, find_ply, study_tools, Case, Plan, StudyKind, StudyMethod, Variant};
use super::runner::CaseRecord;
use super::{symmetry, StudyError};
use crate::io::{read_tool, read_tool_mesh, ToolMesh};
use crate::kinematic::fabric_field::{FabricImage, ShearField};
use crate::kinematic::{GeneratorKind, SurfaceKind};
use crate::layup::auto::{FISHNET_ORDER, MIN_TRUSTED_ORDER};
use crate::layup::Ply;
use crate::mechanics::ContactMode;
use crate::pipeline::Scene;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The study's result file.
pub const FILE: &str = "speed_accuracy.json";
/// Spacings of the kinematic methods when none are given, as multiples of the ply's spacing.
pub const KINEMATIC_SPACING_FACTORS: [f64; 4] = [2.0, 1.0, 0.5, 0.25];
/// Spacings of the mechanical methods when none are given, as multiples of the ply's spacing.
pub const MECHANICAL_SPACING_FACTORS: [f64; 2] = [2.0, 1.0];
/// Bounds on the observed order of convergence a limit is extrapolated with. The fishnet and
/// the mechanical net are second order in d; an observed order above 2 comes from a coarse
/// spacing outside the asymptotic range, and extrapolating with it would understate the error
/// (on the Chebyshev sphere by a factor 4), so it is capped at the formal order. Below the
/// least trusted order the runs are not yet converging steadily and are not extrapolated. The
/// same bounds as `method = "auto"` trusts (one place for them: [`MIN_TRUSTED_ORDER`],
/// [`FISHNET_ORDER`]).
pub const ORDER_RANGE: (f64, f64) = (MIN_TRUSTED_ORDER, FISHNET_ORDER);
/// The fishnet's formal order, assumed where two spacings cannot measure one (or their
/// differences are rounding). The mechanical drape has no order two spacings could trust: on
/// the bundled cone and double dome it converges at order 1 or below.
pub const KINEMATIC_FORMAL_ORDER: f64 = FISHNET_ORDER;
/// Differences (rms, degrees) below this are rounding, not convergence: the order is not
/// measured from them.
const ORDER_NOISE_DEG: f64 = 1e-9;
/// Spacings this close (relative) are the same spacing.
const SAME_SPACING_REL: f64 = 1e-9;

/// What the speed-accuracy study runs.
#[derive(Debug, Clone, Default)]
pub struct Options {
    /// The ply (default: the scene's first).
    pub ply: Option<String>,
    /// Spacings of the kinematic methods, m (default: [`KINEMATIC_SPACING_FACTORS`]).
    pub spacings: Option<Vec<f64>>,
    /// Spacings of the mechanical methods, m (default: [`MECHANICAL_SPACING_FACTORS`]).
    pub mechanical_spacings: Option<Vec<f64>>,
    /// Further resolutions of the tool (files), run with every kinematic method; the finest
    /// tool given carries the reference.
    pub tools: Vec<PathBuf>,
    /// Repeats of each kinematic case (the median time is reported); mechanical cases run once.
    pub repeats: usize,
    /// Further coefficients of friction between ply and tool: the pressed mechanical drape runs
    /// again at each (on the scene's tool, at the mechanical spacings), measured against the
    /// one reference drawn with the ply's own friction: what friction changes, and what it costs.
    pub frictions: Vec<f64>,
}

/// The methods that apply to `ply`.
pub fn methods_for(ply: &Ply) -> Vec<StudyMethod> {
    if is_free(ply) {
        return vec![StudyMethod::MechanicalFree];
    }
    let mut m = vec![StudyMethod::KinematicGeodesic, StudyMethod::KinematicMinShear];
    if matches!(ply.settings.generators, GeneratorKind::Steer(_)) {
        m.push(StudyMethod::KinematicSteered);
    }
    if has_card(ply) {
        m.push(StudyMethod::MechanicalPressed);
        m.push(StudyMethod::Auto);
    }
    m
}

fn is_free(ply: &Ply) -> bool {
    ply.refinement.as_ref().is_some_and(|r| r.mode == ContactMode::Free)
}

fn has_card(ply: &Ply) -> bool {
    ply.material.is_some() || ply.refinement.is_some()
}

/// The kinematic method that draws the ply with its own generators.
fn own_kinematic_method(ply: &Ply) -> StudyMethod {
    match ply.settings.generators {
        GeneratorKind::Geodesic => StudyMethod::KinematicGeodesic,
        GeneratorKind::MinShear => StudyMethod::KinematicMinShear,
        GeneratorKind::Steer(_) => StudyMethod::KinematicSteered,
    }
}

/// One model a reference may be drawn with, and why it is the reference when it is.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReferenceModel {
    /// The method.
    pub method: StudyMethod,
    /// The surface its cases are planned on (a mechanical case's kinematic start: the facets;
    /// its contact slides on the smooth surface whatever it starts from).
    pub surface: SurfaceKind,
    /// Why it is the reference.
    pub why: String,
}

/// The reference of a speed-accuracy study, as planned: the tool it is drawn on and the models
/// the ply allows, most complete first.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReferencePlan {
    /// The finest tool given (the most triangles; the scene's on a tie).
    pub tool: PathBuf,
    /// Its triangles.
    pub tool_triangles: usize,
    /// The models, most complete first: the reference is the first that gave a usable run.
    pub models: Vec<ReferenceModel>,
}

/// The models `ply` allows, most complete first: the mechanical drape where it has a card
/// (pressed; free for a free drape), then the kinematic net of its own generators on the smooth
/// surface (the facets' error then counts against the runs on the facets).
pub fn reference_models(ply: &Ply) -> Vec<ReferenceModel> {
    if is_free(ply) {
        return vec![ReferenceModel {
            method: StudyMethod::MechanicalFree,
            surface: SurfaceKind::Facets,
            why: "the ply is a free drape, which only the mechanical model draws".into(),
        }];
    }
    let kinematic =
        |why: &str| ReferenceModel { method: own_kinematic_method(ply), surface: SurfaceKind::Smooth, why: why.into() };
    if has_card(ply) {
        vec![
            ReferenceModel {
                method: StudyMethod::MechanicalPressed,
                surface: SurfaceKind::Facets,
                why:
                    "the ply has a material card, so the pressed mechanical drape is the most complete model it allows"
                        .into(),
            },
            kinematic(
                "the kinematic net of the ply's generators on the smooth surface is the most complete model after it",
            ),
        ]
    } else {
        vec![kinematic(
            "the ply has no material card, so the kinematic net of its generators on the smooth surface is the most complete model it allows",
        )]
    }
}

/// Of `tools`, the one with the most triangles (the first on a tie), and that many.
fn finest_tool(tools: &[PathBuf], scale: f64) -> Result<(PathBuf, usize), StudyError> {
    let mut best: Option<(PathBuf, usize)> = None;
    for t in tools {
        let n = match read_tool_mesh(t, scale).map_err(|e| StudyError::Input(e.to_string()))? {
            ToolMesh::Surface(mesh, _) | ToolMesh::Shell(mesh) => mesh.triangles.len(),
        };
        if best.as_ref().is_none_or(|b| n > b.1) {
            best = Some((t.clone(), n));
        }
    }
    best.ok_or_else(|| StudyError::Input("the study has no tool".into()))
}

/// The cases of the study of `scene`.
pub fn plan(scene: &Scene, opts: &Options) -> Result<Plan, StudyError> {
    let ply = find_ply(scene, opts.ply.as_deref())?;
    let d0 = ply.settings.spacing;
    let spacings = |given: &Option<Vec<f64>>, factors: &[f64]| -> Result<Vec<f64>, StudyError> {
        let mut s: Vec<f64> = match given {
            Some(s) => s.clone(),
            None => factors.iter().map(|f| f * d0).collect(),
        };
        if s.is_empty() || s.iter().any(|d| !(d.is_finite() && *d > 0.0)) {
            return Err(StudyError::Input(format!("spacings must be positive lengths, got {s:?}")));
        }
        // A spacing given twice is one spacing (twice would extrapolate by 0 / 0).
        let mut seen: Vec<f64> = Vec::new();
        s.retain(|d| {
            let new = !seen.iter().any(|e| (e - d).abs() <= SAME_SPACING_REL * d);
            seen.push(*d);
            new
        });
        Ok(s)
    };
    let kin = spacings(&opts.spacings, &KINEMATIC_SPACING_FACTORS)?;
    let mech = spacings(&opts.mechanical_spacings, &MECHANICAL_SPACING_FACTORS)?;
    let tools = study_tools(scene, &opts.tools)?;
    let (finest, finest_triangles) = finest_tool(&tools, scene.scale)?;
    let methods = methods_for(ply);
    // Only a mechanical reference can break the scene's symmetries (a kinematic net is a
    // function of the ply, so as symmetric as its problem): look for them only then, on the
    // reference's tool.
    let symmetries = if methods.iter().any(|m| m.is_mechanical()) {
        let tool = read_tool(&finest, scene.scale).map_err(|e| StudyError::Input(e.to_string()))?;
        symmetry::symmetries(ply, &scene.layup, &tool)
    } else {
        Vec::new()
    };
    // The mechanical methods run on the scene's tool and on the reference's; auto on the
    // scene's; the kinematic methods on every tool given.
    let mut mechanical_tools = vec![tools[0].clone()];
    if finest != tools[0] {
        mechanical_tools.push(finest.clone());
    }
    if opts.frictions.iter().any(|mu| !(mu.is_finite() && *mu >= 0.0)) {
        return Err(StudyError::Input(format!(
            "frictions must be coefficients of 0 or more, got {:?}",
            opts.frictions
        )));
    }
    if !opts.frictions.is_empty() && !methods.contains(&StudyMethod::MechanicalPressed) {
        return Err(StudyError::Input(format!(
            "--frictions: ply {} has no pressed mechanical drape to vary the friction of (give it a material card; a free drape's friction is its stability study's axis)",
            ply.settings.name
        )));
    }
    let mut cases = Vec::new();
    for method in methods {
        let (ds, ts, repeats) = if method.is_mechanical() {
            (&mech, &mechanical_tools[..], 1)
        } else if method.may_run_mechanics() {
            (&mech, &tools[..1], 1)
        } else {
            (&kin, &tools[..], opts.repeats.max(1))
        };
        // The kinematic methods step on the facets and on the smooth surface over them.
        let surfaces: &[SurfaceKind] =
            if method.may_run_mechanics() { &[SurfaceKind::Facets] } else { &SurfaceKind::ALL };
        for (tool, &surface) in ts.iter().flat_map(|t| surfaces.iter().map(move |s| (t, s))) {
            for &spacing in ds {
                let variant = Variant { surface, ..Variant::baseline(method, tool.clone(), spacing) };
                let params = BTreeMap::from([("spacing".to_string(), spacing)]);
                cases.push(Case { index: cases.len(), variant, params, repeats, keep_field: true });
            }
        }
    }
    // The friction axis: the pressed drape again at each coefficient.
    for &mu in &opts.frictions {
        for &spacing in &mech {
            let variant = Variant {
                friction: Some(mu),
                ..Variant::baseline(StudyMethod::MechanicalPressed, tools[0].clone(), spacing)
            };
            let params = BTreeMap::from([("spacing".to_string(), spacing), ("friction".to_string(), mu)]);
            cases.push(Case { index: cases.len(), variant, params, repeats: 1, keep_field: true });
        }
    }
    Ok(Plan {
        kind: StudyKind::SpeedAccuracy,
        scene: absolute(&scene.path)?,
        ply: ply.settings.name.clone(),
        axes: None,
        symmetries,
        reference: Some(ReferencePlan {
            tool: finest,
            tool_triangles: finest_triangles,
            models: reference_models(ply),
        }),
        search: None,
        cases,
    })
}

/// How a model's runs are carried to their limit in the spacing ([`limit`]).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Convergence {
    /// The spacings of the runs it is drawn from, coarsest first, m.
    pub spacings: Vec<f64>,
    /// Whether it is Richardson-extrapolated from the two finest (else it is the finest run as
    /// drawn).
    pub extrapolated: bool,
    /// The order it is extrapolated with.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub order: Option<f64>,
    /// Whether that order was observed from the three finest spacings (else it is the model's
    /// formal order).
    #[serde(default)]
    pub order_measured: bool,
    /// The order the three finest spacings show, before the cap (where their differences fall).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub observed_order: Option<f64>,
    /// Its own error, estimated, largest over its points, degrees: for an extrapolated limit
    /// the correction it applied (the finest run's estimated error, more than the limit's own);
    /// for a run taken as drawn its difference from the next coarser over (r - 1), the estimate
    /// at order 1, the least trusted. Absent with one spacing.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub uncertainty_max_deg: Option<f64>,
    /// In words: how it was carried to its limit, or why not.
    pub note: String,
}

/// What the errors are measured against.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ReferenceKind {
    /// A mechanical drape (pressed, or free for a free drape).
    Mechanical,
    /// The kinematic net on the smooth surface.
    Kinematic,
    /// No model gave a usable run: nothing is measured.
    None,
}

/// The one reference of the study: every run's error is its distance from it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Reference {
    /// Mechanical, kinematic, or none.
    pub kind: ReferenceKind,
    /// Its method (empty without a reference).
    pub method: String,
    /// The surface of its cases (`facets` for a mechanical drape's kinematic start).
    pub surface: String,
    /// The tool it is drawn on: the finest given.
    pub tool: PathBuf,
    /// Its triangles.
    pub tool_triangles: usize,
    /// The finest spacing it is drawn at, m (0 without a reference).
    pub spacing: f64,
    /// How it is carried to its limit in the spacing.
    pub convergence: Convergence,
    /// The same model on the next coarser tool the study ran it on, at the reference's finest
    /// spacing: how far the tool's resolution moves the reference. The finest tool's own
    /// resolution error is shared by the reference and not measured; absent with one tool.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tool_difference: Option<ToolDifference>,
    /// Why this model (the most complete the ply allows that gave a usable run), or why there is
    /// no reference.
    pub why: String,
    /// The symmetries of the ply's drape problem, the identity left out: a mechanical reference
    /// that broke one is as good as its image, and each run is measured against the nearer.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub symmetries: Vec<FabricImage>,
}

/// The reference model's run on a coarser tool against its run on the reference's tool.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ToolDifference {
    /// Triangles of the coarser tool.
    pub tool_triangles: usize,
    /// The spacing both are drawn at, m.
    pub spacing: f64,
    /// Their largest cell-shear difference, degrees.
    pub max_deg: f64,
}

/// A tool file's name for people.
fn file_name(p: &Path) -> String {
    p.file_name().map_or_else(|| p.display().to_string(), |n| n.to_string_lossy().into_owned())
}

/// A number in at most three significant figures, for labels.
pub fn three_figures(x: f64) -> String {
    format!("{}", format!("{x:.2e}").parse::<f64>().unwrap_or(x))
}

/// A length in metres as millimetres, three significant figures.
pub fn mm(d: f64) -> String {
    three_figures(d * 1e3)
}

impl Reference {
    fn none(why: String) -> Reference {
        Reference {
            kind: ReferenceKind::None,
            method: String::new(),
            surface: String::new(),
            tool: PathBuf::new(),
            tool_triangles: 0,
            spacing: 0.0,
            convergence: Convergence::default(),
            tool_difference: None,
            why,
            symmetries: Vec::new(),
        }
    }

    /// Where it is drawn, in words: the method, the surface and the tool.
    fn drawn(&self) -> String {
        let on = match self.kind {
            ReferenceKind::Kinematic => format!("on the {} surface of", self.surface),
            _ => "on".to_string(),
        };
        format!("{} {on} {} ({} triangles)", self.method, file_name(&self.tool), self.tool_triangles)
    }

    /// The reference in a few words, for a chart's title.
    pub fn label(&self) -> String {
        if self.kind == ReferenceKind::None {
            return "none".into();
        }
        let c = &self.convergence;
        let limit = match c.order {
            Some(p) if c.extrapolated => format!(", extrapolated at order {p:.2}"),
            _ => String::new(),
        };
        format!("{} at d = {} mm{limit}", self.drawn(), mm(self.spacing))
    }

    /// The reference in a sentence: what it is, how it was carried to its limit and why.
    pub fn describe(&self) -> String {
        if self.kind == ReferenceKind::None {
            return format!("no reference: {}", self.why);
        }
        let c = &self.convergence;
        let uncertainty = c
            .uncertainty_max_deg
            .map_or(String::new(), |u| format!("; its own spacing error is estimated at {u:.4} deg at most"));
        let tool = match &self.tool_difference {
            Some(t) => format!(
                "; on the next coarser tool ({} triangles) the same model differs by up to {:.4} deg at d = {} mm (the finest tool's own resolution error is shared, not measured)",
                t.tool_triangles,
                t.max_deg,
                mm(t.spacing)
            ),
            None => "; the tool's own resolution error is shared, not measured: give finer tools with --tools to see it"
                .to_string(),
        };
        format!("{} at d = {} mm, {}{uncertainty}{tool}; {}", self.drawn(), mm(self.spacing), c.note, self.why)
    }
}

/// One method's own limit: its convergence, blind to the tool's facets and to what its model
/// leaves out, shown beside its error against the reference.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OwnLimit {
    /// The method.
    pub method: String,
    /// Its surface.
    pub surface: String,
    /// Triangles of its tool.
    pub tool_triangles: usize,
    /// The friction its cases set (the friction axis); absent for the ply's own.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction: Option<f64>,
    /// How its runs are carried to their limit.
    pub convergence: Convergence,
}

/// One run of the study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SpeedPoint {
    /// The method.
    pub method: String,
    /// Fibre spacing d, m.
    pub spacing: f64,
    /// `facets` or `smooth`.
    pub surface: String,
    /// Triangles of the tool.
    pub tool_triangles: usize,
    /// The coefficient of friction the case sets (the friction axis); absent where the ply's own
    /// applies.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction: Option<f64>,
    /// Median time of the repeats, s.
    pub time_s: f64,
    /// Repeats timed.
    pub repeats: usize,
    /// Largest |shear - reference| over the compared points, degrees (absent without any): the
    /// run's error, whatever its source.
    pub error_max_deg: Option<f64>,
    /// Root mean square of the same, degrees.
    pub error_rms_deg: Option<f64>,
    /// Points compared.
    pub compared: usize,
    /// Its own convergence: largest |shear - the method's own limit| (same method, surface and
    /// tool), degrees. Not an error: it cannot see the tool's facets or the model.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub own_error_max_deg: Option<f64>,
    /// Root mean square of the same, degrees.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub own_error_rms_deg: Option<f64>,
    /// `ok` or why not.
    pub outcome: String,
    /// On the Pareto front: no other successful run is both faster and more accurate.
    pub pareto: bool,
    /// For an `auto` run: the method it ran.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub chosen: Option<String>,
    /// On a symmetric scene: the image of the reference the errors are measured against.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference_image: Option<FabricImage>,
}

impl SpeedPoint {
    /// Its method for people: the method, and the friction where the case sets it.
    pub fn method_label(&self) -> String {
        match self.friction {
            Some(mu) => format!("{} mu={}", self.method, three_figures(mu)),
            None => self.method.clone(),
        }
    }
}

/// What `method = "auto"` saved at one spacing: its result against the reference and its cost
/// against always running mechanics there.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AutoCost {
    /// Fibre spacing d asked for, m.
    pub spacing: f64,
    /// The tool it ran on.
    #[serde(default)]
    pub tool: PathBuf,
    /// The tolerance, degrees.
    pub tolerance_deg: f64,
    /// What it ran.
    pub chosen: String,
    /// Why.
    pub reason: String,
    /// Its largest error against the reference, degrees (absent without a reference point).
    pub error_max_deg: Option<f64>,
    /// Whether that error is within the tolerance.
    pub within_tolerance: Option<bool>,
    /// Auto's own verdict ([`crate::kinematic::MethodChoice::assured`]): whether its estimates
    /// said the result is within the tolerance. Set beside `within_tolerance`, it shows whether
    /// auto can be trusted when it says so ([`AutoCost::verdict`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub assured: Option<bool>,
    /// The spacing auto drew its result at, m (finer than `spacing` where it refined).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ran_spacing: Option<f64>,
    /// Its time, s (the indicators included).
    pub time_s: f64,
    /// The pressed mechanical drape's time at the same spacing, s.
    pub mechanical_time_s: Option<f64>,
    /// `time_s` over `mechanical_time_s`.
    pub cost_ratio: Option<f64>,
    /// The fastest pressed mechanical run within the tolerance of the reference, s: what
    /// mechanics costs for the same accuracy.
    #[serde(default)]
    pub mechanical_within_tolerance_s: Option<f64>,
}

impl AutoCost {
    /// Auto's verdict against the `reference`'s, in words: whether it said rightly that its
    /// result is within the tolerance (or not). A result auto assured and the reference finds
    /// outside the tolerance is a FALSE ASSURANCE, the one answer an engineer cannot catch. Where
    /// auto ran mechanics, a mechanical reference taken as drawn on auto's tool, no finer than
    /// auto's drape, cannot judge it (auto's drape pressed again at the reference's spacing is
    /// the reference itself, or the same model at the same spacing from another start); an
    /// extrapolated reference, one on a finer tool, or a kinematic result it can. None where
    /// either is missing.
    pub fn verdict(&self, reference: &Reference) -> Option<&'static str> {
        let (assured, within) = (self.assured?, self.within_tolerance?);
        let unjudged = reference.kind == ReferenceKind::Mechanical
            && !reference.convergence.extrapolated
            && reference.tool == self.tool
            && self.chosen == "mechanical"
            && self.ran_spacing.is_some_and(|d| d <= reference.spacing * (1.0 + SAME_SPACING_REL));
        if unjudged {
            return Some(if assured {
                "auto assured it; drawn at the reference's spacing or finer, the study has nothing finer to judge that by"
            } else {
                "auto said NOT ASSURED; drawn at the reference's spacing or finer, the study has nothing finer to judge that by"
            });
        }
        Some(match (assured, within) {
            (true, true) => "auto assured it, rightly",
            (false, false) => "auto said NOT ASSURED, rightly",
            (false, true) => "auto said NOT ASSURED, yet it is within (cautious)",
            (true, false) => "FALSE ASSURANCE: auto assured it, and it is outside",
        })
    }
}

/// `speed_accuracy.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SpeedAccuracy {
    /// The ply.
    pub ply: String,
    /// What every run's error is measured against.
    pub reference: Reference,
    /// Each method's own limit (per surface and tool, from two spacings or more): its own
    /// convergence, shown beside the errors.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub own_limits: Vec<OwnLimit>,
    /// Every run.
    pub points: Vec<SpeedPoint>,
    /// The `auto` runs: error kept and cost saved against mechanics.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub auto: Vec<AutoCost>,
    /// Why `auto` was not run, when it was not (a free drape, a ply without a material card).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub auto_not_run: Option<String>,
}

fn rms(x: impl Iterator<Item = f64>) -> f64 {
    let (s, n) = x.fold((0.0, 0usize), |(s, n), e| (s + e * e, n + 1));
    if n == 0 {
        0.0
    } else {
        (s / n as f64).sqrt()
    }
}

/// Every complete cell of `f`: its centre's fabric coordinates and its shear.
fn cells(f: &ShearField) -> impl Iterator<Item = ((f64, f64), f64)> + '_ {
    (0..f.cu).flat_map(move |i| (0..f.cv).filter_map(move |j| Some((f.cell_centre(i, j), f.shear_deg[i * f.cv + j]?))))
}

/// Max and rms of |field - reference| over the complete cells of `field` (its cell shears as
/// drawn, the reference read off between its centres), and how many.
fn compare_at(reference: &ShearField, field: &ShearField) -> (Option<f64>, Option<f64>, usize) {
    let errs: Vec<f64> =
        cells(field).filter_map(|((u, v), s)| Some((s - reference.interpolate(u, v)?).abs())).collect();
    if errs.is_empty() {
        return (None, None, 0);
    }
    (errs.iter().copied().reduce(f64::max), Some(rms(errs.iter().copied())), errs.len())
}

/// Largest errors (degrees) of two images closer than this are a tie, which the reference as it
/// fell wins: differences of rounding (the same arithmetic on a mirrored grid) choose nothing.
const IMAGE_TIE_DEG: f64 = 1e-9;

/// A run's error against a reference field, measured in the image of the reference nearest to
/// it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Comparison {
    /// The image of the reference used.
    pub image: FabricImage,
    /// Largest |shear - reference| over the compared points, degrees (absent without any).
    pub error_max_deg: Option<f64>,
    /// Root mean square of the same, degrees.
    pub error_rms_deg: Option<f64>,
    /// Points compared.
    pub compared: usize,
}

/// A reference field and its images under the symmetries of the ply's drape problem: where the
/// problem is symmetric, the reference's mirror image is an equally valid drape, and a run that
/// broke the symmetry the other way is measured against that.
pub struct ReferenceImages {
    images: Vec<(FabricImage, ShearField)>,
}

impl ReferenceImages {
    /// `reference` as it fell and its images under `symmetries` (the identity left out).
    pub fn new(reference: &ShearField, symmetries: &[FabricImage]) -> ReferenceImages {
        let images = std::iter::once(FabricImage::AsIs)
            .chain(symmetries.iter().copied().filter(|&s| s != FabricImage::AsIs))
            .map(|s| (s, reference.image(s)))
            .collect();
        ReferenceImages { images }
    }

    /// `field` against each image: the one with the least largest error over the whole field
    /// (the reference as it fell on a tie, [`IMAGE_TIE_DEG`]).
    pub fn compare(&self, field: &ShearField) -> Comparison {
        let mut best = Comparison { image: FabricImage::AsIs, error_max_deg: None, error_rms_deg: None, compared: 0 };
        for (image, reference) in &self.images {
            let (error_max_deg, error_rms_deg, compared) = compare_at(reference, field);
            let Some(e) = error_max_deg else { continue };
            if best.error_max_deg.is_none_or(|b| e < b - IMAGE_TIE_DEG) {
                best = Comparison { image: *image, error_max_deg, error_rms_deg, compared };
            }
        }
        best
    }
}

/// The limit in the spacing of one model's runs `runs` (spacing and field, coarsest first), or
/// `None` without any. With two spacings or more it is Richardson-extrapolated from the two
/// finest where the order allows: the order observed from the three finest when their
/// differences fall at [`ORDER_RANGE`]'s least trusted order or faster (capped at its formal
/// 2), else, with two spacings or rounding-level differences, the model's `formal` order;
/// otherwise (no formal order, or an observed one below the least trusted) the finest run is
/// taken as drawn. The one implementation behind the study's reference and each method's own
/// limit.
pub fn limit(runs: &[(f64, &ShearField)], formal: Option<f64>) -> Option<(ShearField, Convergence)> {
    let n = runs.len();
    let &(df, ff) = runs.last()?;
    let spacings: Vec<f64> = runs.iter().map(|r| r.0).collect();
    let as_drawn = |uncertainty_max_deg: Option<f64>, observed_order: Option<f64>, note: String| {
        let c = Convergence {
            spacings: spacings.clone(),
            extrapolated: false,
            order: None,
            order_measured: false,
            observed_order,
            uncertainty_max_deg,
            note,
        };
        (ff.clone(), c)
    };
    if n < 2 {
        return Some(as_drawn(None, None, "one spacing, taken as drawn: its own spacing error is not known".into()));
    }
    let (dm, fm) = runs[n - 2];
    let r = dm / df;
    // At the finest run's cells: its shear and the next coarser's read off there.
    let pairs: Vec<(usize, f64, f64)> = (0..ff.cu * ff.cv)
        .filter_map(|k| {
            let (u, v) = ff.cell_centre(k / ff.cv, k % ff.cv);
            Some((k, ff.shear_deg[k]?, fm.interpolate(u, v)?))
        })
        .collect();
    let step = pairs.iter().map(|&(_, sf, sm)| (sf - sm).abs()).reduce(f64::max);
    // The order observed from the three finest, at the same cells.
    let mut observed: Option<Option<f64>> = None;
    if n >= 3 {
        let (dc, fc) = runs[n - 3];
        let triples: Vec<(f64, f64, f64)> = pairs
            .iter()
            .filter_map(|&(k, sf, sm)| {
                let (u, v) = ff.cell_centre(k / ff.cv, k % ff.cv);
                Some((fc.interpolate(u, v)?, sm, sf))
            })
            .collect();
        let e1 = rms(triples.iter().map(|t| t.0 - t.1));
        let e2 = rms(triples.iter().map(|t| t.1 - t.2));
        if e1 > ORDER_NOISE_DEG && e2 > ORDER_NOISE_DEG {
            observed = Some(crate::numeric::observed_order(e1, e2, dc / dm, dm / df));
        }
    }
    let order = match (observed, formal) {
        (Some(Some(p)), _) if p >= ORDER_RANGE.0 => Ok((p.min(ORDER_RANGE.1), true)),
        (Some(Some(p)), _) => Err(format!(
            "the three finest spacings converge at order {p:.2}, below the least trusted {}: not yet steadily, so the finest is taken as drawn",
            ORDER_RANGE.0
        )),
        (Some(None), _) => Err("the difference between the two finest spacings is no smaller than between the coarser two: not converging, so the finest is taken as drawn".into()),
        (None, Some(p)) => Ok((p, false)),
        (None, None) => Err("two spacings cannot measure the order this model converges at, and it has no formal order to assume, so the finest is taken as drawn".into()),
    };
    let observed_order = observed.flatten();
    let (p, measured) = match order {
        Ok(o) => o,
        // The estimate at the least trusted order: the largest a steady convergence gives.
        Err(why) => return Some(as_drawn(step.map(|s| s / (r - 1.0)), observed_order, why)),
    };
    let factor = 1.0 / (r.powf(p) - 1.0);
    let mut grid = ShearField { shear_deg: vec![None; ff.shear_deg.len()], ..ff.clone() };
    let mut correction = None::<f64>;
    for &(k, sf, sm) in &pairs {
        let c = (sf - sm) * factor;
        correction = Some(correction.map_or(c.abs(), |m: f64| m.max(c.abs())));
        grid.shear_deg[k] = Some(sf + c);
    }
    let note = format!(
        "extrapolated from d = {} and {} mm at order {p:.2} ({})",
        mm(dm),
        mm(df),
        if measured { "observed from the three finest spacings" } else { "the model's formal order" }
    );
    let c = Convergence {
        spacings,
        extrapolated: true,
        order: Some(p),
        order_measured: measured,
        observed_order,
        uncertainty_max_deg: correction,
        note,
    };
    Some((grid, c))
}

/// A run's field, where it can stand in a limit: a mechanical run only when it converged.
fn usable(r: &CaseRecord) -> Option<&ShearField> {
    let f = r.result.field.as_ref()?;
    (!r.case.variant.method.is_mechanical() || r.result.converged == Some(true)).then_some(f)
}

/// The runs of `records` with `select`, usable in a limit, coarsest first.
fn runs_of(records: &[CaseRecord], select: impl Fn(&Variant) -> bool) -> Vec<(f64, &ShearField)> {
    let mut runs: Vec<(f64, &ShearField)> = records
        .iter()
        .filter(|r| select(&r.case.variant))
        .filter_map(|r| Some((r.case.variant.spacing, usable(r)?)))
        .collect();
    runs.sort_by(|a, b| b.0.total_cmp(&a.0));
    runs
}

/// The formal order of a method's convergence in the spacing, where it has one.
fn formal_order(method: StudyMethod) -> Option<f64> {
    (!method.may_run_mechanics()).then_some(KINEMATIC_FORMAL_ORDER)
}

/// The study's reference and its field: the first of the planned models that gave a usable run
/// on the reference's tool, carried to its limit.
fn reference_of(plan: &Plan, records: &[CaseRecord]) -> (Reference, Option<ShearField>) {
    let Some(spec) = &plan.reference else {
        return (
            Reference::none(
                "the study's plan names no reference (planned before the one reference per ply): run the study again into a fresh folder"
                    .into(),
            ),
            None,
        );
    };
    let mut skipped: Vec<&str> = Vec::new();
    for model in &spec.models {
        let runs = runs_of(records, |v| {
            v.method == model.method && v.surface == model.surface && v.tool == spec.tool && v.friction.is_none()
        });
        let Some((field, convergence)) = limit(&runs, formal_order(model.method)) else {
            skipped.push(model.method.name());
            continue;
        };
        let why = if skipped.is_empty() {
            model.why.clone()
        } else {
            format!("{} gave no usable run on this tool; {}", skipped.join(" and "), model.why)
        };
        let kind = if model.method.is_mechanical() { ReferenceKind::Mechanical } else { ReferenceKind::Kinematic };
        // The same model at the finest spacing on the next coarser tool.
        let (df, ff) = *runs.last().unwrap_or_else(|| unreachable!("a limit has a run"));
        let tool_difference = records
            .iter()
            .filter(|r| {
                let v = &r.case.variant;
                v.method == model.method
                    && v.surface == model.surface
                    && v.friction.is_none()
                    && v.tool != spec.tool
                    && (v.spacing - df).abs() <= SAME_SPACING_REL * df
            })
            .filter_map(|r| Some((r.result.tool_triangles, usable(r)?)))
            .max_by_key(|(n, _)| *n)
            .and_then(|(n, f)| Some(ToolDifference { tool_triangles: n, spacing: df, max_deg: compare_at(ff, f).0? }));
        let reference = Reference {
            kind,
            method: model.method.name().into(),
            surface: model.surface.name().into(),
            tool: spec.tool.clone(),
            tool_triangles: spec.tool_triangles,
            spacing: df,
            convergence,
            tool_difference,
            why,
            symmetries: if kind == ReferenceKind::Mechanical { plan.symmetries.clone() } else { Vec::new() },
        };
        return (reference, Some(field));
    }
    let why = format!("none of {} gave a usable run on {}", skipped.join(", "), file_name(&spec.tool));
    (Reference::none(why), None)
}

/// Each method's own limit (per surface and tool) and every run's distance from it.
fn own_limits(plan: &Plan, records: &[CaseRecord], points: &mut [SpeedPoint]) -> Vec<OwnLimit> {
    // Auto draws each spacing with the model it chooses there: it has no limit of its own.
    // A friction the case sets is another model (its bits: f64 is not Ord).
    let mut groups: BTreeMap<(StudyMethod, &str, &Path, Option<u64>), Vec<usize>> = BTreeMap::new();
    for (k, r) in records.iter().enumerate().filter(|(_, r)| r.case.variant.method != StudyMethod::Auto) {
        let v = &r.case.variant;
        groups.entry((v.method, v.surface.name(), v.tool.as_path(), v.friction.map(f64::to_bits))).or_default().push(k);
    }
    let mut out = Vec::new();
    for ((method, surface, tool, friction), ks) in groups {
        let runs = runs_of(records, |v| {
            v.method == method
                && v.surface.name() == surface
                && v.tool.as_path() == tool
                && v.friction.map(f64::to_bits) == friction
        });
        if runs.len() < 2 {
            continue;
        }
        let Some((field, convergence)) = limit(&runs, formal_order(method)) else { continue };
        let symmetries: &[FabricImage] = if method.is_mechanical() { &plan.symmetries } else { &[] };
        let images = ReferenceImages::new(&field, symmetries);
        for &k in &ks {
            if let Some(f) = records[k].result.field.as_ref() {
                let c = images.compare(f);
                (points[k].own_error_max_deg, points[k].own_error_rms_deg) = (c.error_max_deg, c.error_rms_deg);
            }
        }
        out.push(OwnLimit {
            method: method.name().into(),
            surface: surface.into(),
            tool_triangles: records[ks[0]].result.tool_triangles,
            friction: friction.map(f64::from_bits),
            convergence,
        });
    }
    out
}

/// The study's result from every case's record.
pub fn evaluate(plan: &Plan, records: &[CaseRecord]) -> SpeedAccuracy {
    let mut points: Vec<SpeedPoint> = records
        .iter()
        .map(|r| SpeedPoint {
            method: r.case.variant.method.name().into(),
            spacing: r.case.variant.spacing,
            surface: r.case.variant.surface.name().into(),
            tool_triangles: r.result.tool_triangles,
            friction: r.case.variant.friction,
            time_s: r.result.time_s,
            repeats: r.result.times_s.len(),
            error_max_deg: None,
            error_rms_deg: None,
            compared: 0,
            own_error_max_deg: None,
            own_error_rms_deg: None,
            outcome: r.result.outcome.clone(),
            pareto: false,
            chosen: r.result.choice.as_ref().map(|c| c.chosen.clone()),
            reference_image: None,
        })
        .collect();
    let (reference, field) = reference_of(plan, records);
    if let Some(field) = &field {
        // A net with failed nodes is compared where it has cells; its outcome says what failed.
        let images = ReferenceImages::new(field, &reference.symmetries);
        for (p, r) in points.iter_mut().zip(records) {
            if let Some(f) = r.result.field.as_ref() {
                let c = images.compare(f);
                (p.error_max_deg, p.error_rms_deg, p.compared) = (c.error_max_deg, c.error_rms_deg, c.compared);
                p.reference_image = (!reference.symmetries.is_empty()).then_some(c.image);
            }
        }
    }
    let own_limits = own_limits(plan, records, &mut points);
    mark_pareto(&mut points);
    let auto = auto_costs(records, &points);
    let auto_not_run = auto_not_run(plan);
    SpeedAccuracy { ply: plan.ply.clone(), reference, own_limits, points, auto, auto_not_run }
}

/// Why the plan has no `auto` case ([`methods_for`]), or `None` when it has one.
fn auto_not_run(plan: &Plan) -> Option<String> {
    let methods: Vec<StudyMethod> = plan.cases.iter().map(|c| c.variant.method).collect();
    if methods.contains(&StudyMethod::Auto) {
        None
    } else if methods.contains(&StudyMethod::MechanicalFree) {
        Some(format!(
            "ply {} is a free drape: auto chooses between the kinematic net on the tool and the pressed drape, and a sheet hanging under gravity has no kinematic counterpart, so only mechanics applies",
            plan.ply
        ))
    } else {
        Some(format!(
            "ply {} has no material card: auto weighs the kinematic net under the card's mechanical model (give the ply material = ...)",
            plan.ply
        ))
    }
}

/// Each `auto` run against the pressed mechanical run at the same spacing and tool.
fn auto_costs(records: &[CaseRecord], points: &[SpeedPoint]) -> Vec<AutoCost> {
    let mechanical = |r: &CaseRecord| {
        records.iter().zip(points).find(|(m, _)| {
            let (a, b) = (&m.case.variant, &r.case.variant);
            a.method == StudyMethod::MechanicalPressed
                && a.friction.is_none()
                && a.spacing == b.spacing
                && a.tool == b.tool
        })
    };
    records
        .iter()
        .zip(points)
        .filter_map(|(r, p)| {
            let c = r.result.choice.as_ref()?;
            let mech_time = mechanical(r).map(|(m, _)| m.result.time_s).filter(|t| *t > 0.0);
            Some(AutoCost {
                spacing: p.spacing,
                tool: r.case.variant.tool.clone(),
                tolerance_deg: c.tolerance_deg,
                chosen: c.chosen.clone(),
                reason: c.reason.clone(),
                error_max_deg: p.error_max_deg,
                within_tolerance: p.error_max_deg.map(|e| e <= c.tolerance_deg),
                assured: c.assured,
                ran_spacing: Some(c.spacing_m),
                time_s: p.time_s,
                mechanical_time_s: mech_time,
                cost_ratio: mech_time.map(|m| p.time_s / m),
                mechanical_within_tolerance_s: points
                    .iter()
                    .filter(|m| {
                        m.method == StudyMethod::MechanicalPressed.name() && m.friction.is_none() && m.outcome == "ok"
                    })
                    .filter(|m| m.error_max_deg.is_some_and(|e| e <= c.tolerance_deg) && m.time_s > 0.0)
                    .map(|m| m.time_s)
                    .reduce(f64::min),
            })
        })
        .collect()
}

/// Mark the runs no other successful run beats on both time and error.
fn mark_pareto(points: &mut [SpeedPoint]) {
    let scored: Vec<(usize, f64, f64)> =
        points.iter().enumerate().filter_map(|(k, p)| Some((k, p.time_s, p.error_max_deg?))).collect();
    for &(k, t, e) in &scored {
        let beaten = scored.iter().any(|&(j, t2, e2)| j != k && t2 <= t && e2 <= e && (t2 < t || e2 < e));
        points[k].pareto = !beaten;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reference_of_kind(kind: ReferenceKind, extrapolated: bool) -> Reference {
        Reference {
            kind,
            method: "mechanical-pressed".into(),
            surface: "facets".into(),
            tool: PathBuf::from("/t/tool.obj"),
            tool_triangles: 100,
            spacing: 0.002,
            convergence: Convergence { extrapolated, ..Convergence::default() },
            tool_difference: None,
            why: String::new(),
            symmetries: Vec::new(),
        }
    }

    #[test]
    fn auto_s_verdict_is_weighed_against_the_reference() {
        let reference = reference_of_kind(ReferenceKind::Mechanical, false);
        let cost = |assured, within| AutoCost {
            spacing: 0.004,
            tool: PathBuf::from("/t/tool.obj"),
            tolerance_deg: 1.0,
            chosen: "mechanical".into(),
            reason: String::new(),
            error_max_deg: Some(if within { 0.5 } else { 2.0 }),
            within_tolerance: Some(within),
            assured,
            ran_spacing: Some(0.004),
            time_s: 1.0,
            mechanical_time_s: None,
            cost_ratio: None,
            mechanical_within_tolerance_s: None,
        };
        assert_eq!(cost(Some(true), true).verdict(&reference), Some("auto assured it, rightly"));
        assert_eq!(cost(Some(false), false).verdict(&reference), Some("auto said NOT ASSURED, rightly"));
        assert!(cost(Some(true), false).verdict(&reference).unwrap().starts_with("FALSE ASSURANCE"));
        assert!(cost(Some(false), true).verdict(&reference).unwrap().contains("cautious"));
        // A record from before auto gave its verdict has none to weigh.
        assert_eq!(cost(None, true).verdict(&reference), None);
        // Auto's drape pressed again at the reference's spacing is the reference: no judge.
        let at_reference = AutoCost { ran_spacing: Some(0.002), ..cost(Some(false), true) };
        assert!(at_reference.verdict(&reference).unwrap().contains("nothing finer to judge"));
        // An extrapolated reference (a limit) judges every spacing, and so does one on a finer tool.
        let limit = reference_of_kind(ReferenceKind::Mechanical, true);
        assert!(at_reference.verdict(&limit).unwrap().contains("cautious"));
        let finer_tool = Reference { tool: PathBuf::from("/t/fine.obj"), ..reference.clone() };
        assert!(at_reference.verdict(&finer_tool).unwrap().contains("cautious"));
        // A kinematic net at the reference's spacing is judged by the pressed drape there.
        let kinematic = AutoCost { chosen: "kinematic".into(), ..at_reference.clone() };
        assert!(kinematic.verdict(&reference).unwrap().contains("cautious"));
        let json = serde_json::to_value(cost(None, true)).unwrap();
        assert!(json.get("assured").is_none(), "{json}");
    }

    /// A field over 2 m x 2 m of fabric from its centre at spacing `d`: `exact(u, v) + c d^p` at
    /// the cell centres. A linear `exact` is interpolated exactly, so a limit is exact too.
    fn field(d: f64, c: f64, p: f64) -> ShearField {
        let n = (2.0 / d).round() as usize;
        let origin_node = (n / 2, n / 2);
        let mut f = ShearField { spacing: d, cu: n, cv: n, origin_node, shear_deg: vec![None; n * n] };
        for i in 0..n {
            for j in 0..n {
                let (u, v) = f.cell_centre(i, j);
                f.shear_deg[i * n + j] = Some(1.0 + 0.5 * u - 0.3 * v + c * d.powf(p));
            }
        }
        f
    }

    fn largest_error(f: &ShearField) -> f64 {
        f.complete_cell_centres()
            .iter()
            .map(|&(u, v)| (f.at(u, v).unwrap() - (1.0 + 0.5 * u - 0.3 * v)).abs())
            .fold(0.0, f64::max)
    }

    /// A record of `method` on `surface` of `tool` at `d` with `field`, converged or not.
    fn record(
        index: usize,
        method: StudyMethod,
        surface: SurfaceKind,
        tool: &str,
        d: f64,
        field: ShearField,
        converged: Option<bool>,
    ) -> CaseRecord {
        let variant = Variant { surface, ..Variant::baseline(method, PathBuf::from(tool), d) };
        let case = Case { index, variant, params: BTreeMap::new(), repeats: 1, keep_field: true };
        let mut result = super::super::case::CaseResult::refused("ok".into(), 10);
        result.time_s = 1.0;
        result.converged = converged;
        result.field = Some(field);
        CaseRecord { case, result }
    }

    #[test]
    fn the_reference_is_the_most_complete_model_that_gave_a_usable_run() {
        let (pressed, geodesic) = (StudyMethod::MechanicalPressed, StudyMethod::KinematicGeodesic);
        let models = vec![
            ReferenceModel { method: pressed, surface: SurfaceKind::Facets, why: "pressed".into() },
            ReferenceModel { method: geodesic, surface: SurfaceKind::Smooth, why: "kinematic".into() },
        ];
        let plan = |records: &[CaseRecord]| Plan {
            kind: StudyKind::SpeedAccuracy,
            scene: PathBuf::from("/s.toml"),
            ply: "p".into(),
            axes: None,
            symmetries: Vec::new(),
            reference: Some(ReferencePlan {
                tool: PathBuf::from("/fine.obj"),
                tool_triangles: 10,
                models: models.clone(),
            }),
            search: None,
            cases: records.iter().map(|r| r.case.clone()).collect(),
        };
        let smooth = |k, d| record(k, geodesic, SurfaceKind::Smooth, "/fine.obj", d, field(d, 3.0, 2.0), None);
        // The pressed drape did not converge on the finest tool: the kinematic net is the
        // reference, extrapolated at its formal order, and the reason says why.
        let records = vec![
            record(0, pressed, SurfaceKind::Facets, "/fine.obj", 0.25, field(0.25, 1.0, 2.0), Some(false)),
            smooth(1, 0.5),
            smooth(2, 0.25),
            record(3, geodesic, SurfaceKind::Facets, "/coarse.obj", 0.25, field(0.25, 9.0, 2.0), None),
        ];
        let sa = evaluate(&plan(&records), &records);
        assert_eq!(sa.reference.kind, ReferenceKind::Kinematic);
        assert_eq!(sa.reference.why, "mechanical-pressed gave no usable run on this tool; kinematic");
        assert!(sa.reference.convergence.extrapolated && !sa.reference.convergence.order_measured);
        // Errors against the exact limit: 3 d^2 for the smooth runs, 9 d^2 on the coarse tool;
        // the unconverged pressed drape is measured too (1 d^2).
        let errors: Vec<f64> = sa.points.iter().map(|p| p.error_max_deg.unwrap()).collect();
        for (e, want) in errors.iter().zip([0.0625, 0.75, 0.1875, 0.5625]) {
            assert!((e - want).abs() < 1e-12, "{errors:?}");
        }
        // Its own convergence beside it: the smooth runs' own limit is the reference's.
        assert!((sa.points[1].own_error_max_deg.unwrap() - 0.75).abs() < 1e-12);
        // With the pressed drape converged it is the reference, taken as drawn (one spacing).
        let mut converged = records.clone();
        converged[0].result.converged = Some(true);
        let sa = evaluate(&plan(&converged), &converged);
        assert_eq!((sa.reference.kind, sa.reference.why.as_str()), (ReferenceKind::Mechanical, "pressed"));
        assert_eq!(sa.points[0].error_max_deg, Some(0.0));
        // Nothing usable on the finest tool: no reference, and why.
        let coarse_only = vec![records[3].clone()];
        let sa = evaluate(&plan(&coarse_only), &coarse_only);
        assert_eq!(sa.reference.kind, ReferenceKind::None);
        assert!(sa
            .reference
            .describe()
            .contains("none of mechanical-pressed, kinematic-geodesic gave a usable run on fine.obj"));
        assert_eq!(sa.points[0].error_max_deg, None);
    }

    #[test]
    fn limits_extrapolate_where_the_order_allows_and_say_why_not_elsewhere() {
        let ds = [0.5, 0.25, 0.125];
        // Second order, three spacings: the order is observed (2) and the limit is exact.
        let f2: Vec<ShearField> = ds.iter().map(|&d| field(d, 3.0, 2.0)).collect();
        let runs: Vec<(f64, &ShearField)> = ds.iter().copied().zip(&f2).collect();
        let (lim, c) = limit(&runs, None).unwrap();
        assert!(c.extrapolated && c.order_measured, "{c:?}");
        assert!((c.order.unwrap() - 2.0).abs() < 1e-9, "{c:?}");
        assert!(largest_error(&lim) < 1e-12);
        // The correction is the finest run's own error: 3 d^2.
        assert!((c.uncertainty_max_deg.unwrap() - 3.0 * 0.125f64.powi(2)).abs() < 1e-12, "{c:?}");
        // First order: observed 1 and trusted; still exact.
        let f1: Vec<ShearField> = ds.iter().map(|&d| field(d, 3.0, 1.0)).collect();
        let runs: Vec<(f64, &ShearField)> = ds.iter().copied().zip(&f1).collect();
        let (lim, c) = limit(&runs, None).unwrap();
        assert!((c.order.unwrap() - 1.0).abs() < 1e-9 && largest_error(&lim) < 1e-12, "{c:?}");
        // Order 3: capped at the formal 2, so the limit keeps part of the error (never more).
        let f3: Vec<ShearField> = ds.iter().map(|&d| field(d, 3.0, 3.0)).collect();
        let runs: Vec<(f64, &ShearField)> = ds.iter().copied().zip(&f3).collect();
        let (lim, c) = limit(&runs, None).unwrap();
        assert_eq!(c.order, Some(2.0));
        assert!((c.observed_order.unwrap() - 3.0).abs() < 1e-9, "{c:?}");
        // Then the finest run's distance from the limit overstates its true error, never less.
        let (reported, _, _) = compare_at(&lim, &f3[2]);
        assert!(reported.unwrap() >= 3.0 * 0.125f64.powi(3), "{reported:?}");
        // Order 1/2: below the least trusted, so the finest is taken as drawn, with its
        // order-1 estimate as its uncertainty, and the note says why.
        let fh: Vec<ShearField> = ds.iter().map(|&d| field(d, 3.0, 0.5)).collect();
        let runs: Vec<(f64, &ShearField)> = ds.iter().copied().zip(&fh).collect();
        let (lim, c) = limit(&runs, Some(2.0)).unwrap();
        assert!(!c.extrapolated && c.order.is_none(), "{c:?}");
        assert_eq!(lim, fh[2]);
        assert!(c.note.contains("below the least trusted"), "{}", c.note);
        let step = 3.0 * (0.25f64.sqrt() - 0.125f64.sqrt());
        assert!((c.uncertainty_max_deg.unwrap() - step).abs() < 1e-12, "{c:?}");
        // Two spacings: the formal order where the model has one, else as drawn.
        let runs: Vec<(f64, &ShearField)> = ds[1..].iter().copied().zip(&f2[1..]).collect();
        let (lim, c) = limit(&runs, Some(2.0)).unwrap();
        assert!(c.extrapolated && !c.order_measured && largest_error(&lim) < 1e-12, "{c:?}");
        let (lim, c) = limit(&runs, None).unwrap();
        assert!(!c.extrapolated && c.note.contains("no formal order"), "{c:?}");
        assert_eq!(lim, f2[2]);
        // One spacing: as drawn, its error unknown; none: no limit.
        let (_, c) = limit(&runs[1..], Some(2.0)).unwrap();
        assert!(!c.extrapolated && c.uncertainty_max_deg.is_none(), "{c:?}");
        assert!(limit(&[], Some(2.0)).is_none());
    }
}
