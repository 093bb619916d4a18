//! `drape calibrate`: fits written into a new card with the range they were calibrated over and
//! a fit report beside it, several sample sizes at once, bad data refused with the line number;
//! the warnings of every command that uses a shear law past that range.
use assert_cmd::Command;
use drape::material::calibrate::{bias_extension_force, knit_stress, picture_frame_force};
use drape::material::{Fibre, KnitParams, MaterialCard, ShearLaw, TensionLaw};
use std::path::{Path, PathBuf};

/// Deterministic pseudo-noise in [-1, 1].
fn noise(i: usize) -> f64 {
    let mut x = (i as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    x ^= x >> 31;
    x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x ^= x >> 29;
    (x >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
}

/// A synthetic bias-extension test of `law` on an `l` x `w` sample (m): `n` points up to the
/// elongation `d_max` (m), relative noise `amp`, written in mm.
fn bias_test_mm(law: &ShearLaw, l: f64, w: f64, d_max: f64, n: usize, amp: f64, seed: usize) -> Vec<(f64, f64)> {
    (1..=n)
        .map(|i| {
            let d = d_max * i as f64 / n as f64;
            (d * 1e3, bias_extension_force(law, d, l, w).unwrap() * (1.0 + amp * noise(seed * 10_007 + i)))
        })
        .collect()
}

fn stdout(a: &assert_cmd::assert::Assert) -> String {
    String::from_utf8_lossy(&a.get_output().stdout).to_string()
}

fn drape() -> Command {
    Command::cargo_bin("drape").unwrap()
}

fn base_card(dir: &Path) -> PathBuf {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("materials/glass-plain-weave.toml");
    let p = dir.join("base.toml");
    std::fs::copy(src, &p).unwrap();
    p
}

fn write_csv(dir: &Path, name: &str, header: &str, pts: &[(f64, f64)]) -> PathBuf {
    let mut s = format!("{header}\n");
    for (x, y) in pts {
        s += &format!("{x},{y}\n");
    }
    let p = dir.join(name);
    std::fs::write(&p, s).unwrap();
    p
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn picture_frame_two_slope_in_mm() {
    let dir = tempfile::tempdir().unwrap();
    let card = base_card(dir.path());
    let truth = ShearLaw::TwoSlope { g1: 4.0, g2: 120.0, locking_angle_deg: 33.0 };
    let side = 0.15;
    let pts: Vec<(f64, f64)> = (1..=200)
        .map(|i| {
            let d = 0.06 * i as f64 / 200.0;
            (d * 1e3, picture_frame_force(&truth, d, side).unwrap())
        })
        .collect();
    let data = write_csv(dir.path(), "pf.csv", "displacement_mm,force_N", &pts);
    let out = dir.path().join("fitted.toml");
    let assert = drape()
        .args(["calibrate", "picture-frame", "--data", s(&data), "--side", "150", "--units", "mm"])
        .args(["--law", "two-slope", "--card", s(&card), "--out", s(&out), "--name", "glass-fitted"])
        .assert()
        .success();
    let stdout = String::from_utf8_lossy(&assert.get_output().stdout).to_string();
    assert!(stdout.contains("R^2") && stdout.contains("rms relative error") && stdout.contains("0-5"), "{stdout}");
    let fitted = MaterialCard::load(&out).unwrap();
    // Every point is fitted by default for a picture frame: the card is calibrated to the data's
    // reach (d = 60 mm on a 150 mm frame: 90 - 2 acos(1/sqrt 2 + 0.2) = 40.22 deg).
    let reach = fitted.shear_calibrated_max_deg.unwrap();
    let expected = 90.0 - 2.0 * (std::f64::consts::FRAC_1_SQRT_2 + 0.2).acos().to_degrees();
    assert!((reach - expected).abs() < 1e-9, "{reach} vs {expected}");
    let base = MaterialCard::load(&card).unwrap();
    assert_eq!(fitted.name, "glass-fitted");
    assert_eq!((fitted.tension, fitted.bending, fitted.areal_mass), (base.tension, base.bending, base.areal_mass));
    assert!(fitted.source.as_deref().unwrap().contains("picture-frame"));
    match fitted.shear {
        ShearLaw::TwoSlope { g1, g2, locking_angle_deg } => {
            assert!((g1 / 4.0 - 1.0).abs() < 1e-6 && (g2 / 120.0 - 1.0).abs() < 1e-6, "{g1} {g2}");
            assert!((locking_angle_deg / 33.0 - 1.0).abs() < 1e-6, "{locking_angle_deg}");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn bias_extension_polynomial() {
    let dir = tempfile::tempdir().unwrap();
    let card = base_card(dir.path());
    let truth = ShearLaw::Polynomial { coefficients: vec![1.5, 4.0, 30.0] };
    let (l, w) = (0.2, 0.08);
    let pts: Vec<(f64, f64)> = (0..=100)
        .map(|i| {
            let d = 0.04 * i as f64 / 100.0;
            (d, bias_extension_force(&truth, d, l, w).unwrap())
        })
        .collect();
    let data = write_csv(dir.path(), "be.csv", "d,F", &pts);
    let out = dir.path().join("fitted.toml");
    drape()
        .args(["calibrate", "bias-extension", "--data", s(&data), "--length", "0.2", "--width", "0.08"])
        .args(["--law", "polynomial:3", "--card", s(&card), "--out", s(&out)])
        .assert()
        .success();
    match MaterialCard::load(&out).unwrap().shear {
        ShearLaw::Polynomial { coefficients } => {
            for (a, b) in coefficients.iter().zip([1.5, 4.0, 30.0]) {
                assert!((a / b - 1.0).abs() < 1e-6, "{coefficients:?}");
            }
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn knit_weft() {
    let dir = tempfile::tempdir().unwrap();
    let card = base_card(dir.path());
    let truth = KnitParams { c: 300.0, beta: 15.0, alpha: 2.0 };
    let pts: Vec<(f64, f64)> =
        (0..=80).map(|i| (0.45 * i as f64 / 80.0, knit_stress(&truth, 0.45 * i as f64 / 80.0))).collect();
    let data = write_csv(dir.path(), "knit.csv", "strain,stress_N_per_m", &pts);
    let out = dir.path().join("knit.toml");
    drape()
        .args(["calibrate", "knit", "--data", s(&data), "--direction", "weft", "--card", s(&card), "--out", s(&out)])
        .assert()
        .success();
    let fitted = MaterialCard::load(&out).unwrap();
    match fitted.tension.law {
        TensionLaw::Knit { warp, weft } => {
            assert_eq!(warp, KnitParams { c: 8.0e6, beta: 0.0, alpha: 0.0 }); // the base card's linear warp
            assert!((weft.c / 300.0 - 1.0).abs() < 1e-6 && (weft.beta / 15.0 - 1.0).abs() < 1e-6, "{weft:?}");
            assert!((weft.alpha / 2.0 - 1.0).abs() < 1e-6, "{weft:?}");
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(fitted.tension(Fibre::Warp, 0.001).1, 8.0e3);
}

#[test]
fn bad_input_exits_2_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let card = base_card(dir.path());
    let out = dir.path().join("never.toml");
    let bad = dir.path().join("bad.csv");
    std::fs::write(&bad, "d,F\n0.001,1.0\n0.002,oops\n").unwrap();
    let good = write_csv(dir.path(), "good.csv", "d,F", &[(0.001, 1.0), (0.002, 2.0), (0.003, 3.5), (0.004, 6.0)]);
    // Picture-frame data of a fabric that never locks (one straight slope up to 40 deg).
    let linear: Vec<(f64, f64)> = (1..=100)
        .map(|i| {
            let d = 0.04 * i as f64 / 100.0;
            (d, picture_frame_force(&ShearLaw::Polynomial { coefficients: vec![3.0] }, d, 0.15).unwrap())
        })
        .collect();
    let linear = write_csv(dir.path(), "linear.csv", "d,F", &linear);
    let broken_card = dir.path().join("broken.toml");
    std::fs::write(&broken_card, std::fs::read_to_string(&card).unwrap().replace("g2 = 200.0", "g2 = -200.0")).unwrap();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["picture-frame", "--data", s(&bad), "--side", "0.15"], "line 3"),
        (vec!["picture-frame", "--data", s(&good), "--side=-1"], "--side must be"),
        (vec!["picture-frame", "--data", s(&good), "--side", "0.15", "--law", "spline"], "spline"),
        (vec!["picture-frame", "--data", s(&good), "--side", "0.001"], "beyond the travel"),
        (vec!["bias-extension", "--data", s(&good), "--length", "0.1", "--width", "0.08"], "twice"),
        (vec!["knit", "--data", s(&bad), "--direction", "weft"], "line 3"),
        (vec!["knit", "--data", s(&good), "--direction", "bias"], "bias"),
        (
            vec!["picture-frame", "--data", s(&linear), "--side", "0.15", "--law", "two-slope"],
            "do not show a locking angle",
        ),
    ];
    for (args, needle) in cases {
        let assert = drape().arg("calibrate").args(&args).args(["--card", s(&card), "--out", s(&out)]).assert().code(2);
        let err = String::from_utf8_lossy(&assert.get_output().stderr).to_string();
        assert!(err.contains(needle), "{args:?}: expected '{needle}' in: {err}");
        assert!(!err.contains("panicked"), "{err}");
        assert!(!out.exists());
    }
    let assert = drape()
        .args(["calibrate", "picture-frame", "--data", s(&good), "--side", "0.15"])
        .args(["--card", s(&broken_card), "--out", s(&out)])
        .assert()
        .code(2);
    let err = String::from_utf8_lossy(&assert.get_output().stderr).to_string();
    assert!(err.contains("line") && err.contains("shear.g2"), "{err}");
    assert!(!out.exists());
}

#[test]
fn bias_extension_of_two_sizes_in_mm_predicts_each_from_the_other() {
    // Two sizes of one fabric, 0.5 % noise, logged in mm: the joint fit gives the law within 1 %,
    // the card records the 35 deg range, each size's law predicts the other within 2 %, and the
    // fit report (PNG, JSON) is written beside the card.
    let dir = tempfile::tempdir().unwrap();
    let card = base_card(dir.path());
    for (k, (truth, law)) in [
        (ShearLaw::Polynomial { coefficients: vec![1.5, 4.0, 30.0] }, "polynomial:3"),
        (ShearLaw::Polynomial { coefficients: vec![0.9, -1.8, 25.0] }, "polynomial:3"),
        (ShearLaw::TwoSlope { g1: 2.0, g2: 60.0, locking_angle_deg: 26.0 }, "two-slope"),
    ]
    .into_iter()
    .enumerate()
    {
        // Up to 55 and 74 deg: the points past 35 deg are left out.
        let small = bias_test_mm(&truth, 0.2, 0.1, 0.035, 300, 0.005, 2 * k);
        let large = bias_test_mm(&truth, 0.45, 0.15, 0.12, 300, 0.005, 2 * k + 1);
        let a = write_csv(dir.path(), "small.csv", "elongation_mm,force_N", &small);
        let b = write_csv(dir.path(), "large.csv", "elongation_mm,force_N", &large);
        let out = dir.path().join(format!("fitted-{k}.toml"));
        let assert = drape()
            .args(["calibrate", "bias-extension", "--units", "mm", "--law", law])
            .args(["--data", s(&a), "--length", "200", "--width", "100"])
            .args(["--data", s(&b), "--length", "450", "--width", "150"])
            .args(["--card", s(&card), "--out", s(&out)])
            .assert()
            .success();
        let text = stdout(&assert);
        assert!(text.contains("from 0 to 35 deg") && text.contains("past 35 deg"), "{text}");
        let fitted = MaterialCard::load(&out).unwrap();
        let cal = fitted.shear_calibrated_max_deg.unwrap();
        assert!(cal > 34.5 && cal <= 35.0, "{cal}");
        for deg in [2.0, 10.0, 20.0, 30.0, 34.0] {
            let g = f64::to_radians(deg);
            let e = (fitted.shear.moment(g) / truth.moment(g) - 1.0).abs();
            assert!(e < 0.01, "{law} at {deg} deg: {e}");
        }
        assert!(fitted.source.as_deref().unwrap().contains("small.csv, large.csv"), "{:?}", fitted.source);
        // The cross-check: each sample's law predicts the other.
        let cross: Vec<f64> = text
            .lines()
            .filter(|l| l.contains("alone, the law predicts"))
            .map(|l| l.rsplit(' ').next().unwrap().trim_end_matches('%').parse::<f64>().unwrap())
            .collect();
        assert_eq!(cross.len(), 2, "{text}");
        assert!(cross.iter().all(|e| *e < 2.0), "{cross:?}");
        let png = dir.path().join(format!("fitted-{k}.fit.png"));
        let bytes = std::fs::read(&png).unwrap();
        assert!(bytes.starts_with(b"\x89PNG") && bytes.len() > 10_000);
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.path().join(format!("fitted-{k}.fit.json"))).unwrap())
                .unwrap();
        let fit = &json["fit"];
        assert_eq!(fit["bands"].as_array().unwrap().len(), 7);
        assert!(fit["r_squared"].as_f64().unwrap() > 0.999);
        assert!(fit["parameters"].as_array().unwrap().iter().all(|p| p["sigma"].as_f64().unwrap() > 0.0));
        assert_eq!(json["cross_predictions"].as_array().unwrap().len(), 2);
        assert_eq!(json["samples"][1]["size_m"][0].as_f64().unwrap(), 0.45);
    }
}

#[test]
fn the_range_and_the_toe_can_be_chosen() {
    let dir = tempfile::tempdir().unwrap();
    let card = base_card(dir.path());
    let truth = ShearLaw::Polynomial { coefficients: vec![1.5, 4.0, 30.0] };
    let data = write_csv(dir.path(), "be.csv", "d,F", &bias_test_mm(&truth, 0.3, 0.1, 0.08, 200, 0.0, 0));
    let out = dir.path().join("fitted.toml");
    let text = stdout(
        &drape()
            .args(["calibrate", "bias-extension", "--units", "mm", "--data", s(&data), "--length", "300"])
            .args(["--width", "100", "--max-angle", "25", "--min-angle", "4", "--card", s(&card), "--out", s(&out)])
            .assert()
            .success(),
    );
    assert!(text.contains("from 4 to 25 deg") && text.contains("below 4 deg"), "{text}");
    let fitted = MaterialCard::load(&out).unwrap();
    assert!((fitted.shear_calibrated_max_deg.unwrap() - 25.0).abs() < 0.2);
    match fitted.shear {
        ShearLaw::Polynomial { coefficients } => {
            for (a, b) in coefficients.iter().zip([1.5, 4.0, 30.0]) {
                assert!((a / b - 1.0).abs() < 1e-6, "{coefficients:?}");
            }
        }
        other => panic!("{other:?}"),
    }
}

/// A scene of one ply of `card` (kinematic, or pressed mechanically) on the 2k hemisphere.
fn hemisphere_scene(dir: &Path, card: &Path, mechanical: bool) -> PathBuf {
    let tool = Path::new(env!("CARGO_MANIFEST_DIR")).join("geometries/hemisphere/hemisphere-2k.obj");
    let text = format!(
        "units = \"m\"\ntool = \"{}\"\nreference = [1.0, 0.0, 0.0]\n[materials]\nglass = \"{}\"\n\n[[ply]]\nname = \"p0\"\n\
         origin = [0.0, 0.0, 0.1]\nangle_deg = 0.0\nmaterial = \"glass\"\nspacing = 0.01\ngrid = [31, 31]\n{}",
        tool.display(),
        card.display(),
        if mechanical { "method = \"mechanical\"\n" } else { "" }
    );
    let p = dir.join("scene.toml");
    std::fs::write(&p, text).unwrap();
    p
}

/// The base card with `[shear] calibrated_max_deg` set.
fn calibrated_card(dir: &Path, name: &str, max_deg: f64) -> PathBuf {
    let mut card = MaterialCard::load(&base_card(dir)).unwrap();
    card.shear_calibrated_max_deg = Some(max_deg);
    let p = dir.join(name);
    std::fs::write(&p, card.to_toml_string()).unwrap();
    p
}

#[test]
fn drapes_and_studies_past_the_calibrated_range_say_so() {
    let dir = tempfile::tempdir().unwrap();
    // The hemisphere shears the ply to about 45 deg: past a 20 deg calibration, within 80.
    let narrow = calibrated_card(dir.path(), "narrow.toml", 20.0);
    let wide = calibrated_card(dir.path(), "wide.toml", 80.0);
    for (card, warned) in [(&narrow, true), (&wide, false)] {
        // drape run: the table, layup.json and the report.
        let sub = dir.path().join(if warned { "narrow" } else { "wide" });
        std::fs::create_dir_all(&sub).unwrap();
        let scene = hemisphere_scene(&sub, card, false);
        let out = sub.join("run");
        let text = stdout(&drape().args(["run", s(&scene), "--out", s(&out), "--format", "json"]).assert().success());
        let line = "warning: ply 'p0': shear reaches";
        assert_eq!(text.contains(line), warned, "{text}");
        let layup: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("layup.json")).unwrap()).unwrap();
        let w = layup["plies"][0]["shear_range_warning"].as_str();
        assert_eq!(w.is_some(), warned, "{layup}");
        if let Some(w) = w {
            let max = layup["plies"][0]["max_abs_shear_deg"].as_f64().unwrap();
            assert!(w.contains(&format!("{max:.1} deg")) && w.contains("20.0 deg"), "{w}");
        }
        drape().args(["report", s(&out)]).assert().success();
        let html = std::fs::read_to_string(out.join("report/index.html")).unwrap();
        assert_eq!(html.contains("shear-range-warnings"), warned);
        // drape kinematic with the card.
        let tool = Path::new(env!("CARGO_MANIFEST_DIR")).join("geometries/hemisphere/hemisphere-2k.obj");
        let text = stdout(
            &drape()
                .args(["kinematic", "--tool", s(&tool), "--origin", "0,0,0.1", "--warp", "1,0,0", "--spacing", "0.01"])
                .args(["--grid", "31,31", "--material", s(card), "--format", "none", "--out", s(&sub.join("k"))])
                .assert()
                .success(),
        );
        assert_eq!(text.contains("shear reaches"), warned, "{text}");
        // A study of the ply.
        let text = stdout(
            &drape()
                .args(["study", "stability", s(&scene), "--out", s(&sub.join("study")), "--params", "spacing,angle"])
                .args(["--axes", "spacing,angle"])
                .assert()
                .success(),
        );
        assert_eq!(text.contains("cases of ply 'p0': shear reaches"), warned, "{text}");
    }
}

#[test]
fn a_refined_drape_past_the_calibrated_range_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let narrow = calibrated_card(dir.path(), "narrow.toml", 20.0);
    let tool = Path::new(env!("CARGO_MANIFEST_DIR")).join("geometries/hemisphere/hemisphere-2k.obj");
    // The tool in mm: drape kinematic records the scale, drape refine reads the tool in it.
    let mm = dir.path().join("hemisphere-mm.obj");
    let text = std::fs::read_to_string(&tool).unwrap();
    let scaled: String = text
        .lines()
        .map(|l| match l.strip_prefix("v ") {
            Some(rest) => {
                let v: Vec<f64> = rest.split_whitespace().map(|x| x.parse::<f64>().unwrap() * 1e3).collect();
                format!("v {} {} {}\n", v[0], v[1], v[2])
            }
            None => format!("{l}\n"),
        })
        .collect();
    std::fs::write(&mm, scaled).unwrap();
    let k = dir.path().join("k");
    drape()
        .args(["kinematic", "--tool", s(&mm), "--units", "mm", "--origin", "0,0,100", "--warp", "1,0,0"])
        .args(["--spacing", "15", "--grid", "15,15", "--name", "p0", "--out", s(&k)])
        .assert()
        .success();
    let text = stdout(
        &drape()
            .args(["refine", "--net", s(&k.join("p0.drape.json")), "--tool", s(&mm), "--material", s(&narrow)])
            .args(["--mode", "pressed", "--out", s(&dir.path().join("r"))])
            .assert()
            .success(),
    );
    assert!(text.contains("warning: ply 'p0': shear reaches") && text.contains("20.0 deg"), "{text}");
}

#[test]
fn bad_shear_fit_arguments_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let card = base_card(dir.path());
    let out = dir.path().join("never.toml");
    let truth = ShearLaw::Polynomial { coefficients: vec![1.5, 4.0, 30.0] };
    let a = write_csv(dir.path(), "a.csv", "d,F", &bias_test_mm(&truth, 0.2, 0.1, 0.035, 50, 0.0, 0));
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["--data", s(&a), "--length", "0.2", "--width", "0.1", "--max-angle", "0"], "--max-angle"),
        (vec!["--data", s(&a), "--length", "0.2", "--width", "0.1", "--max-angle", "120"], "--max-angle"),
        (vec!["--data", s(&a), "--length", "0.2", "--width", "0.1", "--min-angle", "40"], "--min-angle"),
        (
            vec![
                "--data",
                s(&a),
                "--data",
                s(&a),
                "--length",
                "0.2",
                "--length",
                "0.3",
                "--length",
                "0.4",
                "--width",
                "0.1",
            ],
            "--length is given 3 times",
        ),
        (vec!["--data", s(&a), "--length", "0.2", "--width", "0.1", "--units", "in"], "--units"),
        // Elongations logged in mm read as m: past the sample's travel.
        (vec!["--data", s(&a), "--length", "0.2", "--width", "0.1"], "beyond the travel"),
        // Every point below the smallest angle asked for.
        (
            vec!["--data", s(&a), "--length", "200", "--width", "100", "--units", "mm", "--min-angle", "34.9"],
            "need more",
        ),
    ];
    for (args, needle) in cases {
        let assert = drape()
            .args(["calibrate", "bias-extension"])
            .args(&args)
            .args(["--card", s(&card), "--out", s(&out)])
            .assert()
            .code(2);
        let err = String::from_utf8_lossy(&assert.get_output().stderr).to_string();
        assert!(err.contains(needle), "{args:?}: expected '{needle}' in: {err}");
        assert!(!err.contains("panicked"), "{err}");
        assert!(!out.exists() && !dir.path().join("never.fit.png").exists());
    }
}
