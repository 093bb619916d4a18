//! Cost of one evaluation of the energy model (stretch, shear, bending, gravity) on n x n grids:
//! energy only, with gradient, and with the Convex / Exact sparse Hessian.
//! Run: `cargo bench --bench energy`.
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use drape::geometry::{Point, Vector};
use drape::material::Fibre;
use drape::mechanics::energy::{Evaluation, Grid, HessianKind, Laws, Model};

/// Analytic laws of the size of a glass woven (stiff fibres, soft shear with a cubic rise).
struct Fabric;
impl Laws for Fabric {
    fn tension(&self, _: Fibre, e: f64) -> (f64, f64, f64) {
        let k = 1e5;
        (0.5 * k * e * e, k * e, k)
    }
    fn shear(&self, g: f64) -> (f64, f64, f64) {
        let (g1, g3) = (1.0, 30.0);
        (g1 * g * g / 2.0 + g3 * g.powi(4) / 4.0, g1 * g + g3 * g.powi(3), g1 + 3.0 * g3 * g * g)
    }
    fn bending(&self, _: Fibre) -> f64 {
        1e-4
    }
    fn areal_mass(&self) -> f64 {
        0.6
    }
}

/// An n x n grid of spacing 5 mm laid on a sphere-like cap with some shear.
fn positions(grid: &Grid) -> Vec<Point> {
    let d = grid.spacing;
    (0..grid.num_nodes())
        .map(|k| {
            let (i, j) = ((k / grid.nv) as f64 * d, (k % grid.nv) as f64 * d);
            Point::new(i + 0.1 * j, j, 0.3 * (i * i + j * j))
        })
        .collect()
}

fn energy(c: &mut Criterion) {
    let mut group = c.benchmark_group("energy");
    group.sample_size(20);
    for n in [101usize, 301] {
        let grid = Grid::full(n, n, 0.005);
        let x = positions(&grid);
        let model = Model::new(grid, &Fabric, Vector::new(0.0, 0.0, -9.81));
        group.throughput(Throughput::Elements((n * n) as u64));
        group.bench_with_input(BenchmarkId::new("energy_only", n), &x, |b, x| b.iter(|| model.energy(x)));
        let mut out = model.evaluate(&x, None);
        group.bench_with_input(BenchmarkId::new("gradient", n), &x, |b, x| {
            b.iter(|| model.evaluate_into(x, None, &mut out))
        });
        for (name, kind) in [("hessian_convex", HessianKind::Convex), ("hessian_exact", HessianKind::Exact)] {
            let mut out: Evaluation = model.evaluate(&x, Some(kind));
            group.bench_with_input(BenchmarkId::new(name, n), &x, |b, x| {
                b.iter(|| model.evaluate_into(x, Some(kind), &mut out))
            });
            group.bench_with_input(BenchmarkId::new(format!("{name}_fresh"), n), &x, |b, x| {
                b.iter(|| model.evaluate(x, Some(kind)))
            });
        }
    }
    group.finish();
}

criterion_group!(benches, energy);
criterion_main!(benches);
