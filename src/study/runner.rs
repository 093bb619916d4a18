//! Running a study's cases: in parallel, each case's result written atomically to
//! `DIR/cases/case-NNNNN.json` as soon as it is known, so an interrupted study resumes where it
//! stopped; one shard of N at a time; shards merged; a Slurm job array written.
use super::case::{run_case, CaseResult};
use super::plan::{Case, Plan, Shard, PLAN_FILE};
use super::StudyError;
use crate::geometry::ToolSurface;
use crate::io::read_tool;
use crate::io::write_atomic;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// Folder of the case files in a study folder.
pub const CASES_DIR: &str = "cases";

/// A case file: the case and what it gave.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CaseRecord {
    /// The case as the plan gives it.
    pub case: Case,
    /// Its result.
    pub result: CaseResult,
}

fn case_path(dir: &Path, index: usize) -> PathBuf {
    dir.join(CASES_DIR).join(format!("case-{index:05}.json"))
}

fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<(), StudyError> {
    write_atomic(path, |w| {
        serde_json::to_writer(&mut *w, value).map_err(std::io::Error::other)?;
        w.write_all(b"\n")
    })
    .map_err(|e| StudyError::Write(e.to_string()))
}

fn read_json<T: for<'de> Deserialize<'de>>(path: &Path) -> Result<T, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    serde_json::from_str(&text).map_err(|e| format!("{} is not a study file: {e}", path.display()))
}

/// Read a study folder's plan.
pub fn read_plan(dir: &Path) -> Result<Plan, StudyError> {
    read_json(&dir.join(PLAN_FILE)).map_err(StudyError::Input)
}

/// Make `dir` a study folder for `plan`: create it and write the plan, or check that the plan
/// already there is this one (a resumed study). A folder holding another study is refused.
pub fn prepare(plan: &Plan, dir: &Path) -> Result<(), StudyError> {
    if dir.exists() && !dir.is_dir() {
        return Err(StudyError::Input(format!("--out {} is a file: give a folder", dir.display())));
    }
    std::fs::create_dir_all(dir.join(CASES_DIR)).map_err(|e| {
        StudyError::Input(format!("cannot create {}: {e}. Check the path and its permissions", dir.display()))
    })?;
    let path = dir.join(PLAN_FILE);
    if path.exists() {
        let old: Plan = read_json(&path).map_err(StudyError::Input)?;
        if &old != plan {
            return Err(StudyError::Input(format!(
                "{} holds another study (its {PLAN_FILE} differs): give another --out, or remove that folder to start again",
                dir.display()
            )));
        }
        return Ok(());
    }
    write_json(&path, plan)
}

/// The record of case `case` in `dir`, if it ran there (with this very case).
pub fn finished(dir: &Path, case: &Case) -> Option<CaseRecord> {
    let rec: CaseRecord = read_json(&case_path(dir, case.index)).ok()?;
    (&rec.case == case).then_some(rec)
}

/// The cases run at once: `asked`, else the machine's cores.
pub fn jobs_or_cores(asked: Option<usize>) -> usize {
    asked.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())).max(1)
}

/// What [`run`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RunSummary {
    /// Cases of the shard.
    pub cases: usize,
    /// Cases found finished from an earlier run.
    pub resumed: usize,
}

/// Run the cases of `shard` that have no result in `dir` yet, `jobs` at a time, calling
/// `on_done(done, total)` after each. The folder must be [`prepare`]d.
pub fn run(
    plan: &Plan,
    dir: &Path,
    shard: Shard,
    jobs: usize,
    on_done: impl Fn(usize, usize) + Sync,
) -> Result<RunSummary, StudyError> {
    let (scene, k) = plan.scene_and_ply()?;
    let base = &scene.layup.plies[k];
    let mine: Vec<&Case> = plan.cases.iter().filter(|c| shard.holds(c.index)).collect();
    let pending: Vec<&Case> = mine.iter().copied().filter(|c| finished(dir, c).is_none()).collect();
    let resumed = mine.len() - pending.len();
    // Every tool once, before timing anything.
    let mut tools: BTreeMap<PathBuf, ToolSurface> = BTreeMap::new();
    for c in &pending {
        if !tools.contains_key(&c.variant.tool) {
            let t = read_tool(&c.variant.tool, scene.scale).map_err(|e| StudyError::Input(e.to_string()))?;
            tools.insert(c.variant.tool.clone(), t);
        }
    }
    let done = AtomicUsize::new(resumed);
    on_done(resumed, mine.len());
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs.max(1))
        .build()
        .map_err(|e| StudyError::Write(format!("cannot start {jobs} worker threads: {e}")))?;
    pool.install(|| {
        pending.par_iter().try_for_each(|case| {
            let tool = &tools[&case.variant.tool];
            // A case that panics is a named failure of that case, not the end of the study.
            let result =
                std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| run_case(base, &scene.layup, case, tool)))
                    .unwrap_or_else(|panic| {
                        let what = panic
                            .downcast_ref::<String>()
                            .cloned()
                            .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                            .unwrap_or_default();
                        CaseResult::refused(format!("panic: {what}"), tool.num_triangles())
                    });
            write_json(&case_path(dir, case.index), &CaseRecord { case: (*case).clone(), result })?;
            on_done(done.fetch_add(1, Ordering::SeqCst) + 1, mine.len());
            Ok::<(), StudyError>(())
        })
    })?;
    Ok(RunSummary { cases: mine.len(), resumed })
}

