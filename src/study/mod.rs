//! Studies: many drapes of one ply, to chart speed against accuracy
//! ([`speed_accuracy`]) and map where methods fail ([`stability`]).
//!
//! A study is a [`plan::Plan`] of independent cases, written to `DIR/study.json` first. The
//! [`runner`] runs them in parallel, each case's result written atomically as it finishes, so an
//! interrupted study resumes where it stopped; it runs one shard of N, merges shards and writes
//! a Slurm job array. [`finish`] turns the cases into the study's file once all are in; the
//! pictures are drawn by [`crate::report::study`]. An [`optimise`]ation is a study too: its cases
//! are the global search's candidate placements, and finishing it refines the best of them.
pub mod case;
pub mod optimise;
pub mod plan;
pub mod runner;
pub mod speed_accuracy;
pub mod stability;
pub mod symmetry;

pub use plan::{Plan, Shard, StudyKind, StudyMethod};

use runner::{collect, CaseRecord};
use std::path::{Path, PathBuf};

/// Why a study stopped.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    /// Bad input: the message says what to change.
    #[error("{0}")]
    Input(String),
    /// A file could not be written.
    #[error("{0}")]
    Write(String),
}

impl From<StudyError> for crate::pipeline::failure::Failure {
    /// Bad input is the user's to fix (exit code 2); a file that could not be written is a
    /// failed run (exit code 1).
    fn from(e: StudyError) -> Self {
        use crate::pipeline::failure::{compute, input};
        match e {
            StudyError::Input(_) => input(e),
            StudyError::Write(_) => compute(e),
        }
    }
}

/// A finished study's result.
#[derive(Debug, Clone, PartialEq)]
pub enum Finished {
    /// `speed_accuracy.json` (boxed: far larger than the other).
    SpeedAccuracy(Box<speed_accuracy::SpeedAccuracy>),
    /// `stability.json`.
    Stability(stability::Stability),
    /// `optimise.json` (boxed: it holds every candidate).
    Optimise(Box<optimise::Optimisation>),
}

/// If every case of the study in `dir` has its result, compute the study's result, write its
/// file into `dir` and return it with the file's path; else `None`.
pub fn finish(dir: &Path) -> Result<Option<(Finished, PathBuf)>, StudyError> {
    let plan = runner::read_plan(dir)?;
    let Ok(records) = collect(&plan, dir) else { return Ok(None) };
    Ok(Some(write_result(&plan, &records, dir)?))
}

fn write_pretty<T: serde::Serialize>(path: &Path, value: &T) -> Result<(), StudyError> {
    let text = serde_json::to_string_pretty(value).map_err(|e| StudyError::Write(e.to_string()))? + "\n";
    crate::io::write_atomic(path, |w| std::io::Write::write_all(w, text.as_bytes()))
        .map_err(|e| StudyError::Write(e.to_string()))
}

fn write_result(plan: &Plan, records: &[CaseRecord], dir: &Path) -> Result<(Finished, PathBuf), StudyError> {
    Ok(match plan.kind {
        StudyKind::SpeedAccuracy => {
            let r = speed_accuracy::evaluate(plan, records);
            let path = dir.join(speed_accuracy::FILE);
            write_pretty(&path, &r)?;
            (Finished::SpeedAccuracy(Box::new(r)), path)
        }
        StudyKind::Stability => {
            let r = stability::evaluate(plan, records);
            let path = dir.join(stability::FILE);
            write_pretty(&path, &r)?;
            (Finished::Stability(r), path)
        }
        StudyKind::Optimise => {
            let r = optimise::finish(plan, records, dir)?;
            let path = dir.join(optimise::FILE);
            write_pretty(&path, &r)?;
            (Finished::Optimise(Box::new(r)), path)
        }
    })
}

/// A warning when the cases of the study in `dir` shear the ply past the angle its material
/// card's shear law was calibrated to: how many cases, and how far. `None` within the range,
/// for a ply without a card or a card that records no range, or when the scene cannot be read
/// again.
pub fn shear_range_warning(dir: &Path) -> Option<String> {
    let plan = runner::read_plan(dir).ok()?;
    let (scene, k) = plan.scene_and_ply().ok()?;
    let ply = &scene.layup.plies[k];
    let card = ply.refinement.as_ref().map(|r| &r.material).or(ply.material.as_ref().map(|m| &m.card))?;
    let records = collect(&plan, dir).ok()?;
    let shears: Vec<f64> = records.iter().filter_map(|r| r.result.max_shear_deg).collect();
    let max = shears.iter().copied().fold(0.0, f64::max);
    let warning = card.shear_range_warning(max)?;
    let past = shears.iter().filter(|s| card.shear_range_warning(**s).is_some()).count();
    Some(format!("{past} of {} cases of ply '{}': {warning}", records.len(), plan.ply))
}

/// Run `plan` into `dir`: prepare the folder (or resume the study in it), run the cases of
/// `shard` `jobs` at a time, and when the folder then holds every case, write the study's file.
pub fn run_plan(
    plan: &Plan,
    dir: &Path,
    shard: Shard,
    jobs: usize,
    on_done: impl Fn(usize, usize) + Sync,
) -> Result<(runner::RunSummary, Option<(Finished, PathBuf)>), StudyError> {
    runner::prepare(plan, dir)?;
    let summary = runner::run(plan, dir, shard, jobs, on_done)?;
    Ok((summary, finish(dir)?))
}
