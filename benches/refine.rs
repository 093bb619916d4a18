//! Mechanical refinement of a hemisphere net (pressed, stiff fibres, nonlinear shear: the carbon
//! twill card) on the 200k-triangle hemisphere, nets from the pole to the rim.
//! Run: `cargo bench --bench refine`. `drape bench --refine CARD` prints iterations per run.
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use drape::geometry::shapes;
use drape::geometry::{Point, Vector};
use drape::kinematic::{drape, KinematicSettings};
use drape::material::MaterialCard;
use drape::mechanics::refine::{refine, RefineSettings};
use std::f64::consts::FRAC_PI_2;

fn pressed_hemisphere(c: &mut Criterion) {
    let tool = shapes::hemisphere_with_triangles(1.0, 200_000).into_surface().unwrap();
    let card =
        MaterialCard::load(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("materials/carbon-twill.toml"))
            .unwrap();
    let mut group = c.benchmark_group("refine_pressed_hemisphere_200k");
    group.sample_size(10);
    for nodes in [101usize, 201] {
        let half = (nodes - 1) / 2;
        let spacing = FRAC_PI_2 / half as f64 * 0.999;
        let settings = KinematicSettings::grid("b", Point::new(0.0, 0.0, 1.0), Vector::x(), spacing, nodes, nodes);
        let net = drape(&tool, &settings).unwrap();
        group.bench_with_input(BenchmarkId::from_parameter(nodes), &net, |b, net| {
            b.iter(|| refine(net, &tool, &card, &RefineSettings::default()).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, pressed_hemisphere);
criterion_main!(benches);
