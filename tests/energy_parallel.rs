//! The energy on large grids: bit-identical results for any thread count and strip size, and
//! directional finite-difference checks across strip boundaries; the solver adapter.
use crate::energy_common;
use drape::geometry::{Point, Vector};
use drape::mechanics::energy::{Evaluation, Grid, HessianKind, Model};
use drape::mechanics::refine::NetObjective;
use drape::mechanics::Objective;
use energy_common::*;

const D: f64 = 0.01;

fn holed_grid(nu: usize, nv: usize) -> Grid {
    let mut rng = Rng(77);
    let active = (0..nu * nv).map(|_| rng.next() > -0.96).collect();
    Grid::with_active(nu, nv, D, active)
}

fn bits(ev: &Evaluation) -> (u64, Vec<u64>, Vec<u64>) {
    (
        ev.energy.to_bits(),
        ev.gradient.iter().flat_map(|g| [g.x.to_bits(), g.y.to_bits(), g.z.to_bits()]).collect(),
        ev.hessian.as_ref().map_or(vec![], |h| h.values().iter().map(|v| v.to_bits()).collect()),
    )
}

#[test]
fn bit_identical_for_any_thread_count() {
    let m = TestLaws::default();
    let grid = holed_grid(60, 130);
    let x = perturbed(&grid, 0.4, 0.05, 11);
    let model = full(&grid, &m).with_strip_nodes(700);
    let run = |threads: usize, kind| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| bits(&model.evaluate(&x, Some(kind))))
    };
    for kind in [HessianKind::Exact, HessianKind::Convex] {
        let one = run(1, kind);
        assert_eq!(one, run(2, kind));
        assert_eq!(one, run(3, kind));
        assert_eq!(one, run(8, kind));
    }
}

#[test]
fn gradient_and_hessian_do_not_depend_on_the_strips() {
    let m = TestLaws::default();
    let grid = holed_grid(40, 23);
    let x = perturbed(&grid, -0.7, 0.05, 12);
    let reference = full(&grid, &m).with_strip_nodes(usize::MAX).evaluate(&x, Some(HessianKind::Exact));
    for strip in [1, 23, 50, 100, 8192] {
        let ev = full(&grid, &m).with_strip_nodes(strip).evaluate(&x, Some(HessianKind::Exact));
        assert_eq!(bits(&ev).1, bits(&reference).1, "gradient, strip {strip}");
        assert_eq!(bits(&ev).2, bits(&reference).2, "Hessian, strip {strip}");
        assert!((ev.energy - reference.energy).abs() <= 1e-13 * reference.energy.abs());
        for (a, b) in ev.terms.iter().zip(&reference.terms) {
            assert_eq!(a.0, b.0);
            assert!((a.1 - b.1).abs() <= 1e-13 * b.1.abs().max(1e-300), "{}: {} vs {}", a.0, a.1, b.1);
        }
    }
}

#[test]
fn directional_derivatives_on_a_large_grid() {
    let m = TestLaws::default();
    let grid = holed_grid(90, 70);
    let x = perturbed(&grid, 0.9, 0.05, 13);
    let model = full(&grid, &m).with_strip_nodes(900);
    let mut rng = Rng(5);
    let p: Vec<Vector> = (0..grid.num_nodes()).map(|_| rng.vector() * D).collect();
    let along = |t: f64| -> Vec<Point> { x.iter().zip(&p).map(|(a, b)| a + b * t).collect() };
    let h = 1e-5;
    let ev = model.evaluate(&x, Some(HessianKind::Exact));
    let gp: f64 = ev.gradient.iter().zip(&p).map(|(g, v)| g.dot(v)).sum();
    let fd = (model.energy(&along(h)) - model.energy(&along(-h))) / (2.0 * h);
    assert!((gp - fd).abs() <= 1e-6 * fd.abs(), "{gp} vs {fd}");
    let pf: Vec<f64> = p.iter().flat_map(|v| [v.x, v.y, v.z]).collect();
    let hp = ev.hessian.as_ref().unwrap().mul_vec(&pf);
    let (g1, g0) = (model.evaluate(&along(h), None).gradient_flat(), model.evaluate(&along(-h), None).gradient_flat());
    let fd: Vec<f64> = g1.iter().zip(&g0).map(|(a, b)| (a - b) / (2.0 * h)).collect();
    let err: f64 = hp.iter().zip(&fd).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt();
    let norm: f64 = fd.iter().map(|a| a * a).sum::<f64>().sqrt();
    assert!(err <= 1e-6 * norm, "H p: rel. error {}", err / norm);
}

#[test]
fn solver_objective_splits_internal_forces_and_loads() {
    let m = TestLaws::default();
    let grid = holed_grid(12, 9);
    let x = perturbed(&grid, 0.3, 0.05, 14);
    let model: Model = full(&grid, &m);
    let ev = model.evaluate(&x, Some(HessianKind::Exact));
    // The solver's view of the same model: gravity as constant nodal loads, the exact Hessian
    // (and the convex one on request).
    let objective = NetObjective::new(grid.clone(), &m, Vector::new(0.3, -1.0, -9.81));
    let ob = Objective::evaluate(&objective, &x, true);
    assert!((ob.energy - ev.energy).abs() <= 1e-13 * ev.energy.abs());
    let load = ev.terms.iter().find(|t| t.0 == "gravity").unwrap().1;
    let work: f64 = ob.external.iter().zip(&x).map(|(p, y)| p.dot(&y.coords)).sum();
    assert!((load + work).abs() <= 1e-13 * work.abs());
    for k in 0..grid.num_nodes() {
        let g = ob.internal[k] - ob.external[k];
        assert!((g - ev.gradient[k]).norm() <= 1e-12 * (1.0 + ev.gradient[k].norm()));
    }
    let h = ev.hessian.unwrap();
    let blocks = ob.hessian.unwrap();
    let convex = model.evaluate(&x, Some(HessianKind::Convex)).hessian.unwrap();
    let convex_blocks = objective.convex_hessian(&x).unwrap();
    for (a, b) in objective.coupled_pairs() {
        assert_eq!(blocks.block(a, b), h.block(a, b));
        assert_eq!(convex_blocks.block(a, b), convex.block(a, b));
    }
}
