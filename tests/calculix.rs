//! Fibre orientations through a real solver: a drape exported with `drape export --format
//! calculix` onto a flat plate mesh, included in a CalculiX (`ccx`, Debian's calculix-ccx) job
//! that defines the material as orthotropic and pulls the plate in tension. The modulus CalculiX
//! gives matches the rotated orthotropic answer for the fibre angle.
use assert_cmd::Command;
use std::path::Path;

/// The modulus CalculiX gives may differ from the closed form by this share.
const MODULUS_TOLERANCE: f64 = 0.01;
/// Ply material: engineering constants, Pa (carbon/epoxy-like).
const E1: f64 = 140e9;
const E2: f64 = 10e9;
const NU12: f64 = 0.3;
const G12: f64 = 5e9;
/// Plate, m, and its mesh.
const LENGTH: f64 = 0.1;
const WIDTH: f64 = 0.05;
const NX: usize = 10;
const NY: usize = 5;
/// End displacement, m.
const PULL: f64 = 1e-5;

/// The apparent modulus along x of a ply whose fibres lie at `theta` from x (plane stress,
/// uniaxial stress along x).
fn off_axis_modulus(theta: f64) -> f64 {
    let (c, s) = (theta.cos(), theta.sin());
    1.0 / (c.powi(4) / E1 + (1.0 / G12 - 2.0 * NU12 / E1) * s * s * c * c + s.powi(4) / E2)
}

/// `ccx`, or a message saying how to get it.
fn ccx() -> std::process::Command {
    let found = std::process::Command::new("ccx").arg("-v").output().is_ok();
    assert!(found, "CalculiX's ccx is not installed: apt-get install calculix-ccx (bash .ci/run installs it)");
    std::process::Command::new("ccx")
}

/// A flat plate mesh of S4 elements (Abaqus input), with its node ids by position.
fn plate_mesh(path: &Path) -> Vec<(u64, f64, f64)> {
    let mut nodes = Vec::new();
    let mut s = String::from("*NODE\n");
    for i in 0..=NX {
        for j in 0..=NY {
            let id = (i * (NY + 1) + j + 1) as u64;
            let (x, y) = (i as f64 * LENGTH / NX as f64, j as f64 * WIDTH / NY as f64);
            s += &format!("{id}, {x}, {y}, 0.0\n");
            nodes.push((id, x, y));
        }
    }
    s += "*ELEMENT, TYPE=S4, ELSET=PLATE\n";
    let mut e = 0;
    for i in 0..NX {
        for j in 0..NY {
            let a = i * (NY + 1) + j + 1;
            let b = a + NY + 1;
            e += 1;
            s += &format!("{e}, {a}, {b}, {}, {}\n", b + 1, a + 1);
        }
    }
    std::fs::write(path, s).unwrap();
    nodes
}

/// A 0.4 m plate tool (OBJ) around the flow mesh.
fn tool(path: &Path) {
    let n = 8;
    let mut s = String::new();
    for i in 0..=n {
        for j in 0..=n {
            s += &format!("v {} {} 0\n", 0.4 * i as f64 / n as f64 - 0.15, 0.4 * j as f64 / n as f64 - 0.175);
        }
    }
    for i in 0..n {
        for j in 0..n {
            let a = i * (n + 1) + j + 1;
            let b = a + n + 1;
            s += &format!("f {a} {b} {}\nf {a} {} {}\n", b + 1, b + 1, a + 1);
        }
    }
    std::fs::write(path, s).unwrap();
}

/// The x reaction CalculiX prints for the set RIGHT (`*NODE PRINT, TOTALS=ONLY`).
fn total_force_x(dat: &str) -> f64 {
    let at = dat.find("total force").expect("a total force in the .dat file");
    let line = dat[at..].lines().map(str::trim).find(|l| !l.is_empty() && !l.starts_with("total force")).unwrap();
    line.split_whitespace().next().unwrap().parse().unwrap()
}

