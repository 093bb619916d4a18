//! `drape calibrate`: fits written into a new card, bad data refused with the line number.
use assert_cmd::Command;
use drape::material::calibrate::{bias_extension_force, knit_stress, picture_frame_force};
use drape::material::{Fibre, KnitParams, MaterialCard, ShearLaw, TensionLaw};
use std::path::{Path, PathBuf};

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
    assert!(stdout.contains("R^2") && stdout.contains("rms") && stdout.contains("max |residual|"), "{stdout}");
    let fitted = MaterialCard::load(&out).unwrap();
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
