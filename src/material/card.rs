//! A material card: areal mass, thickness, and the tension, shear and bending laws (TOML, SI units).
//!
//! ```toml
//! name = "glass-plain-weave"
//! areal_mass = 0.3          # kg/m^2
//! thickness = 5.0e-4        # m
//! source = "..."            # optional: where the numbers come from
//!
//! [tension]                 # per fibre family, per unit width
//! law = "linear"            # optional, default "linear": W = D e^2 / 2, D in N/m
//! compression_factor = 1.0  # optional, 0..1: the rigidity for e < 0 is scaled by it
//! warp = 2.0e5              # D, N/m
//! weft = 2.0e5
//!
//! [shear]                   # shear moment per unit area M(gamma), N/m; W = integral of M
//! law = "polynomial"        # M = c1 g + c3 g^3 + c5 g^5 + ...
//! coefficients = [0.5, 2.0] # [c1, c3, ...], N/m
//!
//! [bending]                 # flexural rigidity per unit width, N m
//! warp = 1.0e-7
//! weft = 1.0e-7
//! ```
//!
//! The knit (strain-stiffening) tension law of seed 004, Supplementary Eq. 14, one table per
//! family: sigma(e) = C e + beta (1/(1 - alpha e)^2 - 1 - 2 alpha e), C and beta in N/m, alpha
//! dimensionless (1/alpha is the finite extensibility):
//! ```toml
//! [tension]
//! law = "knit"
//! compression_factor = 1.0  # optional
//! [tension.warp]
//! C = 500.0                 # N/m (`c` is accepted too)
//! beta = 10.0               # N/m
//! alpha = 2.5
//! [tension.weft]
//! C = 120.0
//! beta = 20.0
//! alpha = 1.2
//! ```
//!
//! The other shear laws:
//! ```toml
//! [shear]
//! law = "two-slope"         # M = g1 g up to the locking angle, then slope g2 (continuous, odd)
//! g1 = 2.0                  # N/m per rad
//! g2 = 200.0                # N/m per rad
//! locking_angle_deg = 35.0
//! ```
//! ```toml
//! [shear]
//! law = "table"             # M measured at angles; (0, 0) is implied
//! angles_deg = [10.0, 20.0, 30.0, 40.0, 50.0]
//! moments = [0.2, 0.5, 1.1, 3.0, 12.0]   # N/m, non-decreasing
//! ```
//! The table is interpolated by a monotone piecewise cubic (PCHIP, Fritsch-Carlson slopes as in
//! SciPy's `PchipInterpolator`), extended oddly to negative angles (the slope at 0 is the one of
//! the odd extension, so M is C1 through 0) and continued linearly past the last angle with the
//! interpolant's end slope (C1 there too).
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
use serde::de::{self, Deserializer, MapAccess, Visitor};
use serde::Deserialize;
use std::collections::HashMap;
use std::fmt::{self, Write as _};
use std::path::Path;
use toml::Spanned;

/// Fraction of the finite extensibility 1/alpha up to which the knit law is evaluated as
/// written; beyond it continues as its quadratic Taylor expansion (see the module docs).
pub const KNIT_STRETCH_LIMIT: f64 = 0.999;

/// A polynomial shear law must give M > 0 and dM/dg >= 0 on (0, this angle] (degrees).
pub const POLYNOMIAL_CHECK_MAX_DEG: f64 = 85.0;

/// One of the two fibre families.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Fibre {
    Warp,
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

/// Why a material card could not be read or used. The message names the card, the line and
/// the field at fault, and what is expected.
#[derive(Debug, thiserror::Error)]
pub enum MaterialError {
    #[error("{0}")]
    Invalid(String),
}

/// A fabric material card (SI units).
#[derive(Debug, Clone, PartialEq)]
pub struct MaterialCard {
    pub name: String,
    /// kg/m^2
    pub areal_mass: f64,
    /// m
    pub thickness: f64,
    /// Where the numbers come from (a citation, or the calibration that produced them).
    pub source: Option<String>,
    /// Fibre stretching, per family.
    pub tension: Tension,
    /// In-plane shear.
    pub shear: ShearLaw,
    /// Flexural rigidities per unit width, N m.
    pub bending: Bending,
    /// What resin-flow exports need (optional `[flow]` section).
    pub flow: Option<FlowProperties>,
}

/// The optional `[flow]` section: what resin-flow exports need of the fabric.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlowProperties {
    /// Fibre volume fraction of the ply as laid flat at its `thickness`.
    pub fibre_volume_fraction: f64,
    /// Fibre (filament) radius, m, for the permeability model.
    pub fibre_radius: f64,
}

/// The `[tension]` section.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tension {
    pub law: TensionLaw,
    /// Scales the rigidity for fibre compression (e < 0); 0..=1, default 1.
    pub compression_factor: f64,
}

/// Stretch law of the two fibre families.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TensionLaw {
    /// W = D e^2 / 2 with D (N/m) per family.
    Linear { warp: f64, weft: f64 },
    /// Strain-stiffening law of seed 004 (Supplementary Eq. 14) per family.
    Knit { warp: KnitParams, weft: KnitParams },
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
    pub warp: f64,
    pub weft: f64,
}

