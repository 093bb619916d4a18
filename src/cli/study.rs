//! `drape study`: speed against accuracy, stability maps, shards, merging and Slurm arrays. The
//! studies live in [`crate::study`], their pictures in [`crate::report::study`].
use super::{compute, input, Failure};
use crate::pipeline::Scene;
use crate::study::runner::{jobs_or_cores as jobs, RunSummary};
use crate::study::stability::{self, Parameter};
use crate::study::{self as st, speed_accuracy, Finished, Plan, Shard};
use clap::{Args, Subcommand};
use std::path::{Path, PathBuf};

/// Arguments of `drape study`.
#[derive(Debug, Args)]
pub struct StudyArgs {
    #[command(subcommand)]
    pub command: StudyCommand,
}

/// The studies.
#[derive(Debug, Subcommand)]
pub enum StudyCommand {
    /// Every method at a range of spacings: error against one reference per ply (the most
    /// complete model the ply allows, on the finest tool) against time, and the Pareto front.
    SpeedAccuracy(SpeedAccuracyArgs),
    /// Sweep the conditions that break drape methods and map the outcomes.
    Stability(StabilityArgs),
    /// Join shard folders into one study folder.
    Merge(MergeArgs),
    /// Run one shard of a study's plan (what a Slurm array task runs).
    #[command(hide = true)]
    Shard(ShardArgs),
}

/// What every study takes.
#[derive(Debug, Args)]
pub struct Common {
    /// Scene file (TOML).
    pub scene: PathBuf,
    /// Study folder: `study.json`, `cases/`, the result file and its charts. Run again into the
    /// same folder to resume.
    #[arg(long)]
    pub out: PathBuf,
    /// The ply studied (default: the scene's first).
    #[arg(long)]
    pub ply: Option<String>,
    /// Further resolutions of the tool, comma-separated files in the scene's units. In
    /// speed-accuracy the finest tool given (the most triangles) carries the one reference
    /// every run is measured against.
    #[arg(long, value_delimiter = ',')]
    pub tools: Vec<PathBuf>,
    /// Cases run at once (default: the machine's cores). Times are per case, so use 1 for
    /// timings free of other cases.
    #[arg(long)]
    pub jobs: Option<usize>,
    /// Run only shard K of N (K/N); `drape study merge` joins the shards' folders.
    #[arg(long)]
    pub shard: Option<String>,
    /// Write `OUT/study.sbatch`, a Slurm job array of this many shards that merges itself, and
    /// stop (submit it with sbatch).
    #[arg(long)]
    pub slurm: Option<usize>,
}

/// Arguments of `drape study speed-accuracy`.
#[derive(Debug, Args)]
pub struct SpeedAccuracyArgs {
    #[command(flatten)]
    pub common: Common,
    /// Spacings of the kinematic methods, comma-separated, in the scene's units (default: 2, 1,
    /// 1/2 and 1/4 of the ply's).
    #[arg(long, value_delimiter = ',')]
    pub spacings: Vec<f64>,
    /// Spacings of the mechanical methods (default: 2 and 1 times the ply's).
    #[arg(long, value_delimiter = ',')]
    pub mechanical_spacings: Vec<f64>,
    /// Timed repeats of each kinematic case (the median is reported).
    #[arg(long, default_value_t = 3)]
    pub repeats: usize,
    /// Coefficients of friction between ply and tool, comma-separated: the pressed mechanical
    /// drape runs again at each (at the mechanical spacings), measured against the reference
    /// drawn with the ply's own friction.
    #[arg(long, value_delimiter = ',')]
    pub frictions: Vec<f64>,
}

/// Arguments of `drape study stability`.
#[derive(Debug, Args)]
pub struct StabilityArgs {
    #[command(flatten)]
    pub common: Common,
    /// Parameters swept, comma-separated: spacing, angle, seed_u, seed_v, pre_shear, locking,
    /// tool, stiffness_ratio, load_steps, friction (default: every one that applies to the ply).
    #[arg(long, value_delimiter = ',')]
    pub params: Vec<String>,
    /// The two parameters of the outcome map (swept over their whole product).
    #[arg(long, default_value = "spacing,angle")]
    pub axes: String,
}

/// Arguments of `drape study merge`.
#[derive(Debug, Args)]
pub struct MergeArgs {
    /// The shard folders.
    #[arg(required = true)]
    pub shards: Vec<PathBuf>,
    /// The merged study folder.
    #[arg(long)]
    pub out: PathBuf,
}

/// Arguments of `drape study shard`.
#[derive(Debug, Args)]
pub struct ShardArgs {
    /// A study's `study.json`.
    pub plan: PathBuf,
    /// Which shard, K/N.
    #[arg(long)]
    pub shard: String,
    /// The shard's folder.
    #[arg(long)]
    pub out: PathBuf,
    /// Cases run at once.
    #[arg(long)]
    pub jobs: Option<usize>,
}

