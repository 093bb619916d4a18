//! Self-tests of the sphere Chebyshev-net oracle in `tests/common/chebyshev.rs`.
//! Run with `--nocapture` to see the reference numbers.

use crate::common;

use common::chebyshev::{collapse_s, SphereChebyshev, COLLAPSE_S};

const R: f64 = 2.0; // not 1, so the K scaling is tested too

/// (a) For small u v, shear ≈ u v / R².
#[test]
fn small_uv_matches_leading_order() {
    let net = SphereChebyshev::new(R, 1.5 * R * R);
    let z = 1e-4 * R * R;
    for (u, v) in [(0.01 * R, 0.01 * R), (0.5 * R, 2e-4 * R), (-0.02 * R, -0.005 * R)] {
        assert!((u * v - z).abs() < 1e-15 * R * R);
        let g = net.shear(u, v);
        let lin = u * v / (R * R);
        assert!(((g - lin) / lin).abs() < 1e-3, "g = {g}, uv/R^2 = {lin}");
        // Much tighter: the series is s - s^3/18 + 7 s^5/1800.
        let s = lin;
        let series = s - s.powi(3) / 18.0 + 7.0 * s.powi(5) / 1800.0;
        assert!((g - series).abs() < 1e-16, "g = {g}, series = {series}");
    }
    assert_eq!(net.shear(0.0, 0.7 * R), 0.0);
    assert_eq!(net.shear(0.7 * R, 0.0), 0.0);
    assert!((net.shear_z_derivative(0.0) - 1.0 / (R * R)).abs() < 1e-16);
}

/// (b) The equation residual z g'' + g' − K cos g, from finite differences of the interpolant.
#[test]
fn ode_residual_by_finite_differences() {
    let net = SphereChebyshev::new(R, 1.6 * R * R);
    let k = 1.0 / (R * R);
    let d = 1e-3 * R * R; // FD step in z
    let g = |z: f64| net.shear_z(z);
    let mut worst: f64 = 0.0;
    for s in [-1.5, -0.81, -0.3, -0.05, 0.05, 0.123, 0.25, 0.5, 0.81, 1.0, 1.3, 1.5] {
        let z = s * R * R;
        // Fourth-order central differences.
        let (gm2, gm1, g0, gp1, gp2) = (g(z - 2.0 * d), g(z - d), g(z), g(z + d), g(z + 2.0 * d));
        let d1 = (gm2 - 8.0 * gm1 + 8.0 * gp1 - gp2) / (12.0 * d);
        let d2 = (-gm2 + 16.0 * gm1 - 30.0 * g0 + 16.0 * gp1 - gp2) / (12.0 * d * d);
        let residual = (z * d2 + d1 - k * g0.cos()) / k;
        // The analytic derivative matches the FD one.
        let d1_exact = net.shear_z_derivative(z);
        assert!(((d1 - d1_exact) / k).abs() < 1e-9, "s = {s}: g' fd {d1} vs {d1_exact}");
        // And it satisfies the equation with the exact g'.
        let residual_exact = (z * d2 + d1_exact - k * g0.cos()) / k;
        worst = worst.max(residual.abs()).max(residual_exact.abs());
        assert!(residual.abs() < 1e-8, "s = {s}: residual {residual}");
    }
    println!("max |ODE residual| / K (4th-order FD, step {:.0e} R^2): {worst:.2e}", d / (R * R));
}

/// (c) Symmetries. shear(u,v) = shear(v,u). The equation makes g odd in z, so
/// shear(−u,v) = −shear(u,v). The negative-z branch is integrated separately, so this
/// comparison is a real check.
#[test]
fn symmetry() {
    let net = SphereChebyshev::new(R, 1.6 * R * R);
    for (u, v) in [(0.3, 0.7), (0.9, 0.9), (1.2, 0.4), (0.05, 1.1), (1.2, 1.05)] {
        let (u, v) = (u * R, v * R);
        let g = net.shear(u, v);
        assert!(g > 0.0);
        assert_eq!(g, net.shear(v, u));
        assert_eq!(g, net.shear(-u, -v));
        let odd = net.shear(-u, v);
        assert!((odd + g).abs() < 1e-15 * g.abs().max(1e-300) + 1e-16, "{odd} vs {g}");
        assert_eq!(odd, net.shear(u, -v));
    }
}

/// Solves γ_uv = K cos γ, with γ = 0 on the axes, on an n×n grid that covers
/// [0, u_end] × [0, v_end]. u_end or v_end may be negative. Each cell uses the discrete
/// Chebyshev update, which is the midpoint rule for the double integral and is second order.
/// Returns γ(u_end, v_end).
fn grid_shear(k: f64, u_end: f64, v_end: f64, n: usize) -> f64 {
    let (hu, hv) = (u_end / n as f64, v_end / n as f64);
    let area = hu * hv; // signed: negative in the u v < 0 quadrants
    let w = n + 1;
    let mut gam = vec![0.0f64; w * w];
    for i in 0..n {
        for j in 0..n {
            let a = gam[i * w + j]; // (i, j)
            let b = gam[(i + 1) * w + j]; // (i+1, j)
            let c = gam[i * w + j + 1]; // (i, j+1)
            let mut x = b + c - a;
            for _ in 0..50 {
                let next = b + c - a + area * k * (0.25 * (a + b + c + x)).cos();
                let done = (next - x).abs() <= 1e-17;
                x = next;
                if done {
                    break;
                }
            }
            gam[(i + 1) * w + j + 1] = x;
        }
    }
    gam[n * w + n]
}

