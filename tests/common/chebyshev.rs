//! Reference solution for a Chebyshev net on a sphere. Used as a test oracle.
//!
//! # The problem
//!
//! A continuous pin-jointed net is a Chebyshev net, `ds² = du² + 2 cos ω du dv + dv²`, where
//! `u` and `v` are arc lengths along the fibres. Write the shear as `γ = π/2 − ω`. Then
//! `γ_uv = K cos γ`, where `K` is the Gaussian curvature. Suppose two geodesic generators
//! cross at 90° and are the fibres `u = 0` and `v = 0`. Then `γ = 0` on both. On a sphere
//! of radius `R` (`K = 1/R²`), the solution depends only on `z = u v`: `γ(u, v) = g(u v)`.
//! Using `γ_uv = g' + z g''`, this gives
//!
//! ```text
//!     z g''(z) + g'(z) = K cos g(z),    g(0) = 0,   g'(0) = K.
//! ```
//!
//! `g'(0) = K` is not an extra condition: it follows from the equation at `z = 0`. The point
//! `z = 0` is a regular singular point. Its indicial exponents are `0, 0`, so the other local
//! solution behaves like `log z`. Only one solution is analytic with `g(0) = 0`.
//!
//! # Nondimensional form
//!
//! Put `s = K z = u v / R²`. Then `s g_ss + g_s = cos g`, with `g(0) = 0` and `g_s(0) = 1`.
//! So `γ(u, v) = G(u v / R²)`, where `G` does not depend on `R`.
//!
//! # Negative z (quadrants where u and v have opposite signs)
//!
//! Let `G` solve the equation and put `H(s) = −G(−s)`. Then `H' = G'(−s)` and
//! `H'' = −G''(−s)`. So `s H'' + H' = (−s) G''(−s) + G'(−s) = cos G(−s) = cos H`, with
//! `H(0) = 0`. By uniqueness `H = G`, so **`G` is odd**. This gives
//! `shear(−u, v) = shear(u, −v) = −shear(u, v)` and `shear(−u, −v) = shear(u, v)`. The power
//! series has only odd powers, since `cos G` is even. The code still integrates both directions
//! from `0` separately, so the tests can check the oddness instead of assuming it.
//!
//! # Method
//!
//! This is a high-order Taylor-series method, and it gives exact dense output.
//! The solution is split into segments. On each segment, `G(s_c + t) = Σ b_n tⁿ` with
//! `N = 32` terms. The coefficients come from an exact recurrence. Matching `tⁿ` in
//! `(s_c + t) G'' + G' = cos G` gives
//!
//! ```text
//!     s_c (n+1)(n+2) b_{n+2} + (n+1)² b_{n+1} = C_n,
//! ```
//!
//! where `C_n` and `S_n` are the Taylor coefficients of `cos G` and `sin G`. These come from
//! `C' = −S G'` and `S' = C G'`:
//! `n C_n = −Σ_{k=1..n} k b_k S_{n−k}` and `n S_n = Σ_{k=1..n} k b_k C_{n−k}`.
//! At the singular point `s_c = 0`, the same relation reduces to the Frobenius series
//! `b_{n+1} = C_n / (n+1)²`. That gives `G(s) = s − s³/18 + 7 s⁵/1800 − …`.
//! The step `h` starts at `1/16` at most, and at most `|s_c|`, so the step stays clear of the
//! singular point. It is halved until the last two terms of the series, `|b_n| hⁿ`, are
//! below `1e-18`. The value and slope at the end of a segment start the next one.
//! `shear` evaluates the polynomial of the segment that contains `s`, using Horner's rule.
//! The truncation error is below `1e-18`, and the rounding error is a few ulp. So the
//! relative error is about `1e-15`, well under the required `1e-12`. The test
//! `tests/chebyshev_reference.rs` checks this against an independent RK4 integration.
//!
//! # Valid range
//!
//! `(s G')' = cos G > 0` while `|G| < π/2`. So `G` is strictly increasing, and `s G' ≥ c > 0`,
//! which makes `G` grow at least like `c log s`. So `G` reaches `π/2` at a finite
//! `s* = collapse_s() = COLLAPSE_S ≈ 1.8615917` (u = v ≈ 1.3644 R). There the
//! net collapses: the two fibre families become parallel (`ω = 0`). Past that point the
//! equation has no physical meaning. So the oracle is valid for `|u v| < s* R²`.
//! [`SphereChebyshev::new`] panics if `z_max` reaches that limit. [`SphereChebyshev::shear`]
//! panics if `|u v| > z_max`.

use std::f64::consts::FRAC_PI_2;

/// `u v / R²` at which the sphere net collapses (shear = ±90°); the value of [`collapse_s`].
pub const COLLAPSE_S: f64 = 1.861_591_677_315_46;

