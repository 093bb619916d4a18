//! Shared helpers of the energy tests: analytic material laws and perturbed grids.
#![allow(dead_code)]
use drape::geometry::{Point, Vector};
use drape::material::Fibre;
use drape::mechanics::energy::{Bending, EnergyTerm, Gravity, Grid, Laws, Model, Shear, Stretch};

/// Nonlinear analytic laws: tension `k e^2/2 + k3 e^3/3` (W'' < 0 for e < -k/(2 k3)), shear
/// `G (g^2/2 + 1.5 g^3/3 + 0.3 g^4/4)` (M' < 0 around g = -0.6, M < 0 for g < 0).
#[derive(Debug, Clone)]
pub struct TestLaws {
    pub k: [f64; 2],
    pub k3: [f64; 2],
    pub g: f64,
    pub d: [f64; 2],
    pub rho: f64,
}

impl Default for TestLaws {
    fn default() -> Self {
        TestLaws { k: [800.0, 500.0], k3: [6000.0, 4000.0], g: 2.0, d: [3e-4, 2e-4], rho: 0.4 }
    }
}

fn f(fibre: Fibre) -> usize {
    match fibre {
        Fibre::Warp => 0,
        Fibre::Weft => 1,
    }
}

impl Laws for TestLaws {
    fn tension(&self, fibre: Fibre, e: f64) -> (f64, f64, f64) {
        let (k, k3) = (self.k[f(fibre)], self.k3[f(fibre)]);
        (0.5 * k * e * e + k3 * e * e * e / 3.0, k * e + k3 * e * e, k + 2.0 * k3 * e)
    }
    fn shear(&self, g: f64) -> (f64, f64, f64) {
        let (a, b) = (1.5, 0.3);
        let w = self.g * (g * g / 2.0 + a * g * g * g / 3.0 + b * g.powi(4) / 4.0);
        let m = self.g * (g + a * g * g + b * g * g * g);
        let m1 = self.g * (1.0 + 2.0 * a * g + 3.0 * b * g * g);
        (w, m, m1)
    }
    fn bending(&self, fibre: Fibre) -> f64 {
        self.d[f(fibre)]
    }
    fn areal_mass(&self) -> f64 {
        self.rho
    }
}

/// Tiny deterministic generator (xorshift64*), uniform in [-1, 1).
pub struct Rng(pub u64);
impl Rng {
    pub fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let r = self.0.wrapping_mul(0x2545F4914F6CDD1D);
        (r >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
    pub fn vector(&mut self) -> Vector {
        Vector::new(self.next(), self.next(), self.next())
    }
}

/// A planar grid sheared uniformly by `gamma` (warp along x, weft at pi/2 - gamma from it),
/// scaled by `stretch` along (warp, weft).
pub fn sheared(grid: &Grid, gamma: f64, stretch: (f64, f64)) -> Vec<Point> {
    let d = grid.spacing;
    let warp = Vector::x() * (d * stretch.0);
    let weft = Vector::new(gamma.sin(), gamma.cos(), 0.0) * (d * stretch.1);
    (0..grid.num_nodes()).map(|k| Point::from(warp * (k / grid.nv) as f64 + weft * (k % grid.nv) as f64)).collect()
}

/// A sheared grid, gently curved out of plane and randomly perturbed by `noise * d`.
pub fn perturbed(grid: &Grid, gamma: f64, noise: f64, seed: u64) -> Vec<Point> {
    let d = grid.spacing;
    let mut rng = Rng(seed.wrapping_mul(0x9E3779B97F4A7C15) | 1);
    sheared(grid, gamma, (1.01, 0.99))
        .into_iter()
        .map(|p| {
            let bump = 0.3 * d * ((p.x / d).sin() * (0.7 * p.y / d).cos());
            p + Vector::z() * bump + rng.vector() * (noise * d)
        })
        .collect()
}

pub fn stretch_only<'a>(grid: &Grid, m: &'a TestLaws) -> Model<'a> {
    Model::with_terms(grid.clone(), vec![Box::new(Stretch::new(m))])
}
pub fn shear_only<'a>(grid: &Grid, m: &'a TestLaws) -> Model<'a> {
    Model::with_terms(grid.clone(), vec![Box::new(Shear::new(m))])
}
pub fn bending_only<'a>(grid: &Grid, m: &'a TestLaws) -> Model<'a> {
    Model::with_terms(grid.clone(), vec![Box::new(Bending::new(m))])
}
pub fn gravity_only<'a>(grid: &Grid, m: &'a TestLaws, g: Vector) -> Model<'a> {
    Model::with_terms(grid.clone(), vec![Box::new(Gravity::new(grid, m.rho, g))])
}
/// Every term but gravity.
pub fn internal<'a>(grid: &Grid, m: &'a TestLaws) -> Model<'a> {
    let terms: Vec<Box<dyn EnergyTerm + 'a>> =
        vec![Box::new(Stretch::new(m)), Box::new(Shear::new(m)), Box::new(Bending::new(m))];
    Model::with_terms(grid.clone(), terms)
}
/// Every term, with gravity.
pub fn full<'a>(grid: &Grid, m: &'a TestLaws) -> Model<'a> {
    Model::new(grid.clone(), m, Vector::new(0.3, -1.0, -9.81))
}
/// All the models above, named.
pub fn all_models<'a>(grid: &Grid, m: &'a TestLaws) -> Vec<(&'static str, Model<'a>)> {
    vec![
        ("stretch", stretch_only(grid, m)),
        ("shear", shear_only(grid, m)),
        ("bending", bending_only(grid, m)),
        ("gravity", gravity_only(grid, m, Vector::new(0.3, -1.0, -9.81))),
        ("total", full(grid, m)),
    ]
}
