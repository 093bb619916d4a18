//! Fitting material laws to test data: the shear law to picture-frame or bias-extension
//! force-displacement curves, the knit tension law to uniaxial stress-strain data.
//!
//! Kinematics (REFERENCES.md section 3, seed 002 eqs. 1-4; fibres inextensible):
//! - Picture frame, side L, crosshead displacement d:
//!   gamma = pi/2 - 2 arccos(u), u = 1/sqrt(2) + d/(2L), so dgamma/dd = 1 / (L sqrt(1 - u^2)),
//!   and virtual work F = L^2 M(gamma) dgamma/dd, i.e. M = F sqrt(1 - u^2) / L
//!   (= F (cos(gamma/2) - sin(gamma/2)) / (sqrt(2) L)).
//! - Bias extension, length L >= 2W, width W, D = L - W: gamma_C = pi/2 - 2 arccos((D + d)/(sqrt(2) D))
//!   in the centre zone, gamma_C/2 in zones B, and
//!   F = 2 / (D (cos(gamma_C/2) - sin(gamma_C/2))) (A_C M(gamma_C) + A_B M(gamma_C/2) / 2),
//!   A_C = W (L - 3W/2), A_B = W^2.
//!
//! Both shear laws fitted here are linear in their stiffnesses, so every fit is a linear least
//! squares problem (for two-slope, at each trial locking angle: a grid search refined by golden
//! section picks the locking angle; a polynomial that comes out non-monotone is refitted with
//! non-negative coefficients). The knit law is linear in C and beta at fixed alpha:
//! variable projection (grid + golden section on alpha) then Levenberg-Marquardt on all three.
use super::laws::{KnitParams, ShearLaw, KNIT_STRETCH_LIMIT};
use super::test_kinematics::{BiasExtensionKinematics, PictureFrameKinematics};
use crate::numeric::golden_section_min;
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

/// Which shear law to fit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ShearLawKind {
    /// M = c1 g + c3 g^3 + ... with this many odd-power terms (1..=8).
    Polynomial {
        /// Odd-power terms.
        terms: usize,
    },
    /// M = g1 g up to the locking angle, slope g2 beyond.
    TwoSlope,
}

impl std::str::FromStr for ShearLawKind {
    type Err = String;
    /// `polynomial` (3 terms), `polynomial:N` or `two-slope`.
    fn from_str(s: &str) -> Result<Self, String> {
        let s = s.trim();
        if s == "two-slope" {
            return Ok(ShearLawKind::TwoSlope);
        }
        let terms = match s.strip_prefix("polynomial") {
            Some("") => 3,
            Some(rest) => match rest.strip_prefix(':').and_then(|n| n.trim().parse::<usize>().ok()) {
                Some(n) => n,
                None => {
                    return Err(format!(
                        "'{s}': write polynomial:N with N the number of odd-power terms, like polynomial:3"
                    ))
                }
            },
            None => {
                return Err(format!(
                    "unknown shear law '{s}': use polynomial:N (N terms c1 g + c3 g^3 + ...) or two-slope"
                ))
            }
        };
        if !(1..=MAX_POLYNOMIAL_TERMS).contains(&terms) {
            return Err(format!("polynomial:{terms}: use 1 to {MAX_POLYNOMIAL_TERMS} terms"));
        }
        Ok(ShearLawKind::Polynomial { terms })
    }
}

/// Most odd-power terms a polynomial shear fit may have.
pub const MAX_POLYNOMIAL_TERMS: usize = 8;

/// Quality of a fit, in the units of the fitted quantity (see each fit function).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitReport {
    /// Root mean square residual.
    pub rms: f64,
    /// Coefficient of determination, 1 - SS_res / SS_tot.
    pub r_squared: f64,
    /// Largest |residual|.
    pub max_abs_residual: f64,
    /// Data points fitted.
    pub points: usize,
}

impl FitReport {
    fn new(observed: &[f64], predicted: &[f64]) -> Self {
        let n = observed.len();
        let mean = observed.iter().sum::<f64>() / n as f64;
        let mut ss_res = 0.0;
        let mut ss_tot = 0.0;
        let mut max_abs: f64 = 0.0;
        for (o, p) in observed.iter().zip(predicted) {
            let r = o - p;
            ss_res += r * r;
            ss_tot += (o - mean) * (o - mean);
            max_abs = max_abs.max(r.abs());
        }
        let r_squared = if ss_tot > 0.0 {
            1.0 - ss_res / ss_tot
        } else if ss_res == 0.0 {
            1.0
        } else {
            0.0
        };
        FitReport { rms: (ss_res / n as f64).sqrt(), r_squared, max_abs_residual: max_abs, points: n }
    }
}

/// Why a fit could not be made.
#[derive(Debug, thiserror::Error)]
pub enum FitError {
    /// The data or the test geometry cannot be used; the message says which point and why.
    #[error("{0}")]
    Data(String),
    /// The data do not determine the law, or the best fit is not a physical law.
    #[error("{0}")]
    Fit(String),
}

// ---- forces from the test kinematics --------------------------------------------------------

/// Picture-frame force (N) of a law at displacement `d`: F = L^2 M(gamma) dgamma/dd.
pub fn picture_frame_force(law: &ShearLaw, d: f64, side: f64) -> Option<f64> {
    let (g, dg) = PictureFrameKinematics { side }.shear(d)?;
    Some(side * side * law.moment(g) * dg)
}

