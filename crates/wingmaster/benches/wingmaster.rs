//! Criterion benchmarks of `wingmaster`: one section fit (NACA 2412 file, 69 points, 16
//! design variables), the Eq. (40) modifier on its points, and building + sampling a section.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use std::hint::black_box;
use wingmaster::modify::SectionModifier;
use wingmaster::{Airfoil, FitOptions, fit};

fn airfoil() -> Airfoil {
    let p = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/airfoils/naca2412.dat"
    );
    let f = std::fs::File::open(p).expect("fixture");
    Airfoil::parse(std::io::BufReader::new(f), p).expect("parse")
}

fn bench_fit(c: &mut Criterion) {
    let a = airfoil();
    let mut g = c.benchmark_group("section");
    g.throughput(Throughput::Elements(a.points.len() as u64));
    g.bench_function("fit_naca2412_dv16", |b| {
        b.iter(|| fit(black_box(&a), &FitOptions::default()).expect("fit"))
    });
    let f = fit(&a, &FitOptions::default()).expect("fit");
    let m = SectionModifier::from_fit(&f).expect("modifier");
    let mut t = f.params.thickness.clone();
    t.tmax += 0.005;
    let dq = vec![[0.0, 0.001]; f.params.camber.len()];
    g.bench_function("eq40_modify", |b| {
        b.iter(|| m.apply(black_box(&t), black_box(&dq)).expect("apply"))
    });
    g.bench_function("build_and_sample_241", |b| {
        b.iter(|| f.params.build().expect("build").sample(120))
    });
    g.finish();
}

criterion_group!(benches, bench_fit);
criterion_main!(benches);