/// Run `drape study`.
pub fn run(a: StudyArgs) -> Result<(), Failure> {
    match a.command {
        StudyCommand::SpeedAccuracy(s) => {
            let scene = Scene::load(&s.common.scene).map_err(input)?;
            let none_if_empty = |v: Vec<f64>| (!v.is_empty()).then(|| v.iter().map(|d| d * scene.scale).collect());
            let opts = speed_accuracy::Options {
                ply: s.common.ply.clone(),
                spacings: none_if_empty(s.spacings),
                mechanical_spacings: none_if_empty(s.mechanical_spacings),
                tools: s.common.tools.clone(),
                repeats: s.repeats,
                frictions: s.frictions,
            };
            let plan = speed_accuracy::plan(&scene, &opts)?;
            execute(&plan, &s.common)
        }
        StudyCommand::Stability(s) => {
            let scene = Scene::load(&s.common.scene).map_err(input)?;
            let parse = |n: &str| Parameter::parse(n).map_err(|m| input(anyhow::anyhow!(m)));
            let parameters = if s.params.is_empty() {
                None
            } else {
                Some(s.params.iter().map(|p| parse(p)).collect::<Result<Vec<_>, _>>()?)
            };
            let axes: Vec<&str> = s.axes.split(',').collect();
            let [a0, a1] = axes[..] else {
                return Err(input(anyhow::anyhow!("--axes: give two parameters, like spacing,angle")));
            };
            let opts = stability::Options {
                ply: s.common.ply.clone(),
                parameters,
                axes: Some([parse(a0)?, parse(a1)?]),
                tools: s.common.tools.clone(),
            };
            let plan = stability::plan_for(&scene, &opts)?;
            execute(&plan, &s.common)
        }
        StudyCommand::Merge(m) => {
            st::runner::merge(&m.shards, &m.out)?;
            println!("merged {} shard folders into {}", m.shards.len(), m.out.display());
            let finished = st::finish(&m.out)?;
            report(&m.out, finished)
        }
        StudyCommand::Shard(s) => {
            let shard = Shard::parse(&s.shard).map_err(|m| input(anyhow::anyhow!("--shard: {m}")))?;
            let dir = s.plan.parent().unwrap_or(Path::new("."));
            let plan = st::runner::read_plan(dir)?;
            run_shard(&plan, &s.out, shard, jobs(s.jobs))
        }
    }
}

fn execute(plan: &Plan, c: &Common) -> Result<(), Failure> {
    execute_plan(plan, &c.out, c.shard.as_deref(), c.jobs, c.slurm)
}

/// The `--shard K/N` asked, or the whole plan.
pub(super) fn shard_of(text: Option<&str>) -> Result<Shard, Failure> {
    match text {
        Some(s) => Shard::parse(s).map_err(|m| input(anyhow::anyhow!("--shard: {m}"))),
        None => Ok(Shard::ALL),
    }
}

/// Run `plan` into `out`: its shard (`K/N`), `jobs` cases at a time, or write its Slurm array of
/// `slurm` shards; print what it gave when the study is complete.
fn execute_plan(
    plan: &Plan,
    out: &Path,
    shard: Option<&str>,
    jobs_asked: Option<usize>,
    slurm: Option<usize>,
) -> Result<(), Failure> {
    if let Some(n) = slurm {
        return write_slurm(plan, out, n, jobs(jobs_asked));
    }
    run_shard(plan, out, shard_of(shard)?, jobs(jobs_asked))
}

/// Prepare `out` for `plan` and write its Slurm array of `n` shards of `jobs` threads.
pub(super) fn write_slurm(plan: &Plan, out: &Path, n: usize, jobs: usize) -> Result<(), Failure> {
    if n == 0 {
        return Err(input(anyhow::anyhow!("--slurm: give the number of shards, at least 1")));
    }
    st::runner::prepare(plan, out)?;
    let exe = std::env::current_exe().map_err(compute)?;
    let path = st::runner::write_sbatch(out, n, &exe, jobs)?;
    println!("{} cases in {n} shards; submit with: sbatch {}", plan.cases.len(), path.display());
    Ok(())
}

fn run_shard(plan: &Plan, out: &Path, shard: Shard, jobs: usize) -> Result<(), Failure> {
    let mine = plan.cases.iter().filter(|c| shard.holds(c.index)).count();
    let bar = super::progress::bar(mine as u64, plan.kind.name());
    let started = std::time::Instant::now();
    st::runner::prepare(plan, out)?;
    let summary = st::runner::run(plan, out, shard, jobs, |done, _| bar.set_position(done as u64))?;
    let seconds = started.elapsed().as_secs_f64();
    bar.finish_and_clear();
    let finished = st::finish(out)?;
    print_run(plan, out, shard, summary, seconds, jobs);
    report(out, finished)
}

