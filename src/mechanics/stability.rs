//! Second-order stability of a converged state: is it a minimum of the energy or a saddle?
//!
//! A state where the forces balance is a minimum only if the reduced Hessian H (over the free
//! directions, the tool's curvature included) has no negative eigenvalue. Its spectrum spans
//! 1e-9..1e3 of its mean diagonal on a fabric net (stiff fibres beside soft shear and bending),
//! so Lanczos on H itself does not reach the soft end in affordable iterations. Here Lanczos
//! runs on the pencil H v = mu M v instead, M a positive definite model of H (the elements'
//! convex parts plus a small mass shift: M >= H): M^{-1} H has most eigenvalues near 1, and
//! those of H's negative directions far below 0, so a few tens of iterations separate them. M is
//! factorised once and applied with the solver's own engine (triangular solves on its
//! factorisation). By Sylvester's law of inertia, the pencil has as many negative eigenvalues as
//! H, so the sign of its least one tells a saddle from a minimum.
use super::qp::{dot, QpEngine, QpFailure, Reduction};
use nalgebra::{DMatrix, SymmetricEigen};
use serde::Serialize;

/// Most Lanczos iterations of one check (each a matrix product and one solve with M's
/// factorisation).
pub const LANCZOS_ITERATIONS: usize = 40;
/// Lanczos stops when the least Ritz pair's residual (in M's metric) is below this fraction of
/// its Ritz value and the least Ritz value over the lumped masses changed by less than this
/// fraction in the last iteration: the sign and two digits, what the check is for. (On the
/// double dome's first ply: 13-15 iterations where 1e-6 took 26-40, at 11 ms each.)
const LANCZOS_TOLERANCE: f64 = 1e-2;
/// A Lanczos vector this much shorter than its matrix's scale ends the iteration: the Krylov
/// space is exhausted (a small problem), its Ritz values are exact.
const LANCZOS_BREAKDOWN: f64 = 1e-12;

pub use crate::kinematic::provenance::Stability;

/// A move off a saddle along its direction of negative curvature.
#[derive(Debug, Clone, Serialize)]
pub struct Escape {
    /// Iterations done before it (the saddle's iteration).
    pub after_iteration: usize,
    /// The saddle's least eigenvalue (see [`LeastEigenvalue::least_eigenvalue`]), 1/s^2.
    pub least_eigenvalue: f64,
    /// ... and relative to the check's reference (see [`LeastEigenvalue::reference_eigenvalue`]).
    pub reference_eigenvalue: f64,
    /// Energy at the saddle (J).
    pub energy_saddle: f64,
    /// Energy just after the move (J).
    pub energy_moved: f64,
    /// Largest node move, spacings.
    pub move_spacings: f64,
    /// Whether the iterations from there reached equilibrium (false: the saddle was restored).
    pub kept: bool,
    /// Where they ended when they did not: energy (J) and |F - P| / |P| (the lower state
    /// given up for the converged saddle).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub abandoned: Option<(f64, f64)>,
}

/// How a stability check reached its verdict.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CheckMethod {
    /// One Cholesky factorisation of H + c M proved a minimum ([`positive_definite`]); no
    /// eigenvalue was computed.
    Cholesky,
    /// Lanczos on the pencil (H, M) found its least eigenvalue.
    Lanczos,
}

/// The second-order check of a converged solve: the least eigenvalue of the reduced Hessian and
/// what was done about a negative one.
#[derive(Debug, Clone, Serialize)]
pub struct StabilityCheck {
    /// Whether the final state is a minimum, a saddle, or could not be checked.
    pub verdict: Stability,
    /// How the last check reached its verdict (absent when it could not run).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub method: Option<CheckMethod>,
    /// What the last check found; absent when it could not run (`unresolved`).
    #[serde(flatten)]
    pub found: Option<LeastEigenvalue>,
    /// Checks run (one per converged state: one more per escape).
    pub checks: usize,
    /// Moves off saddles, in order.
    pub escapes: Vec<Escape>,
    /// Time spent in the checks and the escape moves (not the iterations after them), ms.
    pub time_ms: f64,
}

