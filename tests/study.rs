//! `drape study`: the speed-accuracy study's error estimates against exact answers (the Chebyshev
//! net on a sphere, zero shear on a developable tool), the stability study naming known
//! failures, resuming, shards merged equal to the unsharded study, and bad input.
use crate::common;

use assert_cmd::Command;
use common::chebyshev::SphereChebyshev;
use drape::geometry::shapes;
use drape::study::runner::{collect, read_plan, CaseRecord};
use drape::study::speed_accuracy::SpeedAccuracy;
use drape::study::stability::Stability;
use std::path::{Path, PathBuf};

fn drape() -> Command {
    Command::cargo_bin("drape").unwrap()
}

fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

fn read<T: for<'de> serde::Deserialize<'de>>(path: &Path) -> T {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// The Richardson estimate never understates the true error by more than a factor 2: every
/// kinematic run on a finely faceted unit hemisphere, against the exact Chebyshev net at the
/// run's own cell centres.
#[test]
fn speed_accuracy_estimates_bound_the_chebyshev_error_on_a_sphere() {
    let dir = tempfile::tempdir().unwrap();
    // 800k facets: the facets' own error stays below the net's at these spacings.
    let tool = shapes::hemisphere_with_triangles(1.0, 800_000);
    std::fs::write(dir.path().join("sphere.obj"), tool.to_obj_string()).unwrap();
    // d0 = R/12, from the pole, |u|, |v| <= 0.83 R. At these spacings the net's own error stays
    // well above the facets' (about 0.002 deg at 800k facets), which no spacing study can see.
    let scene = r#"
units = "m"
tool = "sphere.obj"
[[ply]]
name = "cap"
origin = [0.0, 0.0, 1.0]
warp = [1.0, 0.0, 0.0]
spacing = 0.08333333333333333
grid = [21, 21]
"#;
    std::fs::write(dir.path().join("scene.toml"), scene).unwrap();
    let out = dir.path().join("study");
    let (r6, r12, r24) = (1.0 / 6.0, 1.0 / 12.0, 1.0 / 24.0);
    drape()
        .arg("study")
        .arg("speed-accuracy")
        .arg(dir.path().join("scene.toml"))
        .arg("--out")
        .arg(&out)
        .arg(format!("--spacings={r6},{r12},{r24}"))
        .args(["--repeats", "1", "--jobs", "1"])
        .assert()
        .success();
    let sa: SpeedAccuracy = read(&out.join("speed_accuracy.json"));
    assert_eq!(sa.reference.kind, "extrapolated", "no card: each method against its own limit");
    let exact = SphereChebyshev::new(1.0, 1.0);
    let plan = read_plan(&out).unwrap();
    let records: Vec<CaseRecord> = collect(&plan, &out).unwrap();
    let mut checked = 0;
    for (p, r) in sa.points.iter().zip(&records) {
        let field = r.result.field.as_ref().expect("kinematic runs keep their field");
        let mut true_max = 0.0f64;
        for (u, v) in field.complete_cell_centres() {
            if u.abs() <= 0.8 && v.abs() <= 0.8 {
                let s = field.at(u, v).unwrap();
                true_max = true_max.max((s - exact.shear(u, v).to_degrees()).abs());
            }
        }
        let est = p.error_max_deg.expect("every run is compared");
        println!("{} d = R/{:.0}: estimated {est:.5} deg, true {true_max:.5} deg", p.method, 1.0 / p.spacing);
        assert!(est >= 0.5 * true_max, "{} at d = {}: estimate {est} understates {true_max}", p.method, p.spacing);
        // Not trivially large either: within a factor 4 of the truth on the coarser runs.
        if p.spacing > r24 * 1.5 {
            assert!(est <= 4.0 * true_max, "{} at d = {}: estimate {est} vs {true_max}", p.method, p.spacing);
        }
        checked += 1;
    }
    assert_eq!(checked, 12, "geodesic and min-shear, on the facets and the smooth surface, at three spacings");
    assert!(sa.points.iter().any(|p| p.pareto));
    for f in ["speed_accuracy.png", "speed_accuracy.svg"] {
        assert!(std::fs::metadata(out.join(f)).unwrap().len() > 1000, "{f}");
    }
}

/// Shear below this (degrees) is rounding on a developable tool.
const FLOOR_DEG: f64 = 1e-4;

/// On the developable half cylinder every kinematic run has (nearly) zero shear, and so does
/// its estimated error.
#[test]
fn speed_accuracy_on_a_developable_tool_reports_near_zero_error() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("study");
    drape()
        .args(["study", "speed-accuracy"])
        .arg(repo("geometries/cylinder/scene.toml"))
        .arg("--out")
        .arg(&out)
        .args(["--spacings=0.008,0.004,0.002", "--repeats", "1"])
        .assert()
        .success();
    let sa: SpeedAccuracy = read(&out.join("speed_accuracy.json"));
    let plan = read_plan(&out).unwrap();
    let records = collect(&plan, &out).unwrap();
    for (p, r) in sa.points.iter().zip(&records) {
        // The true error is the shear itself (exact answer 0).
        let true_max = r.result.max_shear_deg.unwrap();
        let est = p.error_max_deg.unwrap();
        assert!(true_max < 0.05, "{}: shear {true_max} deg on a developable tool", p.method);
        // Below 1e-4 deg the shear is the surface's rounding floor (the smooth surface leaves
        // about 2e-5 deg), not a discretisation error a spacing study could see.
        assert!(
            est >= 0.5 * true_max - FLOOR_DEG && est < 0.05,
            "{} {}: estimate {est}, true {true_max}",
            p.method,
            p.surface
        );
        assert_eq!(p.outcome, "ok");
    }
}