/// Shear moment per unit area as a function of the shear angle (odd in the angle).
#[derive(Debug, Clone, PartialEq)]
pub enum ShearLaw {
    /// M = c1 g + c3 g^3 + c5 g^5 + ...; `coefficients` = [c1, c3, c5, ...], N/m.
    Polynomial { coefficients: Vec<f64> },
    /// M = g1 g for |g| <= locking angle, continued with slope g2 beyond (N/m per rad).
    TwoSlope { g1: f64, g2: f64, locking_angle_deg: f64 },
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
    x: Vec<f64>,
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

impl MaterialCard {
    /// Read and check a card file.
    pub fn load(path: &Path) -> Result<Self, MaterialError> {
        let text = std::fs::read_to_string(path).map_err(|e| {
            MaterialError::Invalid(format!("cannot read material card {}: {e}. Check the path.", path.display()))
        })?;
        Self::parse(&text, &path.display().to_string())
    }

    /// Read and check a card from TOML text; `origin` names it in error messages.
    pub fn parse(text: &str, origin: &str) -> Result<Self, MaterialError> {
        let fail = |m: String| MaterialError::Invalid(format!("material card {origin}: {m}"));
        let raw: RawCard = toml::from_str(text).map_err(|e| fail(e.to_string().trim_end().to_string()))?;
        let mut lines = Lines { text, map: HashMap::new() };
        lines.note("name", raw.name.span());
        lines.note("areal_mass", raw.areal_mass.span());
        lines.note("thickness", raw.thickness.span());
        lines.note("tension", raw.tension.span());
        lines.note("shear", raw.shear.span());
        lines.note("bending", raw.bending.span());
        lines.note("bending.warp", raw.bending.get_ref().warp.span());
        lines.note("bending.weft", raw.bending.get_ref().weft.span());
        if let Some(f) = &raw.flow {
            lines.note("flow", f.span());
        }
        let at = |lines: &Lines, field: &str, m: String| {
            let section = field.split('.').next().unwrap_or(field);
            match lines.map.get(field).or_else(|| lines.map.get(section)) {
                Some(l) => fail(format!("line {l}, field `{field}`: {m}")),
                None => fail(format!("field `{field}`: {m}")),
            }
        };

        // [tension]
        let t = raw.tension.into_inner();
        if let Some(cf) = &t.compression_factor {
            lines.note("tension.compression_factor", cf.span());
        }
        if let Some(l) = &t.law {
            lines.note("tension.law", l.span());
        }
        lines.note("tension.warp", t.warp.span());
        lines.note("tension.weft", t.weft.span());
        let law_name = t.law.as_ref().map(|l| l.get_ref().as_str()).unwrap_or("linear");
        let law = match law_name {
            "linear" => {
                let rigidity = |d: &Spanned<RawDir>, fibre: &str| match d.get_ref() {
                    RawDir::Rigidity(v) => Ok(*v),
                    RawDir::Knit(_) => Err(at(
                        &lines,
                        &format!("tension.{fibre}"),
                        "the linear law takes one rigidity in N/m (a number); for C, beta, alpha set law = \"knit\""
                            .into(),
                    )),
                };
                TensionLaw::Linear { warp: rigidity(&t.warp, "warp")?, weft: rigidity(&t.weft, "weft")? }
            }
            "knit" => {
                let knit = |lines: &mut Lines, d: &Spanned<RawDir>, fibre: &str| match d.get_ref() {
                    RawDir::Knit(k) => {
                        lines.note(&format!("tension.{fibre}.C"), k.c.span());
                        lines.note(&format!("tension.{fibre}.beta"), k.beta.span());
                        lines.note(&format!("tension.{fibre}.alpha"), k.alpha.span());
                        Ok(KnitParams { c: *k.c.get_ref(), beta: *k.beta.get_ref(), alpha: *k.alpha.get_ref() })
                    }
                    RawDir::Rigidity(_) => Err((
                        format!("tension.{fibre}"),
                        format!("the knit law takes a table [tension.{fibre}] with C, beta and alpha, not a number"),
                    )),
                };
                let warp = knit(&mut lines, &t.warp, "warp");
                let weft = knit(&mut lines, &t.weft, "weft");
                match (warp, weft) {
                    (Ok(warp), Ok(weft)) => TensionLaw::Knit { warp, weft },
                    (Err((f, m)), _) | (_, Err((f, m))) => return Err(at(&lines, &f, m)),
                }
            }
            other => {
                return Err(at(&lines, "tension.law", format!("unknown law '{other}': use \"linear\" or \"knit\"")));
            }
        };
        let tension = Tension { law, compression_factor: t.compression_factor.map(|c| c.into_inner()).unwrap_or(1.0) };

        // [shear]
        let s = raw.shear.into_inner();
        lines.note("shear.law", s.law.span());
        for (f, sp) in [
            ("shear.coefficients", s.coefficients.as_ref().map(|v| v.span())),
            ("shear.g1", s.g1.as_ref().map(|v| v.span())),
            ("shear.g2", s.g2.as_ref().map(|v| v.span())),
            ("shear.locking_angle_deg", s.locking_angle_deg.as_ref().map(|v| v.span())),
            ("shear.angles_deg", s.angles_deg.as_ref().map(|v| v.span())),
            ("shear.moments", s.moments.as_ref().map(|v| v.span())),
        ] {
            if let Some(sp) = sp {
                lines.note(f, sp);
            }
        }
        let given: Vec<&str> = [
            ("coefficients", s.coefficients.is_some()),
            ("g1", s.g1.is_some()),
            ("g2", s.g2.is_some()),
            ("locking_angle_deg", s.locking_angle_deg.is_some()),
            ("angles_deg", s.angles_deg.is_some()),
            ("moments", s.moments.is_some()),
        ]
        .iter()
        .filter(|(_, g)| *g)
        .map(|(f, _)| *f)
        .collect();
        let fields_for = |law: &str| -> &'static [&'static str] {
            match law {
                "polynomial" => &["coefficients"],
                "two-slope" => &["g1", "g2", "locking_angle_deg"],
                "table" => &["angles_deg", "moments"],
                _ => &[],
            }
        };
        let shear_law = s.law.get_ref().as_str();
        let wanted = fields_for(shear_law);
        if wanted.is_empty() {
            return Err(at(
                &lines,
                "shear.law",
                format!("unknown law '{shear_law}': use \"polynomial\", \"two-slope\" or \"table\""),
            ));
        }
        if let Some(f) = given.iter().find(|f| !wanted.contains(f)) {
            return Err(at(
                &lines,
                &format!("shear.{f}"),
                format!("does not belong to law = \"{shear_law}\", which takes {}", wanted.join(", ")),
            ));
        }
        if let Some(f) = wanted.iter().find(|f| !given.contains(f)) {
            return Err(at(
                &lines,
                "shear",
                format!("law = \"{shear_law}\" needs `{f}` (it takes {})", wanted.join(", ")),
            ));
        }
        let shear = match shear_law {
            "polynomial" => ShearLaw::Polynomial { coefficients: s.coefficients.unwrap().into_inner() },
            "two-slope" => ShearLaw::TwoSlope {
                g1: s.g1.unwrap().into_inner(),
                g2: s.g2.unwrap().into_inner(),
                locking_angle_deg: s.locking_angle_deg.unwrap().into_inner(),
            },
            _ => ShearLaw::Table(
                ShearTable::new(s.angles_deg.unwrap().into_inner(), s.moments.unwrap().into_inner())
                    .map_err(|(f, m)| at(&lines, &f, m))?,
            ),
        };

