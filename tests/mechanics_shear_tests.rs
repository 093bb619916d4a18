//! The two in-plane shear tests on the mechanical model (REFERENCES.md section 3) with stiff
//! fibres, against the pin-jointed kinematics and the virtual-work forces of
//! tests/common/shear_frames.rs; and the `drape test picture-frame | bias-extension` commands.
//!
//! What the discrete net can and cannot reproduce (numbers printed with `--nocapture`):
//! - Picture frame: the uniformly sheared net is the exact equilibrium of the clamped net, so the
//!   cell shears and the force match the formulas to solver precision.
//! - Bias extension: the net's long free edges are zigzags of whole cells with their tips on the
//!   sample's edge, so each edge lacks a triangle of area a^2 per 2a of length (a = h / sqrt 2):
//!   zones B and C have less fabric than W^2 and W (L - 3W/2). The nominal `be_force` is then
//!   too high by about 1/(3k) for L = 2W (k = W / (sqrt 2 h)); the zone areas of the net's own
//!   cells put into the same formula match the force closely.
//! - Bias extension with L > 2W: the central zone is a hexagon whose fibres cross it over
//!   different lengths; a planar pin-jointed net (a Chebyshev net: each fibre family's direction
//!   varies only along the fibre) lowers its energy below the uniform three-zone state by
//!   shearing more near the A apexes and less in the middle (about +-4 deg at 40 deg, the same
//!   on finer nets: a property of the model, not of the mesh). Zone means stay within a degree
//!   and the energy is below the ideal state's, as a minimum must be.
use crate::common;

use common::shear_frames::{
    be_displacement, be_force, be_shear, half_angle_factor, pf_displacement, pf_force, pf_shear, shear_energy_density,
};
use drape::material::MaterialCard;
use drape::mechanics::refine::NetObjective;
use drape::mechanics::virtual_tests::{
    bias_extension_observed, cell_shears, picture_frame, picture_frame_observed, BiasExtension, PictureFrame,
    ShearState,
};
use drape::mechanics::Objective;
use std::f64::consts::SQRT_2;

/// A card with stiff fibres (1e6 N/m), negligible bending and the given `[shear]` section,
/// written to a temporary TOML file and read back.
fn stiff_card(shear: &str) -> MaterialCard {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("stiff.toml");
    std::fs::write(&path, card_text(shear)).unwrap();
    MaterialCard::load(&path).unwrap()
}

fn card_text(shear: &str) -> String {
    format!(
        "name = \"stiff\"\nareal_mass = 0.3\nthickness = 5e-4\n\n[tension]\nlaw = \"linear\"\nwarp = 1.0e6\nweft = 1.0e6\n\n\
         {shear}\n\n[bending]\nwarp = 1e-9\nweft = 1e-9\n"
    )
}

const LINEAR: &str = "[shear]\nlaw = \"polynomial\"\ncoefficients = [1.0]";
const CUBIC: &str = "[shear]\nlaw = \"polynomial\"\ncoefficients = [0.5, 2.0]";
/// Locks at 30 deg, inside the tested range: the force rises 40-fold in slope past it.
const LOCKING: &str = "[shear]\nlaw = \"two-slope\"\ng1 = 0.5\ng2 = 20.0\nlocking_angle_deg = 30.0";

const LAWS: [(&str, &str); 3] = [("linear", LINEAR), ("cubic", CUBIC), ("two-slope", LOCKING)];