/// Number of Taylor coefficients per segment (`b_0 ..= b_{ORDER-1}`).
const ORDER: usize = 32;
/// Largest step in `s`.
const MAX_STEP: f64 = 1.0 / 16.0;
/// Tolerance on the size of the last two series terms over a step.
const TAIL_TOL: f64 = 1e-18;

#[derive(Clone, Debug)]
struct Segment {
    /// Expansion point `s_c`.
    center: f64,
    /// Signed length. The segment covers `s_c + t` for `t` between 0 and `len`.
    len: f64,
    /// Taylor coefficients of `G` about `center`.
    coeffs: [f64; ORDER],
}

impl Segment {
    fn eval(&self, s: f64) -> f64 {
        let t = s - self.center;
        self.coeffs.iter().rev().fold(0.0, |acc, &b| acc * t + b)
    }

    fn eval_derivative(&self, s: f64) -> f64 {
        let t = s - self.center;
        (1..ORDER).rev().fold(0.0, |acc, n| acc * t + n as f64 * self.coeffs[n])
    }
}

/// Taylor coefficients of the solution of `s G'' + G' = cos G` about `s_c`. They are fixed
/// by `G(s_c) = g0` and `G'(s_c) = g1`. At `s_c = 0`, `g1` is ignored: the equation forces it.
fn taylor_coeffs(s_c: f64, g0: f64, g1: f64) -> [f64; ORDER] {
    let mut b = [0.0; ORDER];
    let mut c = [0.0; ORDER];
    let mut s = [0.0; ORDER];
    b[0] = g0;
    c[0] = g0.cos();
    s[0] = g0.sin();
    // Coefficient n of cos G and sin G, which needs b_1..=b_n.
    let cos_sin_coeff = |n: usize, b: &[f64; ORDER], c: &[f64; ORDER], s: &[f64; ORDER]| {
        let (mut cn, mut sn) = (0.0, 0.0);
        for k in 1..=n {
            let kb = k as f64 * b[k];
            cn -= kb * s[n - k];
            sn += kb * c[n - k];
        }
        (cn / n as f64, sn / n as f64)
    };
    if s_c == 0.0 {
        for n in 0..ORDER - 1 {
            if n >= 1 {
                let (cn, sn) = cos_sin_coeff(n, &b, &c, &s);
                c[n] = cn;
                s[n] = sn;
            }
            let m = (n + 1) as f64;
            b[n + 1] = c[n] / (m * m);
        }
    } else {
        b[1] = g1;
        for n in 0..ORDER - 2 {
            if n >= 1 {
                let (cn, sn) = cos_sin_coeff(n, &b, &c, &s);
                c[n] = cn;
                s[n] = sn;
            }
            let m1 = (n + 1) as f64;
            let m2 = (n + 2) as f64;
            b[n + 2] = (c[n] - m1 * m1 * b[n + 1]) / (s_c * m1 * m2);
        }
    }
    b
}

/// Why an integration stopped.
enum Stop {
    /// Reached `|s| = s_end`.
    Reached,
    /// `|G|` reached `π/2` at this `s` (signed), before `s_end`.
    Collapsed(f64),
}

/// Integrates from `s = 0` in direction `sign` (±1) out to `|s| = s_end`. It stops early
/// if `|G|` reaches `π/2`.
fn integrate(sign: f64, s_end: f64) -> (Vec<Segment>, Stop) {
    let mut segments = Vec::new();
    let (mut s_c, mut g, mut dg) = (0.0f64, 0.0f64, 1.0f64);
    loop {
        let coeffs = taylor_coeffs(s_c, g, dg);
        let remaining = s_end - s_c.abs();
        let mut h = MAX_STEP.min(remaining);
        if s_c != 0.0 {
            h = h.min(s_c.abs());
        }
        loop {
            let tail =
                coeffs[ORDER - 1].abs() * h.powi(ORDER as i32 - 1) + coeffs[ORDER - 2].abs() * h.powi(ORDER as i32 - 2);
            if tail <= TAIL_TOL {
                break;
            }
            h *= 0.5;
            assert!(h > 1e-12, "SphereChebyshev: step size underflow at s = {s_c}");
        }
        let last = h == remaining;
        let seg = Segment { center: s_c, len: sign * h, coeffs };
        let s_next = if last { sign * s_end } else { s_c + sign * h };
        let g_next = seg.eval(s_next);
        let dg_next = seg.eval_derivative(s_next);
        if g_next.abs() >= FRAC_PI_2 {
            // G is monotone, so there is exactly one crossing in this segment. Bisect on the
            // polynomial.
            let (mut a, mut b) = (s_c, s_next);
            for _ in 0..200 {
                let m = 0.5 * (a + b);
                if seg.eval(m).abs() < FRAC_PI_2 {
                    a = m;
                } else {
                    b = m;
                }
            }
            segments.push(seg);
            return (segments, Stop::Collapsed(0.5 * (a + b)));
        }
        segments.push(seg);
        if last {
            return (segments, Stop::Reached);
        }
        s_c = s_next;
        g = g_next;
        dg = dg_next;
    }
}

