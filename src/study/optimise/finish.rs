//! The optimisation once the global search's cases are in: the candidates ranked by their
//! objective, the best few refined by a pattern search at the ply's own spacing (every poll a
//! full drape, each round's polls in parallel), the refined placements ranked, and the scene
//! with the best one written.
use super::candidates::region_of;
use super::refine::{pattern_search, Pattern};
use super::scene_file::optimal_scene;
use super::{Candidate, Optimisation, Placement, Search, Start, REFINE_BUDGET, REFINE_SHRINK, SCENE_FILE};
use crate::geometry::ToolSurface;
use crate::layup::Layup;
use crate::study::case::{run_case, CaseResult, CaseStats};
use crate::study::plan::{Case, Plan, Variant};
use crate::study::runner::CaseRecord;
use crate::study::StudyError;
use rayon::prelude::*;
use std::collections::HashMap;
use std::path::Path;
use std::time::Instant;

/// Refined placements closer than this (times the seed step, or the angle step) are one.
const SAME_PLACEMENT: f64 = 1e-6;

/// A draped placement's objective, when it gave a complete cell.
fn objective_of(search: &Search, r: &CaseResult) -> Option<f64> {
    r.stats.filter(|s| s.cells > 0).map(|s| search.objective.value(&s))
}

/// Everything a refinement drapes with.
struct Evaluator<'a> {
    search: &'a Search,
    region: Option<super::region::Region>,
    base: &'a crate::layup::Ply,
    layup: &'a Layup,
    tool: &'a ToolSurface,
    template: Variant,
}

impl Evaluator<'_> {
    /// The placement at plane coordinates and angle `x` at the ply's spacing, or `None` when it
    /// lies outside the region or the angle range.
    fn drape(&self, x: [f64; 3]) -> Option<(Variant, CaseResult)> {
        let mut v = self.template.clone();
        v.spacing = self.search.ply_spacing;
        if let Some(region) = &self.region {
            v.origin = Some(region.seed(self.tool, [x[0], x[1]])?.point.coords.into());
        }
        if let Some(range) = &self.search.angles {
            if !range.contains(x[2]) {
                return None;
            }
            v.angle_deg = Some(x[2]);
        }
        let case = Case { index: 0, variant: v.clone(), params: Default::default(), repeats: 1, keep_field: false };
        Some((v, run_case(self.base, self.layup, &case, self.tool)))
    }
}

fn placement(
    x: [f64; 3],
    v: &Variant,
    r: &CaseResult,
    objective: f64,
    frame_origin: [f64; 3],
    start: Start,
) -> Placement {
    Placement {
        origin: v.origin.unwrap_or(frame_origin),
        seed_ab: [x[0], x[1]],
        angle_deg: v.angle_deg,
        objective,
        stats: r.stats.unwrap_or(CaseStats {
            max_abs_shear_deg: 0.0,
            mean_abs_shear_deg: 0.0,
            area_over_locking_m2: 0.0,
            coverage: 0.0,
            cells: 0,
        }),
        spacing: v.spacing,
        outcome: r.outcome.clone(),
        start,
    }
}