/// The least eigenvalue a stability check found, in its three scales.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LeastEigenvalue {
    /// The least eigenvalue found, relative to the lumped masses: the Rayleigh quotient
    /// v^T H v / v^T M_lumped v of the softest mode v (1/s^2: a stable mode's angular frequency
    /// squared, minus an unstable one's growth rate squared). An estimate from above.
    pub least_eigenvalue: f64,
    /// The same over the model's mean stiffness per mean mass (its mean diagonal over the mean
    /// nodal mass): dimensionless. On a fabric net the soft modes sit near 1e-9 of it.
    pub relative_eigenvalue: f64,
    /// The least eigenvalue of the pencil H v = mu M v (M the positive definite reference,
    /// M >= H, so mu <= 1): how far H curves down along some direction as a fraction of how
    /// far the reference curves up. The verdict is judged on it.
    pub reference_eigenvalue: f64,
    /// Lanczos iterations of the check.
    pub lanczos_iterations: usize,
    /// Whether the Lanczos iteration met its tolerance (else it stopped at the limit,
    /// [`LANCZOS_ITERATIONS`]).
    pub lanczos_converged: bool,
}

impl StabilityCheck {
    /// Whether the final state was found a minimum.
    pub fn is_minimum(&self) -> bool {
        self.verdict == Stability::Minimum
    }

    /// The check in words, for the log.
    pub fn describe(&self) -> String {
        let what = match self.verdict {
            Stability::Minimum => "stable".to_string(),
            Stability::Saddle => "UNSTABLE (a saddle, not a minimum)".to_string(),
            Stability::Unresolved => "stability not checked (the reference model could not be factorised)".to_string(),
        };
        let mut s = match (&self.verdict, &self.found) {
            (Stability::Minimum, None) if self.method == Some(CheckMethod::Cholesky) => {
                format!("{what}: the Hessian is positive definite (sparse Cholesky; no eigenvalue computed)")
            }
            (Stability::Unresolved, _) | (_, None) => what,
            (_, Some(f)) => format!(
                "{what}: least eigenvalue {:.3e} 1/s^2 ({:.1e} of the mean stiffness), {} Lanczos iterations{}",
                f.least_eigenvalue,
                f.relative_eigenvalue,
                f.lanczos_iterations,
                if f.lanczos_converged { "" } else { " (at the limit)" }
            ),
        };
        for e in &self.escapes {
            s.push_str(&format!(
                "; escaped a saddle after iteration {} ({:.6e} J, least eigenvalue {:.3e} 1/s^2){}",
                e.after_iteration,
                e.energy_saddle,
                e.least_eigenvalue,
                match e.abandoned {
                    Some((energy, residual)) => format!(
                        ", did not converge from there ({energy:.6e} J at |F-P|/|P| {residual:.2e}): the saddle kept"
                    ),
                    None => String::new(),
                }
            ));
        }
        s.push_str(&format!(", {:.0} ms", self.time_ms));
        s
    }
}