/// The nondimensional collapse point `s* = K z*`. At `s*` the shear of the sphere net from
/// two orthogonal geodesic generators reaches `π/2`. Computed by integration; equals
/// [`COLLAPSE_S`] (checked by the self-tests).
pub fn collapse_s() -> f64 {
    match integrate(1.0, 1.0e3).1 {
        Stop::Collapsed(s) => s,
        Stop::Reached => unreachable!("G must reach pi/2 (it grows at least logarithmically)"),
    }
}

/// The exact shear of the Chebyshev net on a sphere of radius `radius`. The net is built from
/// two geodesic generators that cross at 90°, along `u = 0` and `v = 0`. `u` and `v` are
/// signed fibre arc lengths from the crossing point.
#[derive(Clone, Debug)]
pub struct SphereChebyshev {
    radius: f64,
    curvature: f64,
    z_max: f64,
    /// Segments for `s >= 0`, in order of increasing `center`.
    positive: Vec<Segment>,
    /// Segments for `s <= 0`, in order of decreasing `center`.
    negative: Vec<Segment>,
}

impl SphereChebyshev {
    /// Integrates `z g'' + g' = K cos g` once, over `z ∈ [-z_max, z_max]`, with `K = 1/R²`.
    ///
    /// Panics if `radius` or `z_max` is not positive and finite. Also panics if
    /// `z_max ≥ collapse_s() · R²`, the point where the net collapses (shear = ±90°).
    pub fn new(radius: f64, z_max: f64) -> Self {
        assert!(
            radius.is_finite() && radius > 0.0,
            "SphereChebyshev: radius must be positive and finite, got {radius}"
        );
        assert!(z_max.is_finite() && z_max > 0.0, "SphereChebyshev: z_max must be positive and finite, got {z_max}");
        let curvature = 1.0 / (radius * radius);
        let s_max = curvature * z_max;
        let (positive, stop_pos) = integrate(1.0, s_max);
        let (negative, stop_neg) = integrate(-1.0, s_max);
        for stop in [stop_pos, stop_neg] {
            if let Stop::Collapsed(s) = stop {
                panic!(
                    "SphereChebyshev: z_max = {z_max} (u v / R^2 = {s_max}) is beyond the collapse \
                     of the net: the shear reaches 90 deg at |u v| = {} (u v / R^2 = {}); the \
                     solution exists only for |u v| < {} R^2",
                    s.abs() / curvature,
                    s.abs(),
                    s.abs()
                );
            }
        }
        Self { radius, curvature, z_max, positive, negative }
    }

    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// Gaussian curvature `K = 1/R²`.
    pub fn curvature(&self) -> f64 {
        self.curvature
    }

    /// Largest `|u v|` this instance was integrated for.
    pub fn z_max(&self) -> f64 {
        self.z_max
    }

    fn segment(&self, z: f64) -> (&Segment, f64) {
        assert!(
            z.is_finite() && z.abs() <= self.z_max,
            "SphereChebyshev: u v = {z} is outside the integrated range [-{zm}, {zm}] \
             (construct with a larger z_max; the net collapses at |u v| = {COLLAPSE_S} R^2)",
            zm = self.z_max
        );
        let s = self.curvature * z;
        let seg = if s >= 0.0 {
            let i = self.positive.partition_point(|seg| seg.center <= s);
            &self.positive[i - 1]
        } else {
            let i = self.negative.partition_point(|seg| seg.center >= s);
            &self.negative[i - 1]
        };
        debug_assert!((s - seg.center) * seg.len >= 0.0);
        (seg, s)
    }

    /// `g(z)`, the shear in radians as a function of `z = u v`.
    pub fn shear_z(&self, z: f64) -> f64 {
        let (seg, s) = self.segment(z);
        seg.eval(s)
    }

    /// `g'(z) = dg/dz`, in radians per unit area (dimensional, equal to `K` at `z = 0`).
    pub fn shear_z_derivative(&self, z: f64) -> f64 {
        let (seg, s) = self.segment(z);
        self.curvature * seg.eval_derivative(s)
    }

    /// The shear `γ = π/2 − ω` in radians at fibre coordinates `(u, v)`. These are signed arc
    /// lengths along the two generators. The result is `g(u v)`, which is positive when `u v > 0`.
    pub fn shear(&self, u: f64, v: f64) -> f64 {
        self.shear_z(u * v)
    }
}