/// The bias-extension force as a combination of moments: [(angle, weight)] with
/// F = sum weight * M(angle): F = A_C M(gamma) dgamma/dd + A_B M(gamma/2) dgamma/dd / 2, the
/// central zone of area A_C = W (L - 3W/2) at gamma and the zones beside the clamps, of total
/// area A_B = W^2, at gamma / 2.
fn bias_extension_terms(d: f64, length: f64, width: f64) -> Option<[(f64, f64); 2]> {
    let (g, rate) = BiasExtensionKinematics { length, width }.shear(d)?;
    let a_c = width * (length - 1.5 * width);
    let a_b = width * width;
    Some([(g, rate * a_c), (g / 2.0, rate * a_b / 2.0)])
}

/// Bias-extension force (N) of a law at elongation `d`.
pub fn bias_extension_force(law: &ShearLaw, d: f64, length: f64, width: f64) -> Option<f64> {
    Some(bias_extension_terms(d, length, width)?.iter().map(|(g, w)| w * law.moment(*g)).sum())
}

// ---- shear fits --------------------------------------------------------------------------------

/// One observation of a quantity that is a fixed combination of shear moments:
/// target = sum weight * M(angle).
struct Obs {
    terms: Vec<(f64, f64)>,
    target: f64,
}

fn check_points(data: &[(f64, f64)], what: &str) -> Result<(), FitError> {
    for (i, (x, y)) in data.iter().enumerate() {
        if !(x.is_finite() && y.is_finite()) {
            return Err(FitError::Data(format!("{what} point {}: ({x}, {y}) is not a pair of finite numbers", i + 1)));
        }
    }
    Ok(())
}

/// Fit a shear law to picture-frame data: (crosshead displacement m, force N) for a frame of
/// side `side` (m, hinge to hinge). Each point gives M = F / (L^2 dgamma/dd) at its angle and the
/// law is fitted to these moments; the report is in N/m (moment per unit area).
///
/// Polynomial fits are plain linear least squares; if that law is not monotone (M > 0 and
/// dM/dg >= 0 up to 85 deg, as a card requires) the fit is redone with every coefficient >= 0,
/// and the coefficients held at that bound come out exactly 0. Two-slope fits: grid search and
/// golden section on the locking angle, linear least squares for g1 and g2 at each trial.
pub fn fit_shear_picture_frame(
    data: &[(f64, f64)],
    side: f64,
    kind: ShearLawKind,
) -> Result<(ShearLaw, FitReport), FitError> {
    if !(side.is_finite() && side > 0.0) {
        return Err(FitError::Data(format!("the frame side must be a positive length, got {side}")));
    }
    check_points(data, "picture-frame")?;
    let mut obs = Vec::with_capacity(data.len());
    for (i, &(d, f)) in data.iter().enumerate() {
        let (g, dg) = PictureFrameKinematics { side }.shear(d).ok_or_else(|| {
            FitError::Data(format!(
                "picture-frame point {}: displacement {d} is beyond the travel of a frame of side {side} \
                 (the shear angle reaches 90 deg at d = {:.6}); check the units of the data and of the side",
                i + 1,
                PictureFrameKinematics { side }.travel()
            ))
        })?;
        obs.push(Obs { terms: vec![(g, 1.0)], target: f / (side * side * dg) });
    }
    fit_shear(&obs, kind)
}

/// Fit a shear law to bias-extension data: (elongation m, force N) of a specimen of length
/// `length` and width `width` (m, free length between the clamps, length >= 2 width). The force
/// is linear in the law's stiffnesses although M enters at two angles, so the fit is least squares
/// on F directly; the report is in N. The laws are fitted as in [`fit_shear_picture_frame`].
pub fn fit_shear_bias_extension(
    data: &[(f64, f64)],
    length: f64,
    width: f64,
    kind: ShearLawKind,
) -> Result<(ShearLaw, FitReport), FitError> {
    if !(width.is_finite() && width > 0.0 && length.is_finite() && length >= 2.0 * width) {
        return Err(FitError::Data(format!(
            "bias extension needs a positive width and length >= 2 x width (three shear zones), got length {length}, width {width}"
        )));
    }
    check_points(data, "bias-extension")?;
    let mut obs = Vec::with_capacity(data.len());
    for (i, &(d, f)) in data.iter().enumerate() {
        let terms = bias_extension_terms(d, length, width).ok_or_else(|| {
            FitError::Data(format!(
                "bias-extension point {}: elongation {d} takes the central zone past 90 deg shear for a {length} x {width} \
                 specimen (limit d = {:.6}); check the units",
                i + 1,
                BiasExtensionKinematics { length, width }.travel()
            ))
        })?;
        obs.push(Obs { terms: terms.to_vec(), target: f });
    }
    fit_shear(&obs, kind)
}