#[test]
fn picture_frame_shears_uniformly_with_the_frame_force() {
    let side = 0.1;
    let steps = 8;
    let spec =
        PictureFrame { side, spacing: side / 12.0, displacement: pf_displacement(40f64.to_radians(), side), steps };
    for (name, law) in LAWS {
        let card = stiff_card(law);
        let m = |g: f64| card.shear(g).1;
        let (mut worst_shear, mut worst_force) = (0.0f64, 0.0f64);
        let mut observe = |s: &ShearState| {
            let g = pf_shear(s.displacement, side);
            let shears = cell_shears(s.grid, s.nodes);
            assert_eq!(shears.iter().flatten().count(), 12 * 12);
            let dev = shears.iter().flatten().map(|c| (c - g).abs()).fold(0.0, f64::max);
            let reference = pf_force(s.displacement, side, &m);
            let rel = s.force / reference - 1.0;
            println!(
                "picture frame, {name}: d = {:.5} m, gamma = {:5.2} deg, F = {:.5e} N (formula {:.5e}, {:+.1e}), \
                 largest cell shear error {:.1e} rad",
                s.displacement,
                g.to_degrees(),
                s.force,
                reference,
                rel,
                dev
            );
            assert!(dev < 1e-3, "{name}: a cell is {dev} rad off the frame angle at d = {}", s.displacement);
            assert!(rel.abs() < 0.01, "{name}: force {} vs {reference} at d = {}", s.force, s.displacement);
            worst_shear = worst_shear.max(dev);
            worst_force = worst_force.max(rel.abs());
        };
        let r = picture_frame_observed(&card, &spec, &mut observe).unwrap();
        assert!(r.ok(), "{name}: {} of {} steps", r.completed, r.requested);
        assert_eq!(r.displacement.len(), steps + 1);
        assert_eq!((r.displacement[0], r.force[0]), (0.0, 0.0));
        assert!((r.displacement[steps] - spec.displacement).abs() < 1e-15);
        assert!(r.notes.is_empty(), "{:?}", r.notes);
        println!(
            "picture frame, {name}: worst cell shear error {worst_shear:.1e} rad, worst force error {worst_force:.1e}; \
             {} solver iterations",
            r.iterations()
        );
    }
}

#[test]
fn picture_frame_spacing_is_adjusted_to_whole_cells() {
    let card = stiff_card(LINEAR);
    let spec = PictureFrame { side: 0.1, spacing: 0.0123, displacement: 0.01, steps: 2 };
    let r = picture_frame(&card, &spec).unwrap();
    // 0.1 / 0.0123 = 8.13 -> 8 cells of 0.0125 m.
    assert_eq!((r.grid.nu, r.grid.nv), (9, 9));
    assert!((r.grid.spacing - 0.0125).abs() < 1e-15);
    assert_eq!(r.notes.len(), 1);
    for bad in [
        PictureFrame { spacing: 0.07, ..spec },
        PictureFrame { displacement: 0.06, ..spec },
        PictureFrame { displacement: -0.01, ..spec },
        PictureFrame { steps: 0, ..spec },
        PictureFrame { side: f64::NAN, ..spec },
    ] {
        assert!(picture_frame(&card, &bad).is_err(), "{bad:?}");
    }
}

/// Stiff fibres and a linear shear law that is undefined (NaN) past 20 deg: the solver must
/// fail there.
struct BrokenPast20Deg;

impl drape::mechanics::energy::Laws for BrokenPast20Deg {
    fn tension(&self, _: drape::material::Fibre, e: f64) -> (f64, f64, f64) {
        (0.5e6 * e * e, 1e6 * e, 1e6)
    }
    fn shear(&self, g: f64) -> (f64, f64, f64) {
        if g.abs() > 20f64.to_radians() {
            (f64::NAN, f64::NAN, f64::NAN)
        } else {
            (0.5 * g * g, g, 1.0)
        }
    }
    fn bending(&self, _: drape::material::Fibre) -> f64 {
        1e-9
    }
    fn areal_mass(&self) -> f64 {
        0.3
    }
}