/// Every case's record in `dir`, in plan order, or the first case that has none.
pub fn collect(plan: &Plan, dir: &Path) -> Result<Vec<CaseRecord>, usize> {
    plan.cases.iter().map(|c| finished(dir, c).ok_or(c.index)).collect()
}

/// Join shard folders into `out`: their plans must be one plan, and together they must hold
/// every case. Returns the plan.
pub fn merge(shards: &[PathBuf], out: &Path) -> Result<Plan, StudyError> {
    let first = shards.first().ok_or_else(|| StudyError::Input("give at least one shard folder".into()))?;
    let plan = read_plan(first)?;
    for s in &shards[1..] {
        if read_plan(s)? != plan {
            return Err(StudyError::Input(format!(
                "{} and {} hold different studies: merge shards of one study",
                first.display(),
                s.display()
            )));
        }
    }
    prepare(&plan, out)?;
    for case in &plan.cases {
        let rec = shards.iter().find_map(|s| finished(s, case)).ok_or_else(|| {
            StudyError::Input(format!(
                "case {} has no result in any of the shard folders: run its shard (or resume it) first",
                case.index
            ))
        })?;
        write_json(&case_path(out, case.index), &rec)?;
    }
    Ok(plan)
}

/// Write `dir/study.sbatch`: a Slurm job array of `shards` tasks, task K running shard K/N of
/// the plan in `dir` into `dir/shard-K` with `exe` (this program), and the last task to finish
/// merging the shards into `dir`. Returns its path.
pub fn write_sbatch(dir: &Path, shards: usize, exe: &Path, cpus: usize) -> Result<PathBuf, StudyError> {
    let dir = std::path::absolute(dir).map_err(|e| StudyError::Write(e.to_string()))?;
    let q = |p: &Path| format!("'{}'", p.display().to_string().replace('\'', r"'\''"));
    let (d, x) = (q(&dir), q(exe));
    let script = format!(
        r#"#!/bin/bash
# A drape study as a Slurm job array: task K runs shard K/{shards} of the plan in this folder,
# and whichever task finishes last merges the shards into the folder. Submit with
#   sbatch {sbatch}
#SBATCH --job-name=drape-study
#SBATCH --array=1-{shards}
#SBATCH --cpus-per-task={cpus}
#SBATCH --chdir={d}
#SBATCH --output={d}/slurm-%A_%a.out
set -euo pipefail
k=$SLURM_ARRAY_TASK_ID
{x} study shard {d}/{PLAN_FILE} --shard "$k/{shards}" --out {d}/shard-"$k" --jobs {cpus}
touch {d}/shard-"$k"/done
# One merge, by the last task to finish (the lock keeps two from racing).
exec 9>{d}/merge.lock
flock 9
shards=()
for i in $(seq 1 {shards}); do
    [ -e {d}/shard-"$i"/done ] || exit 0
    shards+=({d}/shard-"$i")
done
[ -e {d}/merged ] && exit 0
{x} study merge "${{shards[@]}}" --out {d}
touch {d}/merged
"#,
        sbatch = dir.join("study.sbatch").display(),
    );
    let path = dir.join("study.sbatch");
    write_atomic(&path, |w| w.write_all(script.as_bytes())).map_err(|e| StudyError::Write(e.to_string()))?;
    Ok(path)
}
