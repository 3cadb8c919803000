//! `cargo xtask bench-mpi GRID.su2 [--rounds N] [--ranks N] [--partition metis|rcb]
//! [--given]`: issue 24's measure, the distributed deformation against the serial one on
//! the same grid, in the same rounds (docs/performance.md, "deform over MPI").
//!
//! Builds the release `aeroshape` with the feature `mpi`, then in each round runs the
//! serial `aeroshape deform` on two rayon threads and `mpirun -n RANKS` of the same command
//! with one thread per rank (the motion of `cargo xtask regress`: the wing and fuselage
//! pitched 2°, the symmetry plane sliding, solved to 1e-11), the one first in odd rounds,
//! the other in even ones, so that a drift of the host weighs on both. It reads the
//! reports and prints each round's wall times, their ratio, the ratio without the write
//! (300 MB and an fsync at 1M nodes: the disk, not the program), the iterations and the
//! partition's seconds; `--given` adds, per round, the example `distributed` of `deform`
//! (each rank's part given, as a CFD solver hands it over: set-up and deformation against
//! the serial `deform::Deformer` in the same process, `--bind-to none` so that its serial
//! run has the cores). The table goes to `target/bench/mpi.md` too, with the machine's
//! load average before and after.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use serde_json::Value;

use crate::regress_mpi::FLAGS;

/// What a round measured.
struct Round {
    serial: Run,
    dist: Run,
    /// The example's "distributed / serial" for a given partition (`--given`).
    given: Option<f64>,
}

/// One run's wall time and what its report says.
struct Run {
    wall: f64,
    write: f64,
    iterations: String,
    partition: Option<f64>,
}

/// Runs the task with the arguments after `bench-mpi`.
pub fn run(root: &Path, args: &[String]) -> Result<(), String> {
    let value = |flag: &str| {
        args.iter()
            .position(|a| a == flag)
            .and_then(|i| args.get(i + 1))
            .cloned()
    };
    let grid = args
        .iter()
        .enumerate()
        .find(|(i, a)| {
            !a.starts_with("--")
                && (*i == 0 || !matches!(args[i - 1].as_str(), "--rounds" | "--ranks" | "--partition"))
        })
        .map(|(_, a)| PathBuf::from(a))
        .ok_or("usage: cargo xtask bench-mpi GRID.su2 [--rounds N] [--ranks N] [--partition metis|rcb] [--given]")?;
    let number = |flag: &str, default: usize| -> Result<usize, String> {
        value(flag).map_or(Ok(default), |v| {
            v.parse()
                .ok()
                .filter(|&n: &usize| n > 0)
                .ok_or(format!("{flag} {v}: not a positive count"))
        })
    };
    let rounds = number("--rounds", 3)?;
    let ranks = number("--ranks", 2)?;
    let partition = value("--partition").unwrap_or_else(|| "metis".into());
    let given = args.iter().any(|a| a == "--given");
    if !grid.is_file() {
        return Err(format!("{}: no such grid", grid.display()));
    }
    crate::cargo(&[
        "build",
        "--release",
        "-q",
        "-p",
        "aeroshape-cli",
        "--features",
        "mpi",
    ])?;
    if given {
        crate::cargo(&[
            "build",
            "--release",
            "-q",
            "-p",
            "deform",
            "--features",
            "mpi",
            "--example",
            "distributed",
        ])?;
    }
    let bin = root.join("target/release/aeroshape");
    let out = root.join("target/bench-mpi");
    std::fs::create_dir_all(&out).map_err(|e| format!("{}: {e}", out.display()))?;
    let load_before = crate::bench::load_average();
    let mut table = Vec::new();
    for r in 1..=rounds {
        let serial = || serial_run(&bin, &grid, &out);
        let dist = || dist_run(&bin, &grid, &out, ranks, &partition);
        let (serial, dist) = if r % 2 == 1 {
            let s = serial()?;
            (s, dist()?)
        } else {
            let d = dist()?;
            (serial()?, d)
        };
        let given = if given {
            Some(given_run(root, &grid, ranks)?)
        } else {
            None
        };
        let round = Round {
            serial,
            dist,
            given,
        };
        eprintln!("{}", row(r, &round));
        table.push(row(r, &round));
    }
    let text = format!(
        "# cargo xtask bench-mpi {}\n\nGrid {}; {ranks} ranks, partition {partition}; load average {load_before} before, {} after.\n\n\
         | round | serial | serial without the write | -n {ranks} | without the write | ratio | ratio without the write | iterations (Eq. 21 + 26), serial / -n {ranks} | partition | given partition: distributed / serial |\n\
         |---|---|---|---|---|---|---|---|---|---|\n{}\n",
        args.join(" "),
        grid.display(),
        crate::bench::load_average(),
        table.join("\n")
    );
    println!("{text}");
    let dir = root.join("target/bench");
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let path = dir.join("mpi.md");
    std::fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))
}

