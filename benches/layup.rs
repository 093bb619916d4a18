//! Throughput of the layup stages on a hemisphere (R = 1 m): mapping a 301 x 301 net onto flow
//! meshes of 20k and 200k triangles (elements per second), offsetting a 200k-triangle tool, and
//! unfolding the net into its flat pattern. Run: `cargo bench --bench layup`.
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use drape::geometry::offset::offset_surface;
use drape::geometry::{shapes, TriangleMesh};
use drape::geometry::{Point, Vector};
use drape::kinematic::{drape, KinematicSettings};
use drape::layup::flat::flat_pattern;
use drape::mapping::{map_net, Cavity, PermeabilityModel, PlyMapSettings};
use drape::mapping::{ElementShape, FlowElement, FlowMesh};
use std::f64::consts::FRAC_PI_2;

fn flow_mesh(m: &TriangleMesh) -> FlowMesh {
    FlowMesh {
        path: "bench".into(),
        nodes: m.vertices.clone(),
        node_ids: (1..=m.vertices.len() as u64).collect(),
        elements: m
            .triangles
            .iter()
            .enumerate()
            .map(|(k, t)| FlowElement {
                id: k as u64 + 1,
                shape: ElementShape::Tria3,
                nodes: t.map(|v| v as usize).to_vec(),
                property: 0,
            })
            .collect(),
        ..FlowMesh::default()
    }
}

fn layup(c: &mut Criterion) {
    let tool = shapes::hemisphere_with_triangles(1.0, 200_000).into_surface().unwrap();
    let nodes = 301;
    let spacing = FRAC_PI_2 / ((nodes - 1) / 2) as f64 * 0.999;
    let net =
        drape(&tool, &KinematicSettings::grid("b", Point::new(0.0, 0.0, 1.0), Vector::x(), spacing, nodes, nodes))
            .unwrap();
    let settings = PlyMapSettings {
        thickness: 5e-4,
        vf: 0.5,
        cavity: Cavity::Fixed,
        permeability: Some(PermeabilityModel { fibre_radius: 3.5e-6 }),
        nominal_warp: Vector::x(),
        max_distance: spacing,
    };
    let mut group = c.benchmark_group("layup_hemisphere");
    group.sample_size(10);
    for triangles in [20_000usize, 200_000] {
        let mesh = flow_mesh(&shapes::hemisphere_with_triangles(1.0, triangles));
        group.throughput(Throughput::Elements(mesh.elements.len() as u64));
        group.bench_with_input(BenchmarkId::new("map_301_net", mesh.elements.len()), &mesh, |b, m| {
            b.iter(|| map_net(&net, m, &settings).unwrap())
        });
    }
    let distance = vec![1e-3; tool.vertices().len()];
    group.throughput(Throughput::Elements(tool.num_triangles() as u64));
    group.bench_function("offset_200k", |b| b.iter(|| offset_surface(&tool, &distance).unwrap()));
    group.throughput(Throughput::Elements(((nodes - 1) * (nodes - 1)) as u64));
    group.bench_function("flat_pattern_301", |b| b.iter(|| flat_pattern(&net).unwrap()));
    group.finish();
}

criterion_group!(benches, layup);
criterion_main!(benches);
