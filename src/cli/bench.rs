//! `drape bench`: throughput of the kinematic engine on a generated hemisphere.
use super::{input, Failure};
use crate::geometry::hemisphere::hemisphere_with_triangles;
use crate::geometry::{Point, Vector};
use crate::kinematic::{drape, KinematicSettings, SurfaceKind};
use crate::material::MaterialCard;
use crate::mechanics::refine::{refine_draped, RefineSettings};
use crate::mechanics::SolverSettings;
use clap::Args;
use std::time::Instant;

/// Arguments of `drape bench`.
#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Least number of triangles of the hemisphere (radius 1 m).
    #[arg(long, default_value_t = 200_000)]
    pub triangles: usize,
    /// Nodes along each side of the net (covers the hemisphere from pole to rim).
    #[arg(long, default_value_t = 1000)]
    pub nodes: usize,
    /// Timed repetitions (the best is reported too).
    #[arg(long, default_value_t = 5)]
    pub repeat: usize,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Also refine the net mechanically (pressed) with this material card, and report
    /// iterations and time per iteration.
    #[arg(long)]
    pub refine: Option<std::path::PathBuf>,
    /// The surface the net lies on: facets or smooth.
    #[arg(long, default_value = "facets")]
    pub surface: String,
    /// Iteration limit of the refinement.
    #[arg(long, default_value_t = 100)]
    pub max_iterations: usize,
    /// Friction between the refined ply and the tool (default: the card's `[contact] friction`,
    /// else 0).
    #[arg(long)]
    pub friction: Option<f64>,
}

pub fn run(a: BenchArgs) -> Result<(), Failure> {
    if a.nodes < 2 || a.repeat == 0 {
        return Err(input(anyhow::anyhow!("--nodes must be at least 2 and --repeat at least 1")));
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(a.threads.unwrap_or(0))
        .build()
        .map_err(|e| input(anyhow::anyhow!("cannot start {} threads: {e}", a.threads.unwrap_or(0))))?;
    let surface: SurfaceKind = a.surface.parse().map_err(|m| input(anyhow::anyhow!("--surface: {m}")))?;
    let t = Instant::now();
    let tool = hemisphere_with_triangles(1.0, a.triangles).into_surface().map_err(input)?;
    println!(
        "hemisphere R = 1 m: {} triangles, built in {:.0} ms",
        tool.num_triangles(),
        t.elapsed().as_secs_f64() * 1e3
    );
    // Spacing so the generators reach from the pole to the rim: quarter circumference / half-size.
    let half = (a.nodes - 1) / 2;
    let spacing = std::f64::consts::FRAC_PI_2 / half.max(1) as f64 * 0.999;
    let settings = KinematicSettings {
        surface,
        ..KinematicSettings::grid(
            "bench",
            Point::new(0.0, 0.0, 1.0),
            Vector::new(1.0, 0.0, 0.0),
            spacing,
            a.nodes,
            a.nodes,
        )
    };
    let mut best = f64::INFINITY;
    let mut total = 0.0;
    let mut placed_cells = 0;
    for _ in 0..a.repeat {
        let t = Instant::now();
        let net = pool.install(|| drape(&tool, &settings)).map_err(input)?;
        let s = t.elapsed().as_secs_f64();
        best = best.min(s);
        total += s;
        placed_cells = net.shear_stats(1.0).cells;
    }
    let grid_cells = (a.nodes - 1) * (a.nodes - 1);
    println!(
        "net {n} x {n} nodes on the {surface}, spacing {spacing:.6} m, {threads} thread(s): {placed_cells} of the grid's {grid_cells} cells placed on the tool",
        n = a.nodes,
        threads = pool.current_num_threads()
    );
    println!(
        "throughput: {:.2} M placed cells/s (best), {:.2} M placed cells/s (mean); time per drape: best {:.1} ms, mean {:.1} ms",
        placed_cells as f64 / best / 1e6,
        placed_cells as f64 * a.repeat as f64 / total / 1e6,
        best * 1e3,
        total / a.repeat as f64 * 1e3,
    );
    if let Some(card) = &a.refine {
        let material = MaterialCard::load(card).map_err(input)?;
        let net = pool.install(|| drape(&tool, &settings)).map_err(input)?;
        let refine_settings = RefineSettings {
            solver: SolverSettings::default().max_iterations(a.max_iterations),
            friction: a.friction.or(material.friction).unwrap_or(0.0),
            ..RefineSettings::default()
        };
        // As a scene's pressed ply: a net on the facets starts from the ply draped on the smooth
        // surface its nodes are pressed onto (that drape is timed with the refinement).
        let t = Instant::now();
        let refined =
            pool.install(|| refine_draped(&net, &settings, &tool, None, &material, &refine_settings)).map_err(input)?;
        let total = t.elapsed().as_secs_f64();
        let iterations: Vec<_> = refined.steps.iter().flat_map(|s| s.iterations.iter()).collect();
        let qp: u32 = iterations.iter().map(|i| i.subproblems).sum();
        println!(
            "refinement (pressed, {}, friction {}): {} placed nodes, {:?} after {} iterations in {} load step(s), {} solve(s) ({} Clarabel subproblems) in {:.2} s, {:.0} ms per iteration; |F-P|/|P| {:.1e}",
            card.display(),
            refine_settings.friction,
            placed_nodes(&net),
            refined.outcome(),
            iterations.len(),
            refined.increments.len(),
            refined.steps.len(),
            qp,
            total,
            total * 1e3 / iterations.len().max(1) as f64,
            refined.steps.last().map_or(0.0, |s| s.residual)
        );
        for i in &iterations {
            println!(
                "  iteration {:>3}: |F-P|/|P| {:.1e}, shift {:.0e}, step {:.3} spacings, {} subproblem(s) ({} by CG on the last factorisation, {} solved ahead), {:.0} ms (models {:.0}, Clarabel {:.0}, trial steps {:.0})",
                i.iteration, i.residual, i.shift, i.step, i.subproblems, i.lagged, i.ahead, i.time_ms, i.model_ms, i.solve_ms, i.trial_ms
            );
        }
        let sum = |f: fn(&&crate::mechanics::solver::IterationLog) -> f64| iterations.iter().map(f).sum::<f64>() / 1e3;
        println!(
            "  of which: models {:.2} s (energy, Hessian, contact, reduction), Clarabel {:.2} s, trial steps {:.2} s",
            sum(|i| i.model_ms),
            sum(|i| i.solve_ms),
            sum(|i| i.trial_ms)
        );
        if let Some(c) = refined.steps.last().and_then(|s| s.stability.as_ref()) {
            println!("  stability check: {}", c.describe());
        }
    }
    if let Some(kb) = peak_memory_kb() {
        println!("peak memory (VmHWM): {:.0} MB", kb as f64 / 1024.0);
    }
    Ok(())
}

fn placed_nodes(net: &crate::kinematic::DrapeNet) -> usize {
    net.status.iter().filter(|s| **s == crate::kinematic::NodeStatus::Placed).count()
}

/// Peak resident memory of this process (Linux), in kB.
fn peak_memory_kb() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    s.lines().find(|l| l.starts_with("VmHWM:"))?.split_whitespace().nth(1)?.parse().ok()
}
