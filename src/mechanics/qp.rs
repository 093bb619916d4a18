//! The subproblem engine: quadratic models over the nodes' free directions, solved by Clarabel.
//!
//! Each node moves in `dofs` orthonormal directions (its [`NodeBasis`]); stitched nodes (seams)
//! share the directions of their representative. A [`Reduction`] maps the grid's 3x3 Hessian
//! blocks and force vectors onto these reduced variables. A [`QpEngine`] keeps one Clarabel
//! solver per sparsity pattern of the reduced matrix and only updates its values between
//! iterations (Clarabel's data updating), so the symbolic analysis of the factorisation is done
//! once per pattern, not once per subproblem.
use super::contact::NodeBasis;
use crate::geometry::Vector;
use clarabel::algebra::CscMatrix;
use clarabel::solver::traits::KKTSystem;
use clarabel::solver::{DefaultSettings, DefaultSettingsBuilder, DefaultSolver, SupportedConeT};
use nalgebra::Matrix3;

/// Hessian storage read block by block.
pub trait HessianBlocks: Sync {
    /// The 3x3 block coupling nodes `a` and `b` (rows of `a`, columns of `b`).
    fn block(&self, a: usize, b: usize) -> Matrix3<f64>;
}

/// Where a reduced entry's value comes from: the grid block of a coupled pair (its index in
/// [`Reduction`]'s pairs: node a, node b) and its components (p of a, q of b).
type Source = (u32, u8, u8);

/// A subproblem's solution y is kept when |P y + q| is below this fraction of |q|: rounding
/// beyond it means the model is too near singular for its step to be trusted.
const MODEL_SOLVE_ACCURACY: f64 = 1e-6;
/// Most conjugate-gradient iterations a lagged solve ([`QpEngine::solve_near`]) takes before it
/// gives way to a new factorisation.
pub const LAGGED_ITERATIONS: usize = 4;

/// The reduced variables: node k's components start at `offset[rep[k]]` and number
/// `dofs[rep[k]]`, in the directions of its basis.
///
/// The sparsity pattern is built for a capacity of slots per node (`cap`, at least `dofs`):
/// a node whose freedoms shrink (a pressed node held by an open edge, a free node touching the
/// tool) keeps its slots, the ones beyond its `dofs` pinned (a unit diagonal, no coupling, no
/// force: their value is zero). The pattern, and with it Clarabel's solver and its symbolic
/// factorisation, then outlives changes of the active set ([`Reduction::set_dofs`]); only a
/// node gaining freedoms beyond its slots needs a new one.
pub struct Reduction {
    /// Per node: the node whose variables it uses (itself unless stitched to another).
    rep: Vec<usize>,
    /// Per node: its number of variables (0 for non-representatives).
    dofs: Vec<u8>,
    /// Per node: its slots in the pattern (`>= dofs`).
    cap: Vec<u8>,
    offset: Vec<usize>,
    n: usize,
    /// Live (not pinned) variables.
    live: usize,
    /// Upper-triangular CSC pattern over the reduced variables.
    colptr: Vec<usize>,
    rowval: Vec<usize>,
    /// The coupled grid node pairs (a <= b) the pattern was built over.
    pairs: Vec<(u32, u32)>,
    /// Per stored entry e: the grid blocks and components whose reduced values add up into it,
    /// `sources[source_ptr[e]..source_ptr[e + 1]]`.
    source_ptr: Vec<usize>,
    sources: Vec<Source>,
    /// Position of each column's diagonal entry.
    diag: Vec<usize>,
}

