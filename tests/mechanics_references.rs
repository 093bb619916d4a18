//! Self-tests of the mechanics oracles in `tests/common/elastica.rs` (heavy elastica) and
//! `tests/common/shear_frames.rs` (picture frame and bias extension).
//! Run with `--nocapture` to see the reference numbers.

use crate::common;

use common::elastica::{heavy_elastica, heavy_elastica_with_steps, Elastica};
use common::shear_frames::{
    be_displacement, be_energy, be_force, be_moment_from_force, be_shear, be_shear_rate, be_zone_areas, be_zone_shears,
    half_angle_factor, pf_displacement, pf_energy, pf_force, pf_moment_from_force, pf_shear, pf_shear_rate,
    shear_energy_density,
};
use std::f64::consts::{FRAC_PI_2, SQRT_2};

/// 1 gram-force in newtons.
const GF: f64 = 9.806_65e-3;
/// 1 cm in m.
const CM: f64 = 1e-2;

// Tolerances.
/// Small-load elastica vs linear beam theory (relative).
const LINEAR_BEAM_REL: f64 = 1e-3;
/// Tip condition θ'(L) L (rad).
const TIP_CONDITION_ABS: f64 = 1e-10;
/// Arc length of the sampled curve vs s (relative), polyline with 4000 chords.
const INEXTENSIBLE_REL: f64 = 1e-7;
/// Simpson quadrature of cos θ / sin θ vs the integrated x, z (relative to L).
const QUADRATURE_REL: f64 = 1e-10;
/// Global moment balance B θ'(0) = w ∫ x ds (relative).
const MOMENT_BALANCE_REL: f64 = 1e-10;
/// Finite-difference ODE residual (relative to λ), stride-10 second differences.
const ODE_RESIDUAL_REL: f64 = 1e-5;
/// RK4 grid convergence: tip with 20 000 vs 40 000 steps (relative to L).
const GRID_CONVERGENCE_REL: f64 = 1e-11;
/// Shear-frame identities that are exact algebra (relative).
const ALGEBRA_REL: f64 = 1e-12;
/// Force vs 4-point finite difference of the energy (relative).
const FD_FORCE_REL: f64 = 1e-8;

// ---------------------------------------------------------------------------------------
// Heavy elastica
// ---------------------------------------------------------------------------------------

/// Composite Simpson on a uniform grid (even number of intervals).
fn simpson(ys: &[f64], h: f64) -> f64 {
    let n = ys.len() - 1;
    assert!(n.is_multiple_of(2));
    let mut sum = ys[0] + ys[n];
    for (i, y) in ys.iter().enumerate().take(n).skip(1) {
        sum += if i % 2 == 1 { 4.0 * y } else { 2.0 * y };
    }
    sum * h / 3.0
}

fn elastica_for_lambda(lambda: f64, length: f64) -> Elastica {
    // B = 2.5 (not 1) so that the λ scaling is exercised too.
    let b = 2.5;
    heavy_elastica(b, lambda * b / length.powi(3), length)
}

#[test]
fn elastica_small_load_matches_linear_beam() {
    for length in [1.0, 0.3] {
        let lambda = 4e-3; // tip deflection λ/8 L = 5e-4 L < 1e-3 L
        let e = elastica_for_lambda(lambda, length);
        let (xt, zt) = e.tip();
        let linear = e.w * length.powi(4) / (8.0 * e.b);
        assert!(linear < 1e-3 * length);
        let rel = (-zt - linear).abs() / linear;
        println!("small load L = {length}: tip z = {zt:.6e}, w L^4/(8B) = {linear:.6e}, rel {rel:.2e}");
        assert!(rel < LINEAR_BEAM_REL, "rel = {rel}");
        assert!(zt < 0.0 && xt < length && xt > length * (1.0 - 1e-6));
        // Linear root curvature w L^2 / (2B).
        let k_lin = e.w * length * length / (2.0 * e.b);
        assert!(((e.root_curvature - k_lin) / k_lin).abs() < LINEAR_BEAM_REL);
        // Whole linear shape: z(s) = -w/(24B) (s^4 - 4 L s^3 + 6 L^2 s^2).
        for i in 1..=10 {
            let s = length * i as f64 / 10.0;
            let z_lin = -e.w / (24.0 * e.b) * (s.powi(4) - 4.0 * length * s.powi(3) + 6.0 * (length * s).powi(2));
            let (_, z) = e.at(s);
            assert!(((z - z_lin) / z_lin).abs() < LINEAR_BEAM_REL, "s = {s}: {z} vs {z_lin}");
        }
    }
}

