//! The energy model as the solver's [`Objective`]: internal energy (every term but the loads)
//! with its Convex Hessian, external loads P from the load terms (gravity).
use super::{HessianKind, Model};
use crate::geometry::{Point, Vector};
use crate::mechanics::solver::{Evaluation, HessianBlocks, Objective};
use crate::mechanics::sparse::SymmetricMatrix;
use nalgebra::Matrix3;

impl HessianBlocks for SymmetricMatrix {
    fn block(&self, a: usize, b: usize) -> Matrix3<f64> {
        self.block(a, b)
    }
}

impl Objective for Model<'_> {
    fn evaluate(&self, x: &[Point], hessian: bool) -> Evaluation {
        let n = self.grid.num_nodes();
        assert_eq!(x.len(), n, "one position per node");
        let mut internal = vec![Vector::zeros(); n];
        let mut h = hessian.then(|| SymmetricMatrix::zeros(self.pattern().clone()));
        let values = h.as_mut().map(|h| &mut h.values[..]);
        let want = hessian.then_some(HessianKind::Convex);
        let e_int: f64 = self.run(&|t| !t.is_load(), x, Some(&mut internal), values, want).iter().sum();
        let mut load_grad = vec![Vector::zeros(); n];
        let e_load: f64 = self.run(&|t| t.is_load(), x, Some(&mut load_grad), None, None).iter().sum();
        let external = load_grad.into_iter().map(|g| -g).collect();
        Evaluation { energy: e_int + e_load, internal, external, hessian: h.map(|h| Box::new(h) as Box<dyn HessianBlocks>) }
    }

    fn coupled_pairs(&self) -> Vec<(usize, usize)> {
        self.pattern().coupled_pairs()
    }
}
