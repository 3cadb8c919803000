//! CPU-time measurements of `wingmaster` (the machine is shared, so CPU time of this
//! process, from `/proc/self/stat` on Linux, rather than wall time):
//!
//! * `fit_timing fit FILE [N]`: N fits (default 100) of one airfoil file at 16 design variables;
//! * `fit_timing master [N]`: binding the wing master of `fixtures/geom/wing_body.ron` (121 × 11,
//!   two key sections) 100 times, then N `generate` and N `jacobian` calls (default 1000).
//!
//! `cargo run --release -p wingmaster --example fit_timing -- fit fixtures/airfoils/naca2412.dat`

use std::time::Instant;

use param::MasterSource;
use wingmaster::{Airfoil, FitOptions, WingMasterSpec, fit};

/// User + system CPU time of this process so far (ns) from `/proc/self/stat` (clock ticks,
/// assumed 100 Hz; run long enough for the tick resolution), or wall time elsewhere.
fn cpu_ns(start: Instant) -> f64 {
    std::fs::read_to_string("/proc/self/stat")
        .ok()
        .and_then(|s| {
            // fields after the command name "(…)": state is field 3, utime 14, stime 15
            let rest = &s[s.rfind(')')? + 2..];
            let f: Vec<&str> = rest.split_whitespace().collect();
            let ticks = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
            Some(ticks * 1e7)
        })
        .unwrap_or_else(|| start.elapsed().as_nanos() as f64)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let t0 = Instant::now();
    match args.first().map(String::as_str) {
        Some("fit") => {
            let path = args.get(1).expect("fit_timing fit FILE [N]");
            let n: usize = args.get(2).map_or(100, |s| s.parse().expect("N"));
            let f = std::fs::File::open(path).expect("open");
            let a = Airfoil::parse(std::io::BufReader::new(f), path).expect("parse");
            let opts = FitOptions::default();
            let c0 = cpu_ns(t0);
            let mut it = 0;
            let mut err = 0.0;
            for _ in 0..n {
                let r = fit(&a, &opts).expect("fit");
                it = r.iterations;
                err = r.max_error;
            }
            let c1 = cpu_ns(t0);
            println!(
                "{path}: {n} fits, {:.3} ms CPU per fit, {it} iterations, max error {err:.2e}",
                (c1 - c0) / n as f64 * 1e-6
            );
        }
        Some("master") => {
            let n: usize = args.get(1).map_or(1000, |s| s.parse().expect("N"));
            let root = concat!(
                env!("CARGO_MANIFEST_DIR"),
                "/../../fixtures/geom/wing_body.ron"
            );
            let text = std::fs::read_to_string(root).expect("fixture");
            let db = geom_db::GeomDb::from_ron_str(&text, root).expect("load");
            let spec = WingMasterSpec::from_ron_str(
                r#"(surface: 1, spanwise: V, n_s: 121, n_t: 11,
                    planform: (sweep: "sweep"),
                    key_sections: [
                        (t: 0.0, twist: "root_twist", thickness: {"tmax": "root_tmax"}),
                        (t: 1.0, twist: "tip_twist", thickness: {"tmax": "tip_tmax"},
                         camber: {3: "tip_camber3"}),
                    ])"#,
                "timing",
            )
            .expect("spec");
            let names = spec.variable_names();
            let x0 = vec![0.0; names.len()];
            let c0 = cpu_ns(t0);
            let nb = 100;
            for _ in 0..nb - 1 {
                std::hint::black_box(spec.bind(&db, &names, &x0).expect("bind"));
            }
            let wm = spec.bind(&db, &names, &x0).expect("bind");
            let c1 = cpu_ns(t0);
            let x: Vec<f64> = (0..names.len()).map(|k| 0.001 * (k + 1) as f64).collect();
            for _ in 0..n {
                std::hint::black_box(wm.generate(&x).expect("generate"));
            }
            let c2 = cpu_ns(t0);
            for _ in 0..n {
                std::hint::black_box(wm.jacobian(&x).expect("some").expect("jacobian"));
            }
            let c3 = cpu_ns(t0);
            println!(
                "wing master 121 x 11, {} variables: bind {:.2} ms CPU, generate {:.3} ms, jacobian {:.3} ms (CPU per call, {n} calls)",
                names.len(),
                (c1 - c0) / nb as f64 * 1e-6,
                (c2 - c1) / n as f64 * 1e-6,
                (c3 - c2) / n as f64 * 1e-6
            );
        }
        _ => eprintln!("usage: timing fit FILE [N] | timing master [N]"),
    }
}
