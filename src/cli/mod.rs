//! The `drape` command line: argument parsing and subcommands; nothing numerical lives here.
mod bench;
mod calibrate;
mod export;
mod kinematic;
mod optimise;
mod progress;
mod refine;
mod report;
mod run;
mod study;
mod summary;
mod virtual_test;

use clap::{Parser, Subcommand};

// The failure type lives in the library, so the Python package reports the same messages.
pub(crate) use crate::pipeline::failure::{compute, input, write_failure};
pub use crate::pipeline::failure::{Failure, EXIT_BAD_INPUT, EXIT_FAILED};
pub use crate::pipeline::parse_vec3;

/// Plan how composite plies lie on a part: kinematic (fishnet) drape on OBJ tool surfaces.
#[derive(Debug, Parser)]
#[command(name = "drape", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Drape one ply on a tool with the kinematic (pin-jointed net) method.
    Kinematic(kinematic::KinematicArgs),
    /// Drape every ply of a scene file.
    Run(run::RunArgs),
    /// Refine a kinematic net mechanically (tension, shear, bending, gravity, tool contact).
    Refine(refine::RefineArgs),
    /// Map a draped net onto a resin-flow mesh and write fibre directions, shear, thickness and Vf.
    Export(export::ExportArgs),
    /// Fit a material card's shear or knit tension law to test data.
    Calibrate(calibrate::CalibrateArgs),
    /// Virtual material tests on the mechanical model.
    Test(virtual_test::TestArgs),
    /// Measure the kinematic engine's throughput (placed cells per second) on a generated hemisphere.
    Bench(bench::BenchArgs),
    /// Draw every ply of a run folder (shear maps, histograms, changes) and write an HTML page.
    Report(report::ReportArgs),
    /// Studies of one ply: speed against accuracy, where methods fail; sharded, resumable.
    Study(study::StudyArgs),
    /// The best seed and angle of a ply: a global search of candidate drapes, refined locally.
    Optimise(optimise::OptimiseArgs),
}

/// Run a parsed command line.
pub fn run(cli: Cli) -> Result<(), Failure> {
    match cli.command {
        Command::Kinematic(a) => kinematic::run(a),
        Command::Run(a) => run::run(a),
        Command::Refine(a) => refine::run(a),
        Command::Bench(a) => bench::run(a),
        Command::Test(a) => virtual_test::run(a),
        Command::Calibrate(a) => calibrate::run(a),
        Command::Export(a) => export::run(a),
        Command::Report(a) => report::run(a),
        Command::Study(a) => study::run(a),
        Command::Optimise(a) => optimise::run(a),
    }
}

/// `n` and what it counts, in the singular for one: "1 element", "2 elements".
pub(crate) fn counted(n: usize, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

/// Parse `A,B` into two whole numbers.
pub fn parse_pair(s: &str) -> Result<[usize; 2], String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let nums: Result<Vec<usize>, _> = parts.iter().map(|p| p.parse::<usize>()).collect();
    match nums {
        Ok(v) if v.len() == 2 => Ok([v[0], v[1]]),
        _ => Err(format!("'{s}' is not a pair: give two whole numbers separated by a comma, like 101,101")),
    }
}