/// Known failures are named with their reason: a shear limit below what the hemisphere needs,
/// and a spacing far above the tool's radius of curvature.
#[test]
fn stability_names_known_failures_and_maps_them() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("st");
    drape()
        .args(["study", "stability"])
        .arg(repo("geometries/hemisphere/scene.toml"))
        .arg("--out")
        .arg(&out)
        .args(["--ply", "p45", "--params", "spacing,angle,locking"])
        .assert()
        .success();
    let st: Stability = read(&out.join("stability.json"));
    assert_eq!(st.axes, ["spacing", "angle"]);
    let case = |name: &str, value: f64| {
        st.cases
            .iter()
            .find(|c| c.params.len() == 3 && c.params.get(name) == Some(&value))
            .unwrap_or_else(|| panic!("no case {name} = {value}"))
    };
    // The hemisphere needs about 50 deg at its rim: a 25 deg limit refuses cells.
    let locked = case("locking", 25.0);
    assert_eq!(locked.outcome, "shear_limit");
    assert!(locked.failures["shear_limit"] > 0 && locked.where_.contains_key("shear_limit"));
    assert!(locked.max_shear_deg.unwrap() <= 25.0 + 1e-6);
    // The scene's own ply drapes.
    let own = case("locking", 75.0);
    assert_eq!(own.outcome, "ok", "{own:?}");
    assert!(own.placed_fraction > 0.6);
    // 8 spacings of 4 mm on R = 0.1 m: d / R = 0.32 (the tool's radius estimate is within facets).
    let coarse = st.cases.iter().find(|c| c.params.get("spacing") == Some(&8.0)).unwrap();
    assert!(coarse.params["d_over_r"] > 0.25, "{:?}", coarse.params);
    assert_ne!(coarse.outcome, "ok", "a net of d = 0.32 R cannot follow the rim");
    // Every case of the map's product is there.
    assert_eq!(
        st.cases.iter().filter(|c| c.params.contains_key("spacing") && c.params.contains_key("angle")).count(),
        35
    );
    assert!(std::fs::metadata(out.join("stability.png")).unwrap().len() > 1000);
}

