//! Benchmarks of `geom-db`: point and derivative evaluation of patches (Eq. 9 by Horner's
//! rule), batch evaluation of a support surface, and the control-node solve (Eq. 9 for A) on
//! the wing-body fixture.
//!
//! `cargo bench -p geom-db --bench geom-db`. Throughput is reported in points per second
//! (criterion's elements/s).

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use geom_db::eval::ParamSurface;
use geom_db::prelude::Point3;
use geom_db::{GeomDb, Patch, SupportSurface};

/// A bicubic (or degree n×n) patch with non-trivial coefficients.
fn patch(n: usize) -> Patch {
    Patch::interpolate(n, n, |u, v| {
        Point3::new(
            u + 0.3 * v * v,
            v - 0.2 * u * u * v,
            (3.0 * u).sin() * (2.0 * v).cos(),
        )
    })
}

/// `n` parameter pairs on a scrambled grid of [0, 1]² (deterministic).
fn params(n: usize) -> Vec<(f64, f64)> {
    (0..n)
        .map(|k| {
            let a = (k as f64 * 0.618_033_988_749_895).fract();
            let b = (k as f64 * 0.754_877_666_246_693).fract();
            (a, b)
        })
        .collect()
}

fn bench_patch(c: &mut Criterion) {
    const N: usize = 4096;
    let uv = params(N);
    for deg in [3usize, 8] {
        let p = patch(deg);
        let mut g = c.benchmark_group(format!("patch_deg{deg}"));
        g.throughput(Throughput::Elements(N as u64));
        g.bench_function("point", |b| {
            b.iter(|| {
                let mut acc = 0.0;
                for &(u, v) in &uv {
                    acc += p.point(black_box(u), black_box(v)).x;
                }
                acc
            })
        });
        g.bench_function("derivs", |b| {
            b.iter(|| {
                let mut acc = 0.0;
                for &(u, v) in &uv {
                    let d = p.derivs(black_box(u), black_box(v));
                    acc += d.du.x + d.dvv.y;
                }
                acc
            })
        });
        g.finish();
    }
    // through the ParamSurface trait with global parameters (patch lookup included)
    let s = SupportSurface::new("grid", 4, 4, vec![patch(3); 16]);
    let guv: Vec<(f64, f64)> = uv.iter().map(|&(u, v)| (4.0 * u, 4.0 * v)).collect();
    let mut g = c.benchmark_group("surface_bicubic_4x4");
    g.throughput(Throughput::Elements(N as u64));
    g.bench_function("point_global", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for &(u, v) in &guv {
                acc += s.point(black_box(u), black_box(v)).x;
            }
            acc
        })
    });
    g.bench_function("derivs_global", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for &(u, v) in &guv {
                acc += s.derivs(black_box(u), black_box(v)).du.x;
            }
            acc
        })
    });
    g.finish();
    // batch (rayon above 4096 points)
    const M: usize = 1 << 18;
    let buv: Vec<(f64, f64)> = params(M).iter().map(|&(u, v)| (4.0 * u, 4.0 * v)).collect();
    let mut g = c.benchmark_group("surface_bicubic_batch");
    g.throughput(Throughput::Elements(M as u64));
    g.bench_function("points_262144", |b| b.iter(|| s.points(black_box(&buv))));
    g.finish();
}

fn bench_control(c: &mut Criterion) {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/geom/wing_body.ron"
    );
    let text = std::fs::read_to_string(path).expect("fixture");
    let db = GeomDb::from_ron_str(&text, path).expect("valid fixture");
    let moved: Vec<Point3> = db
        .control_points()
        .iter()
        .map(|p| p + geom_db::prelude::Vector3::new(0.0, 0.0, 1e-3 * p.y))
        .collect();
    let mut g = c.benchmark_group("control_solve_wing_body");
    g.throughput(Throughput::Elements(db.control_nodes.len() as u64));
    g.bench_function("set_control_points", |b| {
        let mut work = db.clone();
        b.iter(|| work.set_control_points(black_box(&moved)).unwrap())
    });
    g.finish();
}

fn config() -> Criterion {
    Criterion::default()
        .sample_size(30)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2))
}

criterion_group! { name = benches; config = config(); targets = bench_patch, bench_control }
criterion_main!(benches);