/// Print what running `shard` of `plan` into `out` did: the cases run, how fast, how many were
/// there from an earlier run.
pub(super) fn print_run(plan: &Plan, out: &Path, shard: Shard, summary: RunSummary, seconds: f64, jobs: usize) {
    let ran = summary.cases - summary.resumed;
    if ran > 0 {
        println!(
            "ran {ran} cases in {seconds:.2} s on {jobs} threads ({:.0} a minute)",
            60.0 * ran as f64 / seconds.max(f64::MIN_POSITIVE)
        );
    }
    println!(
        "{} {}: {} cases ({} from an earlier run) of ply {} in {}",
        plan.kind.name(),
        if shard == Shard::ALL { String::new() } else { format!("shard {}/{}", shard.k, shard.n) },
        summary.cases,
        summary.resumed,
        plan.ply,
        out.display()
    );
}

/// Print a study's result (or that it is not complete), its warnings, and draw its charts.
pub(super) fn report(dir: &Path, finished: Option<(Finished, PathBuf)>) -> Result<(), Failure> {
    let Some((finished, path)) = finished else {
        println!("the study is not complete in {}: run its other shards and merge them", dir.display());
        return Ok(());
    };
    println!("wrote {}", path.display());
    match &finished {
        Finished::SpeedAccuracy(s) => {
            println!("reference: {}", s.reference.describe());
            println!(
                "err: each run's distance from that reference (its spacing, the tool's facets and its model alike); own: its distance from its own limit (its own convergence, not an error)"
            );
            // On a symmetric scene each run names the image of the reference it is measured in.
            let symmetric = !s.reference.symmetries.is_empty();
            if symmetric {
                let names: Vec<&str> = s.reference.symmetries.iter().map(|m| m.name()).collect();
                println!(
                    "the ply's drape problem is symmetric ({}): each run is measured against the reference or its image nearest to it (\"image\")",
                    names.join(", ")
                );
            }
            let image = |x: &str| if symmetric { format!(" {x:>12}") } else { String::new() };
            println!(
                "{:<22} {:>9} {:>8} {:>9} {:>10} {:>11} {:>11} {:>11}{}  outcome",
                "method",
                "d (m)",
                "surface",
                "triangles",
                "time (s)",
                "err max",
                "err rms",
                "own max",
                image("image")
            );
            for p in &s.points {
                let e = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{v:.4}"));
                println!(
                    "{:<22} {:>9.5} {:>8} {:>9} {:>10.4} {:>11} {:>11} {:>11}{}  {}{}",
                    p.method_label(),
                    p.spacing,
                    p.surface,
                    p.tool_triangles,
                    p.time_s,
                    e(p.error_max_deg),
                    e(p.error_rms_deg),
                    e(p.own_error_max_deg),
                    image(p.reference_image.map_or("-", |m| m.name())),
                    p.outcome,
                    if p.pareto { "  (Pareto)" } else { "" }
                );
            }
            if let Some(why) = &s.auto_not_run {
                println!("auto not run: {why}");
            }
            for a in &s.auto {
                println!(
                    "auto at d = {:.5} m ran {}: error {} against the {} deg tolerance ({}), {:.3} s{}",
                    a.spacing,
                    a.chosen,
                    a.error_max_deg.map_or("not compared".to_string(), |e| format!("{e:.4} deg")),
                    a.tolerance_deg,
                    match a.within_tolerance {
                        Some(true) => "within",
                        Some(false) => "OUTSIDE",
                        None => "no reference",
                    },
                    a.time_s,
                    a.cost_ratio.map_or(String::new(), |r| format!(
                        ", {:.0}% of the {:.3} s mechanics takes",
                        100.0 * r,
                        a.mechanical_time_s.unwrap_or_default()
                    ))
                );
                if let Some(verdict) = a.verdict(&s.reference) {
                    println!("  {verdict}");
                }
                // Auto's cost against mechanics of the same accuracy only where it has that accuracy.
                match (a.mechanical_within_tolerance_s, a.within_tolerance) {
                    (Some(m), Some(true)) => println!(
                        "  mechanics within the tolerance takes {m:.3} s at best: auto costs {:.0}% of that",
                        100.0 * a.time_s / m
                    ),
                    (Some(m), _) => println!(
                        "  mechanics within the tolerance takes {m:.3} s at best; auto is not within it here, so it saves nothing against that"
                    ),
                    (None, _) => {}
                }
            }
        }
        Finished::Optimise(o) => super::optimise::print(o, dir),
        Finished::Stability(s) => {
            let mut counts = std::collections::BTreeMap::new();
            for c in &s.cases {
                *counts.entry(c.outcome.as_str()).or_insert(0) += 1;
            }
            let text: Vec<String> = counts.iter().map(|(o, n)| format!("{o}: {n}")).collect();
            println!("{} cases: {}", s.cases.len(), text.join(", "));
        }
    }
    if let Some(w) = st::shear_range_warning(dir) {
        println!("warning: {w}");
    }
    let files = crate::report::study::draw(dir, &finished).map_err(|m| compute(anyhow::anyhow!(m)))?;
    for f in files {
        println!("wrote {}", f.display());
    }
    Ok(())
}