impl Reduction {
    /// The reduction for node bases with `dofs` directions each (representatives only) in a
    /// pattern of `cap` slots per node (each at least `dofs`), `rep` the representative of each
    /// node, over the coupled node pairs `pairs`.
    pub fn new(cap: Vec<u8>, dofs: Vec<u8>, rep: Vec<usize>, pairs: &[(usize, usize)]) -> Self {
        assert!(Self::fits_in(&cap, &dofs), "a node has more freedoms than slots");
        let mut offset = vec![0; cap.len()];
        let mut n = 0;
        for (k, &d) in cap.iter().enumerate() {
            offset[k] = n;
            n += d as usize;
        }
        let live = dofs.iter().map(|&d| d as usize).sum();
        let mut columns: Vec<Vec<(usize, Source)>> = vec![Vec::new(); n];
        for (i, &(a, b)) in pairs.iter().enumerate() {
            let (ra, rb) = (rep[a], rep[b]);
            for p in 0..cap[ra] as usize {
                for q in 0..cap[rb] as usize {
                    let (r, c) = (offset[ra] + p, offset[rb] + q);
                    // Each grid pair is listed once (a <= b). Within one node's diagonal
                    // block the upper triangle keeps p <= q; a pair of distinct nodes sharing a
                    // representative adds its mirror there ([`Reduction::values`]).
                    if ra == rb && p > q {
                        continue;
                    }
                    let src = (i as u32, p as u8, q as u8);
                    if r <= c {
                        columns[c].push((r, src));
                    } else {
                        columns[r].push((c, src));
                    }
                }
            }
        }
        let mut colptr = vec![0];
        let mut rowval = Vec::new();
        let mut source_ptr = vec![0];
        let mut sources: Vec<Source> = Vec::new();
        let mut diag = vec![usize::MAX; n];
        for (c, mut col) in columns.into_iter().enumerate() {
            col.sort_by_key(|e| e.0);
            let mut last = usize::MAX;
            for (r, src) in col {
                if r != last {
                    if r == c {
                        diag[c] = rowval.len();
                    }
                    if last != usize::MAX {
                        source_ptr.push(sources.len());
                    }
                    rowval.push(r);
                    last = r;
                }
                sources.push(src);
            }
            if last != usize::MAX {
                source_ptr.push(sources.len());
            }
            colptr.push(rowval.len());
        }
        let pairs = pairs.iter().map(|&(a, b)| (a as u32, b as u32)).collect();
        // Every variable gets a diagonal slot (the shift goes there even without coupling).
        let mut red = Reduction { rep, dofs, cap, offset, n, live, colptr, rowval, pairs, source_ptr, sources, diag };
        if red.diag.contains(&usize::MAX) {
            red.add_missing_diagonals();
        }
        red
    }

    fn fits_in(cap: &[u8], dofs: &[u8]) -> bool {
        cap.len() == dofs.len() && cap.iter().zip(dofs).all(|(c, d)| d <= c)
    }

    /// Whether every node's `dofs` fit in its slots ([`Reduction::set_dofs`] can take them).
    pub fn fits(&self, dofs: &[u8]) -> bool {
        Self::fits_in(&self.cap, dofs)
    }

    /// New numbers of freedoms per node within the same pattern (they must fit).
    pub fn set_dofs(&mut self, dofs: Vec<u8>) {
        assert!(self.fits(&dofs), "a node has more freedoms than slots");
        self.live = dofs.iter().map(|&d| d as usize).sum();
        self.dofs = dofs;
    }

    /// The slots of each node.
    pub fn capacity(&self) -> &[u8] {
        &self.cap
    }

    /// The number of freedoms of each node.
    pub fn dofs(&self) -> &[u8] {
        &self.dofs
    }

    /// Whether slot `p` of node `r` (a representative) is pinned.
    #[inline]
    fn pinned(&self, r: usize, p: usize) -> bool {
        p >= self.dofs[r] as usize
    }

    /// Adds a diagonal entry to every column that lacks one.
    fn add_missing_diagonals(&mut self) {
        let n = self.n;
        let mut new_colptr = vec![0];
        let mut new_rowval = Vec::with_capacity(self.rowval.len() + n);
        // The source lists stay as they are; a new diagonal entry gets an empty one.
        let mut new_source_ptr = Vec::with_capacity(self.rowval.len() + n + 1);
        new_source_ptr.push(0);
        let mut diag = vec![usize::MAX; n];
        for (c, dc) in diag.iter_mut().enumerate() {
            let mut has = false;
            for k in self.colptr[c]..self.colptr[c + 1] {
                if self.rowval[k] == c {
                    has = true;
                    *dc = new_rowval.len();
                }
                new_rowval.push(self.rowval[k]);
                new_source_ptr.push(self.source_ptr[k + 1]);
            }
            if !has {
                *dc = new_rowval.len();
                new_rowval.push(c);
                new_source_ptr.push(*new_source_ptr.last().expect("starts with 0"));
            }
            new_colptr.push(new_rowval.len());
        }
        self.colptr = new_colptr;
        self.rowval = new_rowval;
        self.source_ptr = new_source_ptr;
        self.diag = diag;
    }

    /// Number of reduced variables (slots, pinned ones included).
    pub fn len(&self) -> usize {
        self.n
    }

    /// Whether there is nothing to move.
    pub fn is_empty(&self) -> bool {
        self.live == 0
    }

    /// The key of the sparsity pattern (equal keys, equal patterns).
    pub fn key(&self) -> &[u8] {
        &self.cap
    }

    /// The representative of node `k`.
    pub fn rep(&self, k: usize) -> usize {
        self.rep[k]
    }

    /// The reduced variables of node `k`: (first index, count).
    pub fn vars(&self, k: usize) -> (usize, usize) {
        let r = self.rep[k];
        (self.offset[r], self.dofs[r] as usize)
    }

