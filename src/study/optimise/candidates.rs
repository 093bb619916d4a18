//! The global search's candidates: every seed of the region's lattice (on the tool) at every
//! angle of the range, as the cases of a study plan, each a drape of the ply at the search's
//! spacing.
use super::region::{Frame, Region, SeedRegion};
use super::{AngleRange, Objective, Search, DEFAULT_MAX_CANDIDATES, DEFAULT_REFINE_STARTS};
use crate::geometry::ToolSurface;
use crate::kinematic::GeneratorKind;
use crate::layup::{Ply, Start};
use crate::pipeline::Scene;
use crate::study::plan::{absolute, find_ply, Case, Plan, StudyKind, StudyMethod, Variant};
use crate::study::StudyError;
use std::collections::BTreeMap;

/// Seeds across the seed region's diameter (or the polygon's larger side) when no step is given.
const DEFAULT_SEEDS_ACROSS: f64 = 8.0;
/// The search's spacing when none is given: the ply's times this.
const DEFAULT_SEARCH_COARSENING: f64 = 2.0;

/// What the user asks of an optimisation (SI units).
#[derive(Debug, Clone)]
pub struct Options {
    /// The ply (default: the scene's first).
    pub ply: Option<String>,
    /// What is minimised.
    pub objective: Objective,
    /// Whether the seed is varied (over `region`).
    pub vary_seed: bool,
    /// Whether the angle is varied (over `angles`).
    pub vary_angle: bool,
    /// Where the seed may lie.
    pub region: Option<SeedRegion>,
    /// The seed lattice's step, m (default: an eighth of the region's size).
    pub seed_step: Option<f64>,
    /// The angles, degrees (default -45 to 45: a balanced fabric at a + 90 is the same ply).
    pub angles: AngleRange,
    /// The global search's spacing, m (default: twice the ply's).
    pub spacing: Option<f64>,
    /// Candidates refined locally.
    pub refine_starts: usize,
    /// The most candidates allowed.
    pub max_candidates: usize,
}

impl Options {
    /// Defaults for `objective`, varying seed and angle over `region`.
    pub fn new(objective: Objective, region: Option<SeedRegion>) -> Options {
        Options {
            ply: None,
            objective,
            vary_seed: true,
            vary_angle: true,
            region,
            seed_step: None,
            angles: AngleRange { lo: -45.0, hi: 45.0, step: 5.0 },
            spacing: None,
            refine_starts: DEFAULT_REFINE_STARTS,
            max_candidates: DEFAULT_MAX_CANDIDATES,
        }
    }
}

fn bad(message: String) -> StudyError {
    StudyError::Input(message)
}

/// The method that drapes the ply kinematically with its own generators.
pub fn method_of(ply: &Ply) -> StudyMethod {
    match ply.settings.generators {
        GeneratorKind::Geodesic => StudyMethod::KinematicGeodesic,
        GeneratorKind::MinShear => StudyMethod::KinematicMinShear,
        GeneratorKind::Steer(_) => StudyMethod::KinematicSteered,
    }
}

/// The region of a plan's search on `tool` (its polygon checked against the tool).
pub fn region_of(search: &Search, tool: &ToolSurface) -> Result<Option<Region>, String> {
    search
        .region
        .clone()
        .map(|r| Region::new(r, search.frame, tool, search.seed_step.max(search.ply_spacing)))
        .transpose()
}

