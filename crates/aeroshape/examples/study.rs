//! The chain as a library: build a [`aeroshape::Study`] once from a case, then evaluate design
//! vectors as an optimiser would (see the `aeroshape::study` docs).
//!
//! ```text
//! cargo run --release -p aeroshape --example study [CASE_DIR]
//! ```
//!
//! `CASE_DIR` (default `fixtures/cases/default`) holds `case.ron` and `dv.ron`. The program
//! evaluates the design vector `x` of `dv.ron` cold (first evaluation) and warm (second, then
//! seven more times), then an optimiser-like step `1.01 x` warm and cold, then the initial
//! vector, and prints the phase times and iterations of each.

use std::path::PathBuf;
use std::time::Instant;

use aeroshape::Study;
use aeroshape::case::load_design_values;
use aeroshape::study::Evaluation;

fn show(label: &str, seconds: f64, ev: &Evaluation) {
    let r = &ev.report;
    println!(
        "{label}: {seconds:.4} s (param {:.4}, model update {:.4}, surface grid {:.4}, deform {:.4} s with {} + {} (R) iterations); min quality {:.4} → {:.4}, {} inverted",
        r.param.seconds,
        r.model.seconds,
        r.surface.seconds,
        r.deform.seconds,
        r.deform.iterations(),
        r.deform.rotation_iterations(),
        r.quality_before.min,
        r.quality_after.min,
        r.quality_after.inverted
    );
}

fn timed(study: &Study, x: &[f64]) -> Result<(f64, Evaluation), aeroshape::study::StudyError> {
    let t = Instant::now();
    let ev = study.evaluate(x)?;
    Ok((t.elapsed().as_secs_f64(), ev))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("fixtures/cases/default"));
    let t = Instant::now();
    let study = Study::load(&dir.join("case.ron"))?;
    let s = study.setup_report();
    println!(
        "set-up: {:.3} s ({} nodes, {} cells, {} wall nodes)",
        t.elapsed().as_secs_f64(),
        s.nodes,
        s.cells,
        s.wall_nodes
    );
    let x = study.vector_from_values(&load_design_values(&dir.join("dv.ron"))?)?;
    let (t1, first) = timed(&study, &x)?;
    show("first evaluate (cold)", t1, &first);
    let (t2, second) = timed(&study, &x)?;
    show("second evaluate (warm, same x)", t2, &second);
    println!("first / second: {:.1}×", t1 / t2);
    // Single calls vary by about a millisecond on a shared machine: the next few warm calls.
    let mut more = Vec::new();
    for _ in 0..7 {
        more.push(timed(&study, &x)?.0);
    }
    let mut sorted = more.clone();
    sorted.sort_by(f64::total_cmp);
    println!(
        "next 7 warm calls, same x: {} s; median {:.4} s, first / median {:.1}×",
        more.iter()
            .map(|t| format!("{t:.4}"))
            .collect::<Vec<_>>()
            .join(" "),
        sorted[3],
        t1 / sorted[3]
    );
    let step: Vec<f64> = x.iter().map(|v| 1.01 * v).collect();
    let (tw, warm) = timed(&study, &step)?;
    show("step 1.01 x (warm)", tw, &warm);
    study.forget_warm_start();
    let (tc, cold) = timed(&study, &step)?;
    show("step 1.01 x (cold)", tc, &cold);
    let diff = testkit::max_coordinate_difference(&warm.grid.coords, &cold.grid.coords);
    println!("step warm vs cold: largest coordinate difference {diff:.2e}");
    let zero = study.evaluate(&study.initial())?;
    println!(
        "initial design vector gives the baseline grid bit for bit: {}",
        zero.grid.coords == study.baseline().coords
    );
    Ok(())
}
