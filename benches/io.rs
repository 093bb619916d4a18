//! Loading a tool and writing a net: reading, checking and indexing a 200k-triangle OBJ
//! (`read_tool`, and its parse alone), and writing the `<ply>.drape.json` of a 1001 x 1001 net.
//! The inputs are generated here: the hemisphere of `drape bench` (R = 1 m, 200,704 triangles)
//! written as OBJ text to a temporary folder, and the net draped on it from the pole to the rim.
//! Run: `cargo bench --bench io`.
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use drape::geometry::shapes;
use drape::geometry::{Point, Vector};
use drape::kinematic::{drape, KinematicSettings};
use std::f64::consts::FRAC_PI_2;

fn tool_load(c: &mut Criterion) {
    let dir = tempfile::tempdir().unwrap();
    let mesh = shapes::hemisphere_with_triangles(1.0, 200_000);
    let path = dir.path().join("hemisphere-200k.obj");
    std::fs::write(&path, mesh.to_obj_string()).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let mut group = c.benchmark_group("tool_load_200k");
    group.sample_size(10);
    group.throughput(Throughput::Elements(mesh.triangles.len() as u64));
    group.bench_function("obj_parse", |b| b.iter(|| drape::io::obj::parse(&bytes).unwrap()));
    group.bench_function("read_obj", |b| b.iter(|| drape::io::obj::read_obj(&path).unwrap()));
    group.bench_function("read_tool", |b| b.iter(|| drape::io::read_tool(&path, 1.0).unwrap()));
    group.finish();
}

fn net_json(c: &mut Criterion) {
    let tool = shapes::hemisphere_with_triangles(1.0, 200_000).into_surface().unwrap();
    let nodes = 1001;
    let spacing = FRAC_PI_2 / ((nodes - 1) / 2) as f64 * 0.999;
    let settings = KinematicSettings::grid("bench", Point::new(0.0, 0.0, 1.0), Vector::x(), spacing, nodes, nodes);
    let net = drape(&tool, &settings).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bench.drape.json");
    drape::io::write_json(&net, &path).unwrap();
    let size = std::fs::metadata(&path).unwrap().len();
    let mut group = c.benchmark_group("net_json_1001");
    group.sample_size(10);
    group.throughput(Throughput::Bytes(size));
    group.bench_function("write_json", |b| b.iter(|| drape::io::write_json(&net, &path).unwrap()));
    group.finish();
}

criterion_group!(benches, tool_load, net_json);
criterion_main!(benches);
