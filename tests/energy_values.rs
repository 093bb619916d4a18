//! Energy terms: known values (reference state, uniform shear and stretch, a cylinder, gravity)
//! and invariance under rigid motions.
use crate::energy_common;
use drape::geometry::{Point, Vector};
use drape::material::Fibre;
use drape::mechanics::energy::{Grid, HessianKind, Laws};
use energy_common::*;
use nalgebra::{Rotation3, Unit};
use proptest::prelude::*;

const D: f64 = 0.005;

#[test]
fn reference_state_has_zero_energy_and_gradient() {
    let m = TestLaws::default();
    let grid = Grid::full(7, 9, D);
    let x = grid.flat_positions();
    // (Zero up to the rounding of the positions i d, j d.)
    let ev = internal(&grid, &m).evaluate(&x, Some(HessianKind::Exact));
    assert!(ev.energy.abs() < 1e-25, "{}", ev.energy);
    assert!(ev.gradient.iter().all(|g| g.norm() < 1e-12));
    assert_eq!(ev.terms.iter().map(|t| t.0).collect::<Vec<_>>(), ["stretch", "shear", "bending"]);
    // Rigidly moved, it stays (numerically) unstressed.
    let rot = Rotation3::from_axis_angle(&Unit::new_normalize(Vector::new(1.0, 2.0, -0.5)), 0.7);
    let y: Vec<Point> = x.iter().map(|p| rot * p + Vector::new(1.0, -2.0, 3.0)).collect();
    let ev = internal(&grid, &m).evaluate(&y, None);
    assert!(ev.energy.abs() < 1e-20, "{}", ev.energy);
    assert!(ev.gradient.iter().all(|g| g.norm() < 1e-10));
}

#[test]
fn uniform_shear_energy_is_cells_times_area_times_w() {
    let m = TestLaws::default();
    let (nu, nv) = (6, 5);
    let grid = Grid::full(nu, nv, D);
    for deg in [-60.0f64, -30.0, -5.0, 5.0, 30.0, 60.0] {
        let gamma = deg.to_radians();
        let x = sheared(&grid, gamma, (1.0, 1.0));
        let ev = full(&grid, &m).evaluate(&x, None);
        let expected = ((nu - 1) * (nv - 1)) as f64 * D * D * m.shear(gamma).0;
        let shear = ev.terms.iter().find(|t| t.0 == "shear").unwrap().1;
        assert!((shear - expected).abs() <= 1e-12 * expected.abs(), "{deg} deg: {shear} vs {expected}");
        // Fibres keep their length and stay straight.
        for t in &ev.terms {
            if t.0 == "stretch" || t.0 == "bending" {
                assert!(t.1.abs() <= 1e-12 * expected.abs(), "{deg} deg: {} = {}", t.0, t.1);
            }
        }
    }
}

#[test]
fn uniform_stretch_energy() {
    let m = TestLaws::default();
    let (nu, nv) = (6, 5);
    let grid = Grid::full(nu, nv, D);
    for (lu, lv) in [(1.02, 1.0), (1.0, 0.97), (1.05, 1.01), (0.9, 1.1)] {
        let x = sheared(&grid, 0.0, (lu, lv));
        let (eu, ev_) = ((lu * lu - 1.0) / 2.0, (lv * lv - 1.0) / 2.0);
        // Edge fibres carry half the width: both families add up to the fabric's area.
        let area_cells = ((nu - 1) * (nv - 1)) as f64;
        let expected = D * D * area_cells * (m.tension(Fibre::Warp, eu).0 + m.tension(Fibre::Weft, ev_).0);
        let e = stretch_only(&grid, &m).energy(&x);
        assert!((e - expected).abs() <= 1e-12 * expected.abs(), "({lu}, {lv}): {e} vs {expected}");
        assert!(shear_only(&grid, &m).energy(&x).abs() < 1e-12 * expected);
        assert!(bending_only(&grid, &m).energy(&x).abs() < 1e-12 * expected);
    }
}

#[test]
fn cylinder_bending_energy_is_half_d_kappa_squared_times_area() {
    let m = TestLaws::default();
    let (nu, nv) = (40, 6);
    let grid = Grid::full(nu, nv, D);
    for r in [0.05, 0.2, 1.0] {
        // Warp around the cylinder (axis along y), weft along its axis; arc length d per segment.
        let x: Vec<Point> = (0..grid.num_nodes())
            .map(|k| {
                let (i, j) = (k / nv, k % nv);
                let phi = i as f64 * D / r;
                Point::new(r * phi.sin(), j as f64 * D, r * (1.0 - phi.cos()))
            })
            .collect();
        let e = bending_only(&grid, &m).energy(&x);
        // Each warp triple's zone is d long (l/2 = d) and d wide (d/2 on the fabric's edges).
        let area = ((nu - 2) * (nv - 1)) as f64 * D * D;
        let continuum = 0.5 * m.bending(Fibre::Warp) / (r * r) * area;
        let rel = (e - continuum).abs() / continuum;
        assert!(rel <= (D / r).powi(2), "R = {r}: {e} vs {continuum} (rel {rel:e})");
        // The discrete value exactly: w = R (1 - cos(d/R)) per triple.
        let w = r * (1.0 - (D / r).cos());
        let exact = ((nu - 2) * (nv - 1)) as f64 * 2.0 * m.bending(Fibre::Warp) * w * w / (D * D);
        assert!((e - exact).abs() <= 1e-10 * exact, "R = {r}: {e} vs {exact}");
    }
}