/// Whether the symmetric matrix with upper triangle `values` in `red`'s pattern is positive
/// definite: its sparse Cholesky factorisation (faer, AMD ordering, no regularisation) runs to
/// the end without a non-positive pivot. None: the matrix has non-finite entries or the
/// factorisation could not be set up.
///
/// A stability check needs no eigenvalue to give its verdict: by Sylvester's law of inertia the
/// pencil (H, M) has no eigenvalue below -c exactly when H + c M is positive definite, so one
/// factorisation proves a minimum (Cholesky is backward stable: the matrix it factorised is the
/// given one to rounding). On the 301 x 301 pressed bench that is one factorisation where the
/// Lanczos check took a factorisation and 22 solves.
pub(super) fn positive_definite(red: &Reduction, values: &[f64]) -> Option<bool> {
    use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
    use faer::linalg::cholesky::llt::factor::{LltParams, LltRegularization};
    use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, SymmetricOrdering};
    use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
    use faer::{Par, Side, Spec};
    if !values.iter().all(|v| v.is_finite()) {
        // No proof from a matrix with NaN or infinite entries (Lanczos then says what it can).
        return None;
    }
    let n = red.len();
    let (colptr, rowval) = red.upper_pattern();
    let symbolic = SymbolicSparseColMatRef::new_checked(n, n, colptr, None, rowval);
    let matrix = SparseColMatRef::new(symbolic, values);
    let factor = factorize_symbolic_cholesky(symbolic, Side::Upper, SymmetricOrdering::Amd, Default::default()).ok()?;
    let params: Spec<LltParams, f64> = Default::default();
    // One thread, as the solver's own factorisations: the verdict must not depend on the
    // thread count.
    let mut memory =
        MemBuffer::try_new(StackReq::any_of(&[factor.factorize_numeric_llt_scratch::<f64>(Par::Seq, params)])).ok()?;
    let mut l = vec![0.0; factor.len_val()];
    let done = factor.factorize_numeric_llt(
        &mut l,
        matrix,
        Side::Upper,
        LltRegularization::default(),
        Par::Seq,
        MemStack::new(&mut memory),
        params,
    );
    Some(done.is_ok())
}

/// The least eigenvalues found of the pencils H v = mu M v and H v = lambda D v.
pub(super) struct LeastMode {
    /// The least Ritz value mu of (H, M).
    pub value: f64,
    /// The least Ritz value lambda of (H, D) on the same Krylov space: an estimate from above
    /// of D's least eigenvalue (where M >= H, the pencil (H, M) crowds all H's positive
    /// eigenvalues near 1 and its Ritz vectors mix them; those of (H, D) keep them apart).
    pub least: f64,
    /// The Ritz vector of `least` (reduced variables).
    pub vector: Vec<f64>,
    /// Lanczos iterations done.
    pub iterations: usize,
    /// Whether the residual tolerance (or an exhausted Krylov space) ended them.
    pub converged: bool,
}

