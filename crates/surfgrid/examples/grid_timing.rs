//! CPU-time figures for the surfgrid table of `docs/performance.md`, logged by date in
//! `docs/perf-log/` (the machine is shared, so wall-clock criterion figures are pessimistic): generation of the whole wing-body fixture, the update after a
//! fuselage radius change of +5 %, and the evaluation at frozen parameters, each timed by the
//! process's CPU time (user + system, from `/proc/self/stat`, Linux) and by the wall clock.
//!
//! `cargo run --profile bench -p surfgrid --example grid_timing [-- H]` (H: far-field size,
//! default 0.05; a line source of H/7.5 along the leading edge). Run with
//! `RAYON_NUM_THREADS=1` for single-thread rates.

use std::time::Instant;

use geom_db::GeomDb;
use geom_db::prelude::Point3;
use surfgrid::spacing::{Growth, LineSource};
use surfgrid::{GenerateOptions, SizeField, UpdateOptions, evaluate_frozen, generate, grid_stats};

/// CPU time of the process (user + system) in seconds, from `/proc/self/stat` (clock ticks
/// of 1/100 s); NaN where unavailable.
fn cpu_seconds() -> f64 {
    let Ok(s) = std::fs::read_to_string("/proc/self/stat") else {
        return f64::NAN;
    };
    // the command name may contain spaces: fields after the closing parenthesis
    let rest = s.rsplit_once(')').map_or("", |x| x.1);
    let f: Vec<&str> = rest.split_whitespace().collect();
    let tick = |i: usize| {
        f.get(i)
            .and_then(|x| x.parse::<f64>().ok())
            .unwrap_or(f64::NAN)
    };
    // utime and stime are fields 14 and 15 of the whole line: 12 and 13 after the name
    (tick(11) + tick(12)) / 100.0
}

fn timed<T>(what: &str, reps: usize, per: f64, unit: &str, mut f: impl FnMut() -> T) -> T {
    let (c0, w0) = (cpu_seconds(), Instant::now());
    let mut out = None;
    for _ in 0..reps {
        out = Some(f());
    }
    let (cpu, wall) = (
        (cpu_seconds() - c0) / reps as f64,
        w0.elapsed().as_secs_f64() / reps as f64,
    );
    println!(
        "{what}: CPU {cpu:.4} s, wall {wall:.4} s per run ({reps} runs): {:.3e} {unit}/CPU-s, {:.3e} {unit}/wall-s",
        per / cpu,
        per / wall
    );
    out.expect("at least one run")
}

fn main() {
    let h: f64 = std::env::args()
        .nth(1)
        .map_or(0.05, |x| x.parse().expect("H"));
    let path = format!(
        "{}/../../fixtures/geom/wing_body.ron",
        env!("CARGO_MANIFEST_DIR")
    );
    let db = GeomDb::from_ron_str(&std::fs::read_to_string(&path).expect("fixture"), &path)
        .expect("fixture");
    let corner = |name: &str| {
        db.corners
            .iter()
            .find(|c| c.name == name)
            .expect(name)
            .point
    };
    let field = SizeField::uniform(h)
        .expect("size")
        .with_line(LineSource {
            a: corner("junction leading edge"),
            b: corner("tip leading edge"),
            h0: h / 7.5,
            r0: 0.02,
            growth: Growth::Smoothstep { radius: 0.4 },
        })
        .expect("source");
    let opts = GenerateOptions::default();
    let g = generate(&db, &field, &opts).expect("generation");
    let st = grid_stats(&g, &field);
    println!(
        "wing-body, h = {h}: {} nodes, {} triangles, min angle {:.1} deg, {:.3} % >= 20 deg, {:.3} % of edges within ±30 %, worst / mean mean ratio {:.3} / {:.3}",
        g.n_nodes(),
        st.triangles,
        st.min_angle_deg,
        100.0 * st.frac_min_angle_ge_20,
        100.0 * st.frac_edges_within_30,
        st.worst_quality,
        st.mean_quality
    );
    timed("generate", 3, st.triangles as f64, "triangles", || {
        generate(&db, &field, &opts).expect("generation")
    });
    timed("evaluate_frozen", 200, g.n_nodes() as f64, "nodes", || {
        evaluate_frozen(&g, &db)
    });
    // fuselage radius +5 %
    let fus = db
        .surfaces
        .iter()
        .position(|s| s.name == "fuselage")
        .expect("fuselage");
    let pts = db.control_points_with_surface_moved(geom_db::SurfaceId::from_index(fus), |p| {
        Point3::new(p.x, p.y * 1.05, p.z * 1.05)
    });
    let (new, _) =
        intersect::update::update_model(&db, &pts, &intersect::update::UpdateOptions::default())
            .expect("model update");
    let (g2, rep) = timed(
        "update (fuselage +5 %)",
        3,
        g.n_nodes() as f64,
        "nodes",
        || surfgrid::update(&g, &db, &new, &UpdateOptions::default()).expect("update"),
    );
    for c in &rep.components {
        println!(
            "  component {}: re-mapped {}, worst mean ratio initial {:.3}, before smoothing {:.3}, after {:.3} ({} passes)",
            c.comp, c.remapped, c.worst_initial, c.worst_before, c.worst_after, c.passes
        );
    }
    let st2 = grid_stats(&g2, &field);
    println!(
        "  after: min angle {:.1} deg, {:.3} % >= 20 deg, worst mean ratio {:.3}",
        st2.min_angle_deg,
        100.0 * st2.frac_min_angle_ge_20,
        st2.worst_quality
    );
}
