//! Benchmarks: reading and writing the ONERA M6 SolidWorks export (98 entities, 1471 lines).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};

fn m6_bytes() -> Vec<u8> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/iges/geom_oneram6.igs");
    std::fs::read(path).expect("fixture present")
}

fn read_write(c: &mut Criterion) {
    let bytes = m6_bytes();
    let file = iges::parse(&bytes, "m6.igs").unwrap();
    let mut g = c.benchmark_group("iges");
    g.throughput(Throughput::Bytes(bytes.len() as u64));
    g.bench_function("read_m6", |b| {
        b.iter(|| iges::parse(std::hint::black_box(&bytes), "m6.igs").unwrap())
    });
    g.bench_function("write_m6", |b| {
        b.iter(|| {
            let mut out = Vec::with_capacity(bytes.len());
            file.write(&mut out, "m6.igs").unwrap();
            out
        })
    });
    g.finish();
}

criterion_group!(benches, read_write);
criterion_main!(benches);
