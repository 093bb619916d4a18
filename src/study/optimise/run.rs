//! An optimisation from the options `drape optimise` and `drape.optimise` take to its result:
//! the options checked and converted to the search's ([`Request::options`]), the search planned
//! ([`super::candidates::plan`]), the global search run into its folder (the whole of it, or one
//! shard), and the result finished once every candidate is in ([`super::finish()`]). The command
//! line and the Python package both call [`optimise`], so they search alike and refuse alike.
use super::candidates::plan_for;
use super::{AngleRange, Objective, Optimisation, Options, SeedRegion, DEFAULT_MAX_CANDIDATES, DEFAULT_REFINE_STARTS};
use crate::io::points::read_points;
use crate::pipeline::{parse_vec3, Scene};
use crate::study::runner::{self, RunSummary};
use crate::study::{finish, Finished, Plan, Shard, StudyError};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What is varied unless the user says: the seed and the angle.
pub const DEFAULT_VARY: &str = "seed,angle";
/// The angles tried unless the user says, degrees (a balanced fabric at a + 90 deg is the same
/// ply).
pub const DEFAULT_ANGLE_RANGE: [f64; 2] = [-45.0, 45.0];
/// The angles' step unless the user says, degrees.
pub const DEFAULT_ANGLE_STEP: f64 = 5.0;
/// What is minimised unless the user says.
pub const DEFAULT_OBJECTIVE: &str = "max-shear";

/// A seed polygon as the user gives it.
#[derive(Debug, Clone, PartialEq)]
pub enum PolygonArg {
    /// A points file (x,y,z per line), or the corners as text, `x,y,z;x,y,z;...`.
    Text(String),
    /// The corners.
    Points(Vec<[f64; 3]>),
}

/// The options of an optimisation as the user gives them: the command line's `drape optimise`
/// options (the Python keywords have the same names), lengths in the scene's units. The
/// defaults ([`Request::default`]) are the command line's.
#[derive(Debug, Clone, PartialEq)]
pub struct Request {
    /// The ply to place (default: the scene's first).
    pub ply: Option<String>,
    /// What is varied: `seed`, `angle` or `seed,angle`.
    pub vary: String,
    /// The seed region: within this distance of the ply's origin.
    pub seed_radius: Option<f64>,
    /// The seed region: a closed polygon on the tool.
    pub seed_polygon: Option<PolygonArg>,
    /// The seed lattice's step (default: an eighth of the region's size).
    pub seed_step: Option<f64>,
    /// The lowest and highest ply angle tried, degrees.
    pub angle_range: [f64; 2],
    /// The angles' step, degrees.
    pub angle_step: f64,
    /// What is minimised: `max-shear`, `locked-area`, `mean-shear`, `coverage` or a weighted
    /// sum like `max-shear:1,coverage:0.5`.
    pub objective: String,
    /// The global search's fibre spacing (default: twice the ply's).
    pub spacing: Option<f64>,
    /// Candidates of the global search refined at the ply's spacing.
    pub refine: usize,
    /// The most candidates the search may have.
    pub max_candidates: usize,
}

impl Default for Request {
    fn default() -> Request {
        Request {
            ply: None,
            vary: DEFAULT_VARY.into(),
            seed_radius: None,
            seed_polygon: None,
            seed_step: None,
            angle_range: DEFAULT_ANGLE_RANGE,
            angle_step: DEFAULT_ANGLE_STEP,
            objective: DEFAULT_OBJECTIVE.into(),
            spacing: None,
            refine: DEFAULT_REFINE_STARTS,
            max_candidates: DEFAULT_MAX_CANDIDATES,
        }
    }
}

fn bad(message: String) -> StudyError {
    StudyError::Input(message)
}

/// `LO,HI`: the lowest and highest ply angle, degrees (`--angle-range`).
pub fn parse_angle_range(text: &str) -> Result<[f64; 2], StudyError> {
    let refuse = || bad(format!("--angle-range: '{text}' is not LO,HI: give two angles in degrees, like -45,45"));
    let range: Vec<f64> =
        text.split(',').map(|x| x.trim().parse::<f64>()).collect::<Result<_, _>>().map_err(|_| refuse())?;
    match range[..] {
        [lo, hi] => Ok([lo, hi]),
        _ => Err(refuse()),
    }
}

/// `seed`, `angle` or `seed,angle`: whether the seed and whether the angle are varied.
fn parse_vary(text: &str) -> Result<(bool, bool), StudyError> {
    let (mut seed, mut angle) = (false, false);
    for v in text.split(',').map(str::trim) {
        match v {
            "seed" => seed = true,
            "angle" => angle = true,
            other => return Err(bad(format!("--vary: unknown '{other}': give seed, angle or seed,angle"))),
        }
    }
    Ok((seed, angle))
}

/// A seed polygon's corners in metres: a points file, `x,y,z;x,y,z;...`, or the corners, in
/// the scene's units (`scale` metres each).
fn polygon(arg: &PolygonArg, scale: f64) -> Result<Vec<[f64; 3]>, StudyError> {
    let scaled = |p: [f64; 3]| p.map(|x| x * scale);
    match arg {
        PolygonArg::Points(points) => Ok(points.iter().copied().map(scaled).collect()),
        PolygonArg::Text(text) => {
            let path = Path::new(text);
            if path.is_file() {
                Ok(read_points(path, scale)
                    .map_err(|m| bad(format!("--seed-polygon: {m}")))?
                    .into_iter()
                    .map(|p| p.coords.into())
                    .collect())
            } else if text.contains(';') {
                text.split(';')
                    .filter(|p| !p.trim().is_empty())
                    .map(|p| parse_vec3(p).map(scaled))
                    .collect::<Result<Vec<_>, _>>()
                    .map_err(|m| bad(format!("--seed-polygon: {m}")))
            } else {
                Err(bad(format!(
                    "--seed-polygon: {text} is not a file, nor points x,y,z;x,y,z;...: give a points file or the corners"
                )))
            }
        }
    }
}