#[test]
fn elastica_inextensible() {
    for lambda in [1.0, 10.0, 40.0] {
        let length = 0.05;
        let e = elastica_for_lambda(lambda, length);
        // (a) Polyline length of the dense-output curve between arbitrary (non-grid) points.
        let n = 4000;
        let mut arc = 0.0;
        let mut prev = e.at(0.0);
        let mut max_rel: f64 = 0.0;
        for i in 1..=n {
            let s = length * i as f64 / n as f64;
            let p = e.at(s);
            arc += ((p.0 - prev.0).powi(2) + (p.1 - prev.1).powi(2)).sqrt();
            prev = p;
            max_rel = max_rel.max((arc - s).abs() / length);
        }
        println!("lambda = {lambda}: polyline arc length deficit max {max_rel:.2e} L");
        assert!(max_rel < INEXTENSIBLE_REL, "lambda = {lambda}: {max_rel}");
        // (b) x(s) = ∫ cos θ, z(s) = -∫ sin θ by Simpson on the stored θ.
        let h = e.s[1] - e.s[0];
        for m in [2000usize, 10_000, e.s.len() - 1] {
            let cos: Vec<f64> = e.theta[..=m].iter().map(|t| t.cos()).collect();
            let sin: Vec<f64> = e.theta[..=m].iter().map(|t| -t.sin()).collect();
            let xs = simpson(&cos, h);
            let zs = simpson(&sin, h);
            assert!((xs - e.x[m]).abs() < QUADRATURE_REL * length, "x: {xs} vs {}", e.x[m]);
            assert!((zs - e.z[m]).abs() < QUADRATURE_REL * length, "z: {zs} vs {}", e.z[m]);
        }
    }
}

#[test]
fn elastica_tip_condition_and_equilibrium() {
    for lambda in [0.1, 1.0, 10.0, 28.6, 40.0, 80.0] {
        let length = 0.05;
        let e = elastica_for_lambda(lambda, length);
        // Tip condition θ'(L) = 0, clamp θ(0) = 0.
        let tip = e.tip_curvature() * length;
        assert!(tip.abs() < TIP_CONDITION_ABS, "lambda = {lambda}: θ'(L) L = {tip}");
        assert_eq!(e.theta[0], 0.0);
        assert_eq!(e.at(0.0), (0.0, 0.0));
        // Physical shape: θ nondecreasing in [0, π/2], z decreasing.
        assert!(e.theta.windows(2).all(|p| p[1] >= p[0] - 1e-15));
        assert!(e.tip_angle() < FRAC_PI_2);
        assert!(e.z.windows(2).all(|p| p[1] <= p[0]));
        // Global moment balance at the clamp: B θ'(0) = w ∫ x ds.
        let h = e.s[1] - e.s[0];
        let moment = e.w * simpson(&e.x, h);
        let rel = (e.b * e.root_curvature - moment).abs() / moment;
        assert!(rel < MOMENT_BALANCE_REL, "lambda = {lambda}: moment balance rel {rel}");
        // ODE residual from second differences of the stored θ (stride 10).
        let stride = 10;
        let hs = stride as f64 * h;
        let mut worst: f64 = 0.0;
        for i in (stride..e.s.len() - stride).step_by(stride) {
            let d2 = (e.theta[i + stride] - 2.0 * e.theta[i] + e.theta[i - stride]) / (hs * hs);
            let res = e.b * d2 + e.w * (length - e.s[i]) * e.theta[i].cos();
            // Scale: w L cos θ ~ B λ / L^2.
            worst = worst.max(res.abs() / (e.w * length));
        }
        assert!(worst < ODE_RESIDUAL_REL, "lambda = {lambda}: ODE residual {worst}");
        println!(
            "lambda = {lambda:5}: tip theta'(L) L = {tip:.1e}, moment rel {rel:.1e}, ODE res {worst:.1e}, tip (x, z)/L = ({:.6}, {:.6}), tip angle {:.4} rad",
            e.tip().0 / length,
            e.tip().1 / length,
            e.tip_angle()
        );
    }
}