#[test]
fn gravity_energy_and_nodal_masses() {
    let m = TestLaws::default();
    let (nu, nv) = (5, 4);
    let g = Vector::new(0.0, 0.0, -9.81);
    let grid = Grid::full(nu, nv, D);
    let areas = grid.nodal_areas();
    assert_eq!(areas[0], D * D / 4.0);
    assert_eq!(areas[1], D * D / 2.0);
    assert_eq!(areas[nv + 1], D * D);
    let total: f64 = areas.iter().sum();
    assert!((total - ((nu - 1) * (nv - 1)) as f64 * D * D).abs() < 1e-15);
    // Lifting the whole flat grid by h costs (mass) g h.
    let h = 0.3;
    let x: Vec<Point> = grid.flat_positions().into_iter().map(|p| p + Vector::z() * h).collect();
    let e = gravity_only(&grid, &m, g).energy(&x);
    let expected = m.rho * total * 9.81 * h;
    assert!((e - expected).abs() < 1e-12 * expected, "{e} vs {expected}");
    // A missing node removes its cells from the mass.
    let mut active = vec![true; nu * nv];
    active[nv + 1] = false;
    let holed = Grid::with_active(nu, nv, D, active);
    let a: f64 = holed.nodal_areas().iter().sum();
    assert!((a - (total - 4.0 * D * D)).abs() < 1e-15);
    let ev = gravity_only(&holed, &m, g).evaluate(&x, None);
    assert_eq!(ev.gradient[nv + 1], Vector::zeros());
    assert_eq!(ev.gradient[0], Vector::zeros(), "node 0 has no complete cell left");
    let last = nu * nv - 1;
    assert!((ev.gradient[last] - Vector::new(0.0, 0.0, m.rho * D * D / 4.0 * 9.81)).norm() < 1e-15);
}

fn rigid(x: &[Point], axis: Vector, angle: f64, t: Vector) -> Vec<Point> {
    let rot = Rotation3::from_axis_angle(&Unit::new_normalize(axis), angle);
    x.iter().map(|p| rot * p + t).collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn energy_is_frame_invariant(
        ax in -1.0f64..1.0, ay in -1.0f64..1.0, az in 0.1f64..1.0, angle in -3.1f64..3.1,
        tx in -1.0f64..1.0, ty in -1.0f64..1.0, tz in -1.0f64..1.0,
        gamma in -1.0f64..1.0, seed in 0u64..1000,
    ) {
        let m = TestLaws::default();
        let grid = Grid::full(6, 5, D);
        let x = perturbed(&grid, gamma, 0.05, seed);
        let y = rigid(&x, Vector::new(ax, ay, az), angle, Vector::new(tx, ty, tz));
        for (name, model) in all_models(&grid, &m) {
            if name == "gravity" || name == "total" {
                continue;
            }
            let (ex, ey) = (model.energy(&x), model.energy(&y));
            prop_assert!((ex - ey).abs() <= 1e-12 * ex.abs(), "{}: {} vs {}", name, ex, ey);
        }
        let model = internal(&grid, &m);
        let (ex, ey) = (model.energy(&x), model.energy(&y));
        prop_assert!((ex - ey).abs() <= 1e-12 * ex.abs(), "internal: {} vs {}", ex, ey);
    }
}

#[test]
fn fast_atan2_is_accurate() {
    use drape::mechanics::energy::atan2_right;
    let mut rng = Rng(3);
    let mut worst: f64 = 0.0;
    for k in 0..200_000 {
        let x = if k % 1000 == 0 { 0.0 } else { (rng.next() + 1.0) * 10f64.powf(3.0 * rng.next()) };
        let y = rng.next() * 10f64.powf(3.0 * rng.next());
        let (a, b) = (atan2_right(y, x), y.atan2(x));
        worst = worst.max((a - b).abs() / b.abs().max(1e-300));
    }
    assert!(worst < 4.0 * f64::EPSILON, "{worst:e}");
    assert_eq!(atan2_right(0.0, 1.0), 0.0);
    assert_eq!(atan2_right(1.0, 0.0), std::f64::consts::FRAC_PI_2);
    assert_eq!(atan2_right(-1.0, 0.0), -std::f64::consts::FRAC_PI_2);
    assert_eq!(atan2_right(1.0, 1.0), std::f64::consts::FRAC_PI_4);
}

/// The model runs on a real material card (the `Laws` of `MaterialCard`).
#[test]
fn model_on_a_material_card() {
    use drape::material::MaterialCard;
    use drape::mechanics::energy::Model;
    let card = MaterialCard::parse(
        r#"
name = "test"
areal_mass = 0.6
thickness = 5e-4
[tension]
law = "linear"
warp = 8.0e6
weft = 6.0e6
[shear]
law = "two-slope"
g1 = 5.0
g2 = 200.0
locking_angle_deg = 30.0
[bending]
warp = 2.0e-4
weft = 1.0e-4
"#,
        "inline",
    )
    .expect("card");
    let (nu, nv) = (5, 6);
    let grid = Grid::full(nu, nv, D);
    let gamma = 40f64.to_radians();
    let x = sheared(&grid, gamma, (1.0, 1.0));
    let model = Model::new(grid.clone(), &card, Vector::new(0.0, 0.0, -9.81));
    let ev = model.evaluate(&x, Some(HessianKind::Convex));
    let shear = ev.terms.iter().find(|t| t.0 == "shear").unwrap().1;
    let expected = ((nu - 1) * (nv - 1)) as f64 * D * D * card.shear(gamma).0;
    assert!(expected > 0.0 && (shear - expected).abs() <= 1e-12 * expected, "{shear} vs {expected}");
    let gravity = ev.terms.iter().find(|t| t.0 == "gravity").unwrap().1;
    assert!(gravity.abs() < 1e-15, "flat at z = 0: {gravity}");
}
