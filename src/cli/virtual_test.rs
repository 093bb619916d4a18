//! `drape test ...`: virtual material tests writing JSON.
//!
//! ```text
//! drape test cantilever --material CARD --direction warp|weft --length L [--nodes N] [--units m|mm] --out F
//! drape test picture-frame --material CARD --side L --displacement D [--steps S] --spacing H [--units m|mm] --out F
//! drape test bias-extension --material CARD --length L --width W --displacement D [--steps S] --spacing H [--units m|mm] --out F
//! ```
//!
//! Lengths are read in `--units` (default m); the output is in metres. A shear test that takes
//! the sample past the angle its card's shear law was calibrated to (`[shear]
//! calibrated_max_deg`) prints a warning and lists it in `"warnings"`.
//!
//! The two shear tests write `{"displacement": [...], "force": [...], "net": {"grid": [nu, nv],
//! "nodes": [[x,y,z] | null, ...], ...}, ...}`: the crosshead displacement (m) and force (N, on
//! the whole sample) with d = 0, F = 0 first and then one entry per completed load step (S + 1
//! entries when every step converged), and the net in its last consistent state (node (i, j) at
//! `i * nv + j`, null for nodes outside the sample). Extra keys: `"test"`, `"sample"` (the
//! dimensions and spacing the net realises), `"net".spacing`, `"net".cell_shear_deg` (final
//! cell shear, null for incomplete cells), `"steps"` (requested, completed), `"converged"`,
//! `"iterations"`, `"notes"` (adjustments made to the request), `"warnings"`.
use super::{compute, input, Failure};
use crate::io::write_atomic;
use crate::material::test_kinematics::{BiasExtensionKinematics, PictureFrameKinematics};
use crate::material::{Fibre, MaterialCard};
use crate::mechanics::virtual_tests::{
    bias_extension, cantilever, picture_frame, BiasExtension, PictureFrame, ShearTest,
};
use crate::pipeline::unit_scale;
use clap::{Args, Subcommand, ValueEnum};
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `drape test`.
#[derive(Debug, Args)]
pub struct TestArgs {
    #[command(subcommand)]
    pub test: VirtualTest,
}

/// Fibre direction on the command line.
#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum Direction {
    Warp,
    Weft,
}

/// The virtual tests.
#[derive(Debug, Subcommand)]
pub enum VirtualTest {
    /// A strip clamped at one end hanging under its own weight (strip along +x, gravity -z).
    Cantilever {
        /// Material card (TOML).
        #[arg(long)]
        material: PathBuf,
        /// Fibre direction along the strip.
        #[arg(long, value_enum)]
        direction: Direction,
        /// Free length of the strip.
        #[arg(long)]
        length: f64,
        /// Nodes along the strip.
        #[arg(long, default_value_t = 21)]
        nodes: usize,
        /// Units of the lengths given: m or mm.
        #[arg(long, default_value = "m")]
        units: String,
        /// Output JSON file: {"nodes": [[x,y,z], ...]} from the clamp to the tip.
        #[arg(long)]
        out: PathBuf,
    },
    /// Picture frame: a square sample clamped in a pin-jointed frame (warp and weft along the
    /// arms), one corner fixed, the opposite corner pulled along the diagonal.
    PictureFrame {
        /// Material card (TOML).
        #[arg(long)]
        material: PathBuf,
        /// Frame side L (hinge to hinge, = sample side).
        #[arg(long)]
        side: f64,
        /// Final crosshead displacement (below (2 - sqrt 2) L, where the frame closes).
        #[arg(long)]
        displacement: f64,
        /// Equal load steps up to the displacement.
        #[arg(long, default_value_t = 10)]
        steps: usize,
        /// Fibre spacing of the net (adjusted to a whole number of cells per side, >= 2).
        #[arg(long)]
        spacing: f64,
        /// Units of the lengths given: m or mm.
        #[arg(long, default_value = "m")]
        units: String,
        /// Output JSON file.
        #[arg(long)]
        out: PathBuf,
    },
    /// Bias extension: a rectangular sample with its fibres at +-45 deg to the load, clamped at
    /// both ends, one clamp pulled along the sample.
    BiasExtension {
        /// Material card (TOML).
        #[arg(long)]
        material: PathBuf,
        /// Free length L between the clamps (L >= 2 W).
        #[arg(long)]
        length: f64,
        /// Width W.
        #[arg(long)]
        width: f64,
        /// Final clamp displacement (below (sqrt 2 - 1)(L - W), 90 deg in the central zone).
        #[arg(long)]
        displacement: f64,
        /// Equal load steps up to the displacement.
        #[arg(long, default_value_t = 10)]
        steps: usize,
        /// Fibre spacing of the net (adjusted so that the clamp corners are nodes).
        #[arg(long)]
        spacing: f64,
        /// Units of the lengths given: m or mm.
        #[arg(long, default_value = "m")]
        units: String,
        /// Output JSON file.
        #[arg(long)]
        out: PathBuf,
    },
}

