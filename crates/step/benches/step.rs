//! Benchmark: parsing an OpenCASCADE-written STEP file (a box, a cylinder, a sphere).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};

fn parse(c: &mut Criterion) {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let mut g = c.benchmark_group("step");
    for name in ["box_ap214.stp", "cylinder_ap203.stp"] {
        let bytes = std::fs::read(dir.join(name)).expect("fixture present");
        g.throughput(Throughput::Bytes(bytes.len() as u64));
        g.bench_function(name, |b| {
            b.iter(|| step::parse(std::hint::black_box(&bytes), name).unwrap())
        });
    }
    g.finish();
}

criterion_group!(benches, parse);
criterion_main!(benches);
