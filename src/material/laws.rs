//! The constitutive laws of a fabric: fibre tension (linear or knit), in-plane shear
//! (polynomial, two-slope with locking, or a measured table) and bending, with exact derivatives.
//!
//! The table is interpolated by a monotone piecewise cubic (PCHIP, Fritsch-Carlson slopes as in
//! SciPy's `PchipInterpolator`), extended oddly to negative angles (the slope at 0 is the one of
//! the odd extension, so M is C1 through 0) and continued linearly past the last angle with the
//! interpolant's end slope (C1 there too).
//!
//!
//! Conventions shared by all laws:
//! - Shear is odd: M(-g) = -M(g), W(-g) = W(g).
//! - Fibre compression (e < 0) keeps the law's tension rigidity (D, or C for knit) times
//!   `compression_factor` (default 1, i.e. symmetric). Real fabrics buckle in compression; a
//!   factor of 0.01..0.1 models that. With a factor other than 1, d2W/de2 jumps at e = 0. For the
//!   knit law only the linear term C acts in compression (the stiffening term describes yarns
//!   pulled straight, which has no counterpart in compression).
//! - The knit law is singular at e = 1/alpha. It is evaluated as written up to
//!   e_c = [`KNIT_STRETCH_LIMIT`] / alpha and continued beyond by its second-order Taylor expansion
//!   at e_c: finite, convex and C2, with a tension there of about 1e6 beta (clearly huge).
//!   Never NaN for finite e.
/// Fraction of the finite extensibility 1/alpha up to which the knit law is evaluated as
/// written; beyond it continues as its quadratic Taylor expansion (see the module docs).
pub const KNIT_STRETCH_LIMIT: f64 = 0.999;

/// A polynomial shear law must give M > 0 and dM/dg >= 0 on (0, this angle] (degrees).
pub const POLYNOMIAL_CHECK_MAX_DEG: f64 = 85.0;

/// One of the two fibre families.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Fibre {
    /// The warp (the first fibre direction, along i).
    Warp,
    /// The weft (along j).
    Weft,
}

impl Fibre {
    /// `"warp"` or `"weft"`.
    pub fn name(self) -> &'static str {
        match self {
            Fibre::Warp => "warp",
            Fibre::Weft => "weft",
        }
    }
}

/// The `[tension]` section.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tension {
    /// The law of each family.
    pub law: TensionLaw,
    /// Scales the rigidity for fibre compression (e < 0); 0..=1, default 1.
    pub compression_factor: f64,
}

/// Stretch law of the two fibre families.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TensionLaw {
    /// W = D e^2 / 2 with D (N/m) per family.
    Linear {
        /// D of the warp, N/m.
        warp: f64,
        /// D of the weft, N/m.
        weft: f64,
    },
    /// Strain-stiffening law of seed 004 (Supplementary Eq. 14) per family.
    Knit {
        /// Parameters of the warp.
        warp: KnitParams,
        /// Parameters of the weft.
        weft: KnitParams,
    },
}

/// Parameters of the knit law sigma(e) = C e + beta (1/(1 - alpha e)^2 - 1 - 2 alpha e).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KnitParams {
    /// Low-strain rigidity, N/m.
    pub c: f64,
    /// Stress scale of the stiffening term, N/m.
    pub beta: f64,
    /// Inverse of the finite extensibility (dimensionless); 0 makes the law linear.
    pub alpha: f64,
}

impl KnitParams {
    /// The strain up to which the law is evaluated as written: `KNIT_STRETCH_LIMIT / alpha`
    /// (infinite for alpha = 0).
    pub fn stretch_limit(&self) -> f64 {
        if self.alpha > 0.0 {
            KNIT_STRETCH_LIMIT / self.alpha
        } else {
            f64::INFINITY
        }
    }