#[test]
fn a_failed_load_step_keeps_the_last_equilibrium() {
    let side = 0.1;
    let spec =
        PictureFrame { side, spacing: side / 6.0, displacement: pf_displacement(30f64.to_radians(), side), steps: 6 };
    let r = picture_frame(&BrokenPast20Deg, &spec).unwrap();
    let reachable =
        (1..=6).filter(|s| pf_shear(spec.displacement * *s as f64 / 6.0, side) <= 20f64.to_radians()).count();
    println!(
        "broken law: {} of {} steps ({reachable} below 20 deg), {} solves, last {:?}",
        r.completed,
        r.requested,
        r.solves.len(),
        r.solves.last().map(|s| s.outcome)
    );
    assert!(!r.ok());
    assert_eq!(r.completed, reachable);
    assert!(!r.solves.last().unwrap().ok());
    assert_eq!(r.displacement.len(), reachable + 1);
    assert_eq!(r.force.len(), reachable + 1);
    // The net is the equilibrium of the last completed step.
    let g = pf_shear(r.displacement[reachable], side);
    for c in r.cell_shears().iter().flatten() {
        assert!((c - g).abs() < 1e-6, "{c} vs {g}");
    }
}

/// Zone of a point of the sample (x along the load from the fixed clamp, y across): 0 = A
/// (at a clamp, no shear), 1 = B (half shear), 2 = C (centre).
fn zone(x: f64, y: f64, length: f64, width: f64) -> usize {
    let u = x.min(length - x);
    if u + y.abs() < 0.5 * width {
        0
    } else if u - y.abs() > 0.5 * width {
        2
    } else {
        1
    }
}

/// Per zone A, B, C: (cells, mean error, largest |error|) of the cell shear against the
/// kinematic zone angle (0, gamma_C / 2, gamma_C), rad, and the zone's area in the net (cells
/// inside the free length).
#[derive(Debug, Default, Clone, Copy)]
struct ZoneStats {
    cells: usize,
    mean: f64,
    worst: f64,
    area: f64,
}

fn zone_stats(s: &ShearState, length: f64, width: f64, gamma_c: f64) -> [ZoneStats; 3] {
    let mut out = [ZoneStats::default(); 3];
    let nv = s.grid.nv;
    let h = s.grid.spacing;
    for (c, g) in cell_shears(s.grid, s.nodes).iter().enumerate() {
        let Some(g) = g else { continue };
        let (i, j) = (c / (nv - 1), c % (nv - 1));
        // The cell's reference centre: the mean of its corners' reference positions.
        let k = i * nv + j;
        let r = s.reference;
        let centre = (r[k].coords + r[k + 1].coords + r[k + nv].coords + r[k + nv + 1].coords) * 0.25;
        let (xc, yc) = (centre.x, centre.y);
        // Cells centred on a clamp line lie half in the clamp (zone A, never sheared).
        if xc < 1e-9 * h || xc > length - 1e-9 * h {
            assert!(g.abs() < 1e-4, "a cell in a clamp sheared by {g}");
            continue;
        }
        let z = zone(xc, yc, length, width);
        let e = g - [0.0, 0.5 * gamma_c, gamma_c][z];
        let st = &mut out[z];
        st.cells += 1;
        st.mean += e;
        st.worst = st.worst.max(e.abs());
        st.area += h * h;
    }
    for st in &mut out {
        st.mean /= st.cells.max(1) as f64;
    }
    out
}

/// Largest |segment length / spacing - 1| over the fibre segments of active nodes.
fn fibre_strain(s: &ShearState) -> f64 {
    let (nu, nv, h) = (s.grid.nu, s.grid.nv, s.grid.spacing);
    let mut worst = 0.0f64;
    for i in 0..nu {
        for j in 0..nv {
            let k = i * nv + j;
            for (ok, q) in [(i + 1 < nu, k + nv), (j + 1 < nv, k + 1)] {
                if ok && s.grid.active[k] && s.grid.active[q] {
                    worst = worst.max(((s.nodes[q] - s.nodes[k]).norm() / h - 1.0).abs());
                }
            }
        }
    }
    worst
}

/// A per-step check: (state, zone statistics, nominal force, force with the net's zone areas,
/// net energy, ideal three-zone energy with the net's zone areas).
type Check<'c> = dyn FnMut(&ShearState, [ZoneStats; 3], f64, f64, f64, f64) + 'c;