/// Finish the optimisation planned in `plan` from its cases' records: refine, rank, write
/// `dir/optimise.json` and `dir/optimal.toml`.
pub fn finish(plan: &Plan, records: &[CaseRecord], dir: &Path) -> Result<Optimisation, StudyError> {
    let search =
        plan.search.as_ref().ok_or_else(|| StudyError::Input("the plan has no search: not an optimisation".into()))?;
    let (scene, k) = plan.scene_and_ply()?;
    let base = &scene.layup.plies[k];
    let template =
        records.first().ok_or_else(|| StudyError::Input("the plan has no candidate".into()))?.case.variant.clone();
    let tool = crate::io::read_tool(&template.tool, scene.scale).map_err(|e| StudyError::Input(e.to_string()))?;
    let landscape: Vec<Candidate> = records
        .iter()
        .map(|r| Candidate {
            index: r.case.index,
            seed_ab: [r.case.params["seed_a"], r.case.params["seed_b"]],
            origin: r.case.variant.origin.unwrap_or(search.frame.origin),
            angle_deg: r.case.variant.angle_deg,
            objective: objective_of(search, &r.result),
            outcome: r.result.outcome.clone(),
        })
        .collect();
    let mut ranked: Vec<(usize, f64)> =
        landscape.iter().enumerate().filter_map(|(k, c)| Some((k, c.objective?))).collect();
    if ranked.is_empty() {
        let mut outcomes: Vec<&str> = landscape.iter().map(|c| c.outcome.as_str()).collect();
        outcomes.sort_unstable();
        outcomes.dedup();
        return Err(StudyError::Input(format!(
            "no candidate placement of ply '{}' gave a complete cell ({}): put the seed region on the tool, or check the ply",
            plan.ply,
            outcomes.join("; ")
        )));
    }
    // Best first; equal objectives in plan order, so the ranking is the same on any machine.
    ranked.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
    let one = Layup {
        reference: scene.layup.reference,
        stack_side: scene.layup.stack_side,
        plies: Vec::new(),
        wrinkles: false,
    };
    let eval = Evaluator {
        search,
        region: region_of(search, &tool).map_err(StudyError::Input)?,
        base,
        layup: &one,
        tool: &tool,
        template,
    };
    let steps = [
        if search.region.is_some() { 0.5 * search.seed_step } else { 0.0 },
        if search.region.is_some() { 0.5 * search.seed_step } else { 0.0 },
        search.angles.map_or(0.0, |a| 0.5 * a.step),
    ];
    let pattern = Pattern { steps, shrink_to: REFINE_SHRINK, budget: REFINE_BUDGET };
    let started = Instant::now();
    let mut refined: Vec<Placement> = Vec::new();
    for &(k, search_objective) in ranked.iter().take(search.refine_starts) {
        let c = &landscape[k];
        let x0 = [c.seed_ab[0], c.seed_ab[1], c.angle_deg.unwrap_or(0.0)];
        // The start again at the ply's spacing: the coarse search's error there.
        let Some((v0, r0)) = eval.drape(x0) else { continue };
        let Some(f0) = objective_of(search, &r0) else { continue };
        let key = |x: &[f64; 3]| x.map(f64::to_bits);
        // Every drape of this refinement, so the best one is kept, not draped again.
        let mut draped: HashMap<[u64; 3], (Variant, CaseResult)> = HashMap::from([(key(&x0), (v0, r0))]);
        let result = pattern_search(x0, f0, &pattern, |xs| {
            let drapes: Vec<Option<(Variant, CaseResult)>> = xs.par_iter().map(|x| eval.drape(*x)).collect();
            let values = drapes.iter().map(|d| d.as_ref().and_then(|(_, r)| objective_of(search, r))).collect();
            for (x, d) in xs.iter().zip(drapes) {
                if let Some(d) = d {
                    draped.insert(key(x), d);
                }
            }
            values
        });
        let (x, f) = result.best;
        let (v, r) = draped.remove(&key(&x)).expect("the search's best point was draped");
        let start =
            Start { candidate: c.index, search_objective, ply_spacing_objective: f0, evaluations: result.trail.len() };
        refined.push(placement(x, &v, &r, f, search.frame.origin, start));
    }
    let refine_s = started.elapsed().as_secs_f64();
    refined.sort_by(|a, b| a.objective.total_cmp(&b.objective).then(a.start.candidate.cmp(&b.start.candidate)));
    // Starts that climbed to the same placement are one.
    let same = |a: &Placement, b: &Placement| {
        let ds = (a.seed_ab[0] - b.seed_ab[0]).hypot(a.seed_ab[1] - b.seed_ab[1]);
        let da = (a.angle_deg.unwrap_or(0.0) - b.angle_deg.unwrap_or(0.0)).abs();
        ds <= SAME_PLACEMENT * search.seed_step.max(search.ply_spacing)
            && da <= SAME_PLACEMENT * search.angles.map_or(1.0, |r| r.step)
    };
    let mut distinct: Vec<Placement> = Vec::new();
    for p in refined {
        if !distinct.iter().any(|q| same(q, &p)) {
            distinct.push(p);
        }
    }
    if distinct.is_empty() {
        return Err(StudyError::Input(format!(
            "no candidate of ply '{}' drapes at the ply's own spacing ({} m): check the ply's spacing and grid",
            plan.ply, search.ply_spacing
        )));
    }
    let best = distinct.remove(0);
    let note = format!(
        "{} with ply '{}' at its optimal placement (drape optimise, {}):\nobjective {:.6} ({}); seed {:?} m, angle {}",
        plan.scene.display(),
        plan.ply,
        dir.display(),
        best.objective,
        search.objective.describe(),
        best.origin,
        best.angle_deg.map_or("as the scene gives it".to_string(), |a| format!("{a} deg")),
    );
    let origin_in_scene_units = best.origin.map(|x| x / scene.scale);
    let text = optimal_scene(&plan.scene, &plan.ply, origin_in_scene_units, best.angle_deg, &note)
        .map_err(StudyError::Input)?;
    crate::io::write_atomic(&dir.join(SCENE_FILE), |w| std::io::Write::write_all(w, text.as_bytes()))
        .map_err(|e| StudyError::Write(e.to_string()))?;
    Ok(Optimisation {
        ply: plan.ply.clone(),
        objective_text: search.objective.describe(),
        search: search.clone(),
        search_spacing: records[0].case.variant.spacing,
        best,
        runners_up: distinct,
        feasible: ranked.len(),
        search_drape_s: records.iter().map(|r| r.result.time_s).sum(),
        landscape,
        refine_s,
        scene: SCENE_FILE.into(),
    })
}
