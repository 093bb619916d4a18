//! `drape refine`: mechanical refinement of a kinematic net.
use super::kinematic::print_tool_report;
use super::summary::summary;
use super::{input, parse_vec3, Failure};
use crate::io::{read_net, write_net, Format};
use crate::layup::DEFAULT_LOCKING_ANGLE_DEG;
use crate::material::MaterialCard;
use crate::mechanics::refine::Refined;
use crate::mechanics::ContactMode;
use crate::pipeline::ply::read_tool;
use crate::pipeline::refine::{check_refined, parse_stack_side, refine_net, RefineOptions};
use clap::{Args, ValueEnum};
use std::path::PathBuf;
use std::time::Instant;

/// Contact mode on the command line.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum Mode {
    /// Held against the tool: nodes slide on it.
    Pressed,
    /// Gravity drape with one-sided contact.
    Free,
}

/// Arguments of `drape refine`.
#[derive(Debug, Args)]
pub struct RefineArgs {
    /// Kinematic net (`<ply>.drape.json` from `drape kinematic` or `drape run`).
    #[arg(long)]
    pub net: PathBuf,
    /// Tool surface (OBJ, STL, or a shell mesh: .inp, .bdf, .msh).
    #[arg(long)]
    pub tool: PathBuf,
    /// Units of the tool file: m or mm (default: the units the net records its tool was read
    /// in, else m). The net itself is in metres.
    #[arg(long)]
    pub units: Option<String>,
    /// Material card (TOML).
    #[arg(long)]
    pub material: PathBuf,
    /// A formed net (one that records `meta.forming`) is held by the tools that formed it,
    /// where its stroke left them: `--tool` is the punch as its file has it, and this is the
    /// die, in the tool's units (default: the die's file the net records).
    #[arg(long)]
    pub die: Option<PathBuf>,
    /// Contact with the tool.
    #[arg(long, value_enum)]
    pub mode: Mode,
    /// Pressed nodes slide on the OBJ's facets exactly as given instead of on smooth patches
    /// through its vertices and normals (on a net finer than the facets this converges slowly).
    #[arg(long)]
    pub facets: bool,
    /// Gravity vector, m/s^2.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true, default_value = "0,0,-9.80665")]
    pub gravity: [f64; 3],
    /// Gravity is applied in this many steps.
    #[arg(long, default_value_t = 1)]
    pub load_steps: usize,
    /// Free drape: nodes the tool holds up stay where they touch instead of sliding on it, until
    /// pulled off by more than a tenth of their weight (seed 000's tables restrain the nodes on
    /// them).
    #[arg(long)]
    pub stick: bool,
    /// Coulomb's coefficient of friction between the ply and the tool (default: the material
    /// card's `[contact] friction`, else 0: frictionless).
    #[arg(long)]
    pub friction: Option<f64>,
    /// Hold node I,J of the grid in place (repeat for more nodes). Nothing else holds the ply
    /// but the tool and friction.
    #[arg(long, value_parser = parse_node)]
    pub hold: Vec<(usize, usize)>,
    /// Move off an equilibrium the solver's stability check finds a saddle and iterate on to a
    /// lower one (default: only report it).
    #[arg(long)]
    pub escape_saddles: bool,
    /// Solver iteration limit per load step.
    #[arg(long, default_value_t = 100)]
    pub max_iterations: usize,
    /// The side of the tool the ply lies on: normal (the side its facets' normals point to) or
    /// opposite (a tool file facing into the part). Default: the side the net records (a layup
    /// with stack_side = "opposite" records it), else normal.
    #[arg(long)]
    pub stack_side: Option<String>,
    /// Output formats: comma-separated json,vtu,csv, or none.
    #[arg(long, default_value = "json")]
    pub format: String,
    /// Output directory.
    #[arg(long)]
    pub out: PathBuf,
}

