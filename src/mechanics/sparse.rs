//! Sparse symmetric matrices on the warp/weft grid, stored as the upper triangle (diagonal
//! included) in compressed sparse column form, the layout Clarabel takes for its `P` matrix.
//!
//! A `nu x nv` grid has 3 degrees of freedom per node: DOF `3 * node + c` (c = x, y, z), over all
//! nodes whether placed or not. Node (i, j) couples with its 8 neighbours (the cells around it)
//! and with the nodes two apart along each fibre (bending triples A-O-B). The pattern is the union
//! of these couplings; it is built once per grid and shared ([`Arc`]) by every matrix on it.
//!
//! Within the column of DOF `3b + cb`, the rows are those of the nodes `a <= b` that couple with
//! `b`, in increasing node order, three rows per node (for `a == b` only the rows `3b..=3b+cb`).
//! Hence the slot of `(3a + ca, 3b + cb)` is `colptr[3b + cb] + 3 * rank(a in b's list) + ca`, and
//! adding a 3x3 block costs a lookup of `rank` and nine (or six) additions.
use nalgebra::{DMatrix, Matrix3};
use std::ops::Range;
use std::sync::Arc;

/// Offsets (di, dj) of the nodes `a = (ib + di, jb + dj)` with `a <= b` that couple with node b,
/// in increasing node order (for every grid, among the offsets valid at a given node).
const LOWER: [(isize, isize); 7] = [(-2, 0), (-1, -1), (-1, 0), (-1, 1), (0, -2), (0, -1), (0, 0)];
const ABSENT: u8 = u8::MAX;

/// The upper-triangular CSC sparsity pattern of the grid's Hessians (see the module docs).
#[derive(Debug, Clone)]
pub struct SymmetricPattern {
    nu: usize,
    nv: usize,
    colptr: Vec<usize>,
    rowval: Vec<usize>,
    /// Per node b and per entry of [`LOWER`]: that neighbour's rank in b's column list.
    ranks: Vec<[u8; 7]>,
}

impl SymmetricPattern {
    /// The pattern of a `nu x nv` grid (3 DOFs per node).
    pub fn grid(nu: usize, nv: usize) -> Self {
        let n = nu * nv;
        let mut colptr = Vec::with_capacity(3 * n + 1);
        let mut rowval = Vec::with_capacity(60 * n);
        let mut ranks = vec![[ABSENT; 7]; n];
        colptr.push(0);
        let mut list = [0usize; 7];
        for (b, rank) in ranks.iter_mut().enumerate() {
            let (ib, jb) = ((b / nv) as isize, (b % nv) as isize);
            let mut m = 0;
            for (k, &(di, dj)) in LOWER.iter().enumerate() {
                let (i, j) = (ib + di, jb + dj);
                if i >= 0 && j >= 0 && (i as usize) < nu && (j as usize) < nv {
                    let a = i as usize * nv + j as usize;
                    debug_assert!(m == 0 || list[m - 1] < a);
                    list[m] = a;
                    rank[k] = m as u8;
                    m += 1;
                }
            }
            for cb in 0..3 {
                for &a in &list[..m] {
                    let top = if a == b { cb + 1 } else { 3 };
                    rowval.extend((0..top).map(|ca| 3 * a + ca));
                }
                colptr.push(rowval.len());
            }
        }
        SymmetricPattern { nu, nv, colptr, rowval, ranks }
    }