    /// Reduced matrix values B^T H B (upper triangle, in the pattern's order); pinned slots get
    /// a unit diagonal and nothing else.
    pub fn values(&self, h: &dyn HessianBlocks, bases: &[NodeBasis]) -> Vec<f64> {
        use rayon::prelude::*;
        // Each pair's reduced block once (up to nine entries read it), then the entries.
        let blocks: Vec<Matrix3<f64>> = self
            .pairs
            .par_iter()
            .map(|&(a, b)| {
                let (ra, rb) = (self.rep[a as usize], self.rep[b as usize]);
                if self.dofs[ra] == 0 || self.dofs[rb] == 0 {
                    // Every slot of one side pinned: no entry reads it.
                    return Matrix3::zeros();
                }
                bases[ra].basis.transpose() * h.block(a as usize, b as usize) * bases[rb].basis
            })
            .collect();
        let mut out: Vec<f64> = (0..self.rowval.len())
            .into_par_iter()
            .map(|e| {
                let mut v = 0.0;
                for &(i, p, q) in &self.sources[self.source_ptr[e]..self.source_ptr[e + 1]] {
                    let (a, b) = self.pairs[i as usize];
                    let (ra, rb) = (self.rep[a as usize], self.rep[b as usize]);
                    if self.pinned(ra, p as usize) || self.pinned(rb, q as usize) {
                        continue;
                    }
                    let blk = &blocks[i as usize];
                    v += blk[(p as usize, q as usize)];
                    // A pair of distinct grid nodes sharing one representative lands on the
                    // diagonal block twice (a, b) and (b, a): add the mirror.
                    if a != b && ra == rb {
                        v += blk[(q as usize, p as usize)];
                    }
                }
                v
            })
            .collect();
        for (r, &o) in self.offset.iter().enumerate() {
            for p in self.dofs[r] as usize..self.cap[r] as usize {
                out[self.diag[o + p]] = 1.0;
            }
        }
        out
    }

    /// The matrix (in this pattern) with `weight` of each node on its variables' diagonal and
    /// nothing else: the lumped mass matrix M, for quotients such as y^T M y.
    pub fn diagonal_of(&self, weight: &[f64]) -> Vec<f64> {
        let mut values = vec![0.0; self.rowval.len()];
        self.add_diagonal(&mut values, weight, 1.0);
        values
    }

    /// Adds `s * weight[k]` to the diagonal of every variable of node k (representatives: the
    /// weights of the nodes they stand for are summed).
    pub fn add_diagonal(&self, values: &mut [f64], weight: &[f64], s: f64) {
        let mut per = vec![0.0; self.dofs.len()];
        for (k, w) in weight.iter().enumerate() {
            per[self.rep[k]] += w;
        }
        for (k, w) in per.iter().enumerate() {
            for p in 0..self.dofs[k] as usize {
                values[self.diag[self.offset[k] + p]] += s * w;
            }
        }
    }

    /// Adds the symmetric block `m` (its leading `dofs x dofs` part) to the diagonal block of
    /// node `k`'s variables.
    pub fn add_node_block(&self, values: &mut [f64], k: usize, m: &Matrix3<f64>) {
        let (o, dofs) = self.vars(k);
        for qq in 0..dofs {
            for p in 0..=qq {
                let (r, c) = (o + p, o + qq);
                let col = &self.rowval[self.colptr[c]..self.colptr[c + 1]];
                if let Ok(at) = col.binary_search(&r) {
                    values[self.colptr[c] + at] += m[(p, qq)];
                }
            }
        }
    }

    /// The mean absolute diagonal entry of `values` over the live variables.
    pub fn mean_diagonal(&self, values: &[f64]) -> f64 {
        if self.live == 0 {
            return 0.0;
        }
        let mut s = 0.0;
        for (r, &o) in self.offset.iter().enumerate() {
            for p in 0..self.dofs[r] as usize {
                s += values[self.diag[o + p]].abs();
            }
        }
        s / self.live as f64
    }

    /// Per-node vectors reduced onto the free directions (summed over stitched nodes).
    pub fn reduce(&self, v: &[Vector], bases: &[NodeBasis]) -> Vec<f64> {
        let mut out = vec![0.0; self.n];
        for (k, vk) in v.iter().enumerate() {
            let r = self.rep[k];
            for p in 0..self.dofs[r] as usize {
                out[self.offset[r] + p] += bases[r].dir(p).dot(vk);
            }
        }
        out
    }

    /// The displacement of every node for reduced variables `y`.
    pub fn expand(&self, y: &[f64], bases: &[NodeBasis]) -> Vec<Vector> {
        (0..self.rep.len())
            .map(|k| {
                let r = self.rep[k];
                (0..self.dofs[r] as usize).fold(Vector::zeros(), |s, p| s + bases[r].dir(p) * y[self.offset[r] + p])
            })
            .collect()
    }

    /// Sets the pinned slots of `y` to zero (the value they have, up to rounding).
    fn clear_pinned(&self, y: &mut [f64]) {
        for (r, &o) in self.offset.iter().enumerate() {
            y[o + self.dofs[r] as usize..o + self.cap[r] as usize].fill(0.0);
        }
    }

