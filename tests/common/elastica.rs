//! Reference solution for the heavy elastica: a cantilever strip bending under its own weight.
//! Used as a test oracle for the cantilever drape test (REFERENCES.md §2, [000] Fig. 7).
//!
//! # The problem
//!
//! A strip of length `L` is clamped horizontally at the origin and points along `+x`. Gravity
//! acts along `−z`. Let `s ∈ [0, L]` be the arc length from the clamp. Let `θ(s)` be the angle of
//! the tangent **below** the horizontal. So `θ > 0` means the strip goes down, and
//!
//! ```text
//!     x'(s) = cos θ(s),    z'(s) = −sin θ(s),    x(0) = z(0) = 0.
//! ```
//!
//! The bending moment at `s` comes from the weight of the strip beyond `s`. Each piece of length
//! `dσ` at `σ > s` has weight `w dσ` and lever arm `x(σ) − x(s)`. With the sign of `θ` above,
//! the curvature is `θ' = M / B`:
//!
//! ```text
//!     B θ'(s) = w ∫_s^L (x(σ) − x(s)) dσ          (≥ 0: the strip bends down)
//! ```
//!
//! Differentiating gives the boundary-value problem of REFERENCES.md §2:
//!
//! ```text
//!     B θ''(s) = −w (L − s) cos θ(s),    θ(0) = 0 (clamp),    θ'(L) = 0 (free tip).
//! ```
//!
//! Here `B` is the flexural rigidity of the strip (N m², rigidity per unit width times width) and
//! `w` its weight per unit length (N/m). Only `w / B` matters. So per unit width one may pass the
//! rigidity per unit width (N m) for `B` and the weight per unit area (N/m²) for `w`.
//!
//! # Nondimensional form
//!
//! Put `σ = s / L` and `λ = w L³ / B`. Then `θ_σσ = −λ (1 − σ) cos θ`, with `θ(0) = 0` and
//! `θ_σ(1) = 0`. Lengths scale with `L`. The integral form at `s = 0` gives a bracket for the
//! unknown `θ_σ(0) = λ ∫_0^1 X dσ ∈ [0, λ/2]`, since `0 ≤ X(σ) ≤ σ`.
//!
//! # Method
//!
//! Shooting on `k = θ_σ(0)`. The state `(θ, θ_σ, X, Z)` is integrated with classical RK4 on a
//! uniform grid of `steps` steps (default 20 000). The error is `O(h⁴)`: about `1e-13` for
//! `λ = 40`. The tip residual `f(k) = θ_σ(1)` is scanned on `[0, λ/2]` for sign changes, and
//! each bracket is bisected down to the last bit. We keep the root whose shape is physical
//! (`0 ≤ θ ≤ π/2` and `θ_σ ≥ 0` everywhere; see the integral form). For the loads used here,
//! there is exactly one bracket.
//!
//! Dense output: `at(s)` takes one RK4 step from the grid node just below `s`. Its error is the
//! local error of one step, `O(h⁵)`, so it is as accurate as the grid values.

use std::f64::consts::FRAC_PI_2;

/// Default number of RK4 steps over the strip.
pub const DEFAULT_STEPS: usize = 20_000;
/// Number of sub-intervals for the sign-change scan of the tip residual over `[0, λ/2]`.
const SCAN_INTERVALS: usize = 64;
/// Bisection stops when the bracket is this many ulps wide (relative to max(|k|, 1)).
const BISECTION_REL_WIDTH: f64 = 4.0 * f64::EPSILON;
/// Safety cap on bisection iterations.
const MAX_BISECTIONS: usize = 200;
/// Slack when testing that a shooting root is physical (0 ≤ θ ≤ π/2, θ' ≥ 0).
const PHYSICAL_SLACK: f64 = 1e-9;

/// A solved heavy elastica.
///
/// The public vectors hold the shape at the arc lengths `s` (m): by default the RK4 grid
/// (`steps + 1` points from 0 to `L`); after [`Elastica::sampled`], the requested points.
/// `theta` is in rad below the horizontal, `x` and `z` in m (`z ≤ 0`).
#[derive(Clone, Debug)]
pub struct Elastica {
    pub s: Vec<f64>,
    pub theta: Vec<f64>,
    pub x: Vec<f64>,
    pub z: Vec<f64>,
    /// Flexural rigidity `B` (N m²) as given.
    pub b: f64,
    /// Weight per unit length `w` (N/m) as given.
    pub w: f64,
    /// Strip length `L` (m).
    pub length: f64,
    /// Load parameter `λ = w L³ / B`.
    pub lambda: f64,
    /// Root curvature `θ'(0)` (1/m). `B θ'(0)` is the clamp moment.
    pub root_curvature: f64,
    /// Nondimensional RK4 grid: state `[θ, θ_σ, X, Z]` at `σ = i h`.
    grid: Vec<[f64; 4]>,
    h: f64,
}

