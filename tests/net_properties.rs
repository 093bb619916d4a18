//! Invariants of the kinematic net: every fibre segment has length d, symmetric tools give
//! symmetric nets, results do not depend on the thread count, failures are recorded.
// The proptest ranges 0..6.28 and 0..3.14 are bounds on angles, not approximations of pi.
#![allow(clippy::approx_constant)]
use drape::geometry::shapes;
use drape::geometry::{Point, ToolSurface, Vector};
use drape::kinematic::{drape, DrapeNet, GeneratorKind, KinematicSettings, NodeStatus, SurfaceKind};
use proptest::prelude::*;
use std::sync::OnceLock;

/// Relative tolerance on fibre segment lengths (rounding of the circle-triangle intersection).
const LENGTH_TOLERANCE: f64 = 1e-9;

fn hemisphere() -> &'static ToolSurface {
    static TOOL: OnceLock<ToolSurface> = OnceLock::new();
    TOOL.get_or_init(|| shapes::hemisphere_with_triangles(1.0, 20_000).into_surface().unwrap())
}

fn saddle() -> &'static ToolSurface {
    static TOOL: OnceLock<ToolSurface> = OnceLock::new();
    TOOL.get_or_init(|| shapes::saddle(2.0, 1.0, 80).into_surface().unwrap())
}

/// Largest relative deviation of a fibre segment from d, and how many segments were checked.
fn segment_error(net: &DrapeNet) -> (f64, usize) {
    let mut worst = 0.0f64;
    let mut count = 0;
    for i in 0..net.nu {
        for j in 0..net.nv {
            let Some(p) = net.node(i, j) else { continue };
            for q in [
                (i + 1 < net.nu).then(|| net.node(i + 1, j)).flatten(),
                (j + 1 < net.nv).then(|| net.node(i, j + 1)).flatten(),
            ]
            .into_iter()
            .flatten()
            {
                worst = worst.max(((q - p).norm() - net.spacing).abs() / net.spacing);
                count += 1;
            }
        }
    }
    (worst, count)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(16))]
    #[test]
    fn every_fibre_segment_has_length_d_on_a_hemisphere(
        theta in 0.0f64..0.9, phi in 0.0f64..6.28, angle in 0.0f64..3.14, d in 0.02f64..0.08, pre in -20.0f64..20.0
    ) {
        let origin = Point::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
        let warp = Vector::new(angle.cos(), angle.sin(), 0.3);
        let mut s = KinematicSettings::grid("h", origin, warp, d, 41, 37);
        s.pre_shear = pre.to_radians();
        let net = drape(hemisphere(), &s).unwrap();
        let (e, n) = segment_error(&net);
        prop_assert!(n > 200, "only {} segments placed", n);
        prop_assert!(e < LENGTH_TOLERANCE, "segment error {}", e);
        // Every placed node lies on the tool.
        for k in 0..net.positions.len() {
            if net.status[k] == NodeStatus::Placed {
                let sp = hemisphere().closest_point(&net.positions[k]);
                prop_assert!(sp.distance < 1e-12, "node {} is {} off the tool", k, sp.distance);
            }
        }
    }

    #[test]
    fn every_fibre_segment_has_length_d_on_a_saddle(ox in -0.3f64..0.3, oy in -0.3f64..0.3, angle in 0.0f64..3.14) {
        let warp = Vector::new(angle.cos(), angle.sin(), 0.0);
        let net = drape(saddle(), &KinematicSettings::grid("s", Point::new(ox, oy, (ox * ox - oy * oy) / 2.0), warp, 0.03, 41, 41)).unwrap();
        let (e, n) = segment_error(&net);
        prop_assert!(n > 1000);
        prop_assert!(e < LENGTH_TOLERANCE, "segment error {}", e);
    }
}