impl Request {
    /// The search's options (lengths in metres: the scene's units are `scale` metres), or what
    /// is wrong with the request.
    pub fn options(&self, scale: f64) -> Result<Options, StudyError> {
        let objective = Objective::parse(&self.objective).map_err(bad)?;
        let (vary_seed, vary_angle) = parse_vary(&self.vary)?;
        let region = match (self.seed_radius, &self.seed_polygon) {
            (Some(_), Some(_)) => return Err(bad("give --seed-radius or --seed-polygon, not both".into())),
            (Some(r), None) => Some(SeedRegion::Disc { radius: r * scale }),
            (None, Some(p)) => Some(SeedRegion::Polygon { points: polygon(p, scale)? }),
            (None, None) => None,
        };
        let [lo, hi] = self.angle_range;
        Ok(Options {
            ply: self.ply.clone(),
            vary_seed,
            vary_angle,
            seed_step: self.seed_step.map(|h| h * scale),
            angles: AngleRange { lo, hi, step: self.angle_step },
            spacing: self.spacing.map(|d| d * scale),
            refine_starts: self.refine,
            max_candidates: self.max_candidates,
            ..Options::new(objective, region)
        })
    }
}

/// What [`optimise`] did.
#[derive(Debug, Clone)]
pub struct Optimised {
    /// The search as planned: its cases are the candidate placements.
    pub plan: Plan,
    /// The cases of the shard run, and how many of them an earlier run into the folder had
    /// finished.
    pub summary: RunSummary,
    /// Wall time of running the shard's cases (the global search, not the refinement), s.
    pub search_s: f64,
    /// The result and the path of its file (`optimise.json`), once every candidate is in:
    /// after the whole search, or after the last of its shards in one folder. `None` while
    /// shards are missing (`drape study merge` joins shard folders and finishes).
    pub result: Option<(Optimisation, PathBuf)>,
}

/// Plan the optimisation `request` asks of `scene`, run its global search (the cases of `shard`
/// that `out` does not hold yet, `jobs` at a time) into the folder `out`, and when the folder
/// then holds every candidate, refine the best, write `optimise.json` and the scene with the
/// optimal ply (`optimal.toml`) and return the result. `on_planned` is called with the plan
/// before any drape, `on_done(done, total)` after each case.
pub fn optimise(
    scene: &Scene,
    request: &Request,
    out: &Path,
    shard: Shard,
    jobs: usize,
    on_planned: impl FnOnce(&Plan),
    on_done: impl Fn(usize, usize) + Sync,
) -> Result<Optimised, StudyError> {
    let opts = request.options(scene.scale)?;
    let plan = plan_for(scene, &opts)?;
    on_planned(&plan);
    let started = Instant::now();
    runner::prepare(&plan, out)?;
    let summary = runner::run(&plan, out, shard, jobs, on_done)?;
    let search_s = started.elapsed().as_secs_f64();
    let result = match finish(out)? {
        Some((Finished::Optimise(o), path)) => Some((*o, path)),
        Some(_) => return Err(bad(format!("{} holds another study: give another --out", out.display()))),
        None => None,
    };
    Ok(Optimised { plan, summary, search_s, result })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_request_converts_to_the_searchs_options_in_metres() {
        let r = Request {
            seed_polygon: Some(PolygonArg::Text("0,0,1;10,0,1;0,10,1".into())),
            seed_step: Some(2.0),
            angle_range: parse_angle_range("-30, 60").unwrap(),
            vary: "angle, seed".into(),
            objective: "max-shear:1,coverage:0.5".into(),
            ..Request::default()
        };
        let o = r.options(0.001).unwrap();
        assert!(o.vary_seed && o.vary_angle);
        assert_eq!(o.seed_step, Some(0.002));
        assert_eq!((o.angles.lo, o.angles.hi, o.angles.step), (-30.0, 60.0, DEFAULT_ANGLE_STEP));
        let Some(SeedRegion::Polygon { points }) = o.region else { panic!("{:?}", o.region) };
        assert_eq!(points, vec![[0.0, 0.0, 0.001], [0.01, 0.0, 0.001], [0.0, 0.01, 0.001]]);
        let given = Request { seed_polygon: Some(PolygonArg::Points(vec![[0.0, 0.0, 1.0]; 3])), ..r.clone() };
        let Some(SeedRegion::Polygon { points }) = given.options(0.001).unwrap().region else { panic!() };
        assert_eq!(points, vec![[0.0, 0.0, 0.001]; 3]);
        let say = |r: Request| r.options(1.0).unwrap_err().to_string();
        assert!(say(Request { vary: "tilt".into(), ..Request::default() }).contains("--vary: unknown 'tilt'"));
        assert!(say(Request { seed_radius: Some(1.0), ..r.clone() }).contains("not both"));
        assert!(say(Request { objective: "wrinkles".into(), ..Request::default() }).contains("'wrinkles'"));
        assert!(parse_angle_range("-45").unwrap_err().to_string().contains("LO,HI"));
    }
}