pub fn run(a: TestArgs) -> Result<(), Failure> {
    match a.test {
        VirtualTest::PictureFrame { material, side, displacement, steps, spacing, units, out } => {
            let s = scale(&units)?;
            check_out(&out)?;
            let card = MaterialCard::load(&material).map_err(input)?;
            let spec = PictureFrame { side: side * s, spacing: spacing * s, displacement: displacement * s, steps };
            let result = picture_frame(&card, &spec).map_err(|m| input(anyhow::anyhow!(m)))?;
            let sample = serde_json::json!({"side": result.sample.0, "spacing": result.sample.2});
            // The frame shears the whole sample to its nominal angle.
            let nominal = PictureFrameKinematics { side: spec.side }.shear(last_displacement(&result)).map(|g| g.0);
            finish_shear_test("picture-frame", &result, sample, &card, nominal, &out)
        }
        VirtualTest::BiasExtension { material, length, width, displacement, steps, spacing, units, out } => {
            let s = scale(&units)?;
            check_out(&out)?;
            let card = MaterialCard::load(&material).map_err(input)?;
            let spec = BiasExtension {
                length: length * s,
                width: width * s,
                spacing: spacing * s,
                displacement: displacement * s,
                steps,
            };
            let result = bias_extension(&card, &spec).map_err(|m| input(anyhow::anyhow!(m)))?;
            let sample =
                serde_json::json!({"length": result.sample.0, "width": result.sample.1, "spacing": result.sample.2});
            let kinematics = BiasExtensionKinematics { length: spec.length, width: spec.width };
            let nominal = kinematics.shear(last_displacement(&result)).map(|g| g.0);
            finish_shear_test("bias-extension", &result, sample, &card, nominal, &out)
        }
        VirtualTest::Cantilever { material, direction, length, nodes, units, out } => {
            let length = length * scale(&units)?;
            let card = MaterialCard::load(&material).map_err(input)?;
            let fibre = match direction {
                Direction::Warp => Fibre::Warp,
                Direction::Weft => Fibre::Weft,
            };
            let result = cantilever(&card, fibre, length, nodes).map_err(|m| input(anyhow::anyhow!(m)))?;
            let nodes: Vec<[f64; 3]> = result.nodes.iter().map(|p| [p.x, p.y, p.z]).collect();
            let iterations: usize = result.steps.iter().map(|s| s.iterations.len()).sum();
            let json = serde_json::json!({
                "nodes": nodes,
                "converged": result.ok(),
                "load_steps": result.steps.len(),
                "iterations": iterations,
            });
            write_atomic(&out, |w| w.write_all(serde_json::to_string_pretty(&json).unwrap_or_default().as_bytes()))
                .map_err(compute)?;
            let tip = nodes.last().copied().unwrap_or_default();
            println!(
                "cantilever {:?}, {length} m, {} nodes: tip at x = {:.6} m, z = {:.6} m; {iterations} iterations",
                direction,
                nodes.len(),
                tip[0],
                tip[2]
            );
            if !result.ok() {
                return Err(compute(anyhow::anyhow!(
                    "the solver did not reach equilibrium; the last state was written to {}",
                    out.display()
                )));
            }
            Ok(())
        }
    }
}

/// Metres per unit of `--units`.
fn scale(units: &str) -> Result<f64, Failure> {
    unit_scale(units).map_err(|m| input(anyhow::anyhow!("--units: {m}")))
}