/// The least eigenpair of H v = mu M v (upper-triangular `h` and `m` in `red`'s pattern, M
/// positive definite) by Lanczos on M^{-1} H in M's inner product, fully reorthogonalised, from
/// `start` (zero on pinned slots), at most `max_iterations` iterations; then the least of
/// H v = lambda D v on the Krylov space it built (D the positive definite `metric`, e.g. the
/// lumped masses). M^{-1} is applied by the engine: one factorisation, then triangular solves
/// without iterative refinement (the Ritz values are computed with the true H and M; only the
/// subspace depends on the solves). None: `start` has no component to iterate on.
pub(super) fn least_mode(
    red: &Reduction,
    engine: &mut QpEngine,
    h: &[f64],
    m: &[f64],
    metric: &[f64],
    start: &[f64],
    max_iterations: usize,
) -> Result<Option<LeastMode>, QpFailure> {
    // The engine minimises 1/2 y^T M y + q^T y: y = -M^{-1} q.
    let mut solve_m = |r: &[f64]| -> Result<Vec<f64>, QpFailure> {
        let q: Vec<f64> = r.iter().map(|v| -v).collect();
        engine.solve_unrefined(red, m, &q)
    };
    // One solve first: M^{-1} damps the stiff directions of a rough start.
    let mut z = solve_m(start)?;
    let mut mz = red.mul(m, &z);
    let mut beta = dot(&z, &mz).max(0.0).sqrt();
    if !(beta > 0.0) || !beta.is_finite() {
        return Ok(None);
    }
    let last = max_iterations.max(1);
    // The basis Q (M-orthonormal) with M Q, H Q and D Q, and the projections T = Q^T H Q and
    // G = Q^T D Q, grown a column at a time.
    let mut qs: Vec<Vec<f64>> = Vec::new();
    let mut mqs: Vec<Vec<f64>> = Vec::new();
    let mut hqs: Vec<Vec<f64>> = Vec::new();
    let mut dqs: Vec<Vec<f64>> = Vec::new();
    let mut t = DMatrix::zeros(last, last);
    let mut g = DMatrix::zeros(last, last);
    let mut previous = f64::NAN;
    for j in 0..last {
        qs.push(z.iter().map(|v| v / beta).collect());
        mqs.push(mz.iter().map(|v| v / beta).collect());
        hqs.push(red.mul(h, &qs[j]));
        dqs.push(red.mul(metric, &qs[j]));
        for i in 0..=j {
            t[(i, j)] = 0.5 * (dot(&qs[i], &hqs[j]) + dot(&qs[j], &hqs[i]));
            t[(j, i)] = t[(i, j)];
            g[(i, j)] = 0.5 * (dot(&qs[i], &dqs[j]) + dot(&qs[j], &dqs[i]));
            g[(j, i)] = g[(i, j)];
        }
        z = solve_m(&hqs[j])?;
        // Full reorthogonalisation in M's inner product (twice: once is not enough in floating
        // point when the new vector has mostly been removed).
        for _ in 0..2 {
            for (q, mq) in qs.iter().zip(&mqs) {
                let c = dot(mq, &z);
                z.iter_mut().zip(q).for_each(|(zi, qi)| *zi -= c * qi);
            }
        }
        mz = red.mul(m, &z);
        beta = dot(&z, &mz).max(0.0).sqrt();
        let k = j + 1;
        let tk = t.view((0, 0), (k, k)).into_owned();
        // The pencil (H, M) on the basis: Q^T M Q = I.
        let eig = SymmetricEigen::new(tk.clone());
        let (at, value) = least_of(&eig.eigenvalues);
        let s = eig.eigenvectors.column(at).into_owned();
        // The pencil (H, D) on the basis: T c = lambda G c.
        let lumped = g.view((0, 0), (k, k)).into_owned().cholesky().and_then(|l| {
            let linv = l.l().try_inverse()?;
            let eig = SymmetricEigen::new(&linv * &tk * linv.transpose());
            let (i, lambda) = least_of(&eig.eigenvalues);
            Some((lambda, linv.transpose() * eig.eigenvectors.column(i)))
        });
        let scale = value.abs().max(1.0);
        let exhausted = beta <= LANCZOS_BREAKDOWN * scale.max(tk.amax());
        let settled = match &lumped {
            Some((lambda, _)) => (lambda - previous).abs() <= LANCZOS_TOLERANCE * lambda.abs(),
            None => true,
        };
        let converged = exhausted || (beta * s[k - 1].abs() <= LANCZOS_TOLERANCE * value.abs() && settled);
        if converged || k == last {
            let combine = |c: &[f64]| {
                let mut vector = vec![0.0; z.len()];
                for (q, &ci) in qs.iter().zip(c) {
                    vector.iter_mut().zip(q).for_each(|(v, qi)| *v += ci * qi);
                }
                vector
            };
            let (least, vector) = match lumped {
                Some((lambda, c)) => (lambda, combine(c.as_slice())),
                None => {
                    // G not factorisable: the pencil's vector and its own quotient.
                    let v = combine(s.as_slice());
                    (dot(&v, &red.mul(h, &v)) / dot(&v, &red.mul(metric, &v)), v)
                }
            };
            return Ok(Some(LeastMode { value, least, vector, iterations: k, converged }));
        }
        previous = lumped.map_or(f64::NAN, |(lambda, _)| lambda);
    }
    unreachable!("the loop returns at its last iteration")
}

/// The position and value of the least entry.
fn least_of(values: &nalgebra::DVector<f64>) -> (usize, f64) {
    values.iter().copied().enumerate().min_by(|a, b| a.1.total_cmp(&b.1)).expect("not empty")
}

