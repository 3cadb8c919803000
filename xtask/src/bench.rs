//! `cargo xtask bench [--quick] [CRATE]...`: runs the criterion benchmarks of the named
//! crates (all crates with a bench by default), then reads criterion's results of this run
//! (`target/criterion/**/new/{benchmark,estimates}.json` written after the start) and prints
//! one table of medians and throughputs, also written to `target/bench/summary.md` with the
//! machine's core count and load average before and after, so that figures logged in
//! `docs/perf-log/` (and summarised in `docs/performance.md`, "How to measure") carry the
//! conditions they were measured in.

use std::path::{Path, PathBuf};
use std::time::SystemTime;

use serde_json::Value;

/// The crates with a `[[bench]]` target named after the crate, in layer order.
const BENCHED: [&str; 10] = [
    "iges",
    "step",
    "geom-db",
    "mesh",
    "intersect",
    "param",
    "surfgrid",
    "deform",
    "wingmaster",
    "aeroshape",
];

/// One benchmark result of this run.
#[derive(Debug, Clone, PartialEq)]
struct Row {
    id: String,
    median_ns: f64,
    /// Elements or bytes per iteration, with the unit name.
    throughput: Option<(f64, &'static str)>,
}

/// Runs the task with the arguments after `bench`.
pub fn run(root: &Path, args: &[String]) -> Result<(), String> {
    let quick = args.iter().any(|a| a == "--quick");
    let crates: Vec<&str> = args
        .iter()
        .filter(|a| !a.starts_with("--"))
        .map(String::as_str)
        .collect();
    if let Some(bad) = crates.iter().find(|c| !BENCHED.contains(c)) {
        return Err(format!(
            "no benchmark for crate '{bad}' (benchmarked: {})",
            BENCHED.join(", ")
        ));
    }
    let crates = if crates.is_empty() {
        BENCHED.to_vec()
    } else {
        crates
    };
    let start = SystemTime::now();
    let load_before = load_average();
    for c in &crates {
        let mut a = vec!["bench", "-p", c, "--bench", c, "--"];
        if quick {
            a.extend(["--warm-up-time", "1", "--measurement-time", "2"]);
        }
        crate::cargo(&a)?;
    }
    let load_after = load_average();
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("target"));
    let mut rows = Vec::new();
    collect(&target.join("criterion"), start, &mut rows)?;
    rows.sort_by(|a, b| a.id.cmp(&b.id));
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    let mut md = format!(
        "# cargo xtask bench{}\n\nCrates: {}. Cores: {cores}. Load average (1 min) before {load_before}, after {load_after}.\n\n| benchmark | median | throughput |\n|---|---|---|\n",
        if quick { " --quick" } else { "" },
        crates.join(", ")
    );
    for r in &rows {
        md.push_str(&format!(
            "| `{}` | {} | {} |\n",
            r.id,
            human_time(r.median_ns),
            r.throughput
                .map(|(n, unit)| human_rate(n / (r.median_ns * 1e-9), unit))
                .unwrap_or_default()
        ));
    }
    print!("{md}");
    let dir = target.join("bench");
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let out = dir.join("summary.md");
    crate::fixtures::write_atomic(&out, md.as_bytes())?;
    println!("\nsummary written to {}", out.display());
    Ok(())
}

/// The 1-minute load average, or "unknown".
pub(crate) fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next().map(str::to_string))
        .unwrap_or_else(|| "unknown".into())
}

/// Walks criterion's output folder for `new/estimates.json` files modified after `since`.
fn collect(dir: &Path, since: SystemTime, rows: &mut Vec<Row>) -> Result<(), String> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Ok(());
    };
    for e in entries {
        let e = e.map_err(|e| format!("{}: {e}", dir.display()))?;
        let path = e.path();
        if !path.is_dir() {
            continue;
        }
        let est = path.join("estimates.json");
        if path.file_name().is_some_and(|n| n == "new") && est.is_file() {
            let fresh = std::fs::metadata(&est)
                .and_then(|m| m.modified())
                .is_ok_and(|t| t >= since);
            if fresh {
                rows.push(read_row(&path)?);
            }
        } else {
            collect(&path, since, rows)?;
        }
    }
    Ok(())
}

fn read_json(path: &Path) -> Result<Value, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))
}

/// Reads one benchmark's `benchmark.json` (id, throughput) and `estimates.json` (median).
fn read_row(new_dir: &Path) -> Result<Row, String> {
    let bench = read_json(&new_dir.join("benchmark.json"))?;
    let est_path = new_dir.join("estimates.json");
    let est = read_json(&est_path)?;
    let id = bench["full_id"].as_str().unwrap_or("?").to_string();
    let median_ns = est["median"]["point_estimate"]
        .as_f64()
        .ok_or_else(|| format!("{}: no median.point_estimate", est_path.display()))?;
    let throughput = match &bench["throughput"] {
        Value::Object(m) => m.iter().find_map(|(k, v)| {
            let unit = match k.as_str() {
                "Elements" | "ElementsAndBytes" => "elem",
                "Bytes" | "BytesDecimal" => "B",
                _ => return None,
            };
            v.as_f64()
                .or_else(|| v["elements"].as_f64())
                .map(|n| (n, unit))
        }),
        _ => None,
    };
    Ok(Row {
        id,
        median_ns,
        throughput,
    })
}

/// A duration in ns with a readable unit.
fn human_time(ns: f64) -> String {
    match ns {
        t if t >= 1e9 => format!("{:.3} s", t * 1e-9),
        t if t >= 1e6 => format!("{:.3} ms", t * 1e-6),
        t if t >= 1e3 => format!("{:.3} µs", t * 1e-3),
        t => format!("{t:.1} ns"),
    }
}

/// A rate per second with an SI prefix.
fn human_rate(per_s: f64, unit: &str) -> String {
    match per_s {
        r if r >= 1e9 => format!("{:.2} G{unit}/s", r * 1e-9),
        r if r >= 1e6 => format!("{:.2} M{unit}/s", r * 1e-6),
        r if r >= 1e3 => format!("{:.2} k{unit}/s", r * 1e-3),
        r => format!("{r:.2} {unit}/s"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_a_criterion_result_folder() {
        let dir = std::env::temp_dir().join(format!("xtask-bench-{}", std::process::id()));
        let new = dir.join("group").join("f").join("new");
        std::fs::create_dir_all(&new).unwrap();
        std::fs::write(
            new.join("benchmark.json"),
            r#"{"full_id":"group/f","throughput":{"Elements":1000}}"#,
        )
        .unwrap();
        std::fs::write(
            new.join("estimates.json"),
            r#"{"median":{"point_estimate":2000000.0}}"#,
        )
        .unwrap();
        let mut rows = Vec::new();
        collect(&dir, SystemTime::UNIX_EPOCH, &mut rows).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(
            rows,
            vec![Row {
                id: "group/f".into(),
                median_ns: 2e6,
                throughput: Some((1000.0, "elem")),
            }]
        );
        assert_eq!(human_time(rows[0].median_ns), "2.000 ms");
        assert_eq!(human_rate(1000.0 / 2e-3, "elem"), "500.00 kelem/s");
    }
}