    /// Nodes along the warp.
    pub fn nu(&self) -> usize {
        self.nu
    }
    /// Nodes along the weft.
    pub fn nv(&self) -> usize {
        self.nv
    }
    /// Number of rows and columns, `3 * nu * nv`.
    pub fn dim(&self) -> usize {
        3 * self.nu * self.nv
    }
    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.rowval.len()
    }
    /// CSC column pointers (length `dim() + 1`).
    pub fn colptr(&self) -> &[usize] {
        &self.colptr
    }
    /// CSC row indices (sorted within each column).
    pub fn rowval(&self) -> &[usize] {
        &self.rowval
    }
    /// The range of stored entries that belong to the columns of the nodes `nodes`.
    pub fn nz_range(&self, nodes: Range<usize>) -> Range<usize> {
        self.colptr[3 * nodes.start]..self.colptr[3 * nodes.end]
    }

    /// Every pair of nodes (a <= b) that couple, a pair (b, b) included for every node; sorted
    /// by b, then a.
    pub fn coupled_pairs(&self) -> Vec<(usize, usize)> {
        let n = self.nu * self.nv;
        let mut out = Vec::with_capacity(7 * n);
        for b in 0..n {
            let (ib, jb) = ((b / self.nv) as isize, (b % self.nv) as isize);
            for (k, &(di, dj)) in LOWER.iter().enumerate() {
                if self.ranks[b][k] != ABSENT {
                    out.push(((ib + di) as usize * self.nv + (jb + dj) as usize, b));
                }
            }
        }
        out
    }

    /// Rank of node `a` in the column list of node `b` (`a <= b`), or None if they do not couple.
    #[inline(always)]
    fn rank(&self, a: usize, b: usize) -> Option<usize> {
        debug_assert!(a <= b && b < self.nu * self.nv);
        let d = b - a;
        let nv = self.nv;
        let k = if nv >= 4 {
            // All seven offsets give distinct index differences.
            match d {
                0 => 6,
                1 => 5,
                2 => 4,
                _ if d == nv - 1 => 3,
                _ if d == nv => 2,
                _ if d == nv + 1 => 1,
                _ if d == 2 * nv => 0,
                _ => return None,
            }
        } else {
            let di = (b / nv) as isize - (a / nv) as isize;
            let dj = (b % nv) as isize - (a % nv) as isize;
            LOWER.iter().position(|&o| o == (-di, -dj))?
        };
        let r = self.ranks[b][k];
        (r != ABSENT).then_some(r as usize)
    }

    /// Index into the stored values of entry (row, col), or None outside the pattern. Requires
    /// `row <= col` (upper triangle).
    #[inline]
    pub fn try_slot(&self, row: usize, col: usize) -> Option<usize> {
        assert!(row <= col, "slot({row}, {col}): not in the upper triangle");
        let r = self.rank(row / 3, col / 3)?;
        Some(self.colptr[col] + 3 * r + row % 3)
    }

    /// Index into the stored values of entry (row, col), `row <= col`.
    /// Panics if the entry is not in the pattern.
    #[inline]
    pub fn slot(&self, row: usize, col: usize) -> usize {
        self.try_slot(row, col).unwrap_or_else(|| panic!("entry ({row}, {col}) is not in the grid pattern"))
    }

    /// Adds the block `m` at rows of node `a`, columns of node `b` (and so `m^T` at rows of `b`,
    /// columns of `a`) into `values`, a window of the stored values starting at entry `offset`
    /// that holds the columns of `max(a, b)`. For `a == b`, `m` must be symmetric (its upper
    /// triangle is used). Panics if the nodes do not couple.
    #[inline(always)]
    pub fn add_block_into(&self, values: &mut [f64], offset: usize, a: usize, b: usize, m: &Matrix3<f64>) {
        if a <= b {
            let r = self.rank(a, b).unwrap_or_else(|| panic!("nodes {a} and {b} do not couple"));
            let c0 = 3 * b;
            if a == b {
                for cb in 0..3 {
                    let base = self.colptr[c0 + cb] + 3 * r - offset;
                    for ca in 0..=cb {
                        values[base + ca] += m[(ca, cb)];
                    }
                }
            } else {
                for cb in 0..3 {
                    let base = self.colptr[c0 + cb] + 3 * r - offset;
                    let dst = &mut values[base..base + 3];
                    dst[0] += m[(0, cb)];
                    dst[1] += m[(1, cb)];
                    dst[2] += m[(2, cb)];
                }
            }
        } else {
            // Upper-triangle entry (3b + cb, 3a + ca) holds m[(ca, cb)].
            let r = self.rank(b, a).unwrap_or_else(|| panic!("nodes {a} and {b} do not couple"));
            let c0 = 3 * a;
            for ca in 0..3 {
                let base = self.colptr[c0 + ca] + 3 * r - offset;
                let dst = &mut values[base..base + 3];
                dst[0] += m[(ca, 0)];
                dst[1] += m[(ca, 1)];
                dst[2] += m[(ca, 2)];
            }
        }
    }

    /// Adds `s I` to the block (a, b) (and (b, a)) in `values` (see [`Self::add_block_into`]).
    #[inline(always)]
    pub fn add_identity_into(&self, values: &mut [f64], offset: usize, a: usize, b: usize, s: f64) {
        let (lo, hi) = (a.min(b), a.max(b));
        let r = self.rank(lo, hi).unwrap_or_else(|| panic!("nodes {a} and {b} do not couple"));
        for c in 0..3 {
            values[self.colptr[3 * hi + c] + 3 * r + c - offset] += s;
        }
    }
}

/// A symmetric matrix on a [`SymmetricPattern`] (upper triangle stored).
#[derive(Debug, Clone)]
pub struct SymmetricMatrix {
    /// Where the entries are.
    pub pattern: Arc<SymmetricPattern>,
    /// The entries, column by column.
    pub values: Vec<f64>,
}

