//! `drape study speed-accuracy`: every method that applies to a ply, at a range of spacings (and
//! tool resolutions), timed and compared with the best reference the study has, at the same
//! fabric coordinates.
//!
//! The reference is the finest converged mechanical result where mechanics applies; otherwise
//! each method's own Richardson-extrapolated limit: with the shear `s_m` of the second-finest
//! spacing and `s_f` of the finest (ratio r, observed order p from three spacings, else 2),
//! `s* = s_f + (s_f - s_m) / (r^p - 1)`. Errors are measured at the complete cell centres of the
//! reference's own grid (the second-finest for an extrapolated one): the finer net's value there
//! is its average of the cells around it, a coarser net's is interpolated from its cell centres,
//! as a user of that net would.
use super::plan::{absolute, find_ply, study_tools, Case, Plan, StudyKind, StudyMethod, Variant};
use super::runner::CaseRecord;
use super::{symmetry, StudyError};
use crate::io::read_tool;
use crate::kinematic::fabric_field::{FabricImage, ShearField};
use crate::kinematic::{GeneratorKind, SurfaceKind};
use crate::layup::auto::{FISHNET_ORDER, MIN_TRUSTED_ORDER};
use crate::layup::Ply;
use crate::mechanics::ContactMode;
use crate::pipeline::Scene;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::PathBuf;

/// The study's result file.
pub const FILE: &str = "speed_accuracy.json";
/// Spacings of the kinematic methods when none are given, as multiples of the ply's spacing.
pub const KINEMATIC_SPACING_FACTORS: [f64; 4] = [2.0, 1.0, 0.5, 0.25];
/// Spacings of the mechanical methods when none are given, as multiples of the ply's spacing.
pub const MECHANICAL_SPACING_FACTORS: [f64; 2] = [2.0, 1.0];
/// Bounds on the observed order of convergence used to extrapolate. The fishnet and the
/// mechanical net are second order in d; an observed order above 2 comes from a coarse spacing
/// outside the asymptotic range, and extrapolating with it would understate the error (on the
/// Chebyshev sphere by a factor 4), so it is capped at the formal order. The same bounds as
/// `method = "auto"` trusts (one place for them: [`MIN_TRUSTED_ORDER`], [`FISHNET_ORDER`]).
pub const ORDER_RANGE: (f64, f64) = (MIN_TRUSTED_ORDER, FISHNET_ORDER);
/// The order assumed when only two spacings converge or the differences vanish: the formal one.
pub const DEFAULT_ORDER: f64 = FISHNET_ORDER;
/// Differences (rms, degrees) below this are rounding, not convergence: the order is not
/// measured from them.
const ORDER_NOISE_DEG: f64 = 1e-9;

/// What the speed-accuracy study runs.
#[derive(Debug, Clone, Default)]
pub struct Options {
    /// The ply (default: the scene's first).
    pub ply: Option<String>,
    /// Spacings of the kinematic methods, m (default: [`KINEMATIC_SPACING_FACTORS`]).
    pub spacings: Option<Vec<f64>>,
    /// Spacings of the mechanical methods, m (default: [`MECHANICAL_SPACING_FACTORS`]).
    pub mechanical_spacings: Option<Vec<f64>>,
    /// Further resolutions of the tool (files), run with every kinematic method.
    pub tools: Vec<PathBuf>,
    /// Repeats of each kinematic case (the median time is reported); mechanical cases run once.
    pub repeats: usize,
}

/// The methods that apply to `ply`.
pub fn methods_for(ply: &Ply) -> Vec<StudyMethod> {
    if ply.refinement.as_ref().is_some_and(|r| r.mode == ContactMode::Free) {
        return vec![StudyMethod::MechanicalFree];
    }
    let mut m = vec![StudyMethod::KinematicGeodesic, StudyMethod::KinematicMinShear];
    if matches!(ply.settings.generators, GeneratorKind::Steer(_)) {
        m.push(StudyMethod::KinematicSteered);
    }
    if ply.material.is_some() || ply.refinement.is_some() {
        m.push(StudyMethod::MechanicalPressed);
        m.push(StudyMethod::Auto);
    }
    m
}