/// Right-hand side of the nondimensional system, state `[θ, θ_σ, X, Z]`.
#[inline]
fn rhs(lambda: f64, sigma: f64, y: &[f64; 4]) -> [f64; 4] {
    let (sn, cs) = y[0].sin_cos();
    [y[1], -lambda * (1.0 - sigma) * cs, cs, -sn]
}

/// One classical RK4 step of size `dt` from `(sigma, y)`.
#[inline]
fn rk4_step(lambda: f64, sigma: f64, y: &[f64; 4], dt: f64) -> [f64; 4] {
    let add = |a: &[f64; 4], k: &[f64; 4], c: f64| [a[0] + c * k[0], a[1] + c * k[1], a[2] + c * k[2], a[3] + c * k[3]];
    let k1 = rhs(lambda, sigma, y);
    let k2 = rhs(lambda, sigma + 0.5 * dt, &add(y, &k1, 0.5 * dt));
    let k3 = rhs(lambda, sigma + 0.5 * dt, &add(y, &k2, 0.5 * dt));
    let k4 = rhs(lambda, sigma + dt, &add(y, &k3, dt));
    let mut out = *y;
    for j in 0..4 {
        out[j] += dt / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j]);
    }
    out
}

/// Integrates from the clamp with `θ_σ(0) = k`. Returns the whole grid if `keep`, else only
/// the tip state (as a one-element vector).
fn shoot(lambda: f64, k: f64, steps: usize, keep: bool) -> Vec<[f64; 4]> {
    let h = 1.0 / steps as f64;
    let mut y = [0.0, k, 0.0, 0.0];
    let mut out = Vec::with_capacity(if keep { steps + 1 } else { 1 });
    if keep {
        out.push(y);
    }
    for i in 0..steps {
        y = rk4_step(lambda, i as f64 * h, &y, h);
        if keep {
            out.push(y);
        }
    }
    if !keep {
        out.push(y);
    }
    out
}

fn tip_residual(lambda: f64, k: f64, steps: usize) -> f64 {
    shoot(lambda, k, steps, false)[0][1]
}

fn is_physical(grid: &[[f64; 4]]) -> bool {
    grid.iter().all(|y| y[0] >= -PHYSICAL_SLACK && y[0] <= FRAC_PI_2 + PHYSICAL_SLACK && y[1] >= -PHYSICAL_SLACK)
}

/// Solves the heavy elastica with [`DEFAULT_STEPS`] RK4 steps.
///
/// `b`: flexural rigidity (N m²); `w`: weight per unit length (N/m); `length`: free length (m).
/// Per unit width, pass rigidity per unit width (N m) and weight per unit area (N/m²).
pub fn heavy_elastica(b: f64, w: f64, length: f64) -> Elastica {
    heavy_elastica_with_steps(b, w, length, DEFAULT_STEPS)
}

/// As [`heavy_elastica`], with a chosen number of RK4 steps (for convergence checks).
pub fn heavy_elastica_with_steps(b: f64, w: f64, length: f64, steps: usize) -> Elastica {
    assert!(b > 0.0 && w >= 0.0 && length > 0.0, "need B > 0, w >= 0, L > 0");
    assert!(steps >= 16, "too few steps");
    let lambda = w * length.powi(3) / b;
    let k = if lambda == 0.0 { 0.0 } else { shoot_root(lambda, steps) };
    let grid = shoot(lambda, k, steps, true);
    let h = 1.0 / steps as f64;
    let s = (0..=steps).map(|i| i as f64 * h * length).collect();
    let theta = grid.iter().map(|y| y[0]).collect();
    let x = grid.iter().map(|y| y[2] * length).collect();
    let z = grid.iter().map(|y| y[3] * length).collect();
    Elastica { s, theta, x, z, b, w, length, lambda, root_curvature: k / length, grid, h }
}