/// Run a bias-extension test up to 40 deg in zone C; for each step call `check` with the zone
/// statistics, the nominal force, the force of the formula with the net's zone areas, and the
/// net's energy against the ideal three-zone state's (with the net's zone areas).
fn run_bias_extension(name: &str, law: &str, length: f64, width: f64, k: usize, check: &mut Check) {
    let card = stiff_card(law);
    let steps = 8;
    let spacing = width / (SQRT_2 * k as f64);
    let spec = BiasExtension {
        length,
        width,
        spacing,
        displacement: be_displacement(40f64.to_radians(), length, width),
        steps,
    };
    let m = |g: f64| card.shear(g).1;
    let dd = length - width;
    let mut observe = |s: &ShearState| {
        let g = be_shear(s.displacement, length, width);
        let zones = zone_stats(s, length, width, g);
        let (a_b, a_c) = (zones[1].area, zones[2].area);
        let nominal = be_force(s.displacement, length, width, &m);
        let discrete = 2.0 / (dd * half_angle_factor(g)) * (a_c * m(g) + 0.5 * a_b * m(0.5 * g));
        let objective = NetObjective::new(s.grid.clone(), &card, nalgebra::Vector3::zeros());
        let energy = objective.evaluate(s.nodes, false).energy;
        let ideal = a_c * shear_energy_density(g, &m) + a_b * shear_energy_density(0.5 * g, &m);
        println!(
            "bias extension {name}, L = {:.0}W, k = {k}: d = {:.5} m, gamma_C = {:5.2} deg; F = {:.5e} N: vs be_force {:+.2}%, \
             vs zone areas of the net {:+.2}%; energy vs ideal zones {:+.2}%; largest fibre strain {:.1e}",
            length / width,
            s.displacement,
            g.to_degrees(),
            s.force,
            100.0 * (s.force / nominal - 1.0),
            100.0 * (s.force / discrete - 1.0),
            100.0 * (energy / ideal - 1.0),
            fibre_strain(s)
        );
        for (z, st) in zones.iter().enumerate() {
            println!(
                "    zone {}: {:3} cells, area {:.5} m^2, mean error {:+.3} deg, largest {:.3} deg",
                ["A", "B", "C"][z],
                st.cells,
                st.area,
                st.mean.to_degrees(),
                st.worst.to_degrees()
            );
        }
        // Stiff fibres: the largest fibre strain stays tiny, so the shear pattern is a mechanism
        // of the inextensible net.
        let strain = fibre_strain(s);
        assert!(strain < 1e-3, "fibre strain {strain}");
        check(s, zones, nominal, discrete, energy, ideal);
    };
    let r = bias_extension_observed(&card, &spec, &mut observe).unwrap();
    assert!(r.ok(), "{name}: {} of {} steps", r.completed, r.requested);
    assert!(r.notes.is_empty(), "{:?}", r.notes);
    assert_eq!(r.force.len(), steps + 1);
    println!("bias extension {name}: {} solver iterations", r.iterations());
}

#[test]
fn bias_extension_with_length_twice_the_width_takes_the_three_zones_exactly() {
    let (length, width, k) = (0.2, 0.1, 10);
    for (name, law) in LAWS {
        run_bias_extension(name, law, length, width, k, &mut |s, zones, nominal, discrete, energy, ideal| {
            let [a, b, c] = zones;
            assert!(a.cells > 0 && b.cells > 0 && c.cells > 0);
            // Measured: all zones within 0.05 deg of the kinematic angles at 40 deg.
            for (z, st) in zones.iter().enumerate() {
                assert!(st.worst.to_degrees() < 0.5, "zone {z}: {st:?}");
            }
            // Zone C keeps its nominal area W (L - 3W/2) = W^2 / 2 (it meets the free edges at
            // points only); zone B lacks the zigzag edge triangles: W^2 (1 - 1/k).
            assert!((c.area / (width * (length - 1.5 * width)) - 1.0).abs() < 1e-9, "{c:?}");
            assert!((b.area / (width * width * (1.0 - 1.0 / k as f64)) - 1.0).abs() < 1e-9, "{b:?}");
            // Measured: within 0.3% of the formula with the net's areas (0.1% without locking)...
            assert!((s.force / discrete - 1.0).abs() < 0.01, "{} vs {discrete}", s.force);
            // ... and 1/(3k) = 3.3% below the nominal formula at small shear (less at large).
            assert!((s.force / nominal - 1.0).abs() < 0.05, "{} vs {nominal}", s.force);
            assert!(energy <= ideal * (1.0 + 1e-6) && energy >= ideal * 0.99, "{energy} vs {ideal}");
        });
    }
}