/// Two shards merged give the unsharded study's cases and results, and a study run again into
/// its folder resumes every case instead of running it.
#[test]
fn shards_merge_to_the_unsharded_study_and_runs_resume() {
    let dir = tempfile::tempdir().unwrap();
    let scene = repo("geometries/hemisphere/scene.toml");
    let args = ["--ply", "p0", "--params", "locking,pre_shear", "--axes", "locking,pre_shear"];
    let run = |out: &Path, extra: &[&str]| {
        drape().args(["study", "stability"]).arg(&scene).arg("--out").arg(out).args(args).args(extra).assert().success()
    };
    let whole = dir.path().join("whole");
    run(&whole, &[]);
    let again = run(&whole, &[]);
    let text = String::from_utf8_lossy(&again.get_output().stdout).to_string();
    assert!(text.contains("30 cases (30 from an earlier run)"), "{text}");
    let (s1, s2) = (dir.path().join("s1"), dir.path().join("s2"));
    run(&s1, &["--shard", "1/2"]);
    run(&s2, &["--shard", "2/2"]);
    assert!(!s1.join("stability.json").exists(), "a shard alone is not the study");
    let merged = dir.path().join("merged");
    drape().args(["study", "merge"]).arg(&s1).arg(&s2).arg("--out").arg(&merged).assert().success();
    let a: Stability = read(&whole.join("stability.json"));
    let b: Stability = read(&merged.join("stability.json"));
    assert_eq!(a.cases.len(), b.cases.len());
    for (x, y) in a.cases.iter().zip(&b.cases) {
        assert_eq!((&x.params, &x.outcome, &x.failures, &x.where_), (&y.params, &y.outcome, &y.failures, &y.where_));
        assert_eq!((x.placed_fraction, x.max_shear_deg), (y.placed_fraction, y.max_shear_deg));
    }
    // A shard folder of another study is refused by merge.
    let other = dir.path().join("other");
    drape()
        .args(["study", "stability"])
        .arg(&scene)
        .arg("--out")
        .arg(&other)
        .args(["--ply", "p0", "--params", "locking", "--axes", "locking,angle", "--shard", "1/2"])
        .assert()
        .success();
    let r =
        drape().args(["study", "merge"]).arg(&s1).arg(&other).arg("--out").arg(dir.path().join("m2")).assert().code(2);
    assert!(String::from_utf8_lossy(&r.get_output().stderr).contains("different studies"));
}

/// Bad input: exit 2 with what to do, and nothing computed is lost.
#[test]
fn study_refuses_bad_input_with_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let scene = repo("geometries/hemisphere/scene.toml");
    let out = dir.path().join("o");
    let cases: [(&[&str], &str); 5] = [
        (&["stability", "--axes", "spacing"], "give two parameters"),
        (&["stability", "--axes", "spacing,colour"], "unknown parameter 'colour'"),
        (&["stability", "--params", "tool"], "--tools"),
        (&["speed-accuracy", "--ply", "nope"], "no ply 'nope'"),
        (&["speed-accuracy", "--shard", "3/2"], "not a shard"),
    ];
    for (args, message) in cases {
        let r = drape().arg("study").arg(args[0]).arg(&scene).arg("--out").arg(&out).args(&args[1..]).assert().code(2);
        let err = String::from_utf8_lossy(&r.get_output().stderr).to_string();
        assert!(err.contains(message), "{args:?}: {err}");
    }
    // A folder holding another study is refused, not overwritten.
    drape()
        .args(["study", "stability"])
        .arg(&scene)
        .arg("--out")
        .arg(&out)
        .args(["--ply", "p0", "--params", "locking", "--axes", "locking,angle"])
        .assert()
        .success();
    let before = std::fs::read(out.join("stability.json")).unwrap();
    let r = drape()
        .args(["study", "stability"])
        .arg(&scene)
        .arg("--out")
        .arg(&out)
        .args(["--ply", "p0", "--params", "pre_shear", "--axes", "pre_shear,angle"])
        .assert()
        .code(2);
    assert!(String::from_utf8_lossy(&r.get_output().stderr).contains("holds another study"));
    assert_eq!(std::fs::read(out.join("stability.json")).unwrap(), before);
}

/// Stops the test's Slurm cluster however the test ends.
struct Cluster {
    conf: String,
}

