//! `drape optimise`: the best seed and angle of a ply. The search lives in
//! [`crate::study::optimise`] and runs as a study (shards, merge, resume); this file parses the
//! arguments into its [`Request`], calls [`opt::optimise`] and prints the result.
use super::{input, Failure};
use crate::pipeline::Scene;
use crate::study::optimise::run::{
    parse_angle_range, DEFAULT_ANGLE_RANGE, DEFAULT_ANGLE_STEP, DEFAULT_OBJECTIVE, DEFAULT_VARY,
};
use crate::study::optimise::{self as opt, Optimisation, PolygonArg, Request};
use crate::study::runner::jobs_or_cores;
use crate::study::{Finished, Plan, StudyKind};
use clap::Args;
use std::path::{Path, PathBuf};

/// Arguments of `drape optimise`.
#[derive(Debug, Args)]
pub struct OptimiseArgs {
    /// Scene file (TOML).
    pub scene: PathBuf,
    /// The ply to place (default: the scene's first).
    #[arg(long)]
    pub ply: Option<String>,
    /// Folder: `study.json`, `cases/`, `optimise.json`, `optimise.png/svg`, `optimal.toml`. Run
    /// again into it to resume.
    #[arg(long)]
    pub out: PathBuf,
    /// What is varied: seed, angle or seed,angle.
    #[arg(long, default_value = DEFAULT_VARY)]
    pub vary: String,
    /// The seed region: within this distance of the ply's origin (scene units).
    #[arg(long)]
    pub seed_radius: Option<f64>,
    /// The seed region: a closed polygon on the tool, a points file (x,y,z per line) or the
    /// points themselves, `x,y,z;x,y,z;...` (scene units).
    #[arg(long)]
    pub seed_polygon: Option<String>,
    /// Step of the seed lattice (scene units; default: an eighth of the region's size).
    #[arg(long)]
    pub seed_step: Option<f64>,
    /// The ply angles tried, LO,HI in degrees (default: -45,45; a balanced fabric at a + 90 deg
    /// is the same ply).
    #[arg(long)]
    pub angle_range: Option<String>,
    /// Step of the angles, degrees.
    #[arg(long, default_value_t = DEFAULT_ANGLE_STEP)]
    pub angle_step: f64,
    /// What is minimised: max-shear, locked-area, mean-shear, coverage (maximised), or a
    /// weighted sum like max-shear:1,coverage:0.5.
    #[arg(long, default_value = DEFAULT_OBJECTIVE)]
    pub objective: String,
    /// Fibre spacing of the global search (scene units; default: twice the ply's).
    #[arg(long)]
    pub spacing: Option<f64>,
    /// Candidates of the global search refined at the ply's spacing.
    #[arg(long, default_value_t = opt::DEFAULT_REFINE_STARTS)]
    pub refine: usize,
    /// The most candidates the search may have.
    #[arg(long, default_value_t = opt::DEFAULT_MAX_CANDIDATES)]
    pub max_candidates: usize,
    /// Candidates draped at once (default: the machine's cores).
    #[arg(long)]
    pub jobs: Option<usize>,
    /// Run only shard K of N of the global search; `drape study merge` joins the shards and
    /// refines.
    #[arg(long)]
    pub shard: Option<String>,
    /// Write `OUT/study.sbatch`, a Slurm job array of this many shards, and stop.
    #[arg(long)]
    pub slurm: Option<usize>,
}

/// Run `drape optimise`.
pub fn run(a: OptimiseArgs) -> Result<(), Failure> {
    let scene = Scene::load(&a.scene).map_err(input)?;
    let request = Request {
        ply: a.ply,
        vary: a.vary,
        seed_radius: a.seed_radius,
        seed_polygon: a.seed_polygon.map(PolygonArg::Text),
        seed_step: a.seed_step,
        angle_range: a.angle_range.as_deref().map_or(Ok(DEFAULT_ANGLE_RANGE), parse_angle_range)?,
        angle_step: a.angle_step,
        objective: a.objective,
        spacing: a.spacing,
        refine: a.refine,
        max_candidates: a.max_candidates,
    };
    let planned = |plan: &Plan| {
        println!(
            "ply {}: {} candidate placements at d = {} m, then the best {} refined at d = {} m",
            plan.ply,
            plan.cases.len(),
            plan.cases[0].variant.spacing,
            request.refine,
            plan.search.as_ref().map_or(0.0, |x| x.ply_spacing)
        )
    };
    let jobs = jobs_or_cores(a.jobs);
    if let Some(n) = a.slurm {
        let plan = opt::candidates::plan_for(&scene, &request.options(scene.scale)?)?;
        planned(&plan);
        return super::study::write_slurm(&plan, &a.out, n, jobs);
    }
    let shard = super::study::shard_of(a.shard.as_deref())?;
    let bar = super::progress::bar(0, StudyKind::Optimise.name());
    let done = opt::optimise(&scene, &request, &a.out, shard, jobs, planned, |done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64)
    })?;
    bar.finish_and_clear();
    super::study::print_run(&done.plan, &a.out, shard, done.summary, done.search_s, jobs);
    super::study::report(&a.out, done.result.map(|(o, path)| (Finished::Optimise(Box::new(o)), path)))
}

/// Print a finished optimisation.
pub(super) fn print(o: &Optimisation, dir: &Path) {
    println!("minimised: {}", o.objective_text);
    println!(
        "global search: {} candidates ({} draped) at d = {} m, {:.2} s of drape time",
        o.landscape.len(),
        o.feasible,
        o.search_spacing,
        o.search_drape_s
    );
    let angle = |a: Option<f64>| a.map_or("as in the scene".to_string(), |a| format!("{a:.3} deg"));
    for (k, p) in std::iter::once(&o.best).chain(&o.runners_up).enumerate() {
        println!(
            "{} {:.5} at seed ({:.5}, {:.5}, {:.5}) m, angle {}: max {:.3} deg, mean {:.3} deg, {:.5} m^2 past locking, coverage {:.1}%{}",
            if k == 0 { "best     " } else { "runner-up" },
            p.objective,
            p.origin[0],
            p.origin[1],
            p.origin[2],
            angle(p.angle_deg),
            p.stats.max_abs_shear_deg,
            p.stats.mean_abs_shear_deg,
            p.stats.area_over_locking_m2,
            100.0 * p.stats.coverage,
            if p.outcome == "ok" { String::new() } else { format!(" ({})", p.outcome) }
        );
        println!(
            "          from candidate {} ({:.5} at the search's d, {:.5} at the ply's d = {} m), {} drapes",
            p.start.candidate, p.start.search_objective, p.start.ply_spacing_objective, p.spacing, p.start.evaluations
        );
    }
    println!("refinement: {:.2} s", o.refine_s);
    println!("wrote {} (the scene with the optimal ply: drape run it)", dir.join(&o.scene).display());
}