#[test]
fn elastica_large_deflection_monotone_in_load() {
    let length = 1.0;
    let lambdas = [0.5, 1.0, 2.0, 5.0, 10.0, 15.0, 20.0, 30.0, 50.0];
    let tips: Vec<(f64, f64, f64)> = lambdas
        .iter()
        .map(|&l| {
            let e = elastica_for_lambda(l, length);
            let (x, z) = e.tip();
            (x, z, e.tip_angle())
        })
        .collect();
    for (l, t) in lambdas.iter().zip(&tips) {
        println!("lambda = {l:5}: tip x/L = {:.9}, z/L = {:.9}, angle = {:.9}", t.0, t.1, t.2);
    }
    for p in tips.windows(2) {
        assert!(p[1].0 < p[0].0, "tip x must decrease with load");
        assert!(p[1].1 < p[0].1, "tip z must decrease with load");
        assert!(p[1].2 > p[0].2, "tip angle must increase with load");
    }
    // λ = 10 is a large deflection: far from the linear prediction λ/8 = 1.25 L.
    let i10 = lambdas.iter().position(|&l| l == 10.0).unwrap();
    let (x10, z10, _) = tips[i10];
    assert!(-z10 > 0.5 && -z10 < 1.0 && x10 < 0.9, "lambda = 10 tip = ({x10}, {z10})");
    // Deflection below the linear value for any finite load (the strip shortens horizontally).
    for (l, t) in lambdas.iter().zip(&tips) {
        assert!(-t.1 < l / 8.0);
        assert!(t.0 * t.0 + t.1 * t.1 < 1.0);
    }
}

#[test]
fn elastica_grid_converged_and_dense_output() {
    let length: f64 = 0.05;
    for lambda in [10.0, 40.0] {
        let b = 1.0;
        let w = lambda * b / length.powi(3);
        let e1 = heavy_elastica_with_steps(b, w, length, 20_000);
        let e2 = heavy_elastica_with_steps(b, w, length, 40_000);
        let (x1, z1) = e1.tip();
        let (x2, z2) = e2.tip();
        let diff = (x1 - x2).abs().max((z1 - z2).abs()) / length;
        println!("lambda = {lambda}: tip change 20k -> 40k steps = {diff:.1e} L");
        assert!(diff < GRID_CONVERGENCE_REL);
        // Dense output between grid nodes vs the finer grid, at points that are nodes of it.
        for i in 0..200 {
            let s = length * (2 * i + 1) as f64 / 400.0 + 0.5 * length / 20_000.0 * (i % 2) as f64;
            let s = s.min(length);
            let (xa, za) = e1.at(s);
            let (xb, zb) = e2.at(s);
            assert!((xa - xb).abs().max((za - zb).abs()) < GRID_CONVERGENCE_REL * length);
        }
        // sampled() agrees with at() and with the grid.
        let req = [0.0, 0.3 * length, 0.777 * length, length];
        let smp = e1.sampled(&req);
        for (k, &s) in req.iter().enumerate() {
            assert_eq!(smp.s[k], s);
            assert_eq!((smp.x[k], smp.z[k]), e1.at(s));
            assert_eq!(smp.theta[k], e1.theta_at(s));
        }
        assert_eq!(e1.at(length), e1.tip());
        assert_eq!(e1.at(e1.s[1234]), (e1.x[1234], e1.z[1234]));
    }
}