        let b = raw.bending.into_inner();
        let card = MaterialCard {
            name: raw.name.into_inner(),
            areal_mass: raw.areal_mass.into_inner(),
            thickness: raw.thickness.into_inner(),
            source: raw.source,
            tension,
            shear,
            bending: Bending { warp: b.warp.into_inner(), weft: b.weft.into_inner() },
            flow: raw.flow.map(|f| {
                let f = f.into_inner();
                FlowProperties { fibre_volume_fraction: f.fibre_volume_fraction, fibre_radius: f.fibre_radius }
            }),
        };
        card.check().map_err(|(f, m)| at(&lines, &f, m))?;
        Ok(card)
    }

    /// Check a card built in code (the same physical checks as [`Self::load`]).
    pub fn validate(&self) -> Result<(), MaterialError> {
        self.check()
            .map_err(|(f, m)| MaterialError::Invalid(format!("material card '{}', field `{f}`: {m}", self.name)))
    }

    /// The physical checks. Err((field, message)).
    fn check(&self) -> Result<(), (String, String)> {
        let positive = |f: &str, v: f64, unit: &str| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err((f.to_string(), format!("must be positive ({unit}), got {v}")))
            }
        };
        if self.name.trim().is_empty() {
            return Err(("name".into(), "must not be empty".into()));
        }
        positive("areal_mass", self.areal_mass, "kg/m^2")?;
        positive("thickness", self.thickness, "m")?;
        if let Some(f) = &self.flow {
            let vf = f.fibre_volume_fraction;
            if !(vf > 0.0 && vf < super::flow::VF_MAX_HEX) {
                return Err((
                    "flow.fibre_volume_fraction".into(),
                    format!("must lie between 0 and {:.4} (fibres touching), got {vf}", super::flow::VF_MAX_HEX),
                ));
            }
            positive("flow.fibre_radius", f.fibre_radius, "m")?;
        }
        let cf = self.tension.compression_factor;
        if !(cf.is_finite() && (0.0..=1.0).contains(&cf)) {
            return Err((
                "tension.compression_factor".into(),
                format!("must lie in [0, 1] (it scales the rigidity in compression), got {cf}"),
            ));
        }
        match self.tension.law {
            TensionLaw::Linear { warp, weft } => {
                positive("tension.warp", warp, "tensile rigidity, N/m")?;
                positive("tension.weft", weft, "tensile rigidity, N/m")?;
            }
            TensionLaw::Knit { warp, weft } => {
                for (fibre, k) in [("warp", warp), ("weft", weft)] {
                    positive(&format!("tension.{fibre}.C"), k.c, "low-strain rigidity, N/m")?;
                    for (f, v) in [("beta", k.beta), ("alpha", k.alpha)] {
                        if !(v.is_finite() && v >= 0.0) {
                            return Err((
                                format!("tension.{fibre}.{f}"),
                                format!("must be a finite number >= 0, got {v}"),
                            ));
                        }
                    }
                }
            }
        }
        self.shear.check()?;
        positive("bending.warp", self.bending.warp, "flexural rigidity, N m")?;
        positive("bending.weft", self.bending.weft, "flexural rigidity, N m")?;
        Ok(())
    }

    /// Stretch energy per unit reference length and unit width of a fibre family at Green strain
    /// `e`: (W, dW/de, d2W/de2), in N/m (dW/de is the fibre tension per unit width).
    pub fn tension(&self, fibre: Fibre, e: f64) -> (f64, f64, f64) {
        let cf = self.tension.compression_factor;
        let linear = |d: f64| {
            let d = if e < 0.0 { cf * d } else { d };
            (0.5 * d * e * e, d * e, d)
        };
        match (self.tension.law, fibre) {
            (TensionLaw::Linear { warp, .. }, Fibre::Warp) | (TensionLaw::Linear { weft: warp, .. }, Fibre::Weft) => {
                linear(warp)
            }
            (TensionLaw::Knit { warp: k, .. }, Fibre::Warp) | (TensionLaw::Knit { weft: k, .. }, Fibre::Weft) => {
                if e < 0.0 {
                    linear(k.c)
                } else {
                    k.stretch(e)
                }
            }
        }
    }

    /// In-plane shear energy per unit area at shear angle `g` (radians, signed):
    /// (W, M = dW/dg, dM/dg), W in J/m^2 and M the shear moment per unit area in N/m.
    pub fn shear(&self, g: f64) -> (f64, f64, f64) {
        self.shear.eval(g)
    }

    /// Flexural rigidity per unit width of a fibre family, N m.
    pub fn bending(&self, fibre: Fibre) -> f64 {
        match fibre {
            Fibre::Warp => self.bending.warp,
            Fibre::Weft => self.bending.weft,
        }
    }

    /// The card as TOML in the schema [`Self::load`] reads; loading it back gives an equal card.
    pub fn to_toml_string(&self) -> String {
        let mut s = String::new();
        let f = |v: f64| format!("{v:?}"); // shortest round-trip form, always a TOML float
        let list = |v: &[f64]| format!("[{}]", v.iter().map(|x| f(*x)).collect::<Vec<_>>().join(", "));
        let q = |t: &str| toml::Value::String(t.to_string()).to_string();
        let _ = writeln!(s, "name = {}", q(&self.name));
        let _ = writeln!(s, "areal_mass = {} # kg/m^2", f(self.areal_mass));
        let _ = writeln!(s, "thickness = {} # m", f(self.thickness));
        if let Some(src) = &self.source {
            let _ = writeln!(s, "source = {}", q(src));
        }
        s.push_str("\n[tension]\n");
        match self.tension.law {
            TensionLaw::Linear { warp, weft } => {
                s.push_str("law = \"linear\" # W = D e^2 / 2, D in N/m\n");
                let _ = writeln!(s, "compression_factor = {}", f(self.tension.compression_factor));
                let _ = writeln!(s, "warp = {}", f(warp));
                let _ = writeln!(s, "weft = {}", f(weft));
            }
            TensionLaw::Knit { warp, weft } => {
                s.push_str(
                    "law = \"knit\" # sigma = C e + beta (1/(1 - alpha e)^2 - 1 - 2 alpha e), C and beta in N/m\n",
                );
                let _ = writeln!(s, "compression_factor = {}", f(self.tension.compression_factor));
                for (fibre, k) in [("warp", warp), ("weft", weft)] {
                    let _ = writeln!(
                        s,
                        "\n[tension.{fibre}]\nC = {}\nbeta = {}\nalpha = {}",
                        f(k.c),
                        f(k.beta),
                        f(k.alpha)
                    );
                }
            }
        }
        s.push_str("\n[shear] # shear moment per unit area M(gamma), N/m\n");
        match &self.shear {
            ShearLaw::Polynomial { coefficients } => {
                s.push_str("law = \"polynomial\" # M = c1 g + c3 g^3 + ...\n");
                let _ = writeln!(s, "coefficients = {}", list(coefficients));
            }
            ShearLaw::TwoSlope { g1, g2, locking_angle_deg } => {
                s.push_str("law = \"two-slope\" # N/m per rad below / above the locking angle\n");
                let _ = writeln!(s, "g1 = {}\ng2 = {}\nlocking_angle_deg = {}", f(*g1), f(*g2), f(*locking_angle_deg));
            }
            ShearLaw::Table(t) => {
                s.push_str("law = \"table\" # monotone cubic through (0, 0) and these points\n");
                let _ = writeln!(s, "angles_deg = {}", list(t.angles_deg()));
                let _ = writeln!(s, "moments = {}", list(t.moments()));
            }
        }
        s.push_str("\n[bending] # flexural rigidity per unit width, N m\n");
        let _ = writeln!(s, "warp = {}\nweft = {}", f(self.bending.warp), f(self.bending.weft));
        if let Some(flow) = &self.flow {
            s.push_str("\n[flow]\n");
            let _ = writeln!(s, "fibre_volume_fraction = {}", f(flow.fibre_volume_fraction));
            let _ = writeln!(s, "fibre_radius = {} # m", f(flow.fibre_radius));
        }
        s
    }
}