fn fit_shear(obs: &[Obs], kind: ShearLawKind) -> Result<(ShearLaw, FitReport), FitError> {
    let n = obs.len();
    let targets: Vec<f64> = obs.iter().map(|o| o.target).collect();
    let predict = |law: &ShearLaw| -> Vec<f64> {
        obs.iter().map(|o| o.terms.iter().map(|(g, w)| w * law.moment(*g)).sum()).collect()
    };
    let law = match kind {
        ShearLawKind::Polynomial { terms } => {
            if !(1..=MAX_POLYNOMIAL_TERMS).contains(&terms) {
                return Err(FitError::Data(format!("polynomial:{terms}: use 1 to {MAX_POLYNOMIAL_TERMS} terms")));
            }
            if n < terms {
                return Err(FitError::Data(format!(
                    "{n} points cannot determine {terms} coefficients: give more data"
                )));
            }
            let cols: Vec<Vec<f64>> = (0..terms)
                .map(|j| obs.iter().map(|o| o.terms.iter().map(|(g, w)| w * g.powi(2 * j as i32 + 1)).sum()).collect())
                .collect();
            let (c, _) = lstsq(&cols, &targets).ok_or_else(|| {
                FitError::Fit(format!(
                    "the data do not determine {terms} polynomial coefficients (the angles are too few or too close together): \
                     use fewer terms"
                ))
            })?;
            let law = ShearLaw::Polynomial { coefficients: c };
            if law.check().is_ok() {
                law
            } else {
                // Not monotone: the best fit with every coefficient >= 0 (which is monotone).
                ShearLaw::Polynomial { coefficients: nonnegative_lstsq(&cols, &targets).unwrap_or(vec![0.0; terms]) }
            }
        }
        ShearLawKind::TwoSlope => {
            if n < 3 {
                return Err(FitError::Data(format!(
                    "{n} points cannot determine g1, g2 and the locking angle: give more data"
                )));
            }
            let a_max = obs.iter().flat_map(|o| o.terms.iter().map(|(g, _)| g.abs())).fold(0.0, f64::max);
            if a_max <= 0.0 {
                return Err(FitError::Data(
                    "all points are at zero shear: the data must reach beyond the locking angle".into(),
                ));
            }
            let cols_at = |gl: f64| -> Vec<Vec<f64>> {
                let col = |f: &dyn Fn(f64) -> f64| -> Vec<f64> {
                    obs.iter().map(|o| o.terms.iter().map(|(g, w)| w * g.signum() * f(g.abs())).sum()).collect()
                };
                vec![col(&|a| a.min(gl)), col(&|a| (a - gl).max(0.0))]
            };
            let sse = |gl: f64| lstsq(&cols_at(gl), &targets).map(|(_, s)| s).unwrap_or(f64::INFINITY);
            let grid: Vec<f64> = (1..GRID).map(|i| a_max * i as f64 / GRID as f64).collect();
            let gl = refine_min(&grid, sse).ok_or_else(|| {
                FitError::Fit("no locking angle fits the data: the data must cover angles on both sides of it".into())
            })?;
            let (p, sse_two) =
                lstsq(&cols_at(gl), &targets).ok_or_else(|| FitError::Fit("the two-slope fit is singular".into()))?;
            check_kink(obs, &targets, gl, sse_two, &cols_at(2.0 * a_max)[0])?;
            ShearLaw::TwoSlope { g1: p[0], g2: p[1], locking_angle_deg: gl.to_degrees() }
        }
    };
    law.check().map_err(|(_, m)| {
        FitError::Fit(format!(
            "the best {} fit is not a physical shear law ({m}); {}",
            law.law_name(),
            match kind {
                ShearLawKind::Polynomial { .. } => "try fewer terms or --law two-slope",
                ShearLawKind::TwoSlope =>
                    "check that the data rise with the shear angle and reach past the locking angle",
            }
        ))
    })?;
    let report = FitReport::new(&targets, &predict(&law));
    Ok((law, report))
}

/// A two-slope fit names a locking angle only when the data have points on both sides of it...
const MIN_POINTS_EACH_SIDE: usize = 2;
/// ...and the kink explains at least this share of what a single straight slope leaves over...
const MIN_KINK_GAIN: f64 = 0.5;
/// ...and more than this share of the data's sum of squares (below it both fits are exact to
/// rounding: the data lie on one line).
const MIN_KINK_GAIN_OF_DATA: f64 = 1e-9;

/// Refuse a two-slope fit whose locking angle the data do not determine: data that never reach
/// locking (one straight slope fits them as well; any kink placed past or among them fits
/// exactly, which gave locking angles of 0.2 deg with R^2 = 1), or too few points on a side.
/// `line` is the column of a single slope.
fn check_kink(obs: &[Obs], targets: &[f64], locking: f64, sse_two: f64, line: &[f64]) -> Result<(), FitError> {
    let angle = |o: &Obs| o.terms.iter().map(|(g, _)| g.abs()).fold(0.0, f64::max);
    let below = obs.iter().filter(|o| angle(o) < locking).count();
    let above = obs.len() - below;
    let sse_line = lstsq(&[line.to_vec()], targets).map_or(f64::INFINITY, |(_, s)| s);
    let data: f64 = targets.iter().map(|t| t * t).sum();
    let gain = sse_line - sse_two;
    if below >= MIN_POINTS_EACH_SIDE
        && above >= MIN_POINTS_EACH_SIDE
        && gain >= MIN_KINK_GAIN * sse_line
        && gain > MIN_KINK_GAIN_OF_DATA * data
    {
        return Ok(());
    }
    let max_deg = obs.iter().map(angle).fold(0.0, f64::max).to_degrees();
    Err(FitError::Data(format!(
        "the data do not show a locking angle, so a two-slope law cannot be fitted: the best kink at {:.2} deg has {below} point(s) below it and {above} above, and one straight slope leaves a residual of {:.3e} against {:.3e} with the kink. \
         The data reach {max_deg:.1} deg of shear: give test data that go past the locking angle (at least {MIN_POINTS_EACH_SIDE} points on each side), or fit --law polynomial:N",
        locking.to_degrees(),
        sse_line,
        sse_two
    )))
}

/// Points of the grid searches (locking angle, knit alpha).
const GRID: usize = 600;