    /// |P y + q| for the upper-triangular `values`.
    pub fn model_residual(&self, values: &[f64], y: &[f64], q: &[f64]) -> f64 {
        let r: Vec<f64> = self.mul(values, y).iter().zip(q).map(|(py, q)| py + q).collect();
        norm(&r)
    }

    /// y^T P y for the upper-triangular `values`.
    pub fn quad(&self, values: &[f64], y: &[f64]) -> f64 {
        let mut s = 0.0;
        for c in 0..self.n {
            let entries = self.colptr[c]..self.colptr[c + 1];
            for (&r, &value) in self.rowval[entries.clone()].iter().zip(&values[entries]) {
                let v = value * y[r] * y[c];
                s += if r == c { v } else { 2.0 * v };
            }
        }
        s
    }

    /// P y for the upper-triangular `values` (the full symmetric product).
    pub fn mul(&self, values: &[f64], y: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; self.n];
        for c in 0..self.n {
            let entries = self.colptr[c]..self.colptr[c + 1];
            for (&r, &value) in self.rowval[entries.clone()].iter().zip(&values[entries]) {
                out[r] += value * y[c];
                if r != c {
                    out[c] += value * y[r];
                }
            }
        }
        out
    }

    /// The upper-triangular CSC pattern of the reduced variables: (column pointers, rows).
    pub fn upper_pattern(&self) -> (&[usize], &[usize]) {
        (&self.colptr, &self.rowval)
    }

    fn matrix(&self, values: &[f64]) -> CscMatrix<f64> {
        CscMatrix::new(self.n, self.n, self.colptr.clone(), self.rowval.clone(), values.to_vec())
    }
}

/// Why a subproblem gave no step.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum QpFailure {
    /// Clarabel could not be set up on the data.
    Setup,
    /// Clarabel ended without a solution (e.g. an indefinite or singular model): its status.
    NotSolved(String),
}

/// One Clarabel solver per sparsity pattern, its data updated between subproblems (and a spare
/// one that solves the next rung of the shift ahead on the other core,
/// [`QpEngine::solve_ahead`]).
#[derive(Default)]
pub struct QpEngine {
    cached: Option<(Vec<u8>, DefaultSolver<f64>)>,
    /// The matrix values the cached solver's KKT system holds factorised (the last subproblem
    /// it solved at its starting point, with no interior-point iterations): a subproblem with
    /// the same matrix (a second-order correction) only needs new triangular solves.
    factored: Option<Vec<f64>>,
    /// The matrix values last solved by conjugate gradients preconditioned with the held
    /// factorisation of `factored` ([`QpEngine::solve_near`]): a second subproblem with them (a
    /// second-order correction) is solved the same way.
    lagged: Option<Vec<f64>>,
    /// Subproblems solved with the factorisation of the one before.
    pub reused_factorisations: u32,
    /// Subproblems solved by conjugate gradients on the factorisation of an earlier matrix.
    pub lagged_solves: u32,
    /// Time spent in Clarabel (set-up, updates and solves), ms.
    pub time_ms: f64,
    /// A second engine, for models solved ahead on the other core ([`QpEngine::solve_ahead`]).
    spare: Option<Box<QpEngine>>,
    /// The model the spare engine solved ahead and holds factorised, and its result.
    ahead: Option<Ahead>,
    /// Subproblems answered by a solve made ahead.
    pub solved_ahead: u32,
}

/// A subproblem solved ahead: its pattern, freedoms, matrix and forces, and its result.
struct Ahead {
    key: Vec<u8>,
    dofs: Vec<u8>,
    values: Vec<f64>,
    q: Vec<f64>,
    result: Result<Vec<f64>, QpFailure>,
}

impl QpEngine {
    /// A new engine with no solver yet.
    pub fn new() -> Self {
        Self::default()
    }

    fn settings() -> DefaultSettings<f64> {
        DefaultSettingsBuilder::default()
            .verbose(false)
            .max_iter(50)
            // Ruiz equilibration makes these subproblems (stiff fibres beside soft shear) far
            // harder, and data updates need the problem as given: no presolve, no dropped zeros.
            .equilibrate_enable(false)
            .presolve_enable(false)
            .input_sparse_dropzeros(false)
            .direct_solve_method("faer".to_string())
            // One thread: the factorisation's result then does not depend on the thread count
            // (faer's parallel supernodes sum in another order: the sphere drape's energy moved
            // in its last digit), and on two cores its threads cost more than they gave (the
            // 91 x 91 sphere drape, 25 k variables: 43 s on one thread against 48 s on two, 10 s
            // of system time in `sched_yield`; the 301 x 301 bench, 124 k: 4-8% slower on one).
            .max_threads(1)
            // No static regularisation: every model the solver builds is positive definite on
            // its live variables (the shift, a unit diagonal on pinned slots), and a model too
            // near singular is caught by the accuracy check below, not hidden. With it, the
            // factorisation is of P + eps I and the starting-point solve needs extra rounds of
            // iterative refinement to undo eps (the square table at 2.5 mm: 37 s against 41 s,
            // the same path to 1e-10 of the energy).
            .static_regularization_enable(false)
            .build()
            .expect("valid Clarabel settings")
    }