/// The optimisation of `opts.ply` of `scene` on `tool` (the scene's tool) as a study plan.
pub fn plan(scene: &Scene, opts: &Options, tool: &ToolSurface) -> Result<Plan, StudyError> {
    let ply = find_ply(scene, opts.ply.as_deref())?;
    let name = &ply.settings.name;
    if !opts.vary_seed && !opts.vary_angle {
        return Err(bad("--vary: give seed, angle or seed,angle".into()));
    }
    if ply.refinement.as_ref().is_some_and(|r| matches!(r.start, Start::Flat { .. })) {
        return Err(bad(format!(
            "ply '{name}' starts as a flat sheet (start = \"flat\"): it has no seed or angle to optimise; choose a ply draped from a seed"
        )));
    }
    if opts.vary_angle && matches!(ply.settings.generators, GeneratorKind::Steer(_)) {
        return Err(bad(format!(
            "ply '{name}' is steered along a curve, which sets its warp: vary only the seed (--vary seed)"
        )));
    }
    let region = match (opts.vary_seed, &opts.region) {
        (true, None) => return Err(bad(
            "--vary seed needs a seed region: give --seed-radius R (around the ply's origin) or --seed-polygon FILE"
                .into(),
        )),
        (false, Some(_)) => {
            return Err(bad("a seed region is given but --vary does not name seed: add it, or drop the region".into()))
        }
        (true, Some(r)) => Some(r.clone()),
        (false, None) => None,
    };
    let a = opts.angles;
    if opts.vary_angle && !(a.lo.is_finite() && a.hi.is_finite() && a.lo <= a.hi) {
        return Err(bad(format!("--angle-range: give LO,HI with LO <= HI in degrees, got {},{}", a.lo, a.hi)));
    }
    if opts.vary_angle && !(a.step.is_finite() && a.step > 0.0) {
        return Err(bad(format!("--angle-step must be a positive angle in degrees, got {}", a.step)));
    }
    let d0 = ply.settings.spacing;
    let spacing = opts.spacing.unwrap_or(DEFAULT_SEARCH_COARSENING * d0);
    if !(spacing.is_finite() && spacing > 0.0) {
        return Err(bad(format!("--spacing must be a positive length, got {spacing}")));
    }
    if opts.refine_starts == 0 {
        return Err(bad("--refine: give at least 1 candidate to refine".into()));
    }
    let frame = Frame::at(tool, &ply.settings.origin, &scene.layup.reference);
    let seed_step = match (opts.seed_step, &region) {
        (Some(s), _) => s,
        (None, Some(SeedRegion::Disc { radius })) => 2.0 * radius / DEFAULT_SEEDS_ACROSS,
        (None, Some(SeedRegion::Polygon { points })) => {
            let ab: Vec<[f64; 2]> = points.iter().map(|p| frame.coordinates(&(*p).into())).collect();
            let side = |k: usize| {
                let (lo, hi) =
                    ab.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| (l.min(p[k]), h.max(p[k])));
                hi - lo
            };
            side(0).max(side(1)) / DEFAULT_SEEDS_ACROSS
        }
        (None, None) => 0.0,
    };
    let search = Search {
        objective: opts.objective.clone(),
        frame,
        region,
        seed_step,
        angles: opts.vary_angle.then_some(a),
        ply_spacing: d0,
        refine_starts: opts.refine_starts,
    };
    let seeds = match super::candidates::region_of(&search, tool).map_err(bad)? {
        Some(r) => r.lattice(tool, seed_step).map_err(bad)?,
        None => vec![super::region::Seed { ab: [0.0, 0.0], point: frame.point([0.0, 0.0]) }],
    };
    if seeds.is_empty() {
        return Err(bad(format!(
            "the seed region holds no seed at a step of {seed_step} m: give a larger region or a finer --seed-step"
        )));
    }
    let angles: Vec<Option<f64>> = match search.angles {
        Some(r) => r.values().into_iter().map(Some).collect(),
        None => vec![None],
    };
    let count = seeds.len().saturating_mul(angles.len());
    if count > opts.max_candidates {
        return Err(bad(format!(
            "the search has {count} candidates ({} seeds x {} angles), more than the limit of {}: give a coarser --seed-step or --angle-step or a smaller region, or raise the limit with --max-candidates {count}",
            seeds.len(),
            angles.len(),
            opts.max_candidates
        )));
    }
    let tool_path = absolute(&scene.tool)?;
    let method = method_of(ply);
    let mut cases = Vec::with_capacity(count);
    for seed in &seeds {
        for angle in &angles {
            let mut v = Variant::baseline(method, tool_path.clone(), spacing);
            v.surface = ply.settings.surface;
            // The ply's own seed stays as the scene gives it when the seed is not varied.
            v.origin = search.region.is_some().then(|| seed.point.coords.into());
            v.angle_deg = *angle;
            let mut params = BTreeMap::from([("seed_a".to_string(), seed.ab[0]), ("seed_b".to_string(), seed.ab[1])]);
            if let Some(a) = angle {
                params.insert("angle".into(), *a);
            }
            cases.push(Case { index: cases.len(), variant: v, params, repeats: 1, keep_field: false });
        }
    }
    Ok(Plan {
        kind: StudyKind::Optimise,
        scene: absolute(&scene.path)?,
        ply: name.clone(),
        axes: None,
        symmetries: Vec::new(),
        reference: None,
        search: Some(search),
        cases,
    })
}

/// [`plan`] on the scene's tool, read here.
pub fn plan_for(scene: &Scene, opts: &Options) -> Result<Plan, StudyError> {
    let tool = crate::io::read_tool(&scene.tool, scene.scale).map_err(|e| StudyError::Input(e.to_string()))?;
    plan(scene, opts, &tool)
}
