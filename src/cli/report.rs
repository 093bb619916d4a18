//! `drape report DIR`: pictures and an HTML page of a run's output folder.
use super::{compute, input, Failure};
use crate::io::ExportError;
use crate::report::{write_report, ReportError};
use clap::Args;
use std::path::PathBuf;

/// Arguments of `drape report`.
#[derive(Debug, Args)]
pub struct ReportArgs {
    /// Folder written by `drape run --out` (holds `<ply>.drape.json` and maybe `layup.json`).
    pub dir: PathBuf,
    /// Report folder (default: DIR/report).
    #[arg(long)]
    pub out: Option<PathBuf>,
}

pub fn run(a: ReportArgs) -> Result<(), Failure> {
    let out = a.out.clone().unwrap_or_else(|| a.dir.join("report"));
    let summary = write_report(&a.dir, &out, true).map_err(|e| match e {
        // Failing to write or draw is not the input's fault.
        ReportError::CreateDir { .. } | ReportError::Draw { .. } | ReportError::Net(ExportError::Write { .. }) => {
            compute(e)
        }
        _ => input(e),
    })?;
    for p in &summary.plies {
        println!(
            "ply {}: {} cells, max |shear| {:.1} deg, mean {:.1} deg (locking {:.0} deg){}",
            p.name,
            p.cells,
            p.max_abs_shear_deg,
            p.mean_abs_shear_deg,
            p.locking_angle_deg,
            if p.tool_drawn { "" } else { ", tool not drawn" }
        );
    }
    for n in &summary.notes {
        println!("  note: {n}");
    }
    println!("wrote {} files; open {}", summary.files.len(), out.join("index.html").display());
    Ok(())
}