    /// Minimise 1/2 y^T P y + q^T y (P positive definite on the reduced variables, upper
    /// triangle `values` in `red`'s pattern). Returns y.
    pub fn solve(&mut self, red: &Reduction, values: &[f64], q: &[f64]) -> Result<Vec<f64>, QpFailure> {
        self.solve_refined(red, values, q, true)
    }

    /// As [`QpEngine::solve`], and meanwhile, on the other core, the same forces with the matrix
    /// `next`: the model the caller tries next if this one's step is refused (the shift's next
    /// rung). A later [`QpEngine::solve`] of exactly that model returns the result at once and
    /// holds its factorisation (for the second-order correction). Each solve is what it would
    /// be alone, so the caller's path is the same with one thread or two; with one, nothing is
    /// solved ahead.
    pub fn solve_ahead(
        &mut self,
        red: &Reduction,
        values: &[f64],
        q: &[f64],
        next: &[f64],
    ) -> Result<Vec<f64>, QpFailure> {
        if rayon::current_num_threads() < 2 || red.is_empty() || self.is_ahead(red, values, q) {
            return self.solve(red, values, q);
        }
        let start = std::time::Instant::now();
        let mut spare = self.spare.take().unwrap_or_default();
        let (now, later) =
            rayon::join(|| self.solve_timed(red, values, q, red.len(), true), || spare.solve(red, next, q));
        self.spare = Some(spare);
        self.ahead = Some(Ahead {
            key: red.key().to_vec(),
            dofs: red.dofs().to_vec(),
            values: next.to_vec(),
            q: q.to_vec(),
            result: later,
        });
        self.time_ms += start.elapsed().as_secs_f64() * 1e3;
        now
    }

    /// Whether the subproblem (`values`, `q`) was solved ahead by the spare engine.
    fn is_ahead(&self, red: &Reduction, values: &[f64], q: &[f64]) -> bool {
        self.ahead.as_ref().is_some_and(|a| {
            a.key.as_slice() == red.key() && a.dofs.as_slice() == red.dofs() && a.values == values && a.q == q
        })
    }

    /// Takes the answer solved ahead, swapping the spare engine's factorisation in as this one's.
    fn take_ahead(&mut self) -> Option<Result<Vec<f64>, QpFailure>> {
        let ahead = self.ahead.take()?;
        let spare = self.spare.as_mut()?;
        std::mem::swap(&mut self.cached, &mut spare.cached);
        std::mem::swap(&mut self.factored, &mut spare.factored);
        std::mem::swap(&mut self.lagged, &mut spare.lagged);
        self.solved_ahead += 1;
        Some(ahead.result)
    }

    /// As [`QpEngine::solve`] for a matrix the caller knows to be near the one last factorised
    /// (a Newton step moved the nodes by a hundredth of a spacing: the stiff fibres turned by
    /// about as much): first conjugate gradients preconditioned with that factorisation, at most
    /// [`LAGGED_ITERATIONS`], to the same accuracy a direct solve must reach
    /// ([`MODEL_SOLVE_ACCURACY`]); a new factorisation where they do not get there. Each
    /// iteration is one pair of triangular solves, a tenth of a factorisation or less.
    pub fn solve_near(&mut self, red: &Reduction, values: &[f64], q: &[f64]) -> Result<Vec<f64>, QpFailure> {
        let start = std::time::Instant::now();
        let lagged = self.lagged_solve(red, values, q);
        self.time_ms += start.elapsed().as_secs_f64() * 1e3;
        match lagged {
            Some(y) => Ok(y),
            None => self.solve(red, values, q),
        }
    }