/// The cases of the study of `scene`.
pub fn plan(scene: &Scene, opts: &Options) -> Result<Plan, StudyError> {
    let ply = find_ply(scene, opts.ply.as_deref())?;
    let d0 = ply.settings.spacing;
    let spacings = |given: &Option<Vec<f64>>, factors: &[f64]| -> Result<Vec<f64>, StudyError> {
        let s: Vec<f64> = match given {
            Some(s) => s.clone(),
            None => factors.iter().map(|f| f * d0).collect(),
        };
        if s.is_empty() || s.iter().any(|d| !(d.is_finite() && *d > 0.0)) {
            return Err(StudyError::Input(format!("spacings must be positive lengths, got {s:?}")));
        }
        Ok(s)
    };
    let kin = spacings(&opts.spacings, &KINEMATIC_SPACING_FACTORS)?;
    let mech = spacings(&opts.mechanical_spacings, &MECHANICAL_SPACING_FACTORS)?;
    let tools = study_tools(scene, &opts.tools)?;
    let methods = methods_for(ply);
    // Only a mechanical reference can break the scene's symmetries (a kinematic net is a
    // function of the ply, so as symmetric as its problem): look for them only then.
    let symmetries = if methods.iter().any(|m| m.is_mechanical()) {
        let tool = read_tool(&tools[0], scene.scale).map_err(|e| StudyError::Input(e.to_string()))?;
        symmetry::symmetries(ply, &scene.layup, &tool)
    } else {
        Vec::new()
    };
    let mut cases = Vec::new();
    for method in methods {
        let (ds, ts, repeats) =
            if method.may_run_mechanics() { (&mech, &tools[..1], 1) } else { (&kin, &tools[..], opts.repeats.max(1)) };
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
    Ok(Plan {
        kind: StudyKind::SpeedAccuracy,
        scene: absolute(&scene.path)?,
        ply: ply.settings.name.clone(),
        axes: None,
        symmetries,
        cases,
    })
}

/// The reference the errors are measured against.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Reference {
    /// The method of the reference (`own` when each method is measured against its own limit).
    pub method: String,
    /// Its spacing (the finest spacing extrapolated from), m.
    pub spacing: f64,
    /// `mechanical` or `extrapolated`.
    pub kind: String,
    /// The symmetries of the ply's drape problem, the identity left out: a mechanical reference
    /// that broke one is as good as its image, and each run is measured against the nearer.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub symmetries: Vec<FabricImage>,
}

/// One method's own extrapolated limit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OwnLimit {
    /// The method.
    pub method: String,
    /// Its surface.
    pub surface: String,
    /// Triangles of its tool.
    pub tool_triangles: usize,
    /// The spacings extrapolated from (the two finest that gave a result), m.
    pub spacings: [f64; 2],
    /// The order of convergence used.
    pub order: f64,
    /// Whether the order was measured from three spacings (else [`DEFAULT_ORDER`]).
    pub order_measured: bool,
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
    /// Median time of the repeats, s.
    pub time_s: f64,
    /// Repeats timed.
    pub repeats: usize,
    /// Largest |shear - reference| over the compared points, degrees (absent without any).
    pub error_max_deg: Option<f64>,
    /// Root mean square of the same, degrees.
    pub error_rms_deg: Option<f64>,
    /// Points compared.
    pub compared: usize,
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

/// What `method = "auto"` saved at one spacing: its result against the reference and its cost
/// against always running mechanics there.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AutoCost {
    /// Fibre spacing d asked for, m.
    pub spacing: f64,
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
    /// auto ran mechanics, a mechanical reference no finer than auto's drape cannot judge it
    /// (auto's drape pressed again at the reference's spacing is the reference itself, or the
    /// same model at the same spacing from another start); a kinematic result it can. None where
    /// either is missing.
    pub fn verdict(&self, reference: &Reference) -> Option<&'static str> {
        let (assured, within) = (self.assured?, self.within_tolerance?);
        let unjudged = reference.kind == "mechanical"
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

/// Spacings this close (relative) are the same spacing.
const SAME_SPACING_REL: f64 = 1e-9;

/// `speed_accuracy.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SpeedAccuracy {
    /// The ply.
    pub ply: String,
    /// What the errors are measured against.
    pub reference: Reference,
    /// For an extrapolated reference: each method's own limit.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub limits: Vec<OwnLimit>,
    /// Every run.
    pub points: Vec<SpeedPoint>,
    /// The `auto` runs: error kept and cost saved against mechanics.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub auto: Vec<AutoCost>,
    /// Why `auto` was not run, when it was not (a free drape, a ply without a material card).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub auto_not_run: Option<String>,
}

/// Cell centres of `f` and the values of the other fields there, where all have one.
fn common(points: &[(f64, f64)], fields: &[&ShearField]) -> Vec<Vec<f64>> {
    points.iter().filter_map(|&(u, v)| fields.iter().map(|f| f.at(u, v)).collect::<Option<Vec<f64>>>()).collect()
}

