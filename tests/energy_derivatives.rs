//! Energy terms: gradients against central finite differences of the energy, exact Hessians
//! against finite differences of the gradient, Convex Hessians positive semidefinite; on randomly
//! perturbed 5 x 4 grids at zero, moderate and large (+-60 deg) shear, with and without inactive
//! nodes.
use crate::energy_common;
use drape::geometry::{Point, Vector};
use drape::kinematic::net::{DrapeNet, NodeStatus};
use drape::material::Fibre;
use drape::mechanics::energy::{HessianKind, Laws, Model, Shear};
use energy_common::*;
use nalgebra::{DMatrix, SymmetricEigen};

const D: f64 = 0.02;

fn grids() -> Vec<Grid> {
    let mut holes = vec![true; 20];
    holes[2 * 4 + 1] = false; // an interior node
    holes[19] = false; // a corner
    vec![Grid::full(5, 4, D), Grid::with_active(5, 4, D, holes)]
}
use drape::mechanics::energy::Grid;

fn cases() -> Vec<(f64, u64)> {
    let deg = std::f64::consts::PI / 180.0;
    vec![(0.0, 1), (25.0 * deg, 2), (60.0 * deg, 3), (-60.0 * deg, 4), (-35.0 * deg, 5)]
}

fn shifted(x: &[Point], dof: usize, h: f64) -> Vec<Point> {
    let mut y = x.to_vec();
    y[dof / 3][dof % 3] += h;
    y
}

fn flat(v: &[Vector]) -> Vec<f64> {
    v.iter().flat_map(|g| [g.x, g.y, g.z]).collect()
}

fn rel(a: &[f64], b: &[f64]) -> f64 {
    let num: f64 = a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>().sqrt();
    let den: f64 = b.iter().map(|y| y * y).sum::<f64>().sqrt();
    num / den.max(1e-300)
}

#[test]
fn gradients_match_finite_differences() {
    let m = TestLaws::default();
    let h = 1e-5 * D;
    for grid in grids() {
        for (gamma, seed) in cases() {
            let x = perturbed(&grid, gamma, 0.05, seed);
            for (name, model) in all_models(&grid, &m) {
                let ev = model.evaluate(&x, None);
                assert!(
                    (ev.energy - model.energy(&x)).abs() <= 1e-14 * ev.energy.abs().max(1e-300),
                    "{name}: energy() differs"
                );
                let g = flat(&ev.gradient);
                let fd: Vec<f64> = (0..3 * grid.num_nodes())
                    .map(|k| (model.energy(&shifted(&x, k, h)) - model.energy(&shifted(&x, k, -h))) / (2.0 * h))
                    .collect();
                let r = rel(&g, &fd);
                assert!(
                    r < 1e-6,
                    "{name}, gamma {gamma:.3}, active {}: gradient rel. error {r:e}",
                    grid.active.iter().filter(|a| **a).count()
                );
                for (k, a) in grid.active.iter().enumerate() {
                    if !a {
                        assert_eq!(ev.gradient[k], Vector::zeros(), "{name}: gradient at an inactive node");
                    }
                }
            }
        }
    }
}

#[test]
fn exact_hessians_match_finite_differences_of_the_gradient() {
    let m = TestLaws::default();
    let h = 1e-5 * D;
    for grid in grids() {
        for (gamma, seed) in cases() {
            let x = perturbed(&grid, gamma, 0.05, seed);
            for (name, model) in all_models(&grid, &m) {
                if name == "gravity" {
                    let ev = model.evaluate(&x, Some(HessianKind::Exact));
                    assert!(ev.hessian.unwrap().values().iter().all(|v| *v == 0.0));
                    continue;
                }
                let n = 3 * grid.num_nodes();
                let hm = model.evaluate(&x, Some(HessianKind::Exact)).hessian.unwrap().to_dense();
                let mut fd = DMatrix::zeros(n, n);
                for k in 0..n {
                    let gp = flat(&model.evaluate(&shifted(&x, k, h), None).gradient);
                    let gm = flat(&model.evaluate(&shifted(&x, k, -h), None).gradient);
                    for r in 0..n {
                        fd[(r, k)] = (gp[r] - gm[r]) / (2.0 * h);
                    }
                }
                let err = (&hm - &fd).norm() / fd.norm();
                assert!(err < 1e-6, "{name}, gamma {gamma:.3}: Hessian rel. error {err:e}");
            }
        }
    }
}

