//! `drape optimise`: the best seed and angle of a ply. The search lives in
//! [`crate::study::optimise`] and runs as a study (shards, merge, resume); this file parses the
//! arguments and prints the result.
use super::{input, parse_vec3, Failure};
use crate::io::points::read_points;
use crate::pipeline::Scene;
use crate::study::optimise::{self as opt, AngleRange, Objective, Optimisation, SeedRegion};
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
    #[arg(long, default_value = "seed,angle")]
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
    /// The ply angles tried, LO,HI in degrees (a balanced fabric at a + 90 deg is the same ply).
    #[arg(long, default_value = "-45,45")]
    pub angle_range: String,
    /// Step of the angles, degrees.
    #[arg(long, default_value_t = 5.0)]
    pub angle_step: f64,
    /// What is minimised: max-shear, locked-area, mean-shear, coverage (maximised), or a
    /// weighted sum like max-shear:1,coverage:0.5.
    #[arg(long, default_value = "max-shear")]
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

fn bad(message: String) -> Failure {
    input(anyhow::anyhow!(message))
}

/// `x,y,z;x,y,z;...`, or a points file.
fn polygon(text: &str, scale: f64) -> Result<Vec<[f64; 3]>, Failure> {
    let path = Path::new(text);
    let points = if path.is_file() {
        read_points(path, scale)
            .map_err(|m| bad(format!("--seed-polygon: {m}")))?
            .into_iter()
            .map(|p| p.coords.into())
            .collect()
    } else if text.contains(';') {
        text.split(';')
            .filter(|p| !p.trim().is_empty())
            .map(|p| parse_vec3(p).map(|v| v.map(|x| x * scale)))
            .collect::<Result<Vec<_>, _>>()
            .map_err(|m| bad(format!("--seed-polygon: {m}")))?
    } else {
        return Err(bad(format!(
            "--seed-polygon: {text} is not a file, nor points x,y,z;x,y,z;...: give a points file or the corners"
        )));
    };
    Ok(points)
}

/// Run `drape optimise`.
pub fn run(a: OptimiseArgs) -> Result<(), Failure> {
    let scene = Scene::load(&a.scene).map_err(input)?;
    let s = scene.scale;
    let objective = Objective::parse(&a.objective).map_err(bad)?;
    let mut vary_seed = false;
    let mut vary_angle = false;
    for v in a.vary.split(',').map(str::trim) {
        match v {
            "seed" => vary_seed = true,
            "angle" => vary_angle = true,
            other => return Err(bad(format!("--vary: unknown '{other}': give seed, angle or seed,angle"))),
        }
    }
    let region = match (a.seed_radius, &a.seed_polygon) {
        (Some(_), Some(_)) => return Err(bad("give --seed-radius or --seed-polygon, not both".into())),
        (Some(r), None) => Some(SeedRegion::Disc { radius: r * s }),
        (None, Some(p)) => Some(SeedRegion::Polygon { points: polygon(p, s)? }),
        (None, None) => None,
    };
    let range: Vec<f64> =
        a.angle_range.split(',').map(|x| x.trim().parse::<f64>()).collect::<Result<_, _>>().map_err(|_| {
            bad(format!("--angle-range: '{}' is not LO,HI: give two angles in degrees, like -45,45", a.angle_range))
        })?;
    let [lo, hi] = range[..] else {
        return Err(bad(format!(
            "--angle-range: '{}' is not LO,HI: give two angles in degrees, like -45,45",
            a.angle_range
        )));
    };
    let opts = opt::Options {
        ply: a.ply.clone(),
        vary_seed,
        vary_angle,
        seed_step: a.seed_step.map(|h| h * s),
        angles: AngleRange { lo, hi, step: a.angle_step },
        spacing: a.spacing.map(|d| d * s),
        refine_starts: a.refine,
        max_candidates: a.max_candidates,
        ..opt::Options::new(objective, region)
    };
    let plan = opt::candidates::plan_for(&scene, &opts).map_err(|e| input(anyhow::anyhow!(e)))?;
    println!(
        "ply {}: {} candidate placements at d = {} m, then the best {} refined at d = {} m",
        plan.ply,
        plan.cases.len(),
        plan.cases[0].variant.spacing,
        opts.refine_starts,
        plan.search.as_ref().map_or(0.0, |x| x.ply_spacing)
    );
    super::study::execute_plan(&plan, &a.out, a.shard.as_deref(), a.jobs, a.slurm)
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
