//! Benchmarks of `param`: binding a parametrisation to the wing-body fixture, applying a
//! design vector and the exact Jacobian (one modifier of each level).

use std::path::PathBuf;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use geom_db::GeomDb;
use param::{MasterSources, Parametrisation};

fn load() -> (GeomDb, Parametrisation) {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let geom = std::fs::read_to_string(root.join("fixtures/geom/wing_body.ron")).unwrap();
    let db = GeomDb::from_ron_str(&geom, "wing_body.ron").unwrap();
    let case = std::fs::read_to_string(root.join("fixtures/cases/wing_body_param.ron")).unwrap();
    // the case file's `parametrisation` field (other fields are ignored here)
    #[derive(serde::Deserialize)]
    struct Case {
        parametrisation: Parametrisation,
    }
    let c: Case = param::ron_from_str(&case, "wing_body_param.ron").unwrap();
    (db, c.parametrisation)
}

fn bench(c: &mut Criterion) {
    let (db, p) = load();
    let n = db.control_points().len() as u64;
    let mut g = c.benchmark_group("param");
    g.throughput(Throughput::Elements(n));
    g.bench_function("bind_wing_body", |b| {
        b.iter(|| p.bind(&db, &MasterSources::new()).unwrap())
    });
    let prep = p.bind(&db, &MasterSources::new()).unwrap();
    let x: Vec<f64> = prep
        .registry()
        .variables()
        .iter()
        .map(|v| v.value + 0.01 * (v.upper - v.lower) * 0.1)
        .collect();
    g.bench_function("apply_wing_body", |b| b.iter(|| prep.apply(&x).unwrap()));
    g.bench_function("jacobian_wing_body", |b| {
        b.iter(|| prep.apply_with_jacobian(&x).unwrap())
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