#[test]
fn convex_hessians_are_positive_semidefinite() {
    let m = TestLaws::default();
    // Compressed fibres (W'' < 0 for e < -k/(2 k3) = -0.067) as well as stretched ones.
    let mut compressed = false;
    for grid in grids() {
        for (gamma, seed) in cases() {
            for (noise, squeeze) in [(0.05, 1.0), (0.15, 0.85)] {
                let x: Vec<Point> =
                    perturbed(&grid, gamma, noise, seed).into_iter().map(|p| Point::from(p.coords * squeeze)).collect();
                compressed |= squeeze < 1.0;
                for (name, model) in all_models(&grid, &m) {
                    let exact = model.evaluate(&x, Some(HessianKind::Exact)).hessian.unwrap().to_dense();
                    let convex = model.evaluate(&x, Some(HessianKind::Convex)).hessian.unwrap().to_dense();
                    let eig = SymmetricEigen::new(convex).eigenvalues;
                    let (lo, hi) = (eig.min(), eig.max());
                    assert!(
                        lo >= -1e-9 * hi.abs().max(1e-300),
                        "{name}, gamma {gamma:.3}: convex eigenvalues [{lo:e}, {hi:e}]"
                    );
                    if name == "bending" {
                        assert_eq!(exact, model.evaluate(&x, Some(HessianKind::Convex)).hessian.unwrap().to_dense());
                    }
                }
            }
        }
    }
    assert!(compressed);
    // The exact Hessian is indefinite somewhere in these cases (so Convex does something).
    let grid = Grid::full(5, 4, D);
    let x = perturbed(&grid, -1.0, 0.15, 9);
    let exact = shear_only(&grid, &m).evaluate(&x, Some(HessianKind::Exact)).hessian.unwrap().to_dense();
    assert!(SymmetricEigen::new(exact).eigenvalues.min() < 0.0);
}

/// The shear angles the energy sees are those of `kinematic::net` (same sign convention).
#[test]
fn shear_angle_matches_the_kinematic_convention() {
    struct Linear;
    impl Laws for Linear {
        fn tension(&self, _: Fibre, _: f64) -> (f64, f64, f64) {
            (0.0, 0.0, 0.0)
        }
        fn shear(&self, g: f64) -> (f64, f64, f64) {
            (g, 1.0, 0.0)
        }
        fn bending(&self, _: Fibre) -> f64 {
            0.0
        }
        fn areal_mass(&self) -> f64 {
            0.0
        }
    }
    let grid = Grid::full(5, 4, D);
    for (gamma, seed) in cases() {
        let x = perturbed(&grid, gamma, 0.05, seed);
        let mut net = DrapeNet::new("t", D, 5, 4, (0, 0));
        net.positions = x.clone();
        net.status = vec![NodeStatus::Placed; 20];
        let expected: f64 =
            (0..4).flat_map(|i| (0..3).map(move |j| (i, j))).map(|(i, j)| net.cell_shear(i, j).unwrap()).sum::<f64>()
                * D
                * D;
        let model = Model::with_terms(grid.clone(), vec![Box::new(Shear::new(&Linear))]);
        let e = model.energy(&x);
        assert!((e - expected).abs() <= 1e-13 * expected.abs().max(D * D), "gamma {gamma}: {e} vs {expected}");
        if gamma != 0.0 {
            assert_eq!(e.signum(), gamma.signum());
        }
    }
}

/// Laws whose first derivatives are dropped and second derivatives clamped at zero, so that the
/// Exact Hessian of a model on them is, term by term, the Convex Hessian of the original laws.
struct Clamped<'a>(&'a TestLaws);
impl Laws for Clamped<'_> {
    fn tension(&self, fibre: Fibre, e: f64) -> (f64, f64, f64) {
        let (w, w1, w2) = self.0.tension(fibre, e);
        (w, w1.max(0.0), w2.max(0.0)) // stretch keeps max(W', 0) hess e (PSD)
    }
    fn shear(&self, g: f64) -> (f64, f64, f64) {
        let (w, _, m1) = self.0.shear(g);
        (w, 0.0, m1.max(0.0))
    }
    fn bending(&self, fibre: Fibre) -> f64 {
        self.0.bending(fibre)
    }
    fn areal_mass(&self) -> f64 {
        self.0.areal_mass()
    }
}

#[test]
fn convex_hessian_is_the_clamped_gauss_newton_part() {
    let m = TestLaws::default();
    let clamped = Clamped(&m);
    for grid in grids() {
        for (gamma, seed) in cases() {
            for squeeze in [1.0, 0.85] {
                let x: Vec<Point> =
                    perturbed(&grid, gamma, 0.1, seed).into_iter().map(|p| Point::from(p.coords * squeeze)).collect();
                let convex = full(&grid, &m).evaluate(&x, Some(HessianKind::Convex)).hessian.unwrap().to_dense();
                let reference = Model::new(grid.clone(), &clamped, Vector::zeros())
                    .evaluate(&x, Some(HessianKind::Exact))
                    .hessian
                    .unwrap()
                    .to_dense();
                let err = (&convex - &reference).norm() / reference.norm();
                assert!(err < 1e-13, "gamma {gamma}: {err:e}");
            }
        }
    }
}