    /// The law itself at `e < 1/alpha` (any sign): (W, sigma, dsigma/de) with W the integral of
    /// sigma from 0, in closed form: W = C e^2/2 + beta alpha^2 e^3 / (1 - alpha e).
    pub fn raw(&self, e: f64) -> (f64, f64, f64) {
        let (c, b, a) = (self.c, self.beta, self.alpha);
        let x = a * e;
        let q = 1.0 - x;
        // 1/q^2 - 1 - 2x = x^2 (3 - 2x) / q^2 and 2a (1/q^3 - 1) = 2a x (3 - 3x + x^2) / q^3:
        // no cancellation at small x.
        let w = 0.5 * c * e * e + b * a * a * e * e * e / q;
        let s = c * e + b * x * x * (3.0 - 2.0 * x) / (q * q);
        let k = c + 2.0 * a * b * x * (3.0 - 3.0 * x + x * x) / (q * q * q);
        (w, s, k)
    }

    /// The tension branch (e >= 0) as the card uses it: the law up to [`Self::stretch_limit`],
    /// then its quadratic Taylor continuation. (W, sigma, dsigma/de).
    pub fn stretch(&self, e: f64) -> (f64, f64, f64) {
        let ec = self.stretch_limit();
        if e <= ec {
            self.raw(e)
        } else {
            let (w, s, k) = self.raw(ec);
            let t = e - ec;
            (w + s * t + 0.5 * k * t * t, s + k * t, k)
        }
    }
}

/// Flexural rigidities per unit width, N m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bending {
    /// Warp rigidity.
    pub warp: f64,
    /// Weft rigidity.
    pub weft: f64,
}

/// Shear moment per unit area as a function of the shear angle (odd in the angle).
#[derive(Debug, Clone, PartialEq)]
pub enum ShearLaw {
    /// M = c1 g + c3 g^3 + c5 g^5 + ...; `coefficients` = [c1, c3, c5, ...], N/m.
    Polynomial {
        /// [c1, c3, ...], N/m.
        coefficients: Vec<f64>,
    },
    /// M = g1 g for |g| <= locking angle, continued with slope g2 beyond (N/m per rad).
    TwoSlope {
        /// Slope below the locking angle, N/m per rad.
        g1: f64,
        /// Slope above it, N/m per rad.
        g2: f64,
        /// Locking angle, degrees.
        locking_angle_deg: f64,
    },
    /// Measured M(g), monotone cubic interpolation.
    Table(ShearTable),
}

impl ShearLaw {
    /// (W, M = dW/dg, dM/dg) at shear angle `g` (radians, signed); W in J/m^2, M in N/m.
    pub fn eval(&self, g: f64) -> (f64, f64, f64) {
        let a = g.abs();
        let sg = if g < 0.0 { -1.0 } else { 1.0 };
        let (w, m, k) = match self {
            ShearLaw::Polynomial { coefficients } => {
                let a2 = a * a;
                let (mut w, mut m, mut k) = (0.0, 0.0, 0.0);
                let mut p = 1.0; // a^(2j)
                for (j, c) in coefficients.iter().enumerate() {
                    let n = (2 * j + 1) as f64;
                    k += n * c * p;
                    m += c * p * a;
                    w += c * p * a2 / (n + 1.0);
                    p *= a2;
                }
                (w, m, k)
            }
            ShearLaw::TwoSlope { g1, g2, locking_angle_deg } => {
                let gl = locking_angle_deg.to_radians();
                if a <= gl {
                    (0.5 * g1 * a * a, g1 * a, *g1)
                } else {
                    let t = a - gl;
                    (0.5 * g1 * gl * gl + g1 * gl * t + 0.5 * g2 * t * t, g1 * gl + g2 * t, *g2)
                }
            }
            ShearLaw::Table(t) => t.eval_abs(a),
        };
        (w, sg * m, k)
    }

    /// Shear moment M(g), N/m.
    pub fn moment(&self, g: f64) -> f64 {
        self.eval(g).1
    }

    /// The locking angle the law names (degrees): the two-slope law's; `None` for a polynomial
    /// or a table, which stiffen gradually.
    pub fn locking_angle_deg(&self) -> Option<f64> {
        match self {
            ShearLaw::TwoSlope { locking_angle_deg, .. } => Some(*locking_angle_deg),
            ShearLaw::Polynomial { .. } | ShearLaw::Table(_) => None,
        }
    }