#[test]
fn mirror_symmetric_tool_gives_a_mirror_symmetric_net() {
    // The hemisphere mesh is symmetric under y -> -y; with the warp along x the weft runs along
    // +y, so node (i0 + a, j0 + b) mirrors node (i0 + a, j0 - b).
    let s = KinematicSettings::grid("h", Point::new(0.0, 0.0, 1.0), Vector::x(), 0.05, 51, 51);
    let net = drape(hemisphere(), &s).unwrap();
    let (_, j0) = net.origin_node;
    let mut checked = 0;
    for i in 0..net.nu {
        for b in 1..=j0 {
            match (net.node(i, j0 + b), net.node(i, j0 - b)) {
                (Some(p), Some(q)) => {
                    let mirrored = Point::new(q.x, -q.y, q.z);
                    assert!((p - mirrored).norm() < 1e-9, "node ({i}, {}) vs mirror: {p} {q}", j0 + b);
                    checked += 1;
                }
                (None, None) => {}
                (p, q) => panic!("node ({i}, {}) placed {} but its mirror {}", j0 + b, p.is_some(), q.is_some()),
            }
        }
    }
    assert!(checked > 500);
    // The saddle is symmetric under x -> -x: node (i0 + a, j) mirrors (i0 - a, j).
    let net =
        drape(saddle(), &KinematicSettings::grid("s", Point::new(0.0, 0.0, 0.0), Vector::x(), 0.04, 41, 41)).unwrap();
    let (i0, _) = net.origin_node;
    for a in 1..=i0 {
        for j in 0..net.nv {
            if let (Some(p), Some(q)) = (net.node(i0 + a, j), net.node(i0 - a, j)) {
                assert!((p - Point::new(-q.x, q.y, q.z)).norm() < 1e-9);
            }
        }
    }
}

#[test]
fn geodesic_generators_follow_great_circles() {
    let tool = shapes::hemisphere_with_triangles(1.0, 200_000).into_surface().unwrap();
    for deg in [0.0f64, 30.0, 45.0] {
        let warp = Vector::new(deg.to_radians().cos(), deg.to_radians().sin(), 0.0);
        let net = drape(&tool, &KinematicSettings::grid("h", Point::new(0.0, 0.0, 1.0), warp, 0.05, 61, 61)).unwrap();
        let (i0, j0) = net.origin_node;
        // The warp generator's plane contains the z axis and the warp direction.
        let plane_normal = Vector::z().cross(&warp).normalize();
        let mut worst = 0.0f64;
        for i in 0..net.nu {
            if let Some(p) = net.node(i, j0) {
                worst = worst.max(p.coords.dot(&plane_normal).abs());
            }
        }
        println!("warp at {deg} deg: largest distance of the warp generator from its great circle {worst:.2e}");
        assert!(net.node(0, j0).is_some() && net.node(net.nu - 1, j0).is_some());
        // Exact along the mesh's symmetry plane; within facet error elsewhere.
        assert!(worst < if deg == 0.0 { 1e-12 } else { 2e-3 }, "{deg}: {worst}");
        // The weft generator is perpendicular at the origin.
        let o = net.node(i0, j0).unwrap();
        let (w, f) = (net.node(i0 + 1, j0).unwrap() - o, net.node(i0, j0 + 1).unwrap() - o);
        assert!(w.angle(&f).to_degrees() - 90.0 < 0.5);
    }
}

/// Drape `s` on the hemisphere with 1, 2 and 3 threads: the same statuses, positions and
/// triangles every time.
fn assert_same_for_any_thread_count(s: &KinematicSettings) {
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| drape(hemisphere(), s).unwrap())
    };
    let one = run(1);
    assert!(one.status.iter().filter(|s| **s == NodeStatus::Placed).count() > 1000, "too few nodes placed to compare");
    for threads in [2, 3] {
        let other = run(threads);
        assert_eq!(one.status, other.status, "{threads} threads: statuses differ");
        assert!(one.positions.iter().zip(&other.positions).all(|(a, b)| a == b), "{threads} threads differ");
        assert_eq!(one.triangles, other.triangles, "{threads} threads: triangles differ");
    }
}

/// 601 x 601 nodes off the pole, so long anti-diagonals are filled in parallel too.
fn thread_count_settings(surface: SurfaceKind) -> KinematicSettings {
    KinematicSettings {
        surface,
        ..KinematicSettings::grid(
            "h",
            Point::from(Vector::new(0.1, 0.2, 1.0).normalize()),
            Vector::new(1.0, 0.4, 0.0),
            0.004,
            601,
            601,
        )
    }
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    assert_same_for_any_thread_count(&thread_count_settings(SurfaceKind::Facets));
}