    /// Conjugate gradients on `values` preconditioned with the held factorisation (None where
    /// there is none on this pattern, or they do not reach the accuracy in
    /// [`LAGGED_ITERATIONS`]).
    fn lagged_solve(&mut self, red: &Reduction, values: &[f64], q: &[f64]) -> Option<Vec<f64>> {
        let held = matches!(&self.cached, Some((key, _)) if key.as_slice() == red.key()) && self.factored.is_some();
        if !held || red.is_empty() {
            return None;
        }
        if self.factored.as_deref() == Some(values) {
            return None;
        }
        let (_, solver) = self.cached.as_mut().expect("checked");
        let mut settings = Self::settings();
        settings.iterative_refinement_enable = false;
        // z = P0^-1 r: the held factorisation's minimiser of 1/2 z^T P0 z - r^T z.
        let mut precondition = |r: &[f64]| -> Option<Vec<f64>> {
            solver.update_q(&r.iter().map(|v| -v).collect::<Vec<f64>>()).ok()?;
            if !solver.kktsystem.solve_initial_point(&mut solver.variables, &solver.data, &settings) {
                return None;
            }
            let z = solver.variables.x.clone();
            z.iter().all(|v| v.is_finite()).then_some(z)
        };
        let target = MODEL_SOLVE_ACCURACY * norm(q);
        let mut y = vec![0.0; q.len()];
        // The residual -q - P y of P y = -q.
        let mut r: Vec<f64> = q.iter().map(|v| -v).collect();
        let mut z = precondition(&r)?;
        let mut p = z.clone();
        let mut rz = dot(&r, &z);
        for _ in 0..LAGGED_ITERATIONS {
            let ap = red.mul(values, &p);
            let curvature = dot(&p, &ap);
            if !(curvature > 0.0 && rz > 0.0) {
                return None;
            }
            let alpha = rz / curvature;
            y.iter_mut().zip(&p).for_each(|(y, p)| *y += alpha * p);
            r.iter_mut().zip(&ap).for_each(|(r, ap)| *r -= alpha * ap);
            if norm(&r) <= target {
                // The recurrence's residual drifts from the true one: judge the true one.
                if red.model_residual(values, &y, q) > target {
                    return None;
                }
                red.clear_pinned(&mut y);
                self.lagged = Some(values.to_vec());
                self.lagged_solves += 1;
                return Some(y);
            }
            z = precondition(&r)?;
            let rz_next = dot(&r, &z);
            let beta = rz_next / rz;
            rz = rz_next;
            p.iter_mut().zip(&z).for_each(|(p, z)| *p = z + beta * *p);
        }
        None
    }

    /// As [`QpEngine::solve`], but a matrix already factorised is solved to the factorisation's
    /// own accuracy, without Clarabel's iterative refinement (the first solve of a matrix is
    /// refined and checked as always). For Krylov iterations that only need the subspace the
    /// solves span (the stability check's Lanczos computes its Ritz values with the true
    /// matrices): there the refinement's extra solves took half the check's time and changed
    /// none of its figures.
    pub fn solve_unrefined(&mut self, red: &Reduction, values: &[f64], q: &[f64]) -> Result<Vec<f64>, QpFailure> {
        self.solve_refined(red, values, q, false)
    }

    fn solve_refined(
        &mut self,
        red: &Reduction,
        values: &[f64],
        q: &[f64],
        refine: bool,
    ) -> Result<Vec<f64>, QpFailure> {
        let n = red.len();
        if n == 0 {
            return Ok(Vec::new());
        }
        if self.is_ahead(red, values, q) {
            if let Some(result) = self.take_ahead() {
                return result;
            }
        }
        let start = std::time::Instant::now();
        let result = self.solve_timed(red, values, q, n, refine);
        self.time_ms += start.elapsed().as_secs_f64() * 1e3;
        result
    }