fn rms(x: impl Iterator<Item = f64>) -> f64 {
    let (s, n) = x.fold((0.0, 0usize), |(s, n), e| (s + e * e, n + 1));
    if n == 0 {
        0.0
    } else {
        (s / n as f64).sqrt()
    }
}

/// A reference field: values at the complete cell centres of `grid`.
struct RefField {
    grid: ShearField,
}

impl RefField {
    /// Max and rms of |field - reference| at the reference's points, and how many.
    fn compare(&self, field: &ShearField) -> (Option<f64>, Option<f64>, usize) {
        let pts = self.grid.complete_cell_centres();
        let errs: Vec<f64> =
            pts.iter().filter_map(|&(u, v)| Some((field.at(u, v)? - self.grid.at(u, v)?).abs())).collect();
        if errs.is_empty() {
            return (None, None, 0);
        }
        (errs.iter().copied().reduce(f64::max), Some(rms(errs.iter().copied())), errs.len())
    }
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
    images: Vec<(FabricImage, RefField)>,
}

impl ReferenceImages {
    /// `reference` as it fell and its images under `symmetries` (the identity left out).
    pub fn new(reference: &ShearField, symmetries: &[FabricImage]) -> ReferenceImages {
        let images = std::iter::once(FabricImage::AsIs)
            .chain(symmetries.iter().copied().filter(|&s| s != FabricImage::AsIs))
            .map(|s| (s, RefField { grid: reference.image(s) }))
            .collect();
        ReferenceImages { images }
    }

    /// `field` against each image: the one with the least largest error over the whole field
    /// (the reference as it fell on a tie, [`IMAGE_TIE_DEG`]).
    pub fn compare(&self, field: &ShearField) -> Comparison {
        let mut best = Comparison { image: FabricImage::AsIs, error_max_deg: None, error_rms_deg: None, compared: 0 };
        for (image, reference) in &self.images {
            let (error_max_deg, error_rms_deg, compared) = reference.compare(field);
            let Some(e) = error_max_deg else { continue };
            if best.error_max_deg.is_none_or(|b| e < b - IMAGE_TIE_DEG) {
                best = Comparison { image: *image, error_max_deg, error_rms_deg, compared };
            }
        }
        best
    }
}

/// The Richardson limit of one method's runs, finest last: `None` with fewer than two fields.
fn extrapolate(runs: &[(f64, &ShearField)]) -> Option<(RefField, [f64; 2], f64, bool)> {
    let n = runs.len();
    if n < 2 {
        return None;
    }
    let (dm, fm) = runs[n - 2];
    let (df, ff) = runs[n - 1];
    let r = dm / df;
    let pts = fm.complete_cell_centres();
    // Observed order from three spacings, measured at the medium grid's points.
    let mut order = (DEFAULT_ORDER, false);
    if n >= 3 {
        let (dc, fc) = runs[n - 3];
        let vals = common(&pts, &[fc, fm, ff]);
        let (e1, e2) = (rms(vals.iter().map(|v| v[0] - v[1])), rms(vals.iter().map(|v| v[1] - v[2])));
        if e1 > ORDER_NOISE_DEG && e2 > ORDER_NOISE_DEG {
            // A difference that does not fall with the spacing has no order: the least trusted.
            let p = crate::numeric::observed_order(e1, e2, dc / dm, dm / df).unwrap_or(ORDER_RANGE.0);
            order = (p.clamp(ORDER_RANGE.0, ORDER_RANGE.1), true);
        }
    }
    let factor = 1.0 / (r.powf(order.0) - 1.0);
    let mut grid = fm.clone();
    for (k, s) in grid.shear_deg.iter_mut().enumerate() {
        let (i, j) = (k / fm.cv, k % fm.cv);
        let (u, v) = fm.cell_centre(i, j);
        *s = match (*s, ff.at(u, v)) {
            (Some(sm), Some(sf)) => Some(sf + (sf - sm) * factor),
            _ => None,
        };
    }
    Some((RefField { grid }, [dm, df], order.0, order.1))
}