#[test]
fn bias_extension_with_length_three_times_the_width_is_close_to_the_three_zones() {
    let (length, width, k) = (0.3, 0.1, 12);
    for (name, law) in [("linear", LINEAR), ("cubic", CUBIC)] {
        run_bias_extension(name, law, length, width, k, &mut |s, zones, nominal, discrete, energy, ideal| {
            let [a, b, c] = zones;
            let deg = |x: f64| x.to_degrees();
            // Zone A does not shear; zones B and C shear on average as the kinematics say, but
            // the hexagonal zone C is not uniform (measured at 40 deg: mean -0.5 deg, extremes
            // +-4.5 deg; zone B mean +0.9 deg, extremes 2.3 deg).
            assert!(deg(a.worst) < 0.1, "A: {a:?}");
            assert!(deg(b.mean).abs() < 1.5 && deg(b.worst) < 3.0, "B: {b:?}");
            assert!(deg(c.mean).abs() < 1.0 && deg(c.worst) < 5.0, "C: {c:?}");
            // The net's energy is a minimum: below the ideal three-zone state's (measured up to
            // 2% below), and the force within 2% of the formula with the net's zone areas.
            assert!(energy <= ideal * (1.0 + 1e-6) && energy >= ideal * 0.95, "{energy} vs {ideal}");
            assert!((s.force / discrete - 1.0).abs() < 0.02, "{} vs {discrete}", s.force);
            // Measured 4.7% below the nominal formula: 3.6% for the zigzag edges, the rest for
            // the non-uniform centre.
            assert!((s.force / nominal - 1.0).abs() < 0.06, "{} vs {nominal}", s.force);
        });
    }
}

#[test]
fn bias_extension_refuses_what_the_net_cannot_represent() {
    use drape::mechanics::virtual_tests::bias_extension;
    let card = stiff_card(LINEAR);
    let good = BiasExtension { length: 0.2, width: 0.1, spacing: 0.01, displacement: 0.01, steps: 2 };
    let r = bias_extension(&card, &good).unwrap();
    // 0.1 / (sqrt 2 0.01) = 7.07 -> k = 7, spacing 0.1 / (7 sqrt 2).
    assert!((r.grid.spacing - 0.1 / (7.0 * SQRT_2)).abs() < 1e-15 && r.notes.len() == 1);
    assert_eq!(r.sample, (0.2, 0.1, r.grid.spacing));
    let refused = |spec: BiasExtension, needle: &str| {
        let e = bias_extension(&card, &spec).unwrap_err();
        assert!(e.contains(needle), "expected '{needle}' in: {e}");
    };
    refused(BiasExtension { length: 0.15, ..good }, "length >= 2 x width");
    refused(BiasExtension { displacement: 0.05, ..good }, "past 90 deg");
    refused(BiasExtension { spacing: 0.2, ..good }, "too coarse");
    refused(BiasExtension { length: 0.2 + 1e-4 * SQRT_2, spacing: 0.02, ..good }, "give a length of");
    refused(BiasExtension { steps: 0, ..good }, "load steps");
    refused(BiasExtension { width: -0.1, ..good }, "width");
}

// ---- the command line -----------------------------------------------------------------------

fn drape() -> assert_cmd::Command {
    assert_cmd::Command::cargo_bin("drape").unwrap()
}

