//! Benchmarks: generation of the whole wing-body fixture (fuselage with its nose and tail
//! poles, wing, tip cap) and of its wing alone (triangles per second), the update at frozen
//! parameters (nodes per second) and the re-map after a fuselage change.

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use geom_db::prelude::Point3;
use geom_db::{GeomDb, SurfCompId};
use surfgrid::spacing::{Growth, LineSource};
use surfgrid::{GenerateOptions, SizeField, UpdateOptions, evaluate_frozen, generate, grid_stats};

fn fixture(name: &str) -> GeomDb {
    let path = format!(
        "{}/../../fixtures/geom/{name}.ron",
        env!("CARGO_MANIFEST_DIR")
    );
    GeomDb::from_ron_str(&std::fs::read_to_string(&path).unwrap(), &path).unwrap()
}

/// Uniform `h` and a line source of h/7.5 along the wing's leading edge (between the corners
/// named "junction leading edge" and "tip leading edge").
fn wing_field(db: &GeomDb, h: f64) -> SizeField {
    let corner = |name: &str| db.corners.iter().find(|c| c.name == name).unwrap().point;
    SizeField::uniform(h)
        .unwrap()
        .with_line(LineSource {
            a: corner("junction leading edge"),
            b: corner("tip leading edge"),
            h0: h / 7.5,
            r0: 0.02,
            growth: Growth::Smoothstep { radius: 0.4 },
        })
        .unwrap()
}

fn bench(c: &mut Criterion) {
    let db = fixture("wing_body");
    let wing = SurfCompId(
        db.surface_components
            .iter()
            .position(|c| c.name == "wing")
            .unwrap() as u32,
    );
    let opts = GenerateOptions::default().with_components(vec![wing]);
    let field = wing_field(&db, 0.05);
    let g = generate(&db, &field, &opts).unwrap();
    let st = grid_stats(&g, &field);
    eprintln!("wing h = 0.05: {} nodes, {st:?}", g.n_nodes());
    let all = GenerateOptions::default();
    let gw = generate(&db, &field, &all).unwrap();
    eprintln!(
        "wing-body h = 0.05: {} nodes, {:?}",
        gw.n_nodes(),
        grid_stats(&gw, &field)
    );
    for c in &gw.components {
        let one = surfgrid::SurfaceGrid {
            coords: gw.coords.clone(),
            support: gw.support.clone(),
            curve_nodes: gw.curve_nodes.clone(),
            components: vec![c.clone()],
        };
        eprintln!("  {}: {:?}", c.comp, grid_stats(&one, &field));
    }
    let sphere = fixture("sphere");
    let sf = SizeField::uniform(0.05).unwrap();
    let gs = generate(&sphere, &sf, &GenerateOptions::default()).unwrap();
    eprintln!(
        "sphere h = 0.05: {} nodes, {:?}",
        gs.n_nodes(),
        grid_stats(&gs, &sf)
    );

    let mut grp = c.benchmark_group("generate");
    grp.sample_size(10);
    grp.throughput(Throughput::Elements(gw.n_triangles() as u64));
    grp.bench_function("wing_body_h0.05", |b| {
        b.iter(|| generate(black_box(&db), &field, &all).unwrap())
    });
    grp.throughput(Throughput::Elements(g.n_triangles() as u64));
    grp.bench_function("wing_h0.05", |b| {
        b.iter(|| generate(black_box(&db), &field, &opts).unwrap())
    });
    grp.throughput(Throughput::Elements(gs.n_triangles() as u64));
    grp.bench_function("sphere_h0.05", |b| {
        b.iter(|| generate(black_box(&sphere), &sf, &GenerateOptions::default()).unwrap())
    });
    grp.finish();

    let mut grp = c.benchmark_group("frozen");
    grp.throughput(Throughput::Elements(gw.n_nodes() as u64));
    grp.bench_function("wing_body_h0.05", |b| {
        b.iter(|| evaluate_frozen(black_box(&gw), &db))
    });
    grp.throughput(Throughput::Elements(g.n_nodes() as u64));
    grp.bench_function("wing_h0.05", |b| {
        b.iter(|| evaluate_frozen(black_box(&g), &db))
    });
    grp.finish();

    // update after a fuselage radius change of +5 % (junction moves: re-map and smoothing)
    let fus = db
        .surfaces
        .iter()
        .position(|s| s.name == "fuselage")
        .unwrap();
    let pts = db.control_points_with_surface_moved(geom_db::SurfaceId::from_index(fus), |p| {
        Point3::new(p.x, p.y * 1.05, p.z * 1.05)
    });
    let (new, _) =
        intersect::update::update_model(&db, &pts, &intersect::update::UpdateOptions::default())
            .unwrap();
    let (_, rep) = surfgrid::update(&gw, &db, &new, &UpdateOptions::default()).unwrap();
    eprintln!("wing-body update, fuselage +5 %: {rep:?}");
    let mut grp = c.benchmark_group("update");
    grp.sample_size(10);
    grp.throughput(Throughput::Elements(gw.n_nodes() as u64));
    grp.bench_function("wing_body_fuselage_plus5pct", |b| {
        b.iter(|| surfgrid::update(black_box(&gw), &db, &new, &UpdateOptions::default()).unwrap())
    });
    grp.throughput(Throughput::Elements(g.n_nodes() as u64));
    grp.bench_function("wing_fuselage_plus5pct", |b| {
        b.iter(|| surfgrid::update(black_box(&g), &db, &new, &UpdateOptions::default()).unwrap())
    });
    grp.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