/// Minimise `f` over `grid` (increasing), then refine the best point by golden section between
/// its neighbours. None if `f` is infinite everywhere.
fn refine_min(grid: &[f64], f: impl Fn(f64) -> f64) -> Option<f64> {
    let vals: Vec<f64> = grid.iter().map(|&x| f(x)).collect();
    let (k, best) = vals.iter().enumerate().min_by(|a, b| a.1.total_cmp(b.1))?;
    if !best.is_finite() {
        return None;
    }
    let (lo, hi) = (grid[k.saturating_sub(1)], grid[(k + 1).min(grid.len() - 1)]);
    let (x, fx) = golden_section_min(&f, lo, hi, 200, 1e-15);
    // The best point seen: the bracket's interior points or the grid point.
    let cands = [(x, fx), (grid[k], *best)];
    cands.into_iter().filter(|c| c.1.is_finite()).min_by(|a, b| a.1.total_cmp(&b.1)).map(|c| c.0)
}

/// Non-negative least squares for a few columns (at most [`MAX_POLYNOMIAL_TERMS`]): the optimum
/// is the unconstrained solution on its set of positive coefficients, so the best feasible
/// subset solution over all subsets is it. None if no subset gives a positive solution.
fn nonnegative_lstsq(cols: &[Vec<f64>], b: &[f64]) -> Option<Vec<f64>> {
    let m = cols.len();
    let mut best: Option<(Vec<f64>, f64)> = None;
    for mask in 1u32..(1 << m) {
        let idx: Vec<usize> = (0..m).filter(|j| mask & (1 << j) != 0).collect();
        let sub: Vec<Vec<f64>> = idx.iter().map(|&j| cols[j].clone()).collect();
        if let Some((p, sse)) = lstsq(&sub, b) {
            if p.iter().all(|x| *x > 0.0) && best.as_ref().is_none_or(|(_, s)| sse < *s) {
                let mut full = vec![0.0; m];
                for (k, &j) in idx.iter().enumerate() {
                    full[j] = p[k];
                }
                best = Some((full, sse));
            }
        }
    }
    best.map(|(p, _)| p)
}

/// Linear least squares: the coefficients p minimising |sum_j p_j cols[j] - b|^2 and that sum of
/// squares, or None if the columns are (numerically) dependent. Columns are scaled to unit norm
/// and the problem is solved by SVD.
fn lstsq(cols: &[Vec<f64>], b: &[f64]) -> Option<(Vec<f64>, f64)> {
    let (n, m) = (b.len(), cols.len());
    if n < m {
        return None;
    }
    let norms: Vec<f64> = cols.iter().map(|c| c.iter().map(|x| x * x).sum::<f64>().sqrt()).collect();
    if norms.iter().any(|s| !(s.is_finite() && *s > 0.0)) {
        return None;
    }
    let a = DMatrix::from_fn(n, m, |i, j| cols[j][i] / norms[j]);
    let svd = a.clone().svd(true, true);
    let smax = svd.singular_values.max();
    let smin = svd.singular_values.min();
    if smin.is_nan() || smin <= 1e-12 * smax {
        return None;
    }
    let rhs = DVector::from_column_slice(b);
    let y = svd.solve(&rhs, 0.0).ok()?;
    let r = &a * &y - &rhs;
    let p: Vec<f64> = (0..m).map(|j| y[j] / norms[j]).collect();
    if p.iter().any(|x| !x.is_finite()) {
        return None;
    }
    Some((p, r.norm_squared()))
}

// ---- knit fit ----------------------------------------------------------------------------------

/// Stress (N/m) of the knit law as a material card evaluates it with compression_factor 1:
/// the law for e >= 0, C e in compression.
pub fn knit_stress(p: &KnitParams, e: f64) -> f64 {
    if e < 0.0 {
        p.c * e
    } else {
        p.stretch(e).1
    }
}

/// The stiffening shape g(x) = 1/(1 - x)^2 - 1 - 2x = x^2 (3 - 2x)/(1 - x)^2 and dg/dx.
fn knit_shape(x: f64) -> (f64, f64) {
    let q = 1.0 - x;
    (x * x * (3.0 - 2.0 * x) / (q * q), 2.0 * x * (3.0 - 3.0 * x + x * x) / (q * q * q))
}