#[test]
fn cli_writes_both_shear_tests() {
    let dir = tempfile::tempdir().unwrap();
    let card = dir.path().join("stiff.toml");
    std::fs::write(&card, card_text(CUBIC)).unwrap();
    let card = card.to_str().unwrap();
    let pf = dir.path().join("pf.json");
    let be = dir.path().join("be.json");
    let out = drape()
        .args(["test", "picture-frame", "--material", card, "--side", "0.1", "--displacement", "0.02", "--steps", "4"])
        .args(["--spacing", "0.0125", "--out", pf.to_str().unwrap()])
        .assert()
        .success();
    println!("{}", String::from_utf8_lossy(&out.get_output().stdout));
    let out = drape()
        .args([
            "test",
            "bias-extension",
            "--material",
            card,
            "--length",
            "0.2",
            "--width",
            "0.1",
            "--displacement",
            "0.02",
        ])
        .args(["--steps", "4", "--spacing", "0.0125", "--out", be.to_str().unwrap()])
        .assert()
        .success();
    println!("{}", String::from_utf8_lossy(&out.get_output().stdout));
    for (path, nulls) in [(&pf, false), (&be, true)] {
        let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
        let d: Vec<f64> = json["displacement"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
        let f: Vec<f64> = json["force"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
        // d = 0, F = 0 first, then one entry per load step.
        assert_eq!(d.len(), 5);
        assert_eq!(f.len(), 5);
        assert_eq!((d[0], f[0]), (0.0, 0.0));
        assert!((d[4] - 0.02).abs() < 1e-15);
        assert!(d.windows(2).all(|w| w[1] > w[0]) && f.windows(2).all(|w| w[1] > w[0]), "{d:?} {f:?}");
        let grid: Vec<usize> =
            json["net"]["grid"].as_array().unwrap().iter().map(|v| v.as_u64().unwrap() as usize).collect();
        let nodes = json["net"]["nodes"].as_array().unwrap();
        assert_eq!(nodes.len(), grid[0] * grid[1]);
        let placed: Vec<&serde_json::Value> = nodes.iter().filter(|n| !n.is_null()).collect();
        assert_eq!(placed.len() < nodes.len(), nulls);
        for n in placed {
            let p = n.as_array().unwrap();
            assert_eq!(p.len(), 3);
            assert!(p.iter().all(|c| c.as_f64().unwrap().is_finite()));
            assert_eq!(p[2].as_f64().unwrap(), 0.0);
        }
        assert_eq!(json["converged"], true);
    }
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&pf).unwrap()).unwrap();
    assert_eq!(json["net"]["grid"], serde_json::json!([9, 9]));
    assert_eq!(json["test"], "picture-frame");
    // The picture-frame force against the formula (cubic law of the card).
    let m = |g: f64| 0.5 * g + 2.0 * g * g * g;
    let f4 = json["force"][4].as_f64().unwrap();
    assert!((f4 / pf_force(0.02, 0.1, &m) - 1.0).abs() < 0.01, "{f4}");
}