impl SymmetricMatrix {
    /// The zero matrix on `pattern`.
    pub fn zeros(pattern: Arc<SymmetricPattern>) -> Self {
        let values = vec![0.0; pattern.nnz()];
        SymmetricMatrix { pattern, values }
    }
    /// Sets every stored value to zero.
    pub fn clear(&mut self) {
        self.values.iter_mut().for_each(|v| *v = 0.0);
    }
    /// Number of rows and columns.
    pub fn dim(&self) -> usize {
        self.pattern.dim()
    }
    /// Start of each column in `rowval` and `values`.
    pub fn colptr(&self) -> &[usize] {
        self.pattern.colptr()
    }
    /// Row of each entry.
    pub fn rowval(&self) -> &[usize] {
        self.pattern.rowval()
    }
    /// The entries.
    pub fn values(&self) -> &[f64] {
        &self.values
    }
    /// The entries, to change them.
    pub fn values_mut(&mut self) -> &mut [f64] {
        &mut self.values
    }
    /// Adds `m` to the block (node a, node b) and `m^T` to the block (b, a). Call once per
    /// unordered pair; for `a == b`, `m` must be symmetric.
    #[inline]
    pub fn add_block(&mut self, a: usize, b: usize, m: &Matrix3<f64>) {
        self.pattern.add_block_into(&mut self.values, 0, a, b, m);
    }
    /// Adds `v` to entry (row, col) and, off the diagonal, to (col, row).
    pub fn add(&mut self, row: usize, col: usize, v: f64) {
        let s = self.pattern.slot(row.min(col), row.max(col));
        self.values[s] += v;
    }
    /// Entry (row, col) (zero outside the pattern).
    pub fn get(&self, row: usize, col: usize) -> f64 {
        self.pattern.try_slot(row.min(col), row.max(col)).map_or(0.0, |s| self.values[s])
    }
    /// The 3x3 block at rows of node `a`, columns of node `b` (zero if they do not couple).
    pub fn block(&self, a: usize, b: usize) -> Matrix3<f64> {
        let p = &self.pattern;
        let (lo, hi) = (a.min(b), a.max(b));
        let Some(r) = p.rank(lo, hi) else { return Matrix3::zeros() };
        // m[(ca, cb)] = A[3 lo + ca, 3 hi + cb] (upper triangle; mirrored on the diagonal block).
        let mut m = Matrix3::zeros();
        for cb in 0..3 {
            let base = p.colptr[3 * hi + cb] + 3 * r;
            for ca in 0..3 {
                if lo == hi && ca > cb {
                    continue;
                }
                m[(ca, cb)] = self.values[base + ca];
                if lo == hi {
                    m[(cb, ca)] = self.values[base + ca];
                }
            }
        }
        if a <= b {
            m
        } else {
            m.transpose()
        }
    }
    /// y = A x.
    pub fn mul_vec(&self, x: &[f64]) -> Vec<f64> {
        let n = self.dim();
        assert_eq!(x.len(), n);
        let mut y = vec![0.0; n];
        let (cp, rv) = (self.colptr(), self.rowval());
        for col in 0..n {
            let mut acc = 0.0;
            let entries = cp[col]..cp[col + 1];
            for (&row, &v) in rv[entries.clone()].iter().zip(&self.values[entries]) {
                acc += v * x[row];
                if row != col {
                    y[row] += v * x[col];
                }
            }
            y[col] += acc;
        }
        y
    }
    /// The full dense matrix (for tests on small grids).
    pub fn to_dense(&self) -> DMatrix<f64> {
        let n = self.dim();
        let mut m = DMatrix::zeros(n, n);
        let (cp, rv) = (self.colptr(), self.rowval());
        for col in 0..n {
            for k in cp[col]..cp[col + 1] {
                m[(rv[k], col)] = self.values[k];
                m[(col, rv[k])] = self.values[k];
            }
        }
        m
    }
    /// A Clarabel matrix (upper triangle, as Clarabel's `P` wants); copies the arrays.
    pub fn to_csc(&self) -> clarabel::algebra::CscMatrix<f64> {
        let n = self.dim();
        clarabel::algebra::CscMatrix::new(n, n, self.colptr().to_vec(), self.rowval().to_vec(), self.values.clone())
    }
}

impl crate::mechanics::solver::HessianBlocks for SymmetricMatrix {
    fn block(&self, a: usize, b: usize) -> Matrix3<f64> {
        SymmetricMatrix::block(self, a, b)
    }
}