impl Drop for Cluster {
    fn drop(&mut self) {
        let _ = std::process::Command::new(repo("tools/slurm-cluster")).arg("stop").status();
    }
}

/// `--slurm` writes a job array that runs the shards on a (one-node) Slurm cluster and merges
/// them into the same study an unsharded run writes.
#[test]
fn slurm_job_array_runs_the_shards_and_merges_them() {
    let start = std::process::Command::new(repo("tools/slurm-cluster")).arg("start").output().unwrap();
    assert!(start.status.success(), "tools/slurm-cluster start failed:\n{}", String::from_utf8_lossy(&start.stderr));
    let stdout = String::from_utf8_lossy(&start.stdout).to_string();
    let conf = stdout
        .lines()
        .find_map(|l| l.trim().strip_prefix("export SLURM_CONF="))
        .expect("start prints export SLURM_CONF=...")
        .trim_matches(['\'', '"'])
        .to_string();
    let cluster = Cluster { conf };
    let dir = tempfile::tempdir().unwrap();
    let scene = repo("geometries/hemisphere/scene.toml");
    let args = ["--ply", "p0", "--params", "locking", "--axes", "locking,angle"];
    let out = dir.path().join("slurm");
    let wrote = drape()
        .args(["study", "stability"])
        .arg(&scene)
        .arg("--out")
        .arg(&out)
        .args(args)
        .args(["--slurm", "3", "--jobs", "1"])
        .assert()
        .success();
    assert!(String::from_utf8_lossy(&wrote.get_output().stdout).contains("sbatch"));
    assert!(!out.join("stability.json").exists(), "--slurm only plans");
    let submitted = std::process::Command::new("sbatch")
        .env("SLURM_CONF", &cluster.conf)
        .args(["--parsable", "--kill-on-invalid-dep=yes"])
        .arg(out.join("study.sbatch"))
        .output()
        .unwrap();
    assert!(submitted.status.success(), "sbatch: {}", String::from_utf8_lossy(&submitted.stderr));
    // Bounded wait for the last task's merge.
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(600);
    while !out.join("merged").exists() {
        assert!(std::time::Instant::now() < deadline, "the job array did not finish in 600 s");
        std::thread::sleep(std::time::Duration::from_millis(500));
    }
    let whole = dir.path().join("whole");
    drape().args(["study", "stability"]).arg(&scene).arg("--out").arg(&whole).args(args).assert().success();
    let a: Stability = read(&whole.join("stability.json"));
    let b: Stability = read(&out.join("stability.json"));
    assert_eq!(a.cases.len(), b.cases.len());
    for (x, y) in a.cases.iter().zip(&b.cases) {
        assert_eq!((&x.params, &x.outcome, &x.failures), (&y.params, &y.outcome, &y.failures));
    }
    for k in 1..=3 {
        assert!(out.join(format!("shard-{k}")).join("done").exists(), "shard {k} ran");
    }
    assert!(out.join("stability.png").exists(), "the merge drew the map");
}

/// A study run into a run folder shows in that folder's report: its chart copied beside the
/// page and a section saying what it shows.
#[test]
fn the_report_shows_the_studies_of_its_folder() {
    let dir = tempfile::tempdir().unwrap();
    let run = dir.path().join("run");
    let scene = repo("geometries/cylinder/scene.toml");
    drape().arg("run").arg(&scene).arg("--out").arg(&run).assert().success();
    drape()
        .args(["study", "stability"])
        .arg(&scene)
        .arg("--out")
        .arg(run.join("stab"))
        .args(["--params", "locking", "--axes", "locking,angle"])
        .assert()
        .success();
    drape().arg("report").arg(&run).assert().success();
    let html = std::fs::read_to_string(run.join("report/index.html")).unwrap();
    assert!(html.contains("<h2 id=\"studies\">Studies</h2>"), "no study section");
    assert!(html.contains("src=\"study-stab-stability.png\""));
    assert!(html.contains("cases,"), "the section says what the map shows");
    assert!(std::fs::metadata(run.join("report/study-stab-stability.png")).unwrap().len() > 1000);
}
