//! `drape optimise`: the seed and angle of a ply that minimise an objective (largest or mean
//! shear, area past the locking angle, uncovered share, or a weighted sum of them).
//!
//! An optimisation is a study ([`super::Plan`] of kind `optimise`): its cases are the candidate
//! placements of the global search ([`candidates`]: every seed of a lattice over the seed
//! region, projected onto the tool, at every angle of the range), each a full kinematic drape at
//! the search's coarse spacing, run in parallel by the study runner, so shards, `study merge`,
//! resuming and Slurm arrays work as for the other studies. When every case is in, [`finish`]
//! ranks them, refines the best few by a pattern search ([`refine`]) at the ply's own spacing,
//! and writes `optimise.json` ([`Optimisation`]) and the scene with the optimal ply
//! ([`scene_file`]); the landscape pictures are drawn by `crate::report::optimise`. [`optimise`]
//! ([`run`]) does all of it from the options as the user gives them, for the command line and
//! the Python package.
//!
//! The ply is draped alone on the tool (a ply higher in the stack is searched on the tool, not
//! on the plies below it), kinematically with its own generators, as `drape run` drapes it
//! before any mechanics.
pub mod candidates;
pub mod finish;
pub mod objective;
pub mod refine;
pub mod region;
pub mod run;
pub mod scene_file;

pub use candidates::{plan, Options};
pub use finish::finish;
pub use objective::{Measure, Objective};
pub use region::{Frame, SeedRegion};
pub use run::{optimise, Optimised, PolygonArg, Request};

use super::case::CaseStats;
use serde::{Deserialize, Serialize};

/// The result file in an optimisation's folder.
pub const FILE: &str = "optimise.json";
/// The scene with the optimal ply, in the same folder.
pub const SCENE_FILE: &str = "optimal.toml";
/// The most candidates a global search may have unless the user raises the limit.
pub const DEFAULT_MAX_CANDIDATES: usize = 10_000;
/// Candidates refined locally when not given.
pub const DEFAULT_REFINE_STARTS: usize = 3;
/// Most drapes of each local refinement (its start included).
pub const REFINE_BUDGET: usize = 60;
/// A refinement stops when its steps are below the global search's lattice and angle steps
/// times this.
pub const REFINE_SHRINK: f64 = 1.0 / 16.0;

/// The ply angles a search tries: `lo`, `lo + step`, ... up to `hi`, degrees.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AngleRange {
    /// Lowest angle, degrees.
    pub lo: f64,
    /// Highest angle, degrees.
    pub hi: f64,
    /// Step, degrees.
    pub step: f64,
}

impl AngleRange {
    /// The angles tried, each `lo + k step` (not accumulated, so mirror-symmetric ranges give
    /// exactly opposite angles).
    pub fn values(&self) -> Vec<f64> {
        let n = ((self.hi - self.lo) / self.step + ANGLE_SLACK).floor().max(0.0) as usize;
        (0..=n).map(|k| self.lo + k as f64 * self.step).collect()
    }

    /// Whether `a` lies in the range.
    pub fn contains(&self, a: f64) -> bool {
        let slack = ANGLE_SLACK * self.step;
        a >= self.lo - slack && a <= self.hi + slack
    }
}

/// Share of a step by which an angle may pass the range's end (rounding).
const ANGLE_SLACK: f64 = 1e-9;

/// What an optimisation searches: stored in its plan (`study.json`), so every shard and the
/// merge agree.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Search {
    /// What is minimised.
    pub objective: Objective,
    /// The plane the seeds are laid out in.
    pub frame: Frame,
    /// Where the seed may lie; `None`: the ply's own seed.
    pub region: Option<SeedRegion>,
    /// The seed lattice's step, m.
    pub seed_step: f64,
    /// The angles tried; `None`: the ply's own orientation.
    pub angles: Option<AngleRange>,
    /// The ply's own spacing, m: the refinement's and the check's.
    pub ply_spacing: f64,
    /// Candidates of the global search refined locally.
    pub refine_starts: usize,
}

/// One placement at the ply's spacing, refined from a candidate of the global search.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Placement {
    /// The seed on the tool, m.
    pub origin: [f64; 3],
    /// Its coordinates in the seed plane ([`Frame`]), m.
    pub seed_ab: [f64; 2],
    /// The ply angle, degrees (`None`: the ply's own warp).
    pub angle_deg: Option<f64>,
    /// The objective.
    pub objective: f64,
    /// The figures it is made of.
    pub stats: CaseStats,
    /// The spacing it was draped at, m.
    pub spacing: f64,
    /// `ok` or the drape's dominant node failure.
    pub outcome: String,
    /// The candidate of the global search it was refined from.
    pub start: Start,
}

/// A refinement's start: the global search's candidate and its objective at both spacings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Start {
    /// The candidate's number (its case).
    pub candidate: usize,
    /// Its objective at the search's spacing.
    pub search_objective: f64,
    /// Its objective at the ply's spacing: the difference is the coarse search's error there.
    pub ply_spacing_objective: f64,
    /// Drapes the refinement ran (the start's at the ply's spacing included).
    pub evaluations: usize,
}

/// One candidate of the global search.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Candidate {
    /// Its number (its case).
    pub index: usize,
    /// The seed's plane coordinates, m.
    pub seed_ab: [f64; 2],
    /// The seed on the tool, m.
    pub origin: [f64; 3],
    /// The ply angle, degrees (`None`: the ply's own warp).
    pub angle_deg: Option<f64>,
    /// Its objective, `None` when it gave no complete cell.
    pub objective: Option<f64>,
    /// `ok` or why not.
    pub outcome: String,
}

/// `optimise.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Optimisation {
    /// The ply.
    pub ply: String,
    /// What was minimised, in words.
    pub objective_text: String,
    /// The search as planned.
    pub search: Search,
    /// The global search's spacing, m.
    pub search_spacing: f64,
    /// The best placement, at the ply's spacing.
    pub best: Placement,
    /// The other refined placements, best first (distinct from the best and each other).
    pub runners_up: Vec<Placement>,
    /// Every candidate of the global search, in plan order: the objective's landscape.
    pub landscape: Vec<Candidate>,
    /// Candidates that gave a complete cell.
    pub feasible: usize,
    /// Time of the global search's drapes summed over the candidates, s.
    pub search_drape_s: f64,
    /// Wall time of the local refinements, s.
    pub refine_s: f64,
    /// The scene with the optimal ply (a file in the optimisation's folder).
    pub scene: String,
}
