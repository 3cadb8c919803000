//! The chain as a library: build a [`aeroshape::Study`] once from a case, then evaluate design
//! vectors as an optimiser would (see the `aeroshape::study` docs).
//!
//! ```text
//! cargo run --release -p aeroshape --example study [CASE_DIR]
//! ```
//!
//! `CASE_DIR` (default `fixtures/cases/default`) holds `case.ron` and `dv.ron`. The program
//! evaluates the design vector twice (the first and a repeated evaluation), then the initial
//! vector, and prints the phase times and the grid quality; the repeated evaluation gives the
//! same grid bit for bit and the initial vector the baseline grid.

use std::path::PathBuf;
use std::time::Instant;

use aeroshape::Study;
use aeroshape::case::load_design_values;

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
    let mut grids = Vec::new();
    for label in ["first evaluate", "second evaluate"] {
        let t = Instant::now();
        let ev = study.evaluate(&x)?;
        let r = &ev.report;
        println!(
            "{label}: {:.4} s wall clock (param {:.4}, model update {:.4}, surface grid {:.4}, deform {:.4} s with {} iterations); min quality {:.4} → {:.4}, {} inverted",
            t.elapsed().as_secs_f64(),
            r.param.seconds,
            r.model.seconds,
            r.surface.seconds,
            r.deform.seconds,
            r.deform.iterations,
            r.quality_before.min,
            r.quality_after.min,
            r.quality_after.inverted
        );
        grids.push(ev.grid.coords);
    }
    println!("repeated evaluation identical: {}", grids[0] == grids[1]);
    let zero = study.evaluate(&study.initial())?;
    println!(
        "initial design vector gives the baseline grid bit for bit: {}",
        zero.grid.coords == study.baseline().coords
    );
    Ok(())
}
