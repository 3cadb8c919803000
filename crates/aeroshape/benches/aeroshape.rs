//! Benchmarks of the chain on the default case (`fixtures/cases/default`, issue 9's target):
//! one `Study::evaluate` of the default design vector `x`
//! - `cold`: every solve from the baseline (the warm start forgotten before each call), as the
//!   first evaluation of a study;
//! - `warm_same_x`: `x` again, warm-started from the previous evaluation of `x`;
//! - `warm_step`: alternately `x` and `1.01 x`, each warm-started from the other (an
//!   optimiser's step).
//!
//! The chain's derivatives at `x` (issue 22), group `gradient`:
//! - `linearise`: `Study::linearise` when the last evaluation was elsewhere (a cold
//!   evaluation at `x` and every phase's linearisation);
//! - `jvp`, `vjp`: one forward / reverse product of that linearisation (volume);
//! - `vjp_wall`: the reverse product from wall sensitivities (no volume solve);
//! - `reverse_total`: `linearise` + `vjp`, the whole gradient from scratch;
//! - `after_evaluate`: `linearise` + `vjp` just after a (cold, untimed) evaluation at `x`,
//!   which it reuses: the gradient's cost beyond the evaluation an optimiser makes anyway;
//! - `fd_gradient`: the gradient by central differences, 2n cold evaluations.

use std::hint::black_box;
use std::path::PathBuf;

use aeroshape::Study;
use aeroshape::case::load_design_values;
use criterion::{BatchSize, Criterion, criterion_group, criterion_main};

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
    gradient(c, &study, &x);
}

fn gradient(c: &mut Criterion, study: &Study, x: &[f64]) {
    let n = study.baseline().n_nodes();
    let w: Vec<[f64; 3]> = (0..n)
        .map(|i| {
            let t = i as f64;
            [(0.37 * t).sin(), (0.11 * t).cos(), (0.23 * t + 1.0).sin()]
        })
        .collect();
    let dx: Vec<f64> = (0..x.len()).map(|l| ((l as f64) * 0.7).sin()).collect();
    let step: Vec<f64> = x.iter().map(|v| 1.01 * v).collect();
    // The last evaluation elsewhere (untimed): `linearise` evaluates x itself.
    let elsewhere = || {
        study.forget_warm_start();
        study.evaluate(&step).unwrap();
    };
    elsewhere();
    let lin = study.linearise(x).unwrap();
    let mut g = c.benchmark_group("gradient");
    g.sample_size(10);
    g.bench_function("linearise", |b| {
        b.iter_batched(
            elsewhere,
            |()| black_box(study.linearise(x).unwrap().x().len()),
            BatchSize::PerIteration,
        )
    });
    g.bench_function("jvp", |b| b.iter(|| black_box(lin.jvp(&dx).unwrap())));
    g.bench_function("vjp", |b| b.iter(|| black_box(lin.vjp(&w).unwrap())));
    g.bench_function("vjp_wall", |b| {
        b.iter(|| black_box(lin.vjp_wall(&w).unwrap()))
    });
    g.bench_function("reverse_total", |b| {
        b.iter_batched(
            elsewhere,
            |()| black_box(study.linearise(x).unwrap().vjp(&w).unwrap()),
            BatchSize::PerIteration,
        )
    });
    g.bench_function("after_evaluate", |b| {
        b.iter_batched(
            || {
                study.forget_warm_start();
                study.evaluate(x).unwrap();
            },
            |()| black_box(study.linearise(x).unwrap().vjp(&w).unwrap()),
            BatchSize::PerIteration,
        )
    });
    g.bench_function("fd_gradient", |b| {
        b.iter(|| {
            let mut y = x.to_vec();
            let grad: Vec<f64> = (0..x.len())
                .map(|l| {
                    let h = 1e-4;
                    let mut j = |s: f64| -> f64 {
                        y[l] = x[l] + s * h;
                        study.forget_warm_start();
                        let c = study.evaluate(&y).unwrap().grid.coords;
                        y[l] = x[l];
                        c.iter()
                            .zip(&w)
                            .map(|(p, q)| p[0] * q[0] + p[1] * q[1] + p[2] * q[2])
                            .sum()
                    };
                    (j(1.0) - j(-1.0)) / (2.0 * h)
                })
                .collect();
            black_box(grad)
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