/// Fit the knit law sigma(e) = C e + beta (1/(1 - alpha e)^2 - 1 - 2 alpha e) (seed 004,
/// Supplementary Eq. 14) to uniaxial data (strain, stress N/m) along one direction, by least
/// squares with C > 0, beta >= 0 and alpha e_max <= [`KNIT_STRETCH_LIMIT`] (so every point lies
/// before the singularity 1/alpha). Points at negative strain are fitted with C e (the card's
/// compression law). The report is in N/m.
///
/// Poisson coupling: seed 004 (Supplementary Note 7) fits both directions at once with the
/// cross rigidities C_xxyy, C_yyxx tied to measured Poisson ratios. Uniaxial data of one
/// direction cannot determine them: with the transverse edges free (sigma_yy = 0) the transverse
/// strain follows the longitudinal one, and the fitted C is the effective uniaxial modulus, the
/// Young's modulus Y = C_xxxx - C_xxyy C_yyxx / C_yyyy of Supplementary Eq. 16. That is the
/// stiffness a drape model with uncoupled warp and weft laws needs, so no constraint is applied.
pub fn fit_knit_uniaxial(data: &[(f64, f64)]) -> Result<(KnitParams, FitReport), FitError> {
    check_points(data, "uniaxial")?;
    let n = data.len();
    if n < 3 {
        return Err(FitError::Data(format!("{n} points cannot determine C, beta and alpha: give more data")));
    }
    let e_max = data.iter().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max);
    if e_max <= 0.0 {
        return Err(FitError::Data("no point has a positive (tensile) strain".into()));
    }
    let stress: Vec<f64> = data.iter().map(|p| p.1).collect();
    let strain: Vec<f64> = data.iter().map(|p| p.0).collect();
    // beta = 0: the linear law.
    let linear_c = {
        let (se, ss) = data.iter().fold((0.0, 0.0), |(a, b), (e, s)| (a + e * s, b + e * e));
        se / ss
    };
    let linear_sse: f64 = data.iter().map(|(e, s)| (s - linear_c * e).powi(2)).sum();
    // At fixed alpha: C and beta by least squares (beta >= 0).
    let solve_at = |alpha: f64| -> (KnitParams, f64) {
        let g: Vec<f64> = strain.iter().map(|&e| if e > 0.0 { knit_shape(alpha * e).0 } else { 0.0 }).collect();
        match lstsq(&[strain.clone(), g], &stress) {
            Some((p, sse)) if p[1] >= 0.0 && p[0] > 0.0 => (KnitParams { c: p[0], beta: p[1], alpha }, sse),
            _ => (KnitParams { c: linear_c, beta: 0.0, alpha: 0.0 }, linear_sse),
        }
    };
    // alpha = s / e_max with s in (0, KNIT_STRETCH_LIMIT]: uniform, then crowding towards the limit.
    let mut grid: Vec<f64> = (1..GRID).map(|i| KNIT_STRETCH_LIMIT * i as f64 / GRID as f64).collect();
    let t_lo = -(1.0 - KNIT_STRETCH_LIMIT * (GRID - 1) as f64 / GRID as f64).log10();
    let t_hi = -(1.0 - KNIT_STRETCH_LIMIT).log10();
    grid.extend((1..=100).map(|i| 1.0 - 10f64.powf(-(t_lo + (t_hi - t_lo) * i as f64 / 100.0))));
    grid.sort_by(f64::total_cmp);
    grid.dedup();
    let s_best = refine_min(&grid, |s| solve_at(s / e_max).1).unwrap_or(KNIT_STRETCH_LIMIT * 0.5);
    let (mut p, sse) = solve_at(s_best / e_max);
    if p.beta > 0.0 {
        p = levenberg_marquardt(&strain, &stress, p, sse, e_max);
    }
    if p.beta == 0.0 {
        p.alpha = 0.0;
    }
    if p.c.is_nan() || p.c <= 0.0 {
        return Err(FitError::Fit(format!(
            "the best fit has a low-strain rigidity C = {:.4e} N/m, not positive: the data do not describe a stretched fabric",
            p.c
        )));
    }
    let predicted: Vec<f64> = strain.iter().map(|&e| knit_stress(&p, e)).collect();
    Ok((p, FitReport::new(&stress, &predicted)))
}

/// Polish (C, beta, alpha) by Levenberg-Marquardt within the constraints.
fn levenberg_marquardt(strain: &[f64], stress: &[f64], p0: KnitParams, sse0: f64, e_max: f64) -> KnitParams {
    let residuals = |p: &KnitParams| -> Option<(Vec<f64>, f64)> {
        if !(p.c > 0.0 && p.beta >= 0.0 && p.alpha >= 0.0 && p.alpha * e_max <= KNIT_STRETCH_LIMIT) {
            return None;
        }
        let r: Vec<f64> = strain.iter().zip(stress).map(|(&e, &s)| knit_stress(p, e) - s).collect();
        let sse = r.iter().map(|x| x * x).sum();
        Some((r, sse))
    };
    let (mut p, mut sse) = (p0, sse0);
    let Some((mut r, _)) = residuals(&p) else { return p };
    let mut lambda = 1e-3;
    for _ in 0..300 {
        let mut jtj = Matrix3::zeros();
        let mut jtr = Vector3::zeros();
        for (i, &e) in strain.iter().enumerate() {
            let row = if e > 0.0 {
                let (g, dg) = knit_shape(p.alpha * e);
                Vector3::new(e, g, p.beta * dg * e)
            } else {
                Vector3::new(e, 0.0, 0.0)
            };
            jtj += row * row.transpose();
            jtr += row * r[i];
        }
        let mut improved = false;
        while lambda < 1e12 {
            let mut a = jtj;
            for k in 0..3 {
                a[(k, k)] += lambda * jtj[(k, k)].max(1e-300);
            }
            let Some(step) = a.lu().solve(&(-jtr)) else {
                lambda *= 10.0;
                continue;
            };
            let q = KnitParams { c: p.c + step[0], beta: p.beta + step[1], alpha: p.alpha + step[2] };
            match residuals(&q) {
                Some((rq, sq)) if sq < sse => {
                    let rel = (sse - sq) / sse.max(1e-300);
                    p = q;
                    r = rq;
                    sse = sq;
                    lambda = (lambda / 10.0).max(1e-12);
                    improved = rel > 1e-15;
                    break;
                }
                _ => lambda *= 10.0,
            }
        }
        if !improved {
            break;
        }
    }
    p
}

// ---- data files --------------------------------------------------------------------------------

