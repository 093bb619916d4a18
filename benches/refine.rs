//! Mechanical refinement: a hemisphere net (pressed, stiff fibres, nonlinear shear: the carbon
//! twill card) on the 200k- and 2k-triangle hemispheres, nets from the pole to the rim; and whole plies of
//! the bundled scenes (kinematic drape, then refinement): the double dome's first ply pressed
//! (101 x 81 at 5 mm) and seed 000's square table from a flat sheet (41 x 41 at 5 mm).
//! Run: `cargo bench --bench refine`. `drape bench --refine CARD` prints iterations per run.
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use drape::geometry::shapes;
use drape::geometry::{Point, Vector};
use drape::kinematic::{drape, KinematicSettings};
use drape::material::MaterialCard;
use drape::mechanics::refine::{refine_draped, RefineSettings};
use std::f64::consts::FRAC_PI_2;

fn pressed_hemisphere(c: &mut Criterion) {
    let card =
        MaterialCard::load(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("materials/carbon-twill.toml"))
            .unwrap();
    // The nets of 101 and 201 nodes on the 200k-triangle hemisphere; issue 10's 301 x 301 net on
    // the 2k-triangle one (`drape bench --triangles 2000 --nodes 301 --refine ...`).
    for (triangles, nodes) in [(200_000, 101usize), (200_000, 201), (2_000, 301)] {
        let tool = shapes::hemisphere_with_triangles(1.0, triangles).into_surface().unwrap();
        let mut group = c.benchmark_group(format!("refine_pressed_hemisphere_{}k", triangles / 1000));
        group.sample_size(10);
        let half = (nodes - 1) / 2;
        let spacing = FRAC_PI_2 / half as f64 * 0.999;
        let settings = KinematicSettings::grid("b", Point::new(0.0, 0.0, 1.0), Vector::x(), spacing, nodes, nodes);
        let net = drape(&tool, &settings).unwrap();
        // As a scene's ply: the refinement starts from the ply draped on the smooth surface, with
        // the card's friction.
        let pressed = RefineSettings { friction: card.friction.unwrap_or(0.0), ..RefineSettings::default() };
        group.bench_with_input(BenchmarkId::from_parameter(nodes), &net, |b, net| {
            b.iter(|| refine_draped(net, &settings, &tool, None, &card, &pressed).unwrap())
        });
        group.finish();
    }
}

/// The first ply of a bundled scene, draped and refined.
fn scene_ply(c: &mut Criterion, name: &str, scene: &str) {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut scene = drape::pipeline::Scene::load(&root.join(scene)).unwrap();
    scene.layup.plies.truncate(1);
    let tool = drape::io::read_tool(&scene.tool, scene.scale).unwrap();
    let mut group = c.benchmark_group("refine_scene");
    group.sample_size(10);
    group.bench_function(name, |b| {
        b.iter(|| {
            let r = drape::layup::stack::drape_layup(&scene.layup, &tool, |_, _| {}).unwrap();
            assert!(r[0].refined.as_ref().unwrap().ok(), "{name} did not converge");
        })
    });
    group.finish();
}

fn scenes(c: &mut Criterion) {
    scene_ply(c, "double_dome_p0_101x81_pressed", "geometries/double-dome/scene.toml");
    scene_ply(c, "square_table_41x41_free", "geometries/square-table/scene.toml");
}

criterion_group!(benches, pressed_hemisphere, scenes);
criterion_main!(benches);