/// A deterministic, evenly spread pseudo-random number in [-1, 1) for index `i` (a start
/// vector with some of every mode; the same on every run).
pub(super) fn spread(i: usize) -> f64 {
    // The fractional part of i times the golden ratio's conjugate, hashed once more through a
    // sine so neighbouring indices are not correlated.
    let t = ((i as f64 + 1.0) * 0.618_033_988_749_895).fract();
    (((t * 12.9898).sin() * 43_758.545_3).fract()) * 2.0 - 1.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::contact::NodeBasis;
    use crate::mechanics::qp::tests::Dense;

    #[test]
    fn lanczos_finds_the_least_eigenvalue_of_the_pencil() {
        // H indefinite, M positive definite and diagonal; the pencil's eigenvalues are those of
        // M^{-1/2} H M^{-1/2}.
        let red = Reduction::new(vec![3, 3], vec![3, 3], vec![0, 1], &[(0, 0), (0, 1), (1, 1)]);
        let bases = [NodeBasis::free(), NodeBasis::free()];
        let b = DMatrix::from_fn(6, 6, |i, j| ((i * 5 + j * 3) as f64 * 0.9).sin());
        let h = &b + b.transpose() - DMatrix::identity(6, 6) * 0.3;
        let md = DMatrix::from_diagonal(&nalgebra::DVector::from_vec(vec![1.0, 2.0, 0.5, 4.0, 1.5, 3.0]));
        let mut engine = QpEngine::new();
        let (hv, mv) = (red.values(&Dense(h.clone()), &bases), red.values(&Dense(md.clone()), &bases));
        let start: Vec<f64> = (0..6).map(spread).collect();
        let mode = least_mode(&red, &mut engine, &hv, &mv, &mv, &start, 10).unwrap().unwrap();
        let inv_sqrt = md.map(|v| if v > 0.0 { 1.0 / v.sqrt() } else { 0.0 });
        let want = SymmetricEigen::new(&inv_sqrt * &h * &inv_sqrt).eigenvalues.min();
        assert!(mode.converged && mode.iterations <= 6, "{} iterations", mode.iterations);
        assert!((mode.value - want).abs() < 1e-9 * want.abs(), "{} vs {want}", mode.value);
        // With D = M the two pencils agree.
        assert!((mode.least - want).abs() < 1e-9 * want.abs(), "{} vs {want}", mode.least);
        // The vector is the eigenvector: H v = mu M v.
        let v = nalgebra::DVector::from_column_slice(&mode.vector);
        let r = &h * &v - &md * &v * mode.value;
        assert!(r.norm() < 1e-8 * (&h * &v).norm(), "{}", r.norm());
    }

    #[test]
    fn cholesky_tells_the_verdict_the_least_eigenvalue_gives() {
        // H + c M is positive definite exactly when the pencil's least eigenvalue is above -c.
        let red = Reduction::new(vec![3, 3], vec![3, 3], vec![0, 1], &[(0, 0), (0, 1), (1, 1)]);
        let bases = [NodeBasis::free(), NodeBasis::free()];
        let b = DMatrix::from_fn(6, 6, |i, j| ((i * 5 + j * 3) as f64 * 0.9).sin());
        let md = DMatrix::from_diagonal(&nalgebra::DVector::from_vec(vec![1.0, 2.0, 0.5, 4.0, 1.5, 3.0]));
        let inv_sqrt = md.map(|v: f64| if v > 0.0 { 1.0 / v.sqrt() } else { 0.0 });
        for tilt in [-0.3, 2.0, 4.0] {
            let h = &b + b.transpose() + DMatrix::identity(6, 6) * tilt;
            let least = SymmetricEigen::new(&inv_sqrt * &h * &inv_sqrt).eigenvalues.min();
            for c in [-least - 1e-6, -least + 1e-6] {
                let values = red.values(&Dense(&h + &md * c), &bases);
                assert_eq!(
                    positive_definite(&red, &values),
                    Some(least + c > 0.0),
                    "tilt {tilt}, c {c}, least {least}"
                );
            }
        }
        // Pinned slots (unit diagonal) do not spoil a positive definite matrix.
        let red = Reduction::new(vec![3, 3], vec![2, 3], vec![0, 1], &[(0, 0), (0, 1), (1, 1)]);
        let mut values = red.values(&Dense(md.clone()), &bases);
        assert_eq!(positive_definite(&red, &values), Some(true));
        // A NaN proves nothing.
        values[0] = f64::NAN;
        assert_eq!(positive_definite(&red, &values), None);
    }
}