/// (d) Independent check. The 2-D grid solution converges to the oracle at second order.
#[test]
fn grid_solution_converges_at_second_order() {
    let net = SphereChebyshev::new(R, 1.0 * R * R);
    let k = 1.0 / (R * R);
    for (su, sv) in [(1.0, 1.0), (-1.0, 1.0)] {
        let (u, v) = (su * 0.9 * R, sv * 0.9 * R);
        let exact = net.shear(u, v);
        let ns = [90usize, 180, 360, 720];
        let errs: Vec<f64> = ns.iter().map(|&n| grid_shear(k, u, v, n) - exact).collect();
        println!("grid check at (u, v) = ({:+.1}R, {:+.1}R): oracle {exact:.15} rad", u / R, v / R);
        for (n, e) in ns.iter().zip(&errs) {
            println!("  n = {n:4}: grid - oracle = {e:+.3e} rad");
        }
        for w in errs.windows(2) {
            let ratio = w[0] / w[1];
            println!("  error ratio {ratio:.4}");
            assert!((3.9..4.1).contains(&ratio), "not second order: ratio {ratio}");
        }
        // Richardson extrapolation of the two finest grids agrees far better.
        let rich = (4.0 * errs[3] - errs[2]) / 3.0;
        println!("  Richardson (360, 720) - oracle = {rich:+.3e} rad");
        assert!(rich.abs() < 1e-3 * errs[3].abs());
    }
}

/// (e) Independent 1-D check. Classic RK4 on (g, g') in s, started from the hand-derived
/// series s − s³/18 + 7 s⁵/1800 at s0 = 0.01. It must match to 1e-12.
#[test]
fn matches_independent_rk4() {
    let net = SphereChebyshev::new(R, 1.6 * R * R);
    let rhs = |s: f64, y: [f64; 2]| [y[1], (y[0].cos() - y[1]) / s];
    let rk4 = |s_end: f64, steps: usize| {
        let s0 = 0.01f64;
        let mut y =
            [s0 - s0.powi(3) / 18.0 + 7.0 * s0.powi(5) / 1800.0, 1.0 - s0.powi(2) / 6.0 + 7.0 * s0.powi(4) / 360.0];
        let h = (s_end - s0) / steps as f64;
        for i in 0..steps {
            let s = s0 + i as f64 * h;
            let k1 = rhs(s, y);
            let k2 = rhs(s + h / 2.0, [y[0] + h / 2.0 * k1[0], y[1] + h / 2.0 * k1[1]]);
            let k3 = rhs(s + h / 2.0, [y[0] + h / 2.0 * k2[0], y[1] + h / 2.0 * k2[1]]);
            let k4 = rhs(s + h, [y[0] + h * k3[0], y[1] + h * k3[1]]);
            for c in 0..2 {
                y[c] += h / 6.0 * (k1[c] + 2.0 * k2[c] + 2.0 * k3[c] + k4[c]);
            }
        }
        y
    };
    for s_end in [0.25, 0.81, 1.5] {
        let y1 = rk4(s_end, 20_000);
        let y2 = rk4(s_end, 40_000);
        let oracle = net.shear_z(s_end * R * R);
        let doracle = net.shear_z_derivative(s_end * R * R) * R * R;
        println!(
            "s = {s_end}: oracle {oracle:.16}, rk4 {:.16} (|diff| {:.1e}, rk4 self-diff {:.1e})",
            y2[0],
            (oracle - y2[0]).abs(),
            (y1[0] - y2[0]).abs()
        );
        assert!((oracle - y2[0]).abs() < 1e-12 * oracle.abs());
        assert!((doracle - y2[1]).abs() < 1e-12);
    }
}

/// The reference numbers for the lead, and the collapse point.
#[test]
fn reference_values() {
    let net = SphereChebyshev::new(R, 1.0 * R * R);
    let g09 = net.shear(0.9 * R, 0.9 * R);
    let g05 = net.shear(0.5 * R, 0.5 * R);
    let s_star = collapse_s();
    println!("gamma(0.9R, 0.9R) = {g09:.15} rad = {:.12} deg", g09.to_degrees());
    println!("gamma(0.5R, 0.5R) = {g05:.15} rad = {:.12} deg", g05.to_degrees());
    println!("collapse (gamma = 90 deg) at u v / R^2 = {s_star:.15} (u = v = {:.12} R)", s_star.sqrt());
    assert!((s_star - COLLAPSE_S).abs() < 1e-12);
    // Construction just below the collapse point works. Just above it panics.
    let near = SphereChebyshev::new(R, 0.999 * s_star * R * R);
    assert!(near.shear_z(0.999 * s_star * R * R) < std::f64::consts::FRAC_PI_2);
    assert!(std::panic::catch_unwind(|| SphereChebyshev::new(R, 1.001 * s_star * R * R)).is_err());
}

#[test]
#[should_panic(expected = "outside the integrated range")]
fn beyond_z_max_panics() {
    let net = SphereChebyshev::new(R, 0.5 * R * R);
    net.shear(0.8 * R, 0.8 * R);
}
