//! Parser throughput on a generated mesh-heavy world (an IndexedFaceSet with millions of
//! points). `cargo bench -p regatta-parser` reports MB/s; peak memory is measured by
//! `regatta bench parse`, which runs the same generator in a fresh process.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};

fn mesh_world(points: usize) -> String {
    regatta_parser::testgen::mesh_world(points)
}

fn bench(c: &mut Criterion) {
    let world = mesh_world(1_000_000);
    let mut group = c.benchmark_group("parse");
    group.throughput(Throughput::Bytes(world.len() as u64));
    group.sample_size(10);
    group.bench_function("mesh_1M_points", |b| {
        b.iter(|| regatta_parser::parse(std::hint::black_box(&world)))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