/// Read two-column numeric data: one point per line, the columns separated by a comma (or a
/// semicolon, a tab or spaces); blank lines and lines starting with `#` are skipped; the first
/// other line may be a header (it is skipped if it is not numeric). Errors name the line.
pub fn parse_xy_csv(text: &str) -> Result<Vec<(f64, f64)>, String> {
    let mut out = Vec::new();
    let mut first = true;
    for (i, raw) in text.lines().enumerate() {
        let line = raw.trim().trim_start_matches('\u{feff}');
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = if line.contains(',') {
            line.split(',').map(str::trim).collect()
        } else if line.contains(';') {
            line.split(';').map(str::trim).collect()
        } else {
            line.split_whitespace().collect()
        };
        let nums: Vec<Option<f64>> = fields.iter().map(|f| f.parse::<f64>().ok()).collect();
        let is_first = first;
        first = false;
        if is_first && nums.iter().any(|x| x.is_none()) {
            continue; // a header
        }
        match nums.as_slice() {
            [Some(x), Some(y)] if x.is_finite() && y.is_finite() => out.push((*x, *y)),
            [Some(_), Some(_)] => return Err(format!("line {}: '{line}' holds a value that is not finite", i + 1)),
            [_, _] => {
                let bad = fields.iter().zip(&nums).find(|(_, n)| n.is_none()).map(|(f, _)| *f).unwrap_or("");
                return Err(format!("line {}: '{bad}' is not a number (in '{line}')", i + 1));
            }
            _ => {
                return Err(format!(
                    "line {}: expected two numbers separated by a comma, got '{line}' ({} field{})",
                    i + 1,
                    fields.len(),
                    if fields.len() == 1 { "" } else { "s" }
                ))
            }
        }
    }
    if out.is_empty() {
        return Err("no data: give one point per line, two numbers separated by a comma".into());
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{FRAC_1_SQRT_2, SQRT_2};

    /// Picture frame of side `side` at `d`: (gamma, dgamma/dd).
    fn picture_frame_angle(d: f64, side: f64) -> Option<(f64, f64)> {
        PictureFrameKinematics { side }.shear(d)
    }

    /// Bias-extension shear of the central zone at `d`.
    fn bias_extension_angle(d: f64, length: f64, width: f64) -> Option<f64> {
        BiasExtensionKinematics { length, width }.shear(d).map(|(g, _)| g)
    }

    /// Deterministic pseudo-noise in [-1, 1].
    fn noise(i: usize) -> f64 {
        let mut x = (i as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        x ^= x >> 31;
        x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
        x ^= x >> 29;
        (x >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs()
    }

    fn coeffs(law: &ShearLaw) -> Vec<f64> {
        match law {
            ShearLaw::Polynomial { coefficients } => coefficients.clone(),
            ShearLaw::TwoSlope { g1, g2, locking_angle_deg } => vec![*g1, *g2, *locking_angle_deg],
            ShearLaw::Table(_) => unreachable!(),
        }
    }

    const SIDE: f64 = 0.15;
    /// Points per synthetic test curve (a test machine logs hundreds; fewer leave c3 of a
    /// three-term polynomial poorly determined under 1 % noise).
    const NPTS: usize = 400;

    const LEN: f64 = 0.21;
    const WID: f64 = 0.07;

    /// Synthetic picture-frame data up to 60 deg shear, relative noise `amp`.
    fn pf_data(law: &ShearLaw, amp: f64) -> Vec<(f64, f64)> {
        // gamma = 60 deg at u = cos(15 deg).
        let d_max = 2.0 * SIDE * (15f64.to_radians().cos() - FRAC_1_SQRT_2);
        (1..=NPTS)
            .map(|i| {
                let d = d_max * i as f64 / NPTS as f64;
                (d, picture_frame_force(law, d, SIDE).unwrap() * (1.0 + amp * noise(i)))
            })
            .collect()
    }

    /// Synthetic bias-extension data up to 60 deg in the centre zone.
    fn be_data(law: &ShearLaw, amp: f64) -> Vec<(f64, f64)> {
        let dd = LEN - WID;
        let d_max = SQRT_2 * dd * 15f64.to_radians().cos() - dd;
        (1..=NPTS)
            .map(|i| {
                let d = d_max * i as f64 / NPTS as f64;
                (d, bias_extension_force(law, d, LEN, WID).unwrap() * (1.0 + amp * noise(i + 1000)))
            })
            .collect()
    }

    #[test]
    fn kinematics_agree_with_the_references() {
        // Picture frame: M = F (cos(g/2) - sin(g/2)) / (sqrt(2) L) [002 eq. 2].
        let law = ShearLaw::Polynomial { coefficients: vec![1.0, 3.0] };
        for d in [0.001, 0.01, 0.05] {
            let (g, dg) = picture_frame_angle(d, SIDE).unwrap();
            let f = picture_frame_force(&law, d, SIDE).unwrap();
            let m = f * ((g / 2.0).cos() - (g / 2.0).sin()) / (SQRT_2 * SIDE);
            assert!(rel(m, law.moment(g)) < 1e-12);
            let h = 1e-7;
            let fd =
                (picture_frame_angle(d + h, SIDE).unwrap().0 - picture_frame_angle(d - h, SIDE).unwrap().0) / (2.0 * h);
            assert!(rel(fd, dg) < 1e-7);
        }
        assert_eq!(picture_frame_angle(0.0, SIDE).unwrap().0, 0.0);
        assert!(picture_frame_angle((2.0 - SQRT_2) * SIDE * 1.001, SIDE).is_none());
        // Bias extension: virtual work. The force times the elongation rate equals the rate of
        // shear energy in the zones (zone C of area A_C at g, zones B of total area A_B at g/2):
        // F = A_C M(g) dg/dd + A_B M(g/2) d(g/2)/dd.
        for d in [0.002, 0.02, 0.04] {
            let g = |d: f64| bias_extension_angle(d, LEN, WID).unwrap();
            let h = 1e-7;
            let dg = (g(d + h) - g(d - h)) / (2.0 * h);
            let a_c = WID * (LEN - 1.5 * WID);
            let a_b = WID * WID;
            let f = a_c * law.moment(g(d)) * dg + a_b * law.moment(g(d) / 2.0) * dg / 2.0;
            assert!(rel(bias_extension_force(&law, d, LEN, WID).unwrap(), f) < 1e-7);
        }
    }

    #[test]
    fn picture_frame_recovers_the_law() {
        let poly = ShearLaw::Polynomial { coefficients: vec![2.0, 5.0, 20.0] };
        let two = ShearLaw::TwoSlope { g1: 3.0, g2: 150.0, locking_angle_deg: 37.3 };
        for (law, kind) in [(&poly, ShearLawKind::Polynomial { terms: 3 }), (&two, ShearLawKind::TwoSlope)] {
            let (fit, rep) = fit_shear_picture_frame(&pf_data(law, 0.0), SIDE, kind).unwrap();
            for (a, b) in coeffs(&fit).iter().zip(coeffs(law)) {
                assert!(rel(*a, b) < 1e-6, "{fit:?} vs {law:?}");
            }
            assert!(rep.r_squared > 1.0 - 1e-12 && rep.points == NPTS, "{rep:?}");
            let (fit, rep) = fit_shear_picture_frame(&pf_data(law, 0.01), SIDE, kind).unwrap();
            for (a, b) in coeffs(&fit).iter().zip(coeffs(law)) {
                assert!(rel(*a, b) < 0.05, "noisy: {fit:?} vs {law:?}");
            }
            assert!(rep.r_squared > 0.999 && rep.rms > 0.0, "{rep:?}");
        }
    }

    #[test]
    fn two_slope_fit_to_data_that_never_lock_is_refused() {
        // A straight slope (no locking in the data): any kink fits it exactly, so the fit
        // named a locking angle of 0.176 deg with R^2 = 1. Now it is refused, with the reach.
        let law = ShearLaw::Polynomial { coefficients: vec![3.0] };
        let e = fit_shear_picture_frame(&pf_data(&law, 0.0), SIDE, ShearLawKind::TwoSlope).unwrap_err();
        assert!(matches!(e, FitError::Data(_)), "{e:?}");
        let m = e.to_string();
        assert!(m.contains("do not show a locking angle") && m.contains("polynomial"), "{m}");
        // With noise too, and for bias extension.
        assert!(fit_shear_picture_frame(&pf_data(&law, 0.01), SIDE, ShearLawKind::TwoSlope).is_err());
        assert!(fit_shear_bias_extension(&be_data(&law, 0.01), LEN, WID, ShearLawKind::TwoSlope).is_err());
        // Data stopping just past locking (one point beyond it) do not determine the second slope.
        let two = ShearLaw::TwoSlope { g1: 3.0, g2: 150.0, locking_angle_deg: 37.3 };
        let data = pf_data(&two, 0.0);
        let g = |d: f64| PictureFrameKinematics { side: SIDE }.shear(d).unwrap().0.to_degrees();
        let first_past = data.iter().position(|(d, _)| g(*d) > 37.3).unwrap();
        assert!(fit_shear_picture_frame(&data[..first_past + 1], SIDE, ShearLawKind::TwoSlope).is_err());
        assert!(fit_shear_picture_frame(&data[..first_past + 3], SIDE, ShearLawKind::TwoSlope).is_ok());
    }

    #[test]
    fn bias_extension_recovers_the_law() {
        let poly = ShearLaw::Polynomial { coefficients: vec![2.0, 5.0, 20.0] };
        let two = ShearLaw::TwoSlope { g1: 3.0, g2: 150.0, locking_angle_deg: 37.3 };
        for (law, kind) in [(&poly, ShearLawKind::Polynomial { terms: 3 }), (&two, ShearLawKind::TwoSlope)] {
            let (fit, rep) = fit_shear_bias_extension(&be_data(law, 0.0), LEN, WID, kind).unwrap();
            for (a, b) in coeffs(&fit).iter().zip(coeffs(law)) {
                assert!(rel(*a, b) < 1e-6, "{fit:?} vs {law:?}");
            }
            assert!(rep.r_squared > 1.0 - 1e-12, "{rep:?}");
            let (fit, rep) = fit_shear_bias_extension(&be_data(law, 0.01), LEN, WID, kind).unwrap();
            for (a, b) in coeffs(&fit).iter().zip(coeffs(law)) {
                assert!(rel(*a, b) < 0.05, "noisy: {fit:?} vs {law:?}");
            }
            assert!(rep.r_squared > 0.999, "{rep:?}");
        }
    }

    #[test]
    fn knit_fit_recovers_the_law() {
        let truth = KnitParams { c: 500.0, beta: 10.0, alpha: 2.5 };
        let data = |amp: f64| -> Vec<(f64, f64)> {
            (0..=100)
                .map(|i| {
                    let e = 0.38 * i as f64 / 100.0; // up to 95 % of 1/alpha
                    (e, knit_stress(&truth, e) * (1.0 + amp * noise(i + 7)))
                })
                .collect()
        };
        let (p, rep) = fit_knit_uniaxial(&data(0.0)).unwrap();
        assert!(
            rel(p.c, truth.c) < 1e-6 && rel(p.beta, truth.beta) < 1e-6 && rel(p.alpha, truth.alpha) < 1e-6,
            "{p:?}"
        );
        assert!(rep.r_squared > 1.0 - 1e-12);
        let (p, rep) = fit_knit_uniaxial(&data(0.01)).unwrap();
        assert!(
            rel(p.c, truth.c) < 0.05 && rel(p.beta, truth.beta) < 0.05 && rel(p.alpha, truth.alpha) < 0.05,
            "{p:?}"
        );
        assert!(rep.r_squared > 0.999);
        assert!(p.alpha * 0.38 <= KNIT_STRETCH_LIMIT);
        // Another parameter set: milder stiffening, data up to 94 % of 1/alpha.
        let truth = KnitParams { c: 165.0, beta: 46.0, alpha: 1.111 };
        let pts: Vec<(f64, f64)> = (0..=60)
            .map(|i| {
                let e = 0.85 * i as f64 / 60.0;
                (e, knit_stress(&truth, e))
            })
            .collect();
        let (p, _) = fit_knit_uniaxial(&pts).unwrap();
        assert!(
            rel(p.c, truth.c) < 1e-6 && rel(p.beta, truth.beta) < 1e-6 && rel(p.alpha, truth.alpha) < 1e-6,
            "{p:?}"
        );
        // Linear data: beta = alpha = 0.
        let pts: Vec<(f64, f64)> = (0..=20).map(|i| (i as f64 * 0.01, 300.0 * i as f64 * 0.01)).collect();
        let (p, rep) = fit_knit_uniaxial(&pts).unwrap();
        assert!(rel(p.c, 300.0) < 1e-9 && p.beta.abs() < 1e-9 * 300.0 && rep.rms < 1e-9, "{p:?}");
    }

    #[test]
    fn bad_data_is_refused() {
        let two = ShearLaw::TwoSlope { g1: 3.0, g2: 150.0, locking_angle_deg: 37.3 };
        let mut d = pf_data(&two, 0.0);
        d.push((0.2, 10.0)); // past the frame's travel (0.088 m)
        let e = fit_shear_picture_frame(&d, SIDE, ShearLawKind::TwoSlope).unwrap_err();
        assert!(matches!(e, FitError::Data(_)) && e.to_string().contains(&format!("point {}", NPTS + 1)), "{e}");
        assert!(fit_shear_bias_extension(&be_data(&two, 0.0), 0.1, 0.07, ShearLawKind::TwoSlope).is_err());
        let e = fit_shear_picture_frame(&[(0.01, 1.0)], SIDE, ShearLawKind::Polynomial { terms: 3 }).unwrap_err();
        assert!(e.to_string().contains("cannot determine"), "{e}");
        // A kinked curve: three unconstrained terms are not monotone; the constrained fit is.
        let (fit, rep) =
            fit_shear_picture_frame(&pf_data(&two, 0.0), SIDE, ShearLawKind::Polynomial { terms: 3 }).unwrap();
        let c = coeffs(&fit);
        assert!(c.iter().all(|x| *x >= 0.0) && c.contains(&0.0) && rep.r_squared > 0.9, "{c:?} {rep:?}");
        // Falling data give no physical law.
        let falling: Vec<(f64, f64)> = (1..30).map(|i| (i as f64 * 0.002, -(i as f64))).collect();
        let e = fit_shear_picture_frame(&falling, SIDE, ShearLawKind::Polynomial { terms: 2 }).unwrap_err();
        assert!(matches!(e, FitError::Fit(_)), "{e}");
        assert!(fit_knit_uniaxial(&[(0.0, 0.0), (-0.1, -1.0), (f64::NAN, 1.0)]).is_err());
    }

    #[test]
    fn law_kinds_parse() {
        assert_eq!("polynomial:3".parse::<ShearLawKind>(), Ok(ShearLawKind::Polynomial { terms: 3 }));
        assert_eq!("polynomial".parse::<ShearLawKind>(), Ok(ShearLawKind::Polynomial { terms: 3 }));
        assert_eq!("two-slope".parse::<ShearLawKind>(), Ok(ShearLawKind::TwoSlope));
        assert!("polynomial:0".parse::<ShearLawKind>().is_err());
        assert!("polynomial:x".parse::<ShearLawKind>().is_err());
        assert!("spline".parse::<ShearLawKind>().is_err());
    }

    #[test]
    fn csv_reading() {
        let t = "\u{feff}displacement_m,force_N\n0.0, 0.0\n\n# comment\n0.001,1.5\n2e-3;3\n0.003\t4.5\n";
        assert_eq!(parse_xy_csv(t).unwrap(), vec![(0.0, 0.0), (0.001, 1.5), (0.002, 3.0), (0.003, 4.5)]);
        assert_eq!(parse_xy_csv("1,2\n3,4").unwrap(), vec![(1.0, 2.0), (3.0, 4.0)]);
        let e = parse_xy_csv("d,F\n1,2\n3,x\n").unwrap_err();
        assert!(e.starts_with("line 3:") && e.contains("'x' is not a number"), "{e}");
        let e = parse_xy_csv("d,F\n1,2\n3,4,5\n").unwrap_err();
        assert!(e.starts_with("line 3:") && e.contains("3 fields"), "{e}");
        let e = parse_xy_csv("1,2\nd,F\n").unwrap_err();
        assert!(e.starts_with("line 2:"), "{e}");
        let e = parse_xy_csv("1,nan\n").unwrap_err();
        assert!(e.contains("not finite"), "{e}");
        assert!(parse_xy_csv("d,F\n").is_err());
    }
}