#[test]
fn each_quadrant_depends_only_on_its_generators() {
    // The quadrants fill their own part of one net in place: a net with the origin node in a
    // corner is exactly the matching quadrant of a centred net (the same generators), with 1
    // and 3 threads.
    let settings = |n: usize, origin_node: (usize, usize)| {
        let mut s = KinematicSettings::grid("h", Point::new(0.05, -0.1, 1.0), Vector::new(1.0, 0.3, 0.0), 0.01, n, n);
        s.extent = drape::kinematic::Extent::Grid { nu: n, nv: n, origin_node: Some(origin_node) };
        s
    };
    for threads in [1, 3] {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        let whole = pool.install(|| drape(hemisphere(), &settings(81, (40, 40))).unwrap());
        for (corner, (di, dj)) in [((0, 0), (40, 40)), ((40, 0), (0, 40)), ((40, 40), (0, 0)), ((0, 40), (40, 0))] {
            let part = pool.install(|| drape(hemisphere(), &settings(41, corner)).unwrap());
            for i in 0..41 {
                for j in 0..41 {
                    let (k, kw) = (part.index(i, j), whole.index(i + di, j + dj));
                    assert_eq!(part.status[k], whole.status[kw], "corner {corner:?}, node ({i}, {j})");
                    if part.status[k] == NodeStatus::Placed {
                        assert_eq!(part.positions[k], whole.positions[kw], "corner {corner:?}, node ({i}, {j})");
                        assert_eq!(part.triangles[k], whole.triangles[kw], "corner {corner:?}, node ({i}, {j})");
                    }
                }
            }
        }
        // Most of the net is on the tool, so the comparison says something.
        assert!(whole.status.iter().filter(|s| **s == NodeStatus::Placed).count() > 81 * 81 / 2);
    }
}

#[test]
fn failures_are_recorded_and_the_rest_of_the_net_goes_on() {
    // A net far larger than the hemisphere: generators run off the rim, cells beyond fail.
    let s = KinematicSettings::grid("h", Point::new(0.0, 0.0, 1.0), Vector::x(), 0.05, 81, 81);
    let net = drape(hemisphere(), &s).unwrap();
    let counts: std::collections::HashMap<NodeStatus, usize> = net.status_counts().into_iter().collect();
    assert_eq!(counts.values().sum::<usize>(), 81 * 81);
    assert!(counts[&NodeStatus::OffTool] > 0, "{counts:?}");
    assert!(!counts.contains_key(&NodeStatus::Pending));
    assert!(counts[&NodeStatus::Placed] > 1000);
    // Generators: a quarter circle is pi/2 = 31.4 spacings; the node past the rim is off the tool.
    let (i0, j0) = net.origin_node;
    assert_eq!(net.status[net.index(i0 + 31, j0)], NodeStatus::Placed);
    assert_eq!(net.status[net.index(i0 + 32, j0)], NodeStatus::OffTool);
    // A tight shear limit stops the net where it shears too far.
    let mut tight = s.clone();
    tight.max_shear = 30f64.to_radians();
    let net = drape(hemisphere(), &tight).unwrap();
    assert!(net.status.contains(&NodeStatus::ShearLimit));
    assert!(net.shear_stats(1.0).max_abs.to_degrees() < 32.0);
}

#[test]
fn vertical_walls_and_fillets_of_a_box_tool_are_draped() {
    let tool = shapes::hat_box(&shapes::HatBox::standard(), 0.004, 6).into_surface().unwrap();
    let top = tool.vertices().iter().map(|p| p.z).fold(f64::MIN, f64::max);
    let s = KinematicSettings::grid("box", Point::new(0.0, 0.0, top), Vector::x(), 0.005, 61, 61);
    let net = drape(&tool, &s).unwrap();
    let (e, _) = segment_error(&net);
    assert!(e < LENGTH_TOLERANCE);
    // Some nodes sit on the vertical walls (wall normals are horizontal).
    let on_walls = (0..net.positions.len())
        .filter(|&k| net.status[k] == NodeStatus::Placed && tool.normal(net.triangles[k]).z.abs() < 1e-9)
        .count();
    println!("nodes on vertical walls: {on_walls}");
    assert!(on_walls > 20, "{on_walls}");
}

