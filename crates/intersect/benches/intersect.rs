//! Criterion benchmarks of `intersect`: foot of the normal for 100k random points near the
//! wing–body fixture's surfaces (fuselage, wing, tip cap), and one curve update.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use geom_db::eval::ParamSurface;
use geom_db::prelude::Point3;
use geom_db::{GeomDb, SupportSurface};
use intersect::project::{ProjectOptions, SurfaceSetProjector};
use intersect::update::{ModelBaseline, UpdateOptions};
use std::hint::black_box;

fn load() -> GeomDb {
    let path = format!(
        "{}/../../fixtures/geom/wing_body.ron",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(&path).expect("fixture");
    GeomDb::from_ron_str(&text, &path).expect("valid fixture")
}

fn lcg(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*state >> 11) as f64) / ((1u64 << 53) as f64)
}

/// `n` points at random (u, v) of random surfaces, offset along the normal by up to ±1 % of
/// the model size (seeded, the same on every run).
pub fn points_near(db: &GeomDb, n: usize) -> Vec<Point3> {
    let scale = db.reference_length();
    let mut st = 42u64;
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let s = &db.surfaces[(lcg(&mut st) * db.surfaces.len() as f64) as usize];
        let (du, dv) = s.domain();
        let u = du[0] + (du[1] - du[0]) * lcg(&mut st);
        let v = dv[0] + (dv[1] - dv[0]) * lcg(&mut st);
        let d = s.derivs(u, v);
        if let Some(nrm) = d.unit_normal() {
            out.push(d.point + nrm * (0.02 * (lcg(&mut st) - 0.5) * scale));
        }
    }
    out
}

fn projection(c: &mut Criterion) {
    let db = load();
    let surfaces: Vec<(String, &SupportSurface)> =
        db.surfaces.iter().map(|s| (s.name.clone(), s)).collect();
    let opts = ProjectOptions::default().with_length_scale(db.reference_length());
    let set = SurfaceSetProjector::new(&surfaces, &opts).unwrap();
    let pts = points_near(&db, 100_000);
    let mut g = c.benchmark_group("projection");
    g.sample_size(10);
    g.throughput(Throughput::Elements(pts.len() as u64));
    g.bench_function("wing_body_100k_points", |b| {
        b.iter(|| {
            let r = set.project_many(black_box(&pts));
            assert!(r.iter().all(|f| f.is_ok()));
            r
        })
    });
    g.bench_function("build_seeding_hierarchy", |b| {
        b.iter(|| SurfaceSetProjector::new(black_box(&surfaces), &opts).unwrap())
    });
    g.finish();
}

fn update(c: &mut Criterion) {
    let db = load();
    let fus = db
        .surfaces
        .iter()
        .position(|s| s.name == "fuselage")
        .unwrap();
    let nodes = db.control_points_with_surface_moved(geom_db::SurfaceId::from_index(fus), |p| {
        Point3::new(p.x, p.y * 1.05, p.z * 1.05)
    });
    let mut g = c.benchmark_group("model_update");
    g.sample_size(10);
    g.bench_function("baseline_seeding", |b| {
        b.iter(|| ModelBaseline::new(black_box(&db), &UpdateOptions::default()).unwrap())
    });
    let base = ModelBaseline::new(&db, &UpdateOptions::default()).unwrap();
    g.bench_function("fuselage_plus_5_percent", |b| {
        b.iter(|| base.update(black_box(&nodes)).unwrap())
    });
    g.finish();
}

criterion_group!(benches, projection, update);
criterion_main!(benches);
