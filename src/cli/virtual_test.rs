//! `drape test ...`: virtual material tests writing JSON.
use super::{compute, input, Failure};
use crate::export::write_atomic;
use crate::material::{Fibre, MaterialCard};
use crate::mechanics::virtual_tests::cantilever;
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
        /// Free length of the strip, m.
        #[arg(long)]
        length: f64,
        /// Nodes along the strip.
        #[arg(long, default_value_t = 21)]
        nodes: usize,
        /// Output JSON file: {"nodes": [[x,y,z], ...]} from the clamp to the tip.
        #[arg(long)]
        out: PathBuf,
    },
}

pub fn run(a: TestArgs) -> Result<(), Failure> {
    match a.test {
        VirtualTest::Cantilever { material, direction, length, nodes, out } => {
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
                return Err(compute(anyhow::anyhow!("the solver did not reach equilibrium; the last state was written to {}", out.display())));
            }
            Ok(())
        }
    }
}