/// The reference numbers for the project's cantilever test: Table 1 fabric of Sze & Liu [000]
/// (Kang & Yu 1995), 5 cm free length, per unit width.
#[test]
fn elastica_table1_fabric_reference() {
    let weight = 0.019 * GF / (CM * CM); // N/m^2 = N/m per m of width
    let length = 5.0 * CM;
    println!("Table 1 fabric: weight {weight:.6} N/m^2, free length {length} m");
    let mut tips = Vec::new();
    for (name, rig) in [("warp", 0.083), ("weft", 0.063)] {
        let b = rig * GF * CM * CM / CM; // gf cm^2/cm -> N m (per unit width)
        let e = heavy_elastica(b, weight, length);
        let (x, z) = e.tip();
        println!(
            "{name}: B = {b:.6e} N m, lambda = w L^3/B = {:.6}, bending length (B/w)^(1/3) = {:.6} cm",
            e.lambda,
            (b / weight).cbrt() / CM
        );
        println!(
            "{name}: tip x = {x:.9} m ({:.6} cm), z = {z:.9} m ({:.6} cm), tip angle {:.6} rad ({:.4} deg), clamp curvature {:.6} 1/m",
            x / CM,
            z / CM,
            e.tip_angle(),
            e.tip_angle().to_degrees(),
            e.root_curvature
        );
        let mut line = String::new();
        for i in 0..=10 {
            let (xs, zs) = e.at(length * i as f64 / 10.0);
            line += &format!(" ({:.4}, {:.4})", xs / CM, zs / CM);
        }
        println!("{name}: shape at s = 0, 0.5, ..., 5 cm (x, z in cm):{line}");
        assert!(e.tip_curvature().abs() * length < TIP_CONDITION_ABS);
        assert!(z < 0.0 && z > -length && x > 0.0 && x < length);
        tips.push((x, z));
    }
    // The stiffer warp strip sags less.
    assert!(tips[0].1 > tips[1].1 && tips[0].0 > tips[1].0);
}

// ---------------------------------------------------------------------------------------
// Shear frames
// ---------------------------------------------------------------------------------------

/// Shear laws (moment per unit area, N/m) with their exact energies W(γ) = ∫ m.
/// A scalar function of the shear angle.
type Law = Box<dyn Fn(f64) -> f64>;

fn laws() -> Vec<(&'static str, Law, Law)> {
    vec![
        ("linear", Box::new(|g: f64| 0.8 * g), Box::new(|g: f64| 0.4 * g * g)),
        (
            "poly135",
            Box::new(|g: f64| 0.12 * g - 0.05 * g.powi(3) + 0.9 * g.powi(5)),
            Box::new(|g: f64| 0.06 * g * g - 0.0125 * g.powi(4) + 0.15 * g.powi(6)),
        ),
        (
            "exp-lock",
            Box::new(|g: f64| 0.02 * ((6.0 * g).exp() - 1.0)),
            Box::new(|g: f64| 0.02 * (((6.0 * g).exp() - 1.0) / 6.0 - g)),
        ),
    ]
}

/// 4-point central difference.
fn fd(f: &dyn Fn(f64) -> f64, x: f64, h: f64) -> f64 {
    (-f(x + 2.0 * h) + 8.0 * f(x + h) - 8.0 * f(x - h) + f(x - 2.0 * h)) / (12.0 * h)
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(f64::MIN_POSITIVE)
}

#[test]
fn shear_energy_density_exact_for_test_laws() {
    for (name, m, wint) in laws() {
        for g in [0.0, 0.1, 0.5, 0.9, 1.3] {
            let q = shear_energy_density(g, &*m);
            let e = wint(g);
            assert!((q - e).abs() <= ALGEBRA_REL * e.abs().max(1e-300), "{name} γ = {g}: {q} vs {e}");
        }
    }
}