#[test]
fn min_shear_generators_shear_the_strip_cells_less_than_geodesics() {
    let tool = saddle();
    let base = KinematicSettings::grid("s", Point::new(0.1, 0.05, 0.0), Vector::new(1.0, 0.5, 0.0), 0.04, 31, 31);
    let geo = drape(tool, &base).unwrap();
    let mut ms = base.clone();
    ms.generators = GeneratorKind::MinShear;
    let min = drape(tool, &ms).unwrap();
    // Cells along the generators (the strips beside them).
    let strip = |net: &DrapeNet| {
        let (i0, j0) = net.origin_node;
        let mut sum = 0.0;
        for i in 0..net.nu - 1 {
            for j in [j0 - 1, j0] {
                sum += net.cell_shear(i, j).unwrap().powi(2);
            }
        }
        for j in 0..net.nv - 1 {
            for i in [i0 - 1, i0] {
                sum += net.cell_shear(i, j).unwrap().powi(2);
            }
        }
        sum
    };
    let (g, m) = (strip(&geo), strip(&min));
    println!("sum of squared strip shear: geodesic {g:.3e}, min-shear {m:.3e}");
    // Shears beside a generator are nearly antisymmetric, so turning it helps one side about as
    // much as it hurts the other: the gain is modest, but it must be a gain.
    assert!(m < g, "{m} vs {g}");
    let (e, _) = segment_error(&min);
    assert!(e < LENGTH_TOLERANCE);
}

#[test]
fn steered_warp_follows_the_curve() {
    // On the cylinder (axis y), a curve around the circumference at y = 0.1: a steered warp.
    let tool = shapes::cylinder(0.5, 2.0, std::f64::consts::PI, 360, 40).into_surface().unwrap();
    let curve: Vec<Point> = (0..=60)
        .map(|k| {
            let a = -1.2 + 2.4 * k as f64 / 60.0;
            Point::new(0.5 * a.sin(), 0.1 + 0.05 * a, 0.5 * a.cos())
        })
        .collect();
    let mut s = KinematicSettings::grid("c", Point::new(0.0, 0.1, 0.5), Vector::x(), 0.02, 41, 21);
    s.generators = GeneratorKind::Steer(curve.clone());
    let net = drape(&tool, &s).unwrap();
    let (_, j0) = net.origin_node;
    for i in 0..net.nu {
        let p = net.node(i, j0).unwrap();
        // The curve is y = 0.1 + 0.05 a with a the angle around: nodes stay on it.
        let a = p.x.atan2(p.z);
        assert!((p.y - (0.1 + 0.05 * a)).abs() < 1e-3, "node {i}: {p}");
    }
    let (e, _) = segment_error(&net);
    assert!(e < LENGTH_TOLERANCE);
}

#[test]
fn an_outline_sizes_the_grid_and_drops_the_nodes_outside_it() {
    use drape::kinematic::Extent;
    let tool = shapes::plate(1.0, 1.0, 10, 10).into_surface().unwrap();
    let r = 0.3;
    let outline: Vec<Point> = (0..96)
        .map(|k| {
            let a = std::f64::consts::TAU * k as f64 / 96.0;
            Point::new(r * a.cos(), r * a.sin(), 0.0)
        })
        .collect();
    let d = 0.01;
    let mut s = KinematicSettings::grid("o", Point::new(0.05, -0.02, 0.0), Vector::new(1.0, 1.0, 0.0), d, 2, 2);
    s.extent = Extent::Outline(outline);
    let net = drape(&tool, &s).unwrap();
    let placed: Vec<Point> =
        (0..net.positions.len()).filter(|&k| net.status[k] == NodeStatus::Placed).map(|k| net.positions[k]).collect();
    // Inside the 96-gon (inscribed in the circle of radius r).
    assert!(placed.iter().all(|p| p.x.hypot(p.y) < r));
    // One node per d^2 of the polygon's area (to within its perimeter's worth of nodes).
    let area = 0.5 * 96.0 * r * r * (std::f64::consts::TAU / 96.0).sin();
    let expected = area / (d * d);
    let perimeter_nodes = std::f64::consts::TAU * r / d;
    assert!((placed.len() as f64 - expected).abs() < perimeter_nodes, "{} vs {expected}", placed.len());
    // Everything not placed is outside the outline: the net covers the whole ply.
    let counts = net.status_counts();
    assert!(counts.iter().all(|(s, _)| matches!(s, NodeStatus::Placed | NodeStatus::OutsideOutline)), "{counts:?}");
}