/// A round's line of the table.
fn row(r: usize, x: &Round) -> String {
    let (s, d) = (&x.serial, &x.dist);
    format!(
        "| {r} | {:.2} s | {:.2} s | {:.2} s | {:.2} s | {:.2} | {:.2} | {} / {} | {} | {} |",
        s.wall,
        s.wall - s.write,
        d.wall,
        d.wall - d.write,
        d.wall / s.wall,
        (d.wall - d.write) / (s.wall - s.write),
        s.iterations,
        d.iterations,
        d.partition.map_or("—".into(), |p| format!("{p:.2} s")),
        x.given.map_or("—".into(), |g| format!("{g:.2}")),
    )
}

/// The serial run on two threads.
fn serial_run(bin: &Path, grid: &Path, out: &Path) -> Result<Run, String> {
    let report = out.join("serial.json");
    let mut c = Command::new(bin);
    c.env("RAYON_NUM_THREADS", "2")
        .arg("deform")
        .arg(grid)
        .arg("-o")
        .arg(out.join("serial.su2"))
        .arg("--report")
        .arg(&report)
        .args(FLAGS);
    let wall = timed(c)?;
    let v = read_json(&report)?;
    Ok(Run {
        wall,
        write: number(&v, &["seconds", "write"])?,
        iterations: iterations(&v)?,
        partition: None,
    })
}

/// The same deformation under `mpirun -n ranks`, one thread per rank.
fn dist_run(bin: &Path, grid: &Path, out: &Path, ranks: usize, by: &str) -> Result<Run, String> {
    let report = out.join("dist.json");
    let mut c = mpirun(ranks);
    c.env("RAYON_NUM_THREADS", "1")
        .arg(bin)
        .arg("deform")
        .arg(grid)
        .arg("-o")
        .arg(out.join("dist.su2"))
        .arg("--report")
        .arg(&report)
        .args(["--partition", by])
        .args(FLAGS);
    let wall = timed(c)?;
    let v = read_json(&report)?;
    let d = v
        .get("distributed")
        .ok_or(format!("{}: no \"distributed\" object", report.display()))?;
    Ok(Run {
        wall,
        write: number(&v, &["seconds_write"])?,
        iterations: iterations(d)?,
        partition: Some(number(d, &["seconds", "partition"])?),
    })
}

/// The example `distributed` on `grid` (each rank's part given, the wing and fuselage
/// pitched 0.1°): its "distributed / serial" figure.
fn given_run(root: &Path, grid: &Path, ranks: usize) -> Result<f64, String> {
    let mut c = mpirun(ranks);
    c.env("RAYON_NUM_THREADS", "1")
        .args(["--bind-to", "none"])
        .arg(root.join("target/release/examples/distributed"))
        .arg(grid)
        .arg("0.1");
    let o = c.output().map_err(|e| format!("cannot run mpirun: {e}"))?;
    let text = String::from_utf8_lossy(&o.stdout);
    if !o.status.success() {
        return Err(format!(
            "the example distributed failed: {}{}",
            text,
            String::from_utf8_lossy(&o.stderr)
        ));
    }
    text.split("distributed / serial ")
        .nth(1)
        .and_then(|s| s.split(';').next())
        .and_then(|s| s.trim().parse().ok())
        .ok_or(format!("the example's output has no ratio: {text}"))
}

/// `mpirun` as root when we are root.
fn mpirun(ranks: usize) -> Command {
    let mut c = Command::new("mpirun");
    if crate::regress_mpi::is_root() {
        c.arg("--allow-run-as-root");
    }
    c.args(["-n", &ranks.to_string()]);
    c
}

/// Runs `c` (its output discarded); its wall time in seconds, or its error.
fn timed(mut c: Command) -> Result<f64, String> {
    let t = Instant::now();
    let o = c.output().map_err(|e| format!("cannot run {c:?}: {e}"))?;
    let wall = t.elapsed().as_secs_f64();
    if !o.status.success() {
        return Err(format!(
            "{c:?} failed: {}",
            String::from_utf8_lossy(&o.stderr).trim()
        ));
    }
    Ok(wall)
}

fn read_json(path: &Path) -> Result<Value, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))
}

/// The number at `keys` in `v`.
fn number(v: &Value, keys: &[&str]) -> Result<f64, String> {
    keys.iter()
        .try_fold(v, |v, k| v.get(k))
        .and_then(Value::as_f64)
        .ok_or(format!("the report has no number at {}", keys.join(".")))
}

/// "Eq. 21 + Eq. 26" iterations of a report (the serial one, or its `distributed` object).
fn iterations(v: &Value) -> Result<String, String> {
    Ok(format!(
        "{} + {}",
        number(v, &["iterations"])?,
        number(v, &["rotation_iterations"])?
    ))
}