#[test]
fn picture_frame_kinematics_and_force() {
    let side = 0.2;
    assert_eq!(pf_shear(0.0, side), 0.0);
    let d_max = pf_displacement(FRAC_PI_2, side); // full closure: diagonal 2L
    assert!((d_max - (2.0 - SQRT_2) * side).abs() < 1e-15);
    for gdeg in [1.0, 10.0, 25.0, 40.0, 55.0, 70.0] {
        let g = f64::to_radians(gdeg);
        let d = pf_displacement(g, side);
        assert!(rel(pf_shear(d, side), g) < ALGEBRA_REL, "inverse at {gdeg} deg");
        // Analytic rate: both forms, and finite differences.
        let rate = pf_shear_rate(d, side);
        let rate2 = SQRT_2 / (side * half_angle_factor(g));
        let rate_fd = fd(&|dd| pf_shear(dd, side), d, 1e-4 * side);
        assert!(rel(rate, rate2) < ALGEBRA_REL);
        assert!(rel(rate_fd, rate) < FD_FORCE_REL, "rate fd {rate_fd} vs {rate}");
        for (name, m, _) in laws() {
            let f = pf_force(d, side, &*m);
            // Force is the derivative of the shear energy L^2 W(γ(d)).
            let f_fd = fd(&|dd| pf_energy(dd, side, &*m), d, 1e-4 * side);
            assert!(rel(f_fd, f) < FD_FORCE_REL, "{name} {gdeg} deg: F = {f}, dE/dd = {f_fd}");
            // REFERENCES / [002] eq. 2: M = F (cos(γ/2) − sin(γ/2)) / (√2 L).
            let m_back = pf_moment_from_force(f, d, side);
            assert!(rel(m_back, m(g)) < ALGEBRA_REL, "{name} {gdeg} deg: M {m_back} vs {}", m(g));
        }
    }
    let d40 = pf_displacement(40f64.to_radians(), side);
    println!(
        "picture frame L = {side} m: 40 deg at d = {d40:.9} m (= {:.9} L); full closure d = {d_max:.9} m",
        d40 / side
    );
}

#[test]
fn bias_extension_kinematics_and_force() {
    for (length, width) in [(0.3, 0.1), (0.2, 0.1), (0.25, 0.08)] {
        let dd = length - width;
        assert_eq!(be_shear(0.0, length, width), 0.0);
        let (a_a, a_b, a_c) = be_zone_areas(length, width);
        assert!(rel(a_a + a_b + a_c, length * width) < ALGEBRA_REL);
        for gdeg in [1.0, 10.0, 25.0, 40.0, 55.0, 70.0] {
            let g = f64::to_radians(gdeg);
            let d = be_displacement(g, length, width);
            assert!(rel(be_shear(d, length, width), g) < ALGEBRA_REL, "inverse at {gdeg} deg");
            let (ga, gb, gc) = be_zone_shears(d, length, width);
            assert_eq!(ga, 0.0);
            assert!(rel(gb, 0.5 * g) < ALGEBRA_REL && rel(gc, g) < ALGEBRA_REL);
            let rate = be_shear_rate(d, length, width);
            let rate_fd = fd(&|x| be_shear(x, length, width), d, 1e-4 * dd);
            assert!(rel(rate_fd, rate) < FD_FORCE_REL, "rate fd {rate_fd} vs {rate}");
            for (name, m, _) in laws() {
                let f = be_force(d, length, width, &*m);
                let f_fd = fd(&|x| be_energy(x, length, width, &*m), d, 1e-4 * dd);
                assert!(
                    rel(f_fd, f) < FD_FORCE_REL,
                    "L = {length}, W = {width}, {name} {gdeg} deg: F = {f}, dE/dd = {f_fd}"
                );
                // [002] eq. 4 written independently (ℓ = W, per unit area).
                let m_eq4 = f * dd * half_angle_factor(g) / (width * (2.0 * dd - width))
                    - width / (2.0 * dd - width) * m(0.5 * g);
                assert!(rel(m_eq4, m(g)) < ALGEBRA_REL, "{name}: eq. 4 gives {m_eq4} vs {}", m(g));
                let m_back = be_moment_from_force(f, d, length, width, m(0.5 * g));
                assert!(rel(m_back, m(g)) < ALGEBRA_REL);
            }
        }
        let g40 = 40f64.to_radians();
        let d40 = be_displacement(g40, length, width);
        println!(
            "bias extension L = {length} m, W = {width} m (D = {dd:.3} m): gamma_C = 40 deg at d = {d40:.9} m (= {:.9} D), zone B {:.1} deg",
            d40 / dd,
            0.5 * 40.0
        );
        assert!(rel(d40, dd * (SQRT_2 * 25f64.to_radians().cos() - 1.0)) < ALGEBRA_REL);
    }
}