/// The study's result from every case's record.
pub fn evaluate(plan: &Plan, records: &[CaseRecord]) -> SpeedAccuracy {
    // A net with failed nodes is compared where it has cells; its outcome says what failed.
    fn field(r: &CaseRecord) -> Option<&ShearField> {
        r.result.field.as_ref()
    }
    // The finest converged mechanical run on the scene's own tool.
    let scene_tool = plan.cases.first().map(|c| c.variant.tool.clone());
    let mech = records
        .iter()
        .filter(|r| r.case.variant.method.is_mechanical() && Some(&r.case.variant.tool) == scene_tool.as_ref())
        .filter(|r| r.result.converged == Some(true) && field(r).is_some())
        .min_by(|a, b| a.case.variant.spacing.total_cmp(&b.case.variant.spacing));
    let mut limits = Vec::new();
    let mut points: Vec<SpeedPoint> = records
        .iter()
        .map(|r| SpeedPoint {
            method: r.case.variant.method.name().into(),
            spacing: r.case.variant.spacing,
            surface: r.case.variant.surface.name().into(),
            tool_triangles: r.result.tool_triangles,
            time_s: r.result.time_s,
            repeats: r.result.times_s.len(),
            error_max_deg: None,
            error_rms_deg: None,
            compared: 0,
            outcome: r.result.outcome.clone(),
            pareto: false,
            chosen: r.result.choice.as_ref().map(|c| c.chosen.clone()),
            reference_image: None,
        })
        .collect();
    let reference = if let Some(m) = mech {
        let grid = field(m).unwrap_or_else(|| unreachable!("filtered on a field"));
        let reference = ReferenceImages::new(grid, &plan.symmetries);
        for (p, r) in points.iter_mut().zip(records) {
            if let Some(f) = field(r) {
                let c = reference.compare(f);
                (p.error_max_deg, p.error_rms_deg, p.compared) = (c.error_max_deg, c.error_rms_deg, c.compared);
                p.reference_image = (!plan.symmetries.is_empty()).then_some(c.image);
            }
        }
        Reference {
            method: m.case.variant.method.name().into(),
            spacing: m.case.variant.spacing,
            kind: "mechanical".into(),
            symmetries: plan.symmetries.clone(),
        }
    } else {
        // Each method (on each surface and tool) against its own limit.
        let mut groups: BTreeMap<(StudyMethod, &str, PathBuf), Vec<usize>> = BTreeMap::new();
        for (k, r) in records.iter().enumerate() {
            let v = &r.case.variant;
            groups.entry((v.method, v.surface.name(), v.tool.clone())).or_default().push(k);
        }
        let mut finest = f64::INFINITY;
        for ((method, surface, _), ks) in &groups {
            let mut runs: Vec<(f64, &ShearField)> =
                ks.iter().filter_map(|&k| Some((records[k].case.variant.spacing, field(&records[k])?))).collect();
            runs.sort_by(|a, b| b.0.total_cmp(&a.0));
            let Some((reference, spacings, order, measured)) = extrapolate(&runs) else { continue };
            finest = finest.min(spacings[1]);
            limits.push(OwnLimit {
                method: method.name().into(),
                surface: surface.to_string(),
                tool_triangles: records[ks[0]].result.tool_triangles,
                spacings,
                order,
                order_measured: measured,
            });
            for &k in ks {
                if let Some(f) = field(&records[k]) {
                    let p = &mut points[k];
                    (p.error_max_deg, p.error_rms_deg, p.compared) = reference.compare(f);
                }
            }
        }
        Reference {
            method: "own".into(),
            spacing: if finest.is_finite() { finest } else { 0.0 },
            kind: "extrapolated".into(),
            symmetries: Vec::new(),
        }
    };
    mark_pareto(&mut points);
    let auto = auto_costs(records, &points);
    let auto_not_run = auto_not_run(plan);
    SpeedAccuracy { ply: plan.ply.clone(), reference, limits, points, auto, auto_not_run }
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
            a.method == StudyMethod::MechanicalPressed && a.spacing == b.spacing && a.tool == b.tool
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
                    .filter(|m| m.method == StudyMethod::MechanicalPressed.name() && m.outcome == "ok")
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

    #[test]
    fn auto_s_verdict_is_weighed_against_the_reference() {
        let reference = Reference {
            method: "mechanical-pressed".into(),
            spacing: 0.002,
            kind: "mechanical".into(),
            symmetries: Vec::new(),
        };
        let cost = |assured, within| AutoCost {
            spacing: 0.004,
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
        // An extrapolated reference (a limit) judges every spacing.
        let limit = Reference { kind: "extrapolated".into(), ..reference.clone() };
        assert!(at_reference.verdict(&limit).unwrap().contains("cautious"));
        // A kinematic net at the reference's spacing is judged by the pressed drape there.
        let kinematic = AutoCost { chosen: "kinematic".into(), ..at_reference.clone() };
        assert!(kinematic.verdict(&reference).unwrap().contains("cautious"));
        let json = serde_json::to_value(cost(None, true)).unwrap();
        assert!(json.get("assured").is_none(), "{json}");
    }
}