#[test]
fn cli_refuses_bad_shear_test_arguments() {
    let dir = tempfile::tempdir().unwrap();
    let card = dir.path().join("stiff.toml");
    std::fs::write(&card, card_text(LINEAR)).unwrap();
    let card = card.to_str().unwrap().to_string();
    let out = dir.path().join("out.json");
    let o = out.to_str().unwrap().to_string();
    let pf = |extra: &[&str]| -> Vec<String> {
        let mut a: Vec<String> =
            ["test", "picture-frame", "--material", &card, "--side", "0.1", "--steps", "2", "--out", &o]
                .iter()
                .map(|s| s.to_string())
                .collect();
        a.extend(extra.iter().map(|s| s.to_string()));
        a
    };
    let be = |extra: &[&str]| -> Vec<String> {
        let mut a: Vec<String> = ["test", "bias-extension", "--material", &card, "--width", "0.1", "--out", &o]
            .iter()
            .map(|s| s.to_string())
            .collect();
        a.extend(extra.iter().map(|s| s.to_string()));
        a
    };
    let cases: Vec<(Vec<String>, &str)> = vec![
        (pf(&["--displacement", "0.07", "--spacing", "0.01"]), "travel"),
        (pf(&["--displacement", "0.01", "--spacing", "0.08"]), "at least 2 cells"),
        (pf(&["--displacement", "0.01", "--spacing", "0"]), "spacing"),
        (
            be(&["--length", "0.15", "--displacement", "0.01", "--spacing", "0.01", "--steps", "2"]),
            "length >= 2 x width",
        ),
        (be(&["--length", "0.2", "--displacement", "0.05", "--spacing", "0.01", "--steps", "2"]), "90 deg"),
        (be(&["--length", "0.2", "--displacement", "0.01", "--spacing", "0.01", "--steps", "0"]), "load steps"),
    ];
    for (args, needle) in cases {
        let a = drape().args(&args).assert().code(2);
        let err = String::from_utf8_lossy(&a.get_output().stderr).to_string();
        assert!(err.contains(needle), "expected '{needle}' in: {err}");
        assert!(!out.exists(), "output written for {args:?}");
    }
    let missing = dir.path().join("no-such-card.toml");
    let mut args = pf(&["--displacement", "0.01", "--spacing", "0.01"]);
    args[3] = missing.to_str().unwrap().to_string();
    drape().args(&args).assert().code(2);
    let mut args = pf(&["--displacement", "0.01", "--spacing", "0.01"]);
    let k = args.iter().position(|a| a == "--out").unwrap();
    args[k + 1] = dir.path().join("nowhere/out.json").to_str().unwrap().to_string();
    let a = drape().args(&args).assert().code(2);
    assert!(String::from_utf8_lossy(&a.get_output().stderr).contains("does not exist"));
    assert!(!out.exists());
}

/// (displacement, force) of a `drape test` JSON file.
fn curve_of(path: &std::path::Path) -> Vec<(f64, f64)> {
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let d = json["displacement"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap());
    let f = json["force"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap());
    d.zip(f).collect()
}