    /// The law's name in the card (`law = ...`).
    pub fn law_name(&self) -> &'static str {
        match self {
            ShearLaw::Polynomial { .. } => "polynomial",
            ShearLaw::TwoSlope { .. } => "two-slope",
            ShearLaw::Table(_) => "table",
        }
    }

    /// Check the law: positive stiffness, sensible angles. Err((field, message)).
    pub(crate) fn check(&self) -> Result<(), (String, String)> {
        let bad = |f: &str, m: String| Err((format!("shear.{f}"), m));
        match self {
            ShearLaw::Polynomial { coefficients } => {
                if coefficients.is_empty() {
                    return bad("coefficients", "must list at least c1 (N/m): M = c1 g + c3 g^3 + ...".into());
                }
                if let Some(c) = coefficients.iter().find(|c| !c.is_finite()) {
                    return bad("coefficients", format!("must be finite numbers, got {c}"));
                }
                if coefficients[0] < 0.0 {
                    return bad(
                        "coefficients",
                        format!("c1 (the initial shear rigidity) must be >= 0, got {}", coefficients[0]),
                    );
                }
                let n = 170;
                for i in 1..=n {
                    let deg = POLYNOMIAL_CHECK_MAX_DEG * i as f64 / n as f64;
                    let (_, m, k) = self.eval(deg.to_radians());
                    if !(m > 0.0 && k >= 0.0) {
                        return bad(
                            "coefficients",
                            format!(
                                "give a shear moment that is positive and non-decreasing up to {POLYNOMIAL_CHECK_MAX_DEG} deg; \
                                 at {deg:.1} deg M = {m:.4e} N/m and dM/dg = {k:.4e} N/m per rad"
                            ),
                        );
                    }
                }
                Ok(())
            }
            ShearLaw::TwoSlope { g1, g2, locking_angle_deg } => {
                for (f, v) in [("g1", g1), ("g2", g2)] {
                    if !(v.is_finite() && *v > 0.0) {
                        return bad(f, format!("must be a positive shear rigidity in N/m per rad, got {v}"));
                    }
                }
                if !(*locking_angle_deg > 0.0 && *locking_angle_deg < 90.0) {
                    return bad(
                        "locking_angle_deg",
                        format!("must lie strictly between 0 and 90, got {locking_angle_deg}"),
                    );
                }
                Ok(())
            }
            ShearLaw::Table(_) => Ok(()), // checked on construction
        }
    }
}

/// A tabulated shear curve M(g) (N/m at angles in degrees), interpolated by PCHIP with the point
/// (0, 0) implied. Build with [`ShearTable::new`].
#[derive(Debug, Clone, PartialEq)]
pub struct ShearTable {
    angles_deg: Vec<f64>,
    moments: Vec<f64>,
    /// Knots in radians, starting at 0.
    pub(crate) x: Vec<f64>,
    /// M at the knots, starting at 0.
    y: Vec<f64>,
    /// dM/dg at the knots.
    d: Vec<f64>,
    /// W at the knots.
    w: Vec<f64>,
}