    fn solve_timed(
        &mut self,
        red: &Reduction,
        values: &[f64],
        q: &[f64],
        n: usize,
        refine: bool,
    ) -> Result<Vec<f64>, QpFailure> {
        let reuse = matches!(&self.cached, Some((key, _)) if key.as_slice() == red.key());
        if reuse && self.lagged.as_deref() == Some(values) {
            // Solved by conjugate gradients on an earlier factorisation before: again.
            if let Some(y) = self.lagged_solve(red, values, q) {
                return Ok(y);
            }
        }
        if reuse && self.factored.as_deref() == Some(values) {
            // The same matrix: Clarabel's own starting-point solve (the step its full solve
            // takes at iteration 0, iterative refinement included unless declined) on the
            // factorisation it holds.
            let (_, solver) = self.cached.as_mut().expect("checked");
            solver.update_q(&q.to_vec()).map_err(|_| QpFailure::Setup)?;
            let mut settings = Self::settings();
            settings.iterative_refinement_enable = refine;
            let ok = solver.kktsystem.solve_initial_point(&mut solver.variables, &solver.data, &settings);
            let mut y = solver.variables.x.clone();
            if ok && y.iter().all(|v| v.is_finite()) {
                self.reused_factorisations += 1;
                red.clear_pinned(&mut y);
                return Ok(y);
            }
            // Fall through to a full solve.
        }
        self.factored = None;
        self.lagged = None;
        if reuse {
            let (_, solver) = self.cached.as_mut().expect("checked");
            solver.update_P(&values.to_vec()).map_err(|_| QpFailure::Setup)?;
            solver.update_q(&q.to_vec()).map_err(|_| QpFailure::Setup)?;
        } else {
            let p = red.matrix(values);
            let a = CscMatrix::new(0, n, vec![0; n + 1], Vec::new(), Vec::new());
            let cones: Vec<SupportedConeT<f64>> = Vec::new();
            let solver = DefaultSolver::new(&p, q, &a, &[], &cones, Self::settings()).map_err(|_| QpFailure::Setup)?;
            self.cached = Some((red.key().to_vec(), solver));
        }
        let (_, solver) = self.cached.as_mut().expect("a solver is cached");
        // No constraints: Clarabel's interior-point loop has nothing to do beyond its starting
        // point, the minimiser of the model (the factorisation, then its solve with iterative
        // refinement). Its termination test can still refuse that point where the model is
        // nearly singular and then fails an interior-point iteration it cannot use (1.5 s on
        // 124 k unknowns, and the solver discarded); the step's accuracy is judged here instead.
        let settings = Self::settings();
        let factorised = solver.kktsystem.update(&solver.data, &solver.cones, &settings);
        if !factorised {
            return Err(QpFailure::NotSolved("the factorisation failed (a singular model)".into()));
        }
        if !solver.kktsystem.solve_initial_point(&mut solver.variables, &solver.data, &settings) {
            return Err(QpFailure::NotSolved("the triangular solves failed".into()));
        }
        self.factored = Some(values.to_vec());
        let mut y = solver.variables.x.clone();
        if !y.iter().all(|v| v.is_finite()) {
            return Err(QpFailure::NotSolved("non-finite solution".into()));
        }
        let error = red.model_residual(values, &y, q);
        if error > MODEL_SOLVE_ACCURACY * norm(q) {
            return Err(QpFailure::NotSolved(format!(
                "inaccurate solve: |Py + q| / |q| = {:.1e} (a nearly singular model)",
                error / norm(q)
            )));
        }
        red.clear_pinned(&mut y);
        Ok(y)
    }
}