pub fn run(a: RefineArgs) -> Result<(), Failure> {
    let formats = Format::parse_list(&a.format).map_err(|m| input(anyhow::anyhow!("--format: {m}")))?;
    let options = RefineOptions {
        mode: match a.mode {
            Mode::Pressed => ContactMode::Pressed,
            Mode::Free => ContactMode::Free,
        },
        units: a.units,
        facets: a.facets,
        gravity: a.gravity,
        load_steps: a.load_steps,
        stick: a.stick,
        friction: a.friction,
        holds: a.hold.iter().map(|&(i, j)| [i, j]).collect(),
        escape_saddles: a.escape_saddles,
        max_iterations: a.max_iterations,
        die: a.die,
        stack_side: a.stack_side.as_deref().map(parse_stack_side).transpose()?,
    };
    options.check()?;
    let net = read_net(&a.net).map_err(input)?;
    let material = MaterialCard::load(&a.material).map_err(input)?;
    let settings = options.settings(&net, &material)?;
    let scale = options.tool_scale(&net)?;
    let t_load = Instant::now();
    let tool = read_tool(&a.tool, scale)?;
    let load_ms = t_load.elapsed().as_secs_f64() * 1e3;
    print_tool_report(&a.tool, &tool);
    let (mut out, refined) = refine_net(
        &net,
        &a.net.display().to_string(),
        &tool,
        options.stack_side(&net),
        &material,
        &a.material,
        &settings,
    )?;
    out.timing.load_ms = load_ms;
    out.timing.total_ms += load_ms;
    // The last consistent state is written even when the solver did not converge.
    let t_write = Instant::now();
    let written = write_net(&out, &a.out, &formats).map_err(super::write_failure)?;
    println!(
        "{}",
        summary(&out, DEFAULT_LOCKING_ANGLE_DEG.to_radians(), load_ms, t_write.elapsed().as_secs_f64() * 1e3)
    );
    print_solver(&refined);
    if let Some(line) = super::summary::wrinkles_line(&out.name, &out) {
        println!("{line}");
    }
    for p in written {
        println!("  wrote {}", p.display());
    }
    let max_shear = out.shear_stats(DEFAULT_LOCKING_ANGLE_DEG.to_radians()).max_abs.to_degrees();
    if let Some(w) = material.shear_range_warning(max_shear) {
        println!("warning: ply '{}': {w}", out.name);
    }
    check_refined(&refined)
}

/// A grid node `I,J`.
fn parse_node(s: &str) -> Result<(usize, usize), String> {
    let bad = || format!("expected a grid node I,J (two whole numbers), got `{s}`");
    let (i, j) = s.split_once(',').ok_or_else(bad)?;
    Ok((i.trim().parse().map_err(|_| bad())?, j.trim().parse().map_err(|_| bad())?))
}

pub(crate) fn print_solver(r: &Refined) {
    let iterations: usize = r.steps.iter().map(|s| s.iterations.len()).sum();
    let ms: f64 = r.steps.iter().map(|s| s.time_ms).sum();
    let residual = r.steps.last().map_or(0.0, |s| s.residual);
    // The check of the state the net ends in (the last load step's).
    let stability = r.steps.last().and_then(|s| s.stability.as_ref()).map(|c| format!("; {}", c.describe()));
    println!(
        "  solver: {:?} after {iterations} iterations in {} load step(s) ({} solves), {:.0} ms; |F-P|/|P| {:.2e}{}",
        r.outcome(),
        r.increments.len(),
        r.steps.len(),
        ms,
        residual,
        stability.unwrap_or_default(),
    );
    println!("  contact: {}", r.contact.summary().describe());
    if r.energy_start == r.energy_kinematic {
        println!("  energy: kinematic {:.6e} J -> refined {:.6e} J", r.energy_kinematic, r.energy_final);
    } else {
        println!(
            "  energy: kinematic {:.6e} J on the facets, {:.6e} J where the solver started (the net moved onto the smooth tool, the ply draped on the smooth surface, or where auto's probe stopped) -> refined {:.6e} J",
            r.energy_kinematic, r.energy_start, r.energy_final
        );
    }
}