/// Line numbers of the fields of a card file, for error messages.
struct Lines<'a> {
    text: &'a str,
    map: HashMap<String, usize>,
}

impl Lines<'_> {
    fn note(&mut self, field: &str, span: std::ops::Range<usize>) {
        let line = 1 + self.text[..span.start.min(self.text.len())].matches('\n').count();
        self.map.insert(field.to_string(), line);
    }
}

// ---- the file as written -------------------------------------------------------------------

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCard {
    name: Spanned<String>,
    areal_mass: Spanned<f64>,
    thickness: Spanned<f64>,
    source: Option<String>,
    tension: Spanned<RawTension>,
    shear: Spanned<RawShear>,
    bending: Spanned<RawBending>,
    flow: Option<Spanned<RawFlow>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFlow {
    fibre_volume_fraction: f64,
    fibre_radius: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTension {
    law: Option<Spanned<String>>,
    compression_factor: Option<Spanned<f64>>,
    warp: Spanned<RawDir>,
    weft: Spanned<RawDir>,
}

/// A tension entry: a rigidity (linear law) or a knit table.
enum RawDir {
    Rigidity(f64),
    Knit(RawKnit),
}

impl<'de> Deserialize<'de> for RawDir {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = RawDir;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a tensile rigidity in N/m (linear law) or a table with C, beta, alpha (knit law)")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<RawDir, E> {
                Ok(RawDir::Rigidity(v))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<RawDir, E> {
                Ok(RawDir::Rigidity(v as f64))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<RawDir, E> {
                Ok(RawDir::Rigidity(v as f64))
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<RawDir, A::Error> {
                RawKnit::deserialize(de::value::MapAccessDeserializer::new(map)).map(RawDir::Knit)
            }
        }
        d.deserialize_any(V)
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawKnit {
    #[serde(rename = "C", alias = "c")]
    c: Spanned<f64>,
    beta: Spanned<f64>,
    alpha: Spanned<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawShear {
    law: Spanned<String>,
    coefficients: Option<Spanned<Vec<f64>>>,
    g1: Option<Spanned<f64>>,
    g2: Option<Spanned<f64>>,
    locking_angle_deg: Option<Spanned<f64>>,
    angles_deg: Option<Spanned<Vec<f64>>>,
    moments: Option<Spanned<Vec<f64>>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBending {
    warp: Spanned<f64>,
    weft: Spanned<f64>,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 1 gf in newtons.
    const GF: f64 = 9.80665e-3;

    fn card_with(tension: &str, shear: &str) -> String {
        format!(
            "name = \"t\"\nareal_mass = 0.3\nthickness = 5.0e-4\n\n[tension]\n{tension}\n\n[shear]\n{shear}\n\n\
             [bending]\nwarp = 1.0e-7\nweft = 2.0e-7\n"
        )
    }

    fn parse(text: &str) -> Result<MaterialCard, String> {
        MaterialCard::parse(text, "test.toml").map_err(|e| e.to_string())
    }

    const LINEAR: &str = "law = \"linear\"\nwarp = 2.0e5\nweft = 1.0e5";
    const KNIT: &str = "law = \"knit\"\n[tension.warp]\nC = 500.0\nbeta = 10.0\nalpha = 2.5\n\
                        [tension.weft]\nc = 120\nbeta = 20.0\nalpha = 1.2";
    const POLY: &str = "law = \"polynomial\"\ncoefficients = [0.5, 2.0, 3.0]";
    const TWO: &str = "law = \"two-slope\"\ng1 = 2.0\ng2 = 200.0\nlocking_angle_deg = 35.0";
    const TABLE: &str =
        "law = \"table\"\nangles_deg = [10.0, 20.0, 30.0, 40.0, 50.0]\nmoments = [0.2, 0.5, 1.1, 3.0, 12.0]";

    fn all_cards() -> Vec<MaterialCard> {
        let mut v = Vec::new();
        for t in [LINEAR, KNIT, "law = \"linear\"\ncompression_factor = 0.05\nwarp = 3.0e5\nweft = 1.0e5"] {
            for s in [POLY, TWO, TABLE] {
                v.push(parse(&card_with(t, s)).unwrap());
            }
        }
        let mut k = parse(&card_with(KNIT, TWO)).unwrap();
        k.tension.compression_factor = 0.1;
        v.push(k);
        v
    }

    /// Central difference of f at x with step h.
    fn fd(f: impl Fn(f64) -> f64, x: f64, h: f64) -> f64 {
        (f(x + h) - f(x - h)) / (2.0 * h)
    }

    fn close(a: f64, b: f64, rel: f64, abs: f64) -> bool {
        (a - b).abs() <= rel * a.abs().max(b.abs()) + abs
    }

    #[test]
    fn tension_derivatives_are_exact() {
        for card in all_cards() {
            for fibre in [Fibre::Warp, Fibre::Weft] {
                let t = |e: f64| card.tension(fibre, e);
                let mut strains: Vec<f64> = (-40..=40).map(|i| i as f64 * 0.0095 + 0.0003).collect();
                if let TensionLaw::Knit { warp, weft } = card.tension.law {
                    let k = if fibre == Fibre::Warp { warp } else { weft };
                    let lim = k.stretch_limit();
                    // Near the singularity and on the continuation.
                    strains.extend([0.9, 0.99, 0.9985, 1.002, 1.5, 3.0].map(|s| s * lim));
                }
                let sing = match card.tension.law {
                    TensionLaw::Knit { warp, weft } => 1.0 / if fibre == Fibre::Warp { warp.alpha } else { weft.alpha },
                    _ => f64::INFINITY,
                };
                for &e in &strains {
                    let (w, dw, d2w) = t(e);
                    assert!(w.is_finite() && dw.is_finite() && d2w.is_finite());
                    // A step well inside the distance to 0 (the compression kink) and to 1/alpha.
                    let h = 1e-5 * e.abs().max(1e-3).min((sing - e).abs());
                    let fd1 = fd(|x| t(x).0, e, h);
                    let fd2 = fd(|x| t(x).1, e, h);
                    assert!(close(fd1, dw, 1e-6, 1e-12 * (1.0 + w.abs() / h)), "{fibre:?} e={e}: dW {fd1} vs {dw}");
                    assert!(close(fd2, d2w, 1e-6, 1e-12 * (1.0 + dw.abs() / h)), "{fibre:?} e={e}: d2W {fd2} vs {d2w}");
                }
                assert_eq!(t(0.0), (0.0, 0.0, t(0.0).2));
            }
        }
    }

    #[test]
    fn shear_derivatives_are_exact_and_odd() {
        for card in all_cards() {
            let kink = match &card.shear {
                ShearLaw::TwoSlope { locking_angle_deg, .. } => Some(locking_angle_deg.to_radians()),
                _ => None,
            };
            let knots: Vec<f64> = match &card.shear {
                ShearLaw::Table(t) => t.x.clone(),
                _ => vec![],
            };
            for i in -150..=150 {
                let g = i as f64 * 0.0105 + 0.0001;
                let h = 1e-6;
                // d2W (dM/dg) jumps at the two-slope kink and is only C0 at table knots: skip them.
                if kink.is_some_and(|k| (g.abs() - k).abs() < 3.0 * h)
                    || knots.iter().any(|k| (g.abs() - k).abs() < 3.0 * h)
                {
                    continue;
                }
                let (w, m, k) = card.shear(g);
                assert!(close(fd(|x| card.shear(x).0, g, h), m, 1e-7, 1e-9), "{} g={g}: M", card.shear.law_name());
                assert!(close(fd(|x| card.shear(x).1, g, h), k, 1e-6, 1e-8), "{} g={g}: dM", card.shear.law_name());
                let (w2, m2, k2) = card.shear(-g);
                assert!(close(w, w2, 1e-14, 0.0) && close(m, -m2, 1e-14, 0.0) && close(k, k2, 1e-14, 0.0));
                assert!(w >= 0.0 && m * g >= 0.0);
            }
            // Near the kink, on each side.
            if let Some(gl) = kink {
                for g in [gl - 1e-4, gl + 1e-4, gl - 1e-3, gl + 1e-3] {
                    let h = 1e-6;
                    let (_, m, k) = card.shear(g);
                    assert!(close(fd(|x| card.shear(x).0, g, h), m, 1e-7, 1e-9));
                    assert!(close(fd(|x| card.shear(x).1, g, h), k, 1e-6, 1e-8));
                }
                let (g1, g2) = match card.shear {
                    ShearLaw::TwoSlope { g1, g2, .. } => (g1, g2),
                    _ => unreachable!(),
                };
                assert_eq!(card.shear(gl - 1e-3).2, g1);
                assert_eq!(card.shear(gl + 1e-3).2, g2);
                assert!(close(card.shear(gl + 1e-12).1, g1 * gl, 1e-9, 0.0)); // continuous
            }
        }
    }

    #[test]
    fn shear_table_interpolates_monotonically() {
        let card = parse(&card_with(LINEAR, TABLE)).unwrap();
        let t = match &card.shear {
            ShearLaw::Table(t) => t.clone(),
            _ => unreachable!(),
        };
        for (a, m) in t.angles_deg().iter().zip(t.moments()) {
            assert!(close(card.shear(a.to_radians()).1, *m, 1e-13, 1e-14));
        }
        let mut last = -1.0;
        for i in 0..=800 {
            let g = (i as f64 * 0.1).to_radians();
            let (_, m, k) = card.shear(g);
            assert!(m >= last - 1e-14 && k >= 0.0, "not monotone at {g}");
            last = m;
        }
        // Linear beyond the table with the end slope.
        let (_, m1, k1) = card.shear(1.0);
        let (_, m2, k2) = card.shear(1.2);
        assert!(close(m2 - m1, 0.2 * k1, 1e-12, 0.0) && k1 == k2);
        // Continuous at the last knot.
        let xl = 50f64.to_radians();
        assert!(close(card.shear(xl - 1e-9).1, card.shear(xl + 1e-9).1, 1e-7, 0.0));
        // Energy is the integral of M (Simpson on a fine grid).
        let n = 2000;
        let g_end = 1.1;
        let hh = g_end / n as f64;
        let mut simpson = 0.0;
        for i in 0..=n {
            let wgt = if i == 0 || i == n {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            };
            simpson += wgt * card.shear(i as f64 * hh).1;
        }
        simpson *= hh / 3.0;
        assert!(close(card.shear(g_end).0, simpson, 1e-8, 0.0));
        // An explicit (0, 0) gives the same law.
        let t0 = ShearTable::new(vec![0.0, 10.0, 20.0, 30.0, 40.0, 50.0], vec![0.0, 0.2, 0.5, 1.1, 3.0, 12.0]).unwrap();
        for g in [0.1, 0.3, 0.7, 1.0] {
            assert_eq!(ShearLaw::Table(t0.clone()).eval(g), card.shear(g));
        }
    }

    #[test]
    fn knit_law_matches_seed_004_and_its_integral() {
        let k = KnitParams { c: 500.0, beta: 10.0, alpha: 2.5 };
        for e in [0.01, 0.1, 0.2, 0.3, 0.39] {
            let x: f64 = 2.5 * e;
            let sigma = 500.0 * e + 10.0 * (1.0 / (1.0 - x).powi(2) - 1.0 - 2.0 * x);
            assert!(close(k.stretch(e).1, sigma, 1e-12, 1e-12));
        }
        // W = integral of sigma, by Simpson.
        let e_end = 0.35;
        let n = 4000;
        let h = e_end / n as f64;
        let mut s = 0.0;
        for i in 0..=n {
            let wgt = if i == 0 || i == n {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            };
            s += wgt * k.stretch(i as f64 * h).1;
        }
        assert!(close(k.stretch(e_end).0, s * h / 3.0, 1e-9, 0.0));
        // Past the singularity: huge, finite, increasing.
        let (w, t, kk) = k.stretch(1.0);
        assert!(w.is_finite() && t > 1e6 * 10.0 && kk > 0.0);
        let (w2, t2, _) = k.stretch(1e6);
        assert!(w2.is_finite() && w2 > w && t2 > t);
        // Linear in compression with the compression factor.
        let card = {
            let mut c = parse(&card_with(KNIT, POLY)).unwrap();
            c.tension.compression_factor = 0.1;
            c
        };
        assert_eq!(card.tension(Fibre::Warp, -0.2), (0.5 * 50.0 * 0.04, 50.0 * -0.2, 50.0));
    }

    #[test]
    fn linear_tension_and_bending() {
        let card =
            parse(&card_with("law = \"linear\"\ncompression_factor = 0.5\nwarp = 2.0e5\nweft = 1.0e5", POLY)).unwrap();
        assert_eq!(card.tension(Fibre::Warp, 0.01), (0.5 * 2.0e5 * 1e-4, 2.0e3, 2.0e5));
        assert_eq!(card.tension(Fibre::Weft, -0.01), (0.5 * 0.5e5 * 1e-4, -0.5e3, 0.5e5));
        assert_eq!(card.bending(Fibre::Warp), 1.0e-7);
        assert_eq!(card.bending(Fibre::Weft), 2.0e-7);
        // law defaults to linear and compression_factor to 1.
        let card = parse(&card_with("warp = 200000\nweft = 1.0e5", POLY)).unwrap();
        assert_eq!(card.tension.compression_factor, 1.0);
        assert_eq!(card.tension.law, TensionLaw::Linear { warp: 2.0e5, weft: 1.0e5 });
    }

    #[test]
    fn round_trip_through_toml() {
        for mut card in all_cards() {
            card.source = Some("Someone et al. \"quoted\"\n2024, p. 3 \\ x".into());
            card.areal_mass = 0.1 + 0.2; // not a short decimal
            card.bending.warp = 1.0 / 3.0 * 1e-7;
            let text = card.to_toml_string();
            let back = parse(&text).unwrap_or_else(|e| panic!("{e}\n{text}"));
            assert_eq!(back, card, "{text}");
        }
    }

    #[test]
    fn errors_name_the_line_and_field() {
        let cases: Vec<(String, &str, usize)> = vec![
            (card_with(LINEAR, POLY).replace("areal_mass = 0.3", "areal_mass = -0.3"), "`areal_mass`", 2),
            (card_with(LINEAR, POLY).replace("thickness = 5.0e-4", "thickness = 0"), "`thickness`", 3),
            (card_with(LINEAR, POLY).replace("warp = 2.0e5", "warp = -2.0e5"), "`tension.warp`", 7),
            (card_with(LINEAR, POLY).replace("weft = 2.0e-7", "weft = 0.0"), "`bending.weft`", 16),
            (card_with(LINEAR, TWO).replace("g2 = 200.0", "g2 = -1.0"), "`shear.g2`", 13),
            (
                card_with(LINEAR, TWO).replace("locking_angle_deg = 35.0", "locking_angle_deg = 95.0"),
                "`shear.locking_angle_deg`",
                14,
            ),
            (card_with(LINEAR, TWO).replace("g1 = 2.0\n", ""), "needs `g1`", 10),
            (
                card_with(LINEAR, POLY).replace("coefficients = [0.5, 2.0, 3.0]", "coefficients = [0.5, -20.0]"),
                "positive and non-decreasing",
                12,
            ),
            (
                card_with(LINEAR, POLY).replace("coefficients = [0.5, 2.0, 3.0]", "coefficients = [0.5]\ng1 = 2.0"),
                "`shear.g1`",
                13,
            ),
            (card_with(LINEAR, POLY).replace("coefficients", "g1"), "expected f64", 12),
            (card_with(LINEAR, TABLE).replace("1.1, 3.0", "3.1, 3.0"), "non-decreasing", 13),
            (card_with(LINEAR, TABLE).replace("40.0, 50.0", "40.0, 40.0"), "strictly increasing", 12),
            (card_with(LINEAR, TABLE).replace(", 12.0]", "]"), "one moment per angle", 13),
            (card_with(KNIT, POLY).replace("beta = 10.0", "beta = -10.0"), "`tension.warp.beta`", 9),
            (card_with(KNIT, POLY).replace("alpha = 2.5", "gamma = 2.5"), "unknown field `gamma`", 10),
            (card_with(KNIT, POLY).replace("law = \"knit\"", "law = \"linear\""), "`tension.warp`", 7),
            (card_with(LINEAR, POLY).replace("law = \"linear\"", "law = \"knit\""), "`tension.warp`", 7),
            (
                card_with(LINEAR, POLY).replace("law = \"linear\"", "law = \"neo-hookean\""),
                "unknown law 'neo-hookean'",
                6,
            ),
            (card_with(LINEAR, POLY).replace("law = \"polynomial\"", "law = \"cubic\""), "unknown law 'cubic'", 11),
            (card_with(LINEAR, POLY).replace("thickness", "thicknes"), "unknown field `thicknes`", 3),
            (card_with(LINEAR, POLY).replace("areal_mass = 0.3", "areal_mass = \"heavy\""), "areal_mass", 2),
            (
                card_with(LINEAR, POLY).replace("weft = 1.0e5", "weft = 1.0e5\ncompression_factor = 2.0"),
                "`tension.compression_factor`",
                9,
            ),
            (card_with(LINEAR, POLY).replace("[bending]\nwarp = 1.0e-7\n", "[bending]\n"), "missing field `warp`", 14),
        ];
        let mut wrong = Vec::new();
        for (text, needle, line) in cases {
            let e = parse(&text).expect_err(&text);
            if !(e.contains(needle)
                && e.contains(&format!("line {line}"))
                && e.starts_with("material card test.toml: "))
            {
                wrong.push(format!("wanted '{needle}' at line {line}, got: {e}"));
            }
        }
        assert!(wrong.is_empty(), "{}", wrong.join("\n"));
    }

    fn materials_dir() -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("materials")
    }

    #[test]
    fn bundled_cards_load() {
        let mut n = 0;
        for entry in std::fs::read_dir(materials_dir()).unwrap() {
            let p = entry.unwrap().path();
            if p.extension().is_some_and(|x| x == "toml") {
                let card = MaterialCard::load(&p).unwrap_or_else(|e| panic!("{e}"));
                assert!(card.source.is_some(), "{}: cite the source", p.display());
                assert_eq!(MaterialCard::parse(&card.to_toml_string(), "rt").unwrap(), card);
                n += 1;
            }
        }
        assert!(n >= 3);
    }

    #[test]
    fn sze_liu_table1_conversion() {
        let card = MaterialCard::load(&materials_dir().join("sze-liu-table1.toml")).unwrap();
        // gf/cm -> N/m; gf cm^2/cm = gf cm -> N m; gf/cm^2 weight -> g/cm^2 mass -> kg/m^2.
        let per_cm = GF / 1e-2;
        let rel = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs();
        match card.tension.law {
            TensionLaw::Linear { warp, weft } => {
                assert!(rel(warp, 1118.2 * per_cm) && rel(weft, 759.5 * per_cm), "{warp} {weft}");
            }
            _ => panic!("Table 1 is linear"),
        }
        assert_eq!(card.tension.compression_factor, 1.0);
        assert!(rel(card.bending(Fibre::Warp), 0.083 * GF * 1e-2));
        assert!(rel(card.bending(Fibre::Weft), 0.063 * GF * 1e-2));
        let (_, m, k) = card.shear(0.1);
        assert!(rel(k, 41.8 * per_cm) && rel(m, 0.1 * 41.8 * per_cm));
        assert!(rel(card.areal_mass, 0.019 * 1e-3 / 1e-4)); // 0.19 kg/m^2
        assert!(rel(card.areal_mass * 9.80665, 0.019 * GF / 1e-4)); // the weight, N/m^2
        assert!(rel(card.thickness, 0.0593e-2));
        // Sanity: the numbers in SI.
        assert!((card.bending.warp - 8.1395e-6).abs() < 1e-9);
        assert!((card.areal_mass - 0.19).abs() < 1e-12);
    }

    #[test]
    fn bundled_woven_cards_lock() {
        // (card, an angle below locking, an angle past it), degrees.
        for (file, below, past) in [("glass-plain-weave.toml", 25.0f64, 40.0f64), ("carbon-twill.toml", 25.0, 55.0)] {
            let card = MaterialCard::load(&materials_dir().join(file)).unwrap();
            // Steep rise: the tangent stiffness well past locking is far above the initial one.
            let k0 = card.shear(1e-3).2;
            let k_hi = card.shear(past.to_radians()).2;
            let k_lo = card.shear(below.to_radians()).2;
            assert!(k_hi > 20.0 * k0 && k_lo < 5.0 * k0, "{file}: {k0} {k_lo} {k_hi}");
        }
    }
}