/// The dot product of two reduced vectors.
pub(super) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The Euclidean norm of a reduced vector.
pub(super) fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    /// Nodes coupled by a fixed symmetric matrix, 3 rows and columns a node (the stability
    /// check's tests use it too).
    pub(in crate::mechanics) struct Dense(pub DMatrix<f64>);
    impl HessianBlocks for Dense {
        fn block(&self, a: usize, b: usize) -> Matrix3<f64> {
            Matrix3::from_fn(|i, j| self.0[(3 * a + i, 3 * b + j)])
        }
    }

    fn spd(seed: f64) -> DMatrix<f64> {
        let b = DMatrix::from_fn(6, 6, |i, j| ((i * 7 + j * 3) as f64 * seed).sin());
        &b * b.transpose() + DMatrix::identity(6, 6) * 0.5
    }

    #[test]
    fn subproblems_solve_the_models_they_are_given() {
        let red = Reduction::new(vec![3, 3], vec![3, 3], vec![0, 1], &[(0, 0), (0, 1), (1, 1)]);
        let bases = [NodeBasis::free(), NodeBasis::free()];
        let (p1, p2) = (spd(0.7), spd(1.3));
        let q1 = [1.0, -2.0, 0.5, 0.25, 3.0, -1.0];
        let q2 = [-0.5, 1.0, 2.0, -1.5, 0.0, 0.75];
        let exact =
            |p: &DMatrix<f64>, q: &[f64]| p.clone().cholesky().unwrap().solve(&(-DVector::from_column_slice(q)));
        let close = |y: &[f64], want: &DVector<f64>| {
            let err = (DVector::from_column_slice(y) - want).norm();
            assert!(err < 1e-9 * want.norm(), "{y:?} vs {want}");
        };
        let mut engine = QpEngine::new();
        let v1 = red.values(&Dense(p1.clone()), &bases);
        let y = engine.solve(&red, &v1, &q1).unwrap();
        close(&y, &exact(&p1, &q1));
        assert!(red.model_residual(&v1, &y, &q1) < 1e-12);
        // The same matrix with other forces (a second-order correction): the factorisation held.
        let y = engine.solve(&red, &v1, &q2).unwrap();
        close(&y, &exact(&p1, &q2));
        assert_eq!(engine.reused_factorisations, 1);
        // A new matrix is factorised anew.
        let v2 = red.values(&Dense(p2.clone()), &bases);
        let y = engine.solve(&red, &v2, &q2).unwrap();
        close(&y, &exact(&p2, &q2));
        assert_eq!(engine.reused_factorisations, 1);
    }

    #[test]
    fn a_nearby_model_is_solved_on_the_last_factorisation_and_a_far_one_factorised() {
        let red = Reduction::new(vec![3, 3], vec![3, 3], vec![0, 1], &[(0, 0), (0, 1), (1, 1)]);
        let bases = [NodeBasis::free(), NodeBasis::free()];
        let p1 = spd(0.7);
        // A hundredth of the matrix changed, as after a tiny Newton step.
        let near = &p1 + DMatrix::from_fn(6, 6, |i, j| 0.01 * ((i + 2 * j) as f64).cos() * ((2 * i + j) as f64).cos());
        let far = spd(1.3);
        let q = [1.0, -2.0, 0.5, 0.25, 3.0, -1.0];
        let exact = |p: &DMatrix<f64>| p.clone().cholesky().unwrap().solve(&(-DVector::from_column_slice(&q)));
        let mut engine = QpEngine::new();
        let v1 = red.values(&Dense(p1), &bases);
        engine.solve(&red, &v1, &q).unwrap();
        // The nearby model by conjugate gradients, to the accuracy a direct solve must reach.
        let v_near = red.values(&Dense(near.clone()), &bases);
        let y = engine.solve_near(&red, &v_near, &q).unwrap();
        assert_eq!(engine.lagged_solves, 1);
        assert!(red.model_residual(&v_near, &y, &q) <= MODEL_SOLVE_ACCURACY * norm(&q));
        let want = exact(&near);
        assert!((DVector::from_column_slice(&y) - &want).norm() < 1e-5 * want.norm());
        // Its second-order correction (the same matrix) goes the same way.
        engine.solve(&red, &v_near, &q).unwrap();
        assert_eq!(engine.lagged_solves, 2);
        // A model far from the factorised one: the conjugate gradients give up and it is
        // factorised, solved exactly.
        let v_far = red.values(&Dense(far.clone()), &bases);
        let y = engine.solve_near(&red, &v_far, &q).unwrap();
        assert_eq!(engine.lagged_solves, 2);
        let want = exact(&far);
        assert!((DVector::from_column_slice(&y) - &want).norm() < 1e-9 * want.norm());
    }

    #[test]
    fn the_next_rung_solved_ahead_is_the_one_a_lone_solve_gives() {
        let red = Reduction::new(vec![3, 3], vec![3, 3], vec![0, 1], &[(0, 0), (0, 1), (1, 1)]);
        let bases = [NodeBasis::free(), NodeBasis::free()];
        let (p, m) = (spd(0.7), DMatrix::identity(6, 6));
        let q1 = [1.0, -2.0, 0.5, 0.25, 3.0, -1.0];
        let q2 = [-0.5, 1.0, 2.0, -1.5, 0.0, 0.75];
        let now = red.values(&Dense(&p + &m * 1e-3), &bases);
        let next = red.values(&Dense(&p + &m * 4e-3), &bases);
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        let mut engine = QpEngine::new();
        let (y_now, y_next, y_corrected) = pool.install(|| {
            let y_now = engine.solve_ahead(&red, &now, &q1, &next).unwrap();
            // The step was refused: the next rung is answered at once ...
            let y_next = engine.solve(&red, &next, &q1).unwrap();
            // ... and its factorisation is the one held for the correction that follows.
            let y_corrected = engine.solve(&red, &next, &q2).unwrap();
            (y_now, y_next, y_corrected)
        });
        assert_eq!(engine.solved_ahead, 1);
        assert_eq!(engine.reused_factorisations, 1);
        // Bit for bit what one engine solving them in turn gives: the path does not depend on
        // whether the second core was there.
        let mut alone = QpEngine::new();
        assert_eq!(y_now, alone.solve(&red, &now, &q1).unwrap());
        assert_eq!(y_next, alone.solve(&red, &next, &q1).unwrap());
        assert_eq!(y_corrected, alone.solve(&red, &next, &q2).unwrap());
        // Another model is not taken for the one solved ahead.
        let other = red.values(&Dense(&p + &m * 16e-3), &bases);
        pool.install(|| engine.solve_ahead(&red, &now, &q2, &other).unwrap());
        assert_eq!(engine.solve(&red, &other, &q1).unwrap(), alone.solve(&red, &other, &q1).unwrap());
        assert_eq!(engine.solved_ahead, 1);
    }

    #[test]
    fn a_model_too_near_singular_for_its_step_is_refused() {
        // A diagonal spanning 1 .. 1e-30: rounding swamps the step along the soft direction.
        let red = Reduction::new(vec![3], vec![3], vec![0], &[(0, 0)]);
        let p = DMatrix::from_diagonal(&DVector::from_vec(vec![1.0, 1e-30, 1.0]));
        let values = red.values(&Dense(p), &[NodeBasis::free()]);
        let q = [1.0, 1.0, 1.0];
        let mut engine = QpEngine::new();
        match engine.solve(&red, &values, &q) {
            Err(QpFailure::NotSolved(why)) => assert!(why.contains("singular"), "{why}"),
            Ok(y) => panic!("a step {y:?} from a singular model"),
            Err(e) => panic!("{e:?}"),
        }
    }
}