#[test]
fn calculix_reads_the_orientations_and_gives_the_off_axis_modulus() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    tool(&d.join("tool.obj"));
    let nodes = plate_mesh(&d.join("plate.inp"));
    let thickness = 0.001;
    for theta_deg in [0.0f64, 30.0, 60.0] {
        let theta = theta_deg.to_radians();
        let warp = format!("{},{},0", theta.cos(), theta.sin());
        let net_dir = d.join(format!("net{theta_deg}"));
        Command::cargo_bin("drape")
            .unwrap()
            .args(["kinematic", "--tool", "tool.obj", "--origin", "0.05,0.025,0", "--warp", &warp])
            .args(["--spacing", "0.005", "--grid", "61,61", "--name", "ply", "--out", net_dir.to_str().unwrap()])
            .current_dir(d)
            .assert()
            .success();
        Command::cargo_bin("drape")
            .unwrap()
            .args(["export", "--net", net_dir.join("ply.drape.json").to_str().unwrap(), "--mesh", "plate.inp"])
            .args(["--format", "calculix", "--material-name", "CFRP", "--thickness", &thickness.to_string()])
            .args(["--out", "ply.inp"])
            .current_dir(d)
            .assert()
            .success();
        let deck = std::fs::read_to_string(d.join("ply.inp")).unwrap();
        assert!(deck.contains("MATERIAL=CFRP") && !deck.contains("DRAPE_UNCOVERED"));
        // The job: the drape's deck, an orthotropic material, a pull along x with the ends free
        // to slide (uniaxial stress, shear free).
        let ids = |at: f64| -> String {
            nodes.iter().filter(|n| (n.1 - at).abs() < 1e-9).map(|n| n.0.to_string()).collect::<Vec<_>>().join("\n")
        };
        let job = format!(
            "*INCLUDE, INPUT=ply.inp\n*MATERIAL, NAME=CFRP\n*ELASTIC, TYPE=ENGINEERING CONSTANTS\n{E1:e}, {E2:e}, {E2:e}, {NU12}, {NU12}, 0.4, {G12:e}, {G12:e}\n3.5e9, 0.\n\
             *NSET, NSET=LEFT\n{}\n*NSET, NSET=RIGHT\n{}\n*BOUNDARY\nLEFT, 1, 1, 0.\n1, 2, 2, 0.\nDRAPE_NODES, 3, 3, 0.\n\
             *STEP\n*STATIC\n*BOUNDARY\nRIGHT, 1, 1, {PULL:e}\n*NODE PRINT, NSET=RIGHT, TOTALS=ONLY\nRF\n*END STEP\n",
            ids(0.0),
            ids(LENGTH)
        );
        std::fs::write(d.join("job.inp"), job).unwrap();
        let run = ccx().args(["-i", "job"]).current_dir(d).output().unwrap();
        let log = String::from_utf8_lossy(&run.stdout);
        assert!(run.status.success() && !log.contains("*ERROR"), "ccx failed:\n{log}");
        let force = total_force_x(&std::fs::read_to_string(d.join("job.dat")).unwrap());
        let modulus = (force / (WIDTH * thickness)) / (PULL / LENGTH);
        let expected = off_axis_modulus(theta);
        assert!(
            (modulus / expected - 1.0).abs() < MODULUS_TOLERANCE,
            "{theta_deg} deg: CalculiX gives {modulus:.4e} Pa, the rotated orthotropic answer is {expected:.4e} Pa"
        );
    }
    // The Abaqus deck (Abaqus applies its distributions) keeps every number within the
    // 20-character fields of readers like CalculiX.
    Command::cargo_bin("drape")
        .unwrap()
        .args(["export", "--net", d.join("net30/ply.drape.json").to_str().unwrap(), "--mesh", "plate.inp"])
        .args(["--format", "abaqus", "--out", "abaqus.inp"])
        .current_dir(d)
        .assert()
        .success();
    let deck = std::fs::read_to_string(d.join("abaqus.inp")).unwrap();
    let numbers: Vec<&str> = deck
        .lines()
        .filter(|l| !l.starts_with('*'))
        .flat_map(|l| l.split(','))
        .map(str::trim)
        .filter(|f| f.parse::<f64>().is_ok())
        .collect();
    assert!(numbers.len() > 300);
    assert!(numbers.iter().all(|f| f.len() <= 20), "{:?}", numbers.iter().find(|f| f.len() > 20));
}