#[test]
fn virtual_tests_of_two_sizes_calibrate_a_card_that_warns_past_its_range() {
    // `drape test bias-extension` at two sizes (given in mm) of a card, `drape calibrate` on
    // their curves: the fitted law is the card's within the net's edge deficit (the zigzag
    // free edges lack 1/(3k) of zone B and C's fabric, k = 8 lattice steps per half width: 4 %;
    // the longer sample's centre also shears unevenly), each size's law predicts the other's
    // test within 2.5 % (measured 1.9 and 2.0 %: the analytic tests of src/material/calibrate.rs
    // hold 2 %; the net adds its own departure from the three-zone kinematics, which differs
    // between L = 2W and L = 2.5W), and the new card records its 35 deg range. A test run past
    // it warns.
    let dir = tempfile::tempdir().unwrap();
    let card = dir.path().join("stiff.toml");
    std::fs::write(&card, card_text(CUBIC)).unwrap();
    let m = |g: f64| 0.5 * g + 2.0 * g * g * g;
    let k = 8.0;
    let mut csvs = Vec::new();
    for (l, w) in [(200.0, 100.0), (300.0, 120.0)] {
        let out = dir.path().join(format!("be-{l}.json"));
        let spacing = w / (SQRT_2 * k);
        let d = be_displacement(45f64.to_radians(), l * 1e-3, w * 1e-3) * 1e3;
        let text = drape()
            .args(["test", "bias-extension", "--material", card.to_str().unwrap(), "--units", "mm"])
            .args(["--length", &l.to_string(), "--width", &w.to_string(), "--displacement", &d.to_string()])
            .args(["--steps", "30", "--spacing", &spacing.to_string(), "--out", out.to_str().unwrap()])
            .assert()
            .success();
        // The card records no calibrated range: nothing to warn about.
        assert!(!String::from_utf8_lossy(&text.get_output().stdout).contains("warning"));
        let csv = dir.path().join(format!("be-{l}.csv"));
        let rows: String = curve_of(&out).iter().map(|(d, f)| format!("{},{f}\n", d * 1e3)).collect();
        std::fs::write(&csv, format!("elongation_mm,force_N\n{rows}")).unwrap();
        csvs.push((csv, l, w));
    }
    let fitted = dir.path().join("fitted.toml");
    let mut cmd = drape();
    cmd.args(["calibrate", "bias-extension", "--units", "mm", "--law", "polynomial:2"]);
    for (csv, l, w) in &csvs {
        cmd.args(["--data", csv.to_str().unwrap(), "--length", &l.to_string(), "--width", &w.to_string()]);
    }
    let out = cmd.args(["--card", card.to_str().unwrap(), "--out", fitted.to_str().unwrap()]).assert().success();
    let text = String::from_utf8_lossy(&out.get_output().stdout).to_string();
    println!("{text}");
    let cross: Vec<f64> = text
        .lines()
        .filter(|l| l.contains("alone, the law predicts"))
        .map(|l| l.rsplit(' ').next().unwrap().trim_end_matches('%').parse::<f64>().unwrap())
        .collect();
    assert!(cross.len() == 2 && cross.iter().all(|e| *e < 2.5), "{cross:?}");
    let law = MaterialCard::load(&fitted).unwrap();
    assert!(law.shear_calibrated_max_deg.unwrap() <= 35.0 && law.shear_calibrated_max_deg.unwrap() > 33.0);
    for deg in [5.0, 15.0, 25.0, 34.0] {
        let g = f64::to_radians(deg);
        let e = law.shear(g).1 / m(g) - 1.0;
        println!("fitted law against the card's at {deg} deg: {:+.2}%", 100.0 * e);
        assert!(e < 0.0 && e > -1.5 / (3.0 * k), "{deg} deg: {e}");
    }
    // The fitted card used to 30 deg is within its range; to 50 deg it warns.
    for (deg, warned) in [(30.0, false), (50.0, true)] {
        let out = dir.path().join(format!("check-{deg}.json"));
        let d = be_displacement(f64::to_radians(deg), 0.2, 0.1);
        let a = drape()
            .args(["test", "bias-extension", "--material", fitted.to_str().unwrap(), "--length", "0.2"])
            .args(["--width", "0.1", "--displacement", &d.to_string(), "--steps", "6", "--spacing", "0.01"])
            .args(["--out", out.to_str().unwrap()])
            .assert()
            .success();
        let stdout = String::from_utf8_lossy(&a.get_output().stdout).to_string();
        assert_eq!(stdout.contains("warning: bias-extension test: shear reaches"), warned, "{stdout}");
        let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
        assert_eq!(json["warnings"].as_array().unwrap().len(), warned as usize);
    }
}

#[test]
fn cli_lengths_in_mm_give_the_test_in_m() {
    let dir = tempfile::tempdir().unwrap();
    let card = dir.path().join("stiff.toml");
    std::fs::write(&card, card_text(CUBIC)).unwrap();
    let run = |units: &str, s: f64, name: &str| -> serde_json::Value {
        let out = dir.path().join(name);
        let num = |x: f64| (x * s).to_string();
        drape()
            .args(["test", "picture-frame", "--material", card.to_str().unwrap(), "--units", units])
            .args(["--side", &num(0.1), "--displacement", &num(0.02), "--steps", "3", "--spacing", &num(0.0125)])
            .args(["--out", out.to_str().unwrap()])
            .assert()
            .success();
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap()
    };
    let (m, mm) = (run("m", 1.0, "m.json"), run("mm", 1e3, "mm.json"));
    for key in ["displacement", "force"] {
        let a = m[key].as_array().unwrap();
        let b = mm[key].as_array().unwrap();
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(b) {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            assert!((x - y).abs() <= 1e-9 * x.abs().max(1e-12), "{key}: {x} vs {y}");
        }
    }
    assert_eq!(mm["sample"]["side"].as_f64().unwrap(), m["sample"]["side"].as_f64().unwrap());
    drape()
        .args(["test", "picture-frame", "--material", card.to_str().unwrap(), "--units", "inch", "--side", "4"])
        .args(["--displacement", "1", "--spacing", "1", "--out", dir.path().join("x.json").to_str().unwrap()])
        .assert()
        .code(2);
}
