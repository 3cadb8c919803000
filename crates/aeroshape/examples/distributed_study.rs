//! The distributed study's reuse of its set-up, as an optimiser's loop calls it:
//! `mpirun -n N distributed_study [CASE.ron DV.ron]` (the default case and its design
//! vector by default) evaluates the midpoint between the initial design and DV, then DV, on
//! one `DistributedStudy` (the second evaluation reuses the first's distributed set-up),
//! and DV again on a new study (a new set-up). Rank 0 prints the gap between the two
//! results for DV, which must be 0 (the same partition, roles and operators, bit for bit),
//! and the distance between the midpoint's grid and DV's, which must not be (the second
//! design moved the grid); the reused evaluation must report 2 deformations on its set-up.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use aeroshape::study::distributed::DistributedStudy;
use deform::distributed::mpi;
use deform::distributed::mpi::traits::*;

/// The largest distance between the nodes of two grids.
fn gap(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    let dist =
        |p: &[f64; 3], q: &[f64; 3]| (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt();
    a.iter().zip(b).map(|(p, q)| dist(p, q)).fold(0.0, f64::max)
}

/// The check (see the module's doc); errors are one line.
fn run(world: &deform::distributed::Comm, case: &Path, dv: &Path) -> Result<(), String> {
    let e = |e: aeroshape::study::StudyError| e.to_string();
    let text = std::fs::read_to_string(dv).map_err(|e| format!("{}: {e}", dv.display()))?;
    let values =
        param::parse_design_values(&text, &dv.display().to_string()).map_err(|e| e.to_string())?;
    let study = DistributedStudy::load(world, case).map_err(e)?;
    let x1 = study.vector_from_values(&values).map_err(e)?;
    let x0 = study.initial();
    let mid: Vec<f64> = x0.iter().zip(&x1).map(|(a, b)| 0.5 * (a + b)).collect();
    let quiet = &mut |_: &str| {};
    let first = study.evaluate(&mid, quiet).map_err(e)?;
    let reused = study.evaluate(&x1, quiet).map_err(e)?;
    let deformations = reused.distributed.as_ref().map_or(0, |r| r.deformations);
    let fresh = DistributedStudy::load(world, case).map_err(e)?;
    let new = fresh.evaluate(&x1, quiet).map_err(e)?;
    let (Some(a), Some(b), Some(m)) = (&reused.root, &new.root, &first.root) else {
        return Ok(());
    };
    let same = gap(&a.grid.coords, &b.grid.coords);
    let moved = gap(&a.grid.coords, &m.grid.coords);
    println!(
        "{} ranks, distributed study: DV on the reused set-up {same:.3e} from a new set-up ({deformations} deformations on it); the midpoint's grid {moved:.3e} from DV's",
        world.size()
    );
    if same != 0.0 {
        return Err(format!(
            "the reused set-up's grid is {same:e} from a new set-up's"
        ));
    }
    if moved == 0.0 {
        return Err("the second design did not move the grid from the first".into());
    }
    if deformations != 2 {
        return Err(format!(
            "{deformations} deformations on the reused set-up, not 2"
        ));
    }
    Ok(())
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().collect();
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/cases/default");
    let case = args.get(1).map_or(dir.join("case.ron"), PathBuf::from);
    let dv = args.get(2).map_or(dir.join("dv.ron"), PathBuf::from);
    let Some(universe) = mpi::initialize() else {
        eprintln!("error: MPI could not be initialised");
        return ExitCode::from(1);
    };
    let world = universe.world();
    match run(&world, &case, &dv) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: rank {}: {e}", world.rank());
            ExitCode::from(1)
        }
    }
}
