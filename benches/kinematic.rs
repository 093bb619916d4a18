//! Throughput of the kinematic engine: cells per second on a 200k-triangle hemisphere (R = 1 m),
//! nets from the pole reaching the rim, and the cost of loading/checking the tool mesh.
//! Run: `cargo bench --bench kinematic`.
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use drape::geometry::shapes;
use drape::geometry::{Point, Vector};
use drape::kinematic::{drape, KinematicSettings};
use std::f64::consts::FRAC_PI_2;

fn fishnet(c: &mut Criterion) {
    let tool = shapes::hemisphere_with_triangles(1.0, 200_000).into_surface().unwrap();
    let mut group = c.benchmark_group("fishnet_hemisphere_200k");
    group.sample_size(10);
    for nodes in [101usize, 301, 1000] {
        let half = (nodes - 1) / 2;
        let spacing = FRAC_PI_2 / half as f64 * 0.999;
        let settings = KinematicSettings::grid("b", Point::new(0.0, 0.0, 1.0), Vector::x(), spacing, nodes, nodes);
        group.throughput(Throughput::Elements(((nodes - 1) * (nodes - 1)) as u64));
        group.bench_with_input(BenchmarkId::from_parameter(nodes), &settings, |b, s| {
            b.iter(|| drape(&tool, s).unwrap())
        });
    }
    group.finish();
}

fn tool_mesh(c: &mut Criterion) {
    let mut group = c.benchmark_group("tool_surface");
    group.sample_size(10);
    let mesh = shapes::hemisphere_with_triangles(1.0, 200_000);
    group.throughput(Throughput::Elements(mesh.triangles.len() as u64));
    group.bench_function("check_and_build_200k", |b| b.iter(|| mesh.clone().into_surface().unwrap()));
    group.finish();
}

criterion_group!(benches, fishnet, tool_mesh);
criterion_main!(benches);
