//! Developable tools (plate, cylinder, cone) drape without shear (REFERENCES.md §1), at any fibre
//! angle: exactly on a plane, and on faceted curved tools to a tolerance that shrinks as d^2.
use drape::geometry::shapes;
use drape::geometry::{Point, ToolSurface, Vector};
use drape::kinematic::{drape, DrapeNet, KinematicSettings, SurfaceKind};
use proptest::prelude::*;

/// Largest |cell shear| of a net (radians) and the number of complete cells.
fn max_shear(net: &DrapeNet) -> (f64, usize) {
    let s = net.shear_stats(1.0);
    (s.max_abs, s.cells)
}

fn warp_at(angle: f64, u: Vector, v: Vector) -> Vector {
    u * angle.cos() + v * angle.sin()
}

/// Rounding-level shear on an exactly flat tool.
const FLAT_TOLERANCE: f64 = 1e-9;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    #[test]
    fn plate_drapes_without_shear_at_any_angle(angle in 0.0f64..std::f64::consts::PI, ox in -0.1f64..0.1, oy in -0.1f64..0.1) {
        let tool = shapes::plate(1.0, 1.0, 13, 17).into_surface().unwrap();
        let warp = warp_at(angle, Vector::x(), Vector::y());
        let s = KinematicSettings::grid("p", Point::new(ox, oy, 0.01), warp, 0.02, 31, 25);
        let net = drape(&tool, &s).unwrap();
        let (g, cells) = max_shear(&net);
        prop_assert_eq!(cells, 30 * 24);
        prop_assert!(g < FLAT_TOLERANCE, "max shear {} rad", g);
    }
}

/// Max shear at spacing d and d/2 over the same patch of the tool (same fibre lengths).
fn shear_at_two_spacings(tool: &ToolSurface, origin: Point, warp: Vector, d: f64, half_len: f64) -> (f64, f64) {
    let run = |d: f64| {
        let n = 2 * (half_len / d).round() as usize + 1;
        let net = drape(tool, &KinematicSettings::grid("c", origin, warp, d, n, n)).unwrap();
        let (g, cells) = max_shear(&net);
        assert_eq!(cells, (n - 1) * (n - 1), "every cell of the patch should be on the tool");
        g
    };
    (run(d), run(d / 2.0))
}

#[test]
fn cylinder_drapes_without_shear_at_any_angle_error_shrinking_as_d_squared() {
    // Radius 0.5 m, half a turn, 720 facets around: a polyhedral developable surface.
    let tool = shapes::cylinder(0.5, 2.0, std::f64::consts::PI, 720, 40).into_surface().unwrap();
    let top = Point::new(0.0, 0.0, 0.5);
    for deg in [0.0f64, 17.0, 30.0, 45.0, 60.0, 90.0, 123.0] {
        // The tangent plane at the top is spanned by x (around) and y (along the axis).
        let warp = warp_at(deg.to_radians(), Vector::y(), Vector::x());
        let (g1, g2) = shear_at_two_spacings(&tool, top, warp, 0.08, 0.48);
        println!(
            "cylinder {deg} deg: max |shear| {:.2e} deg (d = 0.08), {:.2e} deg (d = 0.04)",
            g1.to_degrees(),
            g2.to_degrees()
        );
        // At 0 and 90 degrees the fibres follow generator lines and circles: exact.
        if deg == 0.0 || deg == 90.0 {
            assert!(g1 < 1e-7 && g2 < 1e-7, "{deg}: {g1} {g2}");
        } else {
            assert!(g1 < 0.2f64.to_radians(), "{deg}: {}", g1.to_degrees());
            assert!(g2 < g1 / 3.0, "{deg} deg: halving d must divide the shear by ~4: {g1} -> {g2}");
        }
    }
}

#[test]
fn cone_drapes_without_shear_error_shrinking_as_d_squared() {
    // A frustum (radius 0.6 -> 0.3 over 0.5 m), half a turn, 720 facets around.
    let tool = shapes::cone(0.6, 0.3, 0.5, std::f64::consts::PI, 720, 50).into_surface().unwrap();
    let r_mid = 0.45;
    let seed = Point::new(r_mid, 0.0, 0.25);
    // Tangent plane at the seed: around (+y) and up the slant.
    let slant = Vector::new(-0.3, 0.0, 0.5).normalize();
    for deg in [0.0f64, 30.0, 45.0, 75.0] {
        let warp = warp_at(deg.to_radians(), slant, Vector::y());
        let (g1, g2) = shear_at_two_spacings(&tool, seed, warp, 0.04, 0.16);
        println!(
            "cone {deg} deg: max |shear| {:.2e} deg (d = 0.04), {:.2e} deg (d = 0.02)",
            g1.to_degrees(),
            g2.to_degrees()
        );
        assert!(g1 < 0.2f64.to_radians(), "{deg}: {}", g1.to_degrees());
        assert!(g2 < g1 / 3.0 || g2 < 1e-7, "{deg} deg: {g1} -> {g2}");
    }
}

#[test]
fn smooth_surface_over_a_coarse_cylinder_drapes_without_shear() {
    // Radius 0.5 m, half a turn in 36 facets (5 degrees each): the smooth surface over them
    // stands for the round cylinder, which is developable: the net has next to no shear, and
    // what there is shrinks with d as the fishnet's own error does.
    let tool = shapes::cylinder(0.5, 2.0, std::f64::consts::PI, 36, 20).into_surface().unwrap();
    let top = Point::new(0.0, 0.0, 0.5);
    for deg in [0.0f64, 30.0, 45.0, 60.0, 90.0] {
        let warp = warp_at(deg.to_radians(), Vector::y(), Vector::x());
        let run = |d: f64| {
            let n = 2 * (0.48 / d).round() as usize + 1;
            let s =
                KinematicSettings { surface: SurfaceKind::Smooth, ..KinematicSettings::grid("c", top, warp, d, n, n) };
            let net = drape(&tool, &s).unwrap();
            assert_eq!(net.meta.surface, SurfaceKind::Smooth);
            let (g, cells) = max_shear(&net);
            assert_eq!(cells, (n - 1) * (n - 1), "every cell of the patch should be on the tool");
            g
        };
        let (g1, g2) = (run(0.08), run(0.04));
        println!(
            "smooth cylinder (36 facets a half turn) {deg} deg: max |shear| {:.2e} deg (d = 0.08), {:.2e} deg (d = 0.04)",
            g1.to_degrees(),
            g2.to_degrees()
        );
        assert!(
            g1 < SMOOTH_CYLINDER_SHEAR_DEG.to_radians() && g2 < SMOOTH_CYLINDER_SHEAR_DEG.to_radians(),
            "{deg}: {g1} {g2}"
        );
    }
}

/// Largest shear (degrees) of a net on the smooth surface over the coarse cylinder (3.3e-3
/// measured: the smooth surface over the facets is developable only to its own small error).
const SMOOTH_CYLINDER_SHEAR_DEG: f64 = 0.01;
