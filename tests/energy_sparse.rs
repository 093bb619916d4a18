//! The grid's symmetric sparse pattern and matrices.
use drape::mechanics::sparse::{SymmetricMatrix, SymmetricPattern};
use nalgebra::{DMatrix, Matrix3};
use std::sync::Arc;

fn couples(nv: usize, a: usize, b: usize) -> bool {
    let (di, dj) = ((a / nv) as isize - (b / nv) as isize, (a % nv) as isize - (b % nv) as isize);
    (di.abs() <= 1 && dj.abs() <= 1) || (di.abs() == 2 && dj == 0) || (di == 0 && dj.abs() == 2)
}

#[test]
fn pattern_is_the_upper_triangle_of_the_grid_couplings() {
    for nu in 1..7 {
        for nv in 1..7 {
            let p = SymmetricPattern::grid(nu, nv);
            let n = nu * nv;
            assert_eq!(p.dim(), 3 * n);
            assert_eq!(p.colptr().len(), 3 * n + 1);
            // Every stored entry is upper, sorted, and slot() finds it.
            for col in 0..3 * n {
                let rows = &p.rowval()[p.colptr()[col]..p.colptr()[col + 1]];
                assert!(rows.windows(2).all(|w| w[0] < w[1]));
                for (k, &row) in rows.iter().enumerate() {
                    assert!(row <= col);
                    assert_eq!(p.slot(row, col), p.colptr()[col] + k);
                }
            }
            // Exactly the coupled node pairs are present.
            let mut count = 0;
            for b in 0..n {
                for a in 0..=b {
                    let c = couples(nv, a, b);
                    assert_eq!(p.try_slot(3 * a, 3 * b + 2).is_some(), c, "{nu}x{nv}: nodes {a}, {b}");
                    count += c as usize;
                }
            }
            assert_eq!(p.coupled_pairs().len(), count);
            assert!(p.coupled_pairs().iter().all(|&(a, b)| a <= b && couples(nv, a, b)));
            let entries = 9 * (count - n) + 6 * n;
            assert_eq!(p.nnz(), entries, "{nu}x{nv}");
        }
    }
}

#[test]
fn blocks_products_and_csc() {
    let (nu, nv) = (4, 5);
    let p = Arc::new(SymmetricPattern::grid(nu, nv));
    let mut m = SymmetricMatrix::zeros(p.clone());
    let n = 3 * nu * nv;
    let mut dense = DMatrix::<f64>::zeros(n, n);
    let mut seed = 1.0f64;
    let mut next = || {
        seed = (seed * 7.3 + 0.37) % 1.0;
        seed - 0.5
    };
    for (a, b) in p.coupled_pairs() {
        for (x, y) in [(a, b), (b, a)] {
            if x == y && x % 2 == 1 {
                continue;
            }
            let mut blk = Matrix3::from_fn(|_, _| next());
            if x == y {
                blk = blk + blk.transpose();
            }
            m.add_block(x, y, &blk);
            for r in 0..3 {
                for c in 0..3 {
                    dense[(3 * x + r, 3 * y + c)] += blk[(r, c)];
                    if x != y {
                        dense[(3 * y + c, 3 * x + r)] += blk[(r, c)];
                    }
                }
            }
        }
    }
    assert_eq!(m.to_dense(), dense);
    for (a, b) in p.coupled_pairs() {
        let blk = dense.fixed_view::<3, 3>(3 * a, 3 * b).into_owned();
        assert_eq!(m.block(a, b), blk);
        assert_eq!(m.block(b, a), blk.transpose());
    }
    assert_eq!(m.block(0, 3 * nv), Matrix3::zeros());
    let x: Vec<f64> = (0..n).map(|k| (k as f64 * 0.37).sin()).collect();
    let y = m.mul_vec(&x);
    let yd = &dense * nalgebra::DVector::from_vec(x.clone());
    for k in 0..n {
        assert!((y[k] - yd[k]).abs() < 1e-12);
    }
    m.add(3, 7, 1.5);
    assert_eq!(m.get(7, 3), dense[(3, 7)] + 1.5);
    let csc = m.to_csc();
    assert_eq!((csc.m, csc.n), (n, n));
    assert_eq!(csc.nzval, m.values());
    m.clear();
    assert!(m.values().iter().all(|v| *v == 0.0));
}