impl ShearTable {
    /// Check and prepare a table: angles in degrees, strictly increasing in [0, 90); moments in
    /// N/m, >= 0, non-decreasing, the last one positive. The point (0, 0) is implied; an angle 0
    /// may be given if its moment is 0. Err((field, message)) names `angles_deg` or `moments`.
    pub fn new(angles_deg: Vec<f64>, moments: Vec<f64>) -> Result<Self, (String, String)> {
        let bad = |f: &str, m: String| Err((format!("shear.{f}"), m));
        if angles_deg.is_empty() {
            return bad("angles_deg", "must list at least one angle (degrees)".into());
        }
        if angles_deg.len() != moments.len() {
            return bad(
                "moments",
                format!(
                    "has {} values but angles_deg has {}: give one moment per angle",
                    moments.len(),
                    angles_deg.len()
                ),
            );
        }
        for (i, a) in angles_deg.iter().enumerate() {
            if !(a.is_finite() && *a >= 0.0 && *a < 90.0) {
                return bad("angles_deg", format!("entry {} must lie in [0, 90) degrees, got {a}", i + 1));
            }
            if i > 0 && *a <= angles_deg[i - 1] {
                return bad(
                    "angles_deg",
                    format!("must be strictly increasing; entry {} ({a}) follows {}", i + 1, angles_deg[i - 1]),
                );
            }
        }
        for (i, m) in moments.iter().enumerate() {
            if !(m.is_finite() && *m >= 0.0) {
                return bad("moments", format!("entry {} must be a finite moment >= 0 (N/m), got {m}", i + 1));
            }
            if i > 0 && *m < moments[i - 1] {
                return bad(
                    "moments",
                    format!("must be non-decreasing; entry {} ({m}) is below {}", i + 1, moments[i - 1]),
                );
            }
        }
        if angles_deg[0] == 0.0 && moments[0] != 0.0 {
            return bad("moments", format!("the moment at 0 deg must be 0 (shear is odd), got {}", moments[0]));
        }
        if moments[moments.len() - 1] <= 0.0 {
            return bad("moments", "the last moment must be positive".into());
        }
        let mut x = vec![0.0];
        let mut y = vec![0.0];
        for (a, m) in angles_deg.iter().zip(&moments) {
            if *a > 0.0 {
                x.push(a.to_radians());
                y.push(*m);
            }
        }
        let n = x.len(); // >= 2
        let h: Vec<f64> = (0..n - 1).map(|k| x[k + 1] - x[k]).collect();
        let del: Vec<f64> = (0..n - 1).map(|k| (y[k + 1] - y[k]) / h[k]).collect();
        let mut d = vec![0.0; n];
        // Knot 0: the odd extension has the same secant on both sides, whose weighted harmonic
        // mean is that secant.
        d[0] = del[0];
        for k in 1..n - 1 {
            d[k] = if del[k - 1] * del[k] <= 0.0 {
                0.0
            } else {
                let w1 = 2.0 * h[k] + h[k - 1];
                let w2 = h[k] + 2.0 * h[k - 1];
                (w1 + w2) / (w1 / del[k - 1] + w2 / del[k])
            };
        }
        d[n - 1] = if n == 2 {
            del[0]
        } else {
            // SciPy's one-sided three-point end slope, limited to keep monotonicity.
            let (h0, h1, m0, m1) = (h[n - 2], h[n - 3], del[n - 2], del[n - 3]);
            let e = ((2.0 * h0 + h1) * m0 - h0 * m1) / (h0 + h1);
            if e.signum() != m0.signum() || m0 == 0.0 {
                0.0
            } else if m0.signum() != m1.signum() && e.abs() > 3.0 * m0.abs() {
                3.0 * m0
            } else {
                e
            }
        };
        let mut w = vec![0.0; n];
        for k in 0..n - 1 {
            // Exact integral of the cubic Hermite piece.
            w[k + 1] = w[k] + h[k] * (y[k] + y[k + 1]) / 2.0 + h[k] * h[k] * (d[k] - d[k + 1]) / 12.0;
        }
        Ok(ShearTable { angles_deg, moments, x, y, d, w })
    }

    /// The angles as given, degrees.
    pub fn angles_deg(&self) -> &[f64] {
        &self.angles_deg
    }

    /// The moments as given, N/m.
    pub fn moments(&self) -> &[f64] {
        &self.moments
    }

    /// (W, M, dM/dg) at |g| = a >= 0.
    fn eval_abs(&self, a: f64) -> (f64, f64, f64) {
        let n = self.x.len();
        if a >= self.x[n - 1] {
            let t = a - self.x[n - 1];
            let (y, d) = (self.y[n - 1], self.d[n - 1]);
            return (self.w[n - 1] + y * t + 0.5 * d * t * t, y + d * t, d);
        }
        // Interval k with x[k] <= a < x[k+1].
        let k = self.x.partition_point(|&xk| xk <= a).saturating_sub(1).min(n - 2);
        let h = self.x[k + 1] - self.x[k];
        let s = a - self.x[k];
        let (y0, d0, d1) = (self.y[k], self.d[k], self.d[k + 1]);
        let del = (self.y[k + 1] - y0) / h;
        let c2 = (3.0 * del - 2.0 * d0 - d1) / h;
        let c3 = (d0 + d1 - 2.0 * del) / (h * h);
        let m = y0 + s * (d0 + s * (c2 + s * c3));
        let dm = d0 + s * (2.0 * c2 + s * 3.0 * c3);
        let w = self.w[k] + s * (y0 + s * (d0 / 2.0 + s * (c2 / 3.0 + s * c3 / 4.0)));
        (w, m, dm)
    }
}