#[test]
fn a_closed_sphere_is_draped_past_its_equator_into_the_undercut() {
    // Close the hemisphere with its mirror image (rim vertices are welded by the mesh checks).
    let top = shapes::hemisphere(1.0, 40);
    let mut vertices = top.vertices.clone();
    let n = vertices.len() as u32;
    vertices.extend(top.vertices.iter().map(|p| Point::new(p.x, p.y, -p.z)));
    let mut triangles = top.triangles.clone();
    triangles.extend(top.triangles.iter().map(|t| [t[0] + n, t[2] + n, t[1] + n]));
    let tool = ToolSurface::from_triangles(vertices, triangles).unwrap();
    assert_eq!(tool.report().boundary_edges, 0, "{:?}", tool.report());
    assert_eq!(tool.report().flipped_faces, 0);
    // Generators of 40 x 0.05 = 2.0 > pi/2: past the equator on every side.
    let net =
        drape(&tool, &KinematicSettings::grid("ball", Point::new(0.0, 0.0, 1.0), Vector::x(), 0.05, 81, 81)).unwrap();
    let below =
        (0..net.positions.len()).filter(|&k| net.status[k] == NodeStatus::Placed && net.positions[k].z < -0.3).count();
    assert!(below > 8, "{below} nodes below the equator");
    let (e, _) = segment_error(&net);
    assert!(e < LENGTH_TOLERANCE);
}

/// Nodes on the smooth surface satisfy its implicit equation to this (m, on a unit hemisphere).
const ON_SMOOTH_TOLERANCE: f64 = 1e-12;

#[test]
fn on_the_smooth_surface_segments_have_length_d_and_nodes_lie_on_it_for_every_generator() {
    let tool = hemisphere();
    let smooth = drape::geometry::SmoothSurface::new(tool);
    let origin = Point::from(Vector::new(0.1, 0.2, 1.0).normalize());
    // A steering curve through the seed: a small circle tilted off the great circle along x.
    let curve: Vec<Point> = (0..=80)
        .map(|k| {
            let a = -1.0 + 2.0 * k as f64 / 80.0;
            let p = Vector::new(a.sin(), 0.05 * a, a.cos()).normalize();
            Point::from(nalgebra::Rotation3::rotation_between(&Vector::z(), &origin.coords).unwrap() * p)
        })
        .collect();
    for generators in [GeneratorKind::Geodesic, GeneratorKind::MinShear, GeneratorKind::Steer(curve)] {
        let mut s = KinematicSettings::grid("h", origin, Vector::new(1.0, 0.4, 0.0), 0.05, 31, 31);
        s.surface = SurfaceKind::Smooth;
        s.generators = generators.clone();
        let net = drape(tool, &s).unwrap();
        assert_eq!(net.meta.surface, SurfaceKind::Smooth);
        assert!(!net.status.contains(&NodeStatus::Pending));
        let (e, n) = segment_error(&net);
        assert!(n > 1500, "{generators:?}: only {n} segments");
        assert!(e < LENGTH_TOLERANCE, "{generators:?}: segment error {e}");
        for k in 0..net.positions.len() {
            if net.status[k] == NodeStatus::Placed {
                let p = net.positions[k];
                let (f, _) = smooth.value_and_gradient(smooth.region_of(net.triangles[k]), &p).unwrap();
                assert!(f.abs() < ON_SMOOTH_TOLERANCE, "{generators:?}: node {k} is {f:e} off the smooth surface");
                // Its facet is the one under it.
                let l = tool.barycentric(net.triangles[k], &p);
                assert!(l.iter().all(|&x| x > -1e-9), "{generators:?}: node {k} not over its facet: {l:?}");
            }
        }
    }
}

#[test]
fn on_the_smooth_surface_results_do_not_depend_on_the_thread_count() {
    assert_same_for_any_thread_count(&thread_count_settings(SurfaceKind::Smooth));
}
