//! Project automation (`cargo xtask <task>`), in the manner of rust-analyzer's xtask.
//!
//! Tasks: `ci` (fmt, clippy, tests, docs), `tidy` (the architecture invariants: layering,
//! geometry and grid, no environment in libraries, file length and headers, commit subjects),
//! `fixtures` (geometry fixtures and the chain cases' volume grids), `chain` (the default
//! case end to end), `regress` (references, ignored tests, round trips), `bench`, `bench-mpi` (the distributed
//! deformation against the serial one).

mod bench;
mod bench_mpi;
mod chain;
mod fixtures;
mod regress;
mod regress_mpi;
mod regress_mpi_slide;
mod regress_mpi_study;
mod tidy;

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.first().map(String::as_str) {
        Some("ci") => ci(),
        Some("tidy") => tidy::run(&root()),
        Some("fixtures") => fixtures::run(&root(), &args[1..]),
        Some("chain") => chain::run(&root()),
        Some("regress") => regress::run(&root(), &args[1..]),
        Some("bench") => bench::run(&root(), &args[1..]),
        Some("bench-mpi") => bench_mpi::run(&root(), &args[1..]),
        _ => {
            eprintln!(
                "usage: cargo xtask <task>\n\ntasks:\n  ci     fmt --check, clippy -D warnings, tests, docs\n  tidy   check the architecture invariants (ARCHITECTURE.md)\n  fixtures [--geometry-only]  write the geometry fixtures (fixtures/geom/) and the chain cases' volume grids (needs pip gmsh)\n  chain  run the default case (fixtures/cases/default) into target/chain/ and print a summary\n  regress [--bless] [--skip-ignored-tests]  chain cases against fixtures/reference/, ignored tests, meshio/Gmsh round trips\n  bench [--quick] [CRATE]...  criterion benchmarks of the crates, summary in target/bench/summary.md\n  bench-mpi GRID.su2 [--rounds N] [--ranks N] [--partition metis|rcb] [--given]  mpirun -n N against the serial deform, in the same rounds, summary in target/bench/mpi.md"
            );
            return ExitCode::from(2);
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("xtask: {e}");
            ExitCode::from(1)
        }
    }
}

/// The workspace root (the parent of this crate's manifest directory).
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask lives in the workspace")
        .to_path_buf()
}

/// Runs `cargo` (the one that invoked us) with `args` in the workspace root.
pub fn cargo(args: &[&str]) -> Result<(), String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    eprintln!("$ cargo {}", args.join(" "));
    let status = Command::new(&cargo)
        .args(args)
        .current_dir(root())
        .status()
        .map_err(|e| format!("cannot run {cargo}: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("cargo {} failed ({status})", args.join(" ")))
    }
}

/// Runs the `aeroshape` program (crate `aeroshape-cli`), or the example `example` of the
/// library `aeroshape`, in the release profile with the arguments `args`.
pub fn aeroshape(example: Option<&str>, args: &[&str]) -> Result<(), String> {
    let mut a = vec!["run", "--release", "-q"];
    match example {
        Some(e) => a.extend(["-p", "aeroshape", "--example", e]),
        None => a.extend(["-p", "aeroshape-cli", "--bin", "aeroshape"]),
    }
    a.push("--");
    a.extend_from_slice(args);
    cargo(&a)
}

fn ci() -> Result<(), String> {
    cargo(&["fmt", "--all", "--", "--check"])?;
    cargo(&[
        "clippy",
        "--workspace",
        "--all-targets",
        "--",
        "-D",
        "warnings",
    ])?;
    cargo(&["test", "--workspace"])?;
    tidy::run(&root())?;
    cargo(&["doc", "--workspace", "--no-deps"])
}
