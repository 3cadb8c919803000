//! Benchmarks of the CAD import (issue 19: each < 1 s): the SolidWorks IGES of the ONERA M6
//! (`shared/data/iges` next to the workspace or one of its parents, skipped when absent) and
//! the OpenCASCADE wing-body as IGES faces, IGES B-rep, STEP AP214 and the periodic-wing
//! STEP (`fixtures/cad`), from the bytes in memory to the validated database with its
//! control nodes and its junctions rebuilt on their supports.
//!
//! `cargo bench -p geom-db --bench import`.

use std::hint::black_box;
use std::path::PathBuf;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use geom_db::import::{ImportOptions, import_bytes};

fn files() -> Vec<(String, Vec<u8>)> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut out = Vec::new();
    let m6 = root
        .ancestors()
        .map(|d| d.join("shared/data/iges/geom_oneram6.igs"))
        .find(|p| p.is_file());
    match m6.map(std::fs::read) {
        Some(Ok(b)) => out.push(("m6_iges".to_string(), b)),
        _ => eprintln!("skipping the M6: no shared/data/iges/geom_oneram6.igs above the workspace"),
    }
    for (name, file) in [
        ("wing_body_iges_faces", "wing_body_faces_m.igs"),
        ("wing_body_iges_brep", "wing_body_brep_m.igs"),
        ("wing_body_step_ap214", "wing_body_ap214_m.stp"),
        ("wing_body_periodic_step", "wing_body_periodic_ap214_m.stp"),
    ] {
        let path = root.join("fixtures/cad").join(file);
        out.push((name.to_string(), std::fs::read(&path).expect("fixture")));
    }
    out
}

fn bench_import(c: &mut Criterion) {
    let opts = ImportOptions::default();
    let mut g = c.benchmark_group("import");
    for (name, bytes) in files() {
        g.bench_function(&name, |b| {
            b.iter(|| import_bytes(black_box(&bytes), &name, &opts).expect("imports"))
        });
    }
    g.finish();
}

fn config() -> Criterion {
    Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(5))
}

criterion_group! { name = benches; config = config(); targets = bench_import }
criterion_main!(benches);
