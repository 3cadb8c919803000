//! Benchmarks of the chain on the default case (`fixtures/cases/default`, issue 9's target):
//! one `Study::evaluate` of the default design vector `x`
//! - `cold`: every solve from the baseline (the warm start forgotten before each call), as the
//!   first evaluation of a study;
//! - `warm_same_x`: `x` again, warm-started from the previous evaluation of `x`;
//! - `warm_step`: alternately `x` and `1.01 x`, each warm-started from the other (an
//!   optimiser's step).

use std::hint::black_box;
use std::path::PathBuf;

use aeroshape::Study;
use aeroshape::case::load_design_values;
use criterion::{Criterion, criterion_group, criterion_main};

fn bench(c: &mut Criterion) {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/cases/default");
    let study = Study::load(&dir.join("case.ron")).unwrap();
    let x = study
        .vector_from_values(&load_design_values(&dir.join("dv.ron")).unwrap())
        .unwrap();
    let step: Vec<f64> = x.iter().map(|v| 1.01 * v).collect();
    // The first evaluation factorises the surface grid's re-maps; the benchmarks below reuse
    // them.
    study.evaluate(&x).unwrap();
    let mut g = c.benchmark_group("chain");
    g.bench_function("evaluate/cold", |b| {
        b.iter(|| {
            study.forget_warm_start();
            black_box(study.evaluate(&x).unwrap())
        })
    });
    study.evaluate(&x).unwrap();
    g.bench_function("evaluate/warm_same_x", |b| {
        b.iter(|| black_box(study.evaluate(&x).unwrap()))
    });
    let mut flip = false;
    g.bench_function("evaluate/warm_step", |b| {
        b.iter(|| {
            flip = !flip;
            black_box(study.evaluate(if flip { &step } else { &x }).unwrap())
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
