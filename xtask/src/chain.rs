//! `cargo xtask chain`: the end-to-end default case (paper Figure 5). Runs
//! `aeroshape run fixtures/cases/default/case.ron --dv fixtures/cases/default/dv.ron -o
//! target/chain` (release build), then prints a summary from `target/chain/report.json`:
//! phase times, junction residual, grid quality before/after, inverted cells, output paths.

use std::path::{Path, PathBuf};

use serde_json::Value;

/// The default case folder, relative to the workspace root.
pub const DEFAULT_CASE: &str = "fixtures/cases/default";

/// Runs the default case into `target/chain/` and prints the summary.
pub fn run(root: &Path) -> Result<(), String> {
    let out = run_case(root, DEFAULT_CASE, &root.join("target").join("chain"))?;
    let report = read_report(&out)?;
    print_summary(&report, &out);
    Ok(())
}

/// Runs `aeroshape run` on `case_dir` (relative to the root) into `out`; returns `out`.
pub fn run_case(root: &Path, case_dir: &str, out: &Path) -> Result<PathBuf, String> {
    let case = root.join(case_dir).join("case.ron");
    let dv = root.join(case_dir).join("dv.ron");
    let (case_s, dv_s, out_s) = (
        case.display().to_string(),
        dv.display().to_string(),
        out.display().to_string(),
    );
    crate::aeroshape(None, &["run", &case_s, "--dv", &dv_s, "-o", &out_s])?;
    Ok(out.to_path_buf())
}

/// Reads `OUT/report.json`.
pub fn read_report(out: &Path) -> Result<Value, String> {
    let p = out.join("report.json");
    let text = std::fs::read_to_string(&p).map_err(|e| format!("{}: {e}", p.display()))?;
    serde_json::from_str(&text).map_err(|e| format!("{}: {e}", p.display()))
}

fn f(v: &Value, path: &[&str]) -> f64 {
    let mut x = v;
    for k in path {
        x = &x[*k];
    }
    x.as_f64().unwrap_or(f64::NAN)
}

/// Prints the summary of a run.
pub fn print_summary(r: &Value, out: &Path) {
    let e = &r["evaluation"];
    let s = &r["setup"];
    println!("chain: {}", r["case"].as_str().unwrap_or("?"));
    println!(
        "  grid: {} nodes, {} cells, {} wall nodes; set-up {:.3} s (read {:.3}, param {:.3}, model seeds {:.3}, classify {:.3})",
        s["nodes"],
        s["cells"],
        s["wall_nodes"],
        f(s, &["read"]) + f(s, &["param"]) + f(s, &["model"]) + f(s, &["classify"]),
        f(s, &["read"]),
        f(s, &["param"]),
        f(s, &["model"]),
        f(s, &["classify"])
    );
    println!(
        "  param        {:>8.3} s  {} control nodes moved (max {:.3e})",
        f(e, &["param", "seconds"]),
        e["param"]["nodes_moved"],
        f(e, &["param", "max_move"])
    );
    println!(
        "  model update {:>8.3} s  {} surfaces re-solved, {} curves re-intersected, {} corners; junction residual {:.2e} ({:.2e} relative)",
        f(e, &["model", "seconds"]),
        e["model"]["surfaces_changed"],
        e["model"]["curves_reintersected"],
        e["model"]["corners_updated"],
        f(e, &["model", "junction_residual"]),
        f(e, &["model", "junction_residual_rel"])
    );
    println!(
        "  surface grid {:>8.3} s  {} wall nodes moved (max {:.3e}), {} components re-mapped",
        f(e, &["surface", "seconds"]),
        e["surface"]["moved_nodes"],
        f(e, &["surface", "max_displacement"]),
        e["surface"]["remapped_components"]
    );
    println!(
        "  deform       {:>8.3} s  {} iterations, residual {:.1e}, {} increment(s), {} sliding nodes",
        f(e, &["deform", "seconds"]),
        e["deform"]["report"]["iterations"],
        f(e, &["deform", "report", "residual"]),
        e["deform"]["report"]["increments"],
        e["deform"]["report"]["sliding"]
    );
    println!("  evaluation   {:>8.3} s", f(e, &["seconds"]));
    println!(
        "  quality: min {:.4} → {:.4}, mean {:.4} → {:.4}, 1st percentile {:.4} → {:.4}; inverted {} → {}",
        f(e, &["quality_before", "min"]),
        f(e, &["quality_after", "min"]),
        f(e, &["quality_before", "mean"]),
        f(e, &["quality_after", "mean"]),
        f(e, &["quality_before", "p1"]),
        f(e, &["quality_after", "p1"]),
        e["quality_before"]["inverted"],
        e["quality_after"]["inverted"]
    );
    println!(
        "  wall nodes vs their support evaluated at their parameters (after deform): max {:.2e} (relative)",
        f(e, &["wall_support_rel"])
    );
    println!("  outputs in {}:", out.display());
    if let Some(list) = r["outputs"].as_array() {
        for o in list {
            println!("    {}", o.as_str().unwrap_or("?"));
        }
    }
}
