//! The distributed study's reuse of its set-up, as an optimiser's loop calls it:
//! `mpirun -n N distributed_study [CASE.ron DV.ron]` (the default case and its design
//! vector by default) evaluates the midpoint between the initial design and DV, then DV, on
//! one `DistributedStudy` (the second evaluation reuses the first's distributed set-up and,
//! with the case's `warm_start`, starts its solves from the first's solutions), and DV
//! again on a new study (a new set-up). Rank 0 prints the deviation between the two
//! results for DV, which must be within 100 × the solves' `rel_tol` of the largest
//! displacement (two solves converged to `rel_tol` differ by it times the conditioning of
//! what is left; 100 is the margin), and the distance
//! between the midpoint's grid and DV's, which must not be 0 (the second design moved the
//! grid). After `forget_warm_start`, DV on the reused set-up must be the new study's grid
//! bit for bit (the same partition, roles and operators), with 3 deformations on the
//! set-up; DV once more, warm started from that one, must take no iteration.

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
    if !study.case().deform.warm_start {
        return Err("the case does not warm start".into());
    }
    let first = study.evaluate(&mid, quiet).map_err(e)?;
    let warm = study.evaluate(&x1, quiet).map_err(e)?;
    study.forget_warm_start();
    let cold = study.evaluate(&x1, quiet).map_err(e)?;
    let again = study.evaluate(&x1, quiet).map_err(e)?;
    let report = |r: &aeroshape::study::distributed::DistEvaluation| {
        r.distributed.as_ref().map_or((0, 0, 0), |r| {
            (r.deformations, r.iterations, r.rotation_iterations)
        })
    };
    let (deformations, _, _) = report(&cold);
    let again_it = report(&again);
    let fresh = DistributedStudy::load(world, case).map_err(e)?;
    let new = fresh.evaluate(&x1, quiet).map_err(e)?;
    let (Some(w), Some(c), Some(b), Some(m), Some(x0)) = (
        &warm.root,
        &cold.root,
        &new.root,
        &first.root,
        study.baseline(),
    ) else {
        return Ok(());
    };
    let same = gap(&c.grid.coords, &b.grid.coords);
    let moved = gap(&c.grid.coords, &m.grid.coords);
    let scale = gap(&b.grid.coords, &x0.coords);
    let warm_dev = gap(&w.grid.coords, &b.grid.coords) / scale;
    println!(
        "{} ranks, distributed study: DV warm started {warm_dev:.3e} (of the largest displacement) from a new set-up, in {:?} iterations (Eq. 21, Eq. 26) against {:?} cold; cold on the reused set-up {same:.3e} from a new set-up ({deformations} deformations on it); the midpoint's grid {moved:.3e} from DV's; DV again warm: {:?} iterations",
        world.size(),
        (report(&warm).1, report(&warm).2),
        (report(&cold).1, report(&cold).2),
        (again_it.1, again_it.2),
    );
    if warm_dev.is_nan() || warm_dev > 100.0 * study.case().deform.rel_tol {
        return Err(format!(
            "the warm-started grid is {warm_dev:e} of the displacement from a new set-up's"
        ));
    }
    if same != 0.0 {
        return Err(format!(
            "the reused set-up's grid is {same:e} from a new set-up's"
        ));
    }
    if moved == 0.0 {
        return Err("the second design did not move the grid from the first".into());
    }
    if deformations != 3 {
        return Err(format!(
            "{deformations} deformations on the reused set-up, not 3"
        ));
    }
    if (again_it.1, again_it.2) != (0, 0) {
        return Err(format!(
            "DV again, warm started, took {:?} iterations",
            (again_it.1, again_it.2)
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