/// The crosshead displacement the test reached (0 before any step).
fn last_displacement(r: &ShearTest) -> f64 {
    r.displacement.last().copied().unwrap_or(0.0)
}

/// Refuse an output path whose directory does not exist (before any computation).
fn check_out(out: &std::path::Path) -> Result<(), Failure> {
    let dir = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => std::path::Path::new("."),
    };
    if !dir.is_dir() {
        return Err(input(anyhow::anyhow!("--out {}: the directory {} does not exist", out.display(), dir.display())));
    }
    if out.is_dir() {
        return Err(input(anyhow::anyhow!("--out {} is a directory: give a file name", out.display())));
    }
    Ok(())
}

/// Write a shear test's JSON, print a summary, and fail (exit code 1) if a load step did not
/// reach equilibrium (the file then holds the steps up to the last equilibrium). `nominal`: the
/// rig's shear (rad) at the displacement reached; with the largest cell shear it says whether
/// the card's shear law was used past its calibrated range.
fn finish_shear_test(
    name: &str,
    r: &ShearTest,
    sample: serde_json::Value,
    card: &MaterialCard,
    nominal: Option<f64>,
    out: &std::path::Path,
) -> Result<(), Failure> {
    let reached_deg = r.cell_shears().iter().flatten().fold(nominal.unwrap_or(0.0), |m, g| m.max(g.abs())).to_degrees();
    let warnings: Vec<String> = card.shear_range_warning(reached_deg).into_iter().collect();
    let nodes: Vec<serde_json::Value> = r
        .nodes
        .iter()
        .zip(&r.grid.active)
        .map(|(p, a)| if *a { serde_json::json!([p.x, p.y, p.z]) } else { serde_json::Value::Null })
        .collect();
    let shear: Vec<Option<f64>> = r.cell_shears().iter().map(|g| g.map(f64::to_degrees)).collect();
    let json = serde_json::json!({
        "test": name,
        "displacement": r.displacement,
        "force": r.force,
        "net": {"grid": [r.grid.nu, r.grid.nv], "spacing": r.grid.spacing, "nodes": nodes, "cell_shear_deg": shear},
        "sample": sample,
        "steps": {"requested": r.requested, "completed": r.completed},
        "converged": r.ok(),
        "iterations": r.iterations(),
        "notes": r.notes,
        "warnings": warnings,
    });
    let finite =
        r.force.iter().all(|f| f.is_finite()) && r.nodes.iter().all(|p| p.coords.iter().all(|c| c.is_finite()));
    if !finite {
        return Err(compute(anyhow::anyhow!(
            "the {name} test produced non-finite forces or positions; nothing was written"
        )));
    }
    write_atomic(out, |w| w.write_all(serde_json::to_string_pretty(&json).unwrap_or_default().as_bytes()))
        .map_err(compute)?;
    for note in &r.notes {
        println!("note: {note}");
    }
    for w in &warnings {
        println!("warning: {name} test: {w}");
    }
    let cells = r.cell_shears().iter().flatten().count();
    let (d, f) = (r.displacement.last().copied().unwrap_or(0.0), r.force.last().copied().unwrap_or(0.0));
    let gmax = r.cell_shears().iter().flatten().fold(0.0f64, |m, g| m.max(g.abs())).to_degrees();
    println!(
        "{name}: {cells} cells, spacing {:.6} m; {} of {} load steps, d = {d:.6} m, force {f:.6e} N, largest cell shear {gmax:.2} deg; \
         {} iterations; written to {}",
        r.grid.spacing,
        r.completed,
        r.requested,
        r.iterations(),
        out.display()
    );
    if !r.ok() {
        let last = r.solves.last().map(|s| format!("{:?}", s.outcome)).unwrap_or_default();
        return Err(compute(anyhow::anyhow!(
            "load step {} of {} did not reach equilibrium (solver: {last}) even in {} sub-steps; the state after step {} \
             (d = {d:.6} m) was written to {}",
            r.completed + 1,
            r.requested,
            1usize << crate::mechanics::virtual_tests::SHEAR_TEST_MAX_HALVINGS,
            r.completed,
            out.display()
        )));
    }
    Ok(())
}