/// Finds `k = θ_σ(0)` with `θ_σ(1) = 0` and a physical shape.
fn shoot_root(lambda: f64, steps: usize) -> f64 {
    let k_max = 0.5 * lambda;
    let ks: Vec<f64> = (0..=SCAN_INTERVALS).map(|i| k_max * i as f64 / SCAN_INTERVALS as f64).collect();
    let fs: Vec<f64> = ks.iter().map(|&k| tip_residual(lambda, k, steps)).collect();
    let mut roots = Vec::new();
    for i in 0..SCAN_INTERVALS {
        let (mut lo, mut hi) = (ks[i], ks[i + 1]);
        let (mut flo, fhi) = (fs[i], fs[i + 1]);
        if flo == 0.0 {
            roots.push(lo);
            continue;
        }
        if flo.signum() == fhi.signum() {
            continue;
        }
        for _ in 0..MAX_BISECTIONS {
            if hi - lo <= BISECTION_REL_WIDTH * hi.abs().max(1.0) {
                break;
            }
            let mid = 0.5 * (lo + hi);
            let fm = tip_residual(lambda, mid, steps);
            if fm == 0.0 {
                lo = mid;
                hi = mid;
                break;
            }
            if fm.signum() == flo.signum() {
                lo = mid;
                flo = fm;
            } else {
                hi = mid;
            }
        }
        roots.push(0.5 * (lo + hi));
    }
    if fs[SCAN_INTERVALS] == 0.0 {
        roots.push(ks[SCAN_INTERVALS]);
    }
    roots.sort_by(f64::total_cmp);
    roots.dedup_by(|a, b| (*a - *b).abs() <= 2.0 * BISECTION_REL_WIDTH * a.abs().max(1.0));
    let physical: Vec<f64> = roots.into_iter().filter(|&k| is_physical(&shoot(lambda, k, steps, true))).collect();
    assert!(
        physical.len() == 1,
        "heavy elastica, lambda = {lambda}: expected one physical shooting root, got {physical:?}"
    );
    physical[0]
}

impl Elastica {
    /// Nondimensional state `[θ, θ_σ, X, Z]` at arc length `s` (m), by one RK4 step from the
    /// grid node just below `s`. `s` is clamped to `[0, L]`.
    fn state_at(&self, s: f64) -> [f64; 4] {
        let sigma = (s / self.length).clamp(0.0, 1.0);
        let n = self.grid.len() - 1;
        let i = ((sigma / self.h).floor() as usize).min(n - 1);
        let s_i = i as f64 * self.h;
        let dt = sigma - s_i;
        if dt == 0.0 {
            self.grid[i]
        } else {
            rk4_step(self.lambda, s_i, &self.grid[i], dt)
        }
    }

    /// Position `(x, z)` (m) of the point at arc length `s` from the clamp.
    pub fn at(&self, s: f64) -> (f64, f64) {
        let y = self.state_at(s);
        (y[2] * self.length, y[3] * self.length)
    }

    /// Angle below the horizontal (rad) at arc length `s`.
    pub fn theta_at(&self, s: f64) -> f64 {
        self.state_at(s)[0]
    }

    /// Curvature `θ'(s)` (1/m); `B θ'` is the bending moment.
    pub fn curvature_at(&self, s: f64) -> f64 {
        self.state_at(s)[1] / self.length
    }

    /// Tip position `(x(L), z(L))` (m).
    pub fn tip(&self) -> (f64, f64) {
        let y = self.grid[self.grid.len() - 1];
        (y[2] * self.length, y[3] * self.length)
    }

    /// Tip angle `θ(L)` (rad).
    pub fn tip_angle(&self) -> f64 {
        self.grid[self.grid.len() - 1][0]
    }

    /// Tip curvature `θ'(L)` (1/m); zero up to the shooting accuracy.
    pub fn tip_curvature(&self) -> f64 {
        self.grid[self.grid.len() - 1][1] / self.length
    }

    /// The same solution with the public vectors `s`, `theta`, `x`, `z` at the requested arc
    /// lengths (m, each clamped to `[0, L]`).
    pub fn sampled(&self, s: &[f64]) -> Elastica {
        let mut out = self.clone();
        out.s = s.iter().map(|&si| si.clamp(0.0, self.length)).collect();
        let states: Vec<[f64; 4]> = out.s.iter().map(|&si| self.state_at(si)).collect();
        out.theta = states.iter().map(|y| y[0]).collect();
        out.x = states.iter().map(|y| y[2] * self.length).collect();
        out.z = states.iter().map(|y| y[3] * self.length).collect();
        out
    }
}
