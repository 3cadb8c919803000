//! `mpirun -n N aeroshape run CASE.ron [--dv DV.ron] -o OUTDIR` (cargo feature `mpi`): the
//! flags of the serial command; the study over the ranks
//! ([`aeroshape::study::distributed::DistributedStudy`]): the geometry phases on every rank,
//! the grid read on rank 0, the deformation distributed and gathered on rank 0, which writes
//! the serial command's files (`report.json` with the distributed deformation's report under
//! `distributed`). Every rank reports an error, and exits 1, alike.

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, bail};
use deform::distributed::{DistReport, first_failure, mpi};
use mpi::traits::*;
use serde::Serialize;

use aeroshape::case::load_design_values;
use aeroshape::fsio::write_atomic;
use aeroshape::study::distributed::DistributedStudy;
use aeroshape::study::{Report, SetupReport};

use crate::run::RunArgs;

/// The file `report.json` of a distributed run: the serial one's fields and the distributed
/// deformation's report.
#[derive(Serialize)]
struct RunReport<'a> {
    case: String,
    design_vector: Option<String>,
    ranks: i32,
    setup: &'a SetupReport,
    evaluation: &'a Report,
    /// `None` when no wall node moved (the deformation was skipped).
    distributed: Option<&'a DistReport>,
    outputs: Vec<String>,
}

/// Runs `aeroshape run` on the world communicator of an MPI job.
pub fn run(a: RunArgs) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let universe = mpi::initialize().context("MPI could not be initialised")?;
    let world = universe.world();
    run_on(&world, a, t0).map_err(|e| crate::deform_mpi::reported(&world, &e))
}

/// [`run`] on the world communicator `world`.
fn run_on(world: &deform::distributed::Comm, a: RunArgs, t0: Instant) -> anyhow::Result<()> {
    let root = world.rank() == 0;
    let case = super::run::load_case(&a)?;
    let made = if root {
        std::fs::create_dir_all(&a.output)
            .with_context(|| format!("{}: cannot create the output folder", a.output.display()))
    } else {
        Ok(())
    };
    agree(world, made, &a.output)?;
    if root {
        eprintln!(
            "[run] building the study from {} on {} ranks",
            a.case.display(),
            world.size()
        );
    }
    let study = DistributedStudy::new(world, case, &a.case)?;
    let x = match &a.dv {
        Some(p) => load_design_values(p)
            .map_err(anyhow::Error::from)
            .and_then(|v| {
                study
                    .vector_from_values(&v)
                    .with_context(|| p.display().to_string())
            }),
        None => Ok(study.initial()),
    };
    // The same files on every rank: the same outcome.
    let x = agree(world, x, &a.case)?;
    let feasible = super::param::check_constraints(
        &study.case().parametrisation,
        &x,
        &a.case,
        a.allow_infeasible,
        "run",
    );
    agree(world, feasible, &a.case)?;
    let ev = study.evaluate(&x, &mut |p| {
        if root {
            eprintln!("[run] {p}");
        }
    })?;
    let written = match (&ev.root, study.baseline(), study.baseline_quality()) {
        (Some(r), Some(baseline), Some(q0)) => {
            write(&a, &study, &ev, r, (baseline, q0), world.size(), t0)
        }
        _ => Ok(()),
    };
    agree(world, written, &a.output)
}

/// `local` on every rank when it is `Ok` everywhere; otherwise the error of the lowest
/// failing rank on every rank, with the same text (collective).
fn agree<T>(
    world: &deform::distributed::Comm,
    local: anyhow::Result<T>,
    subject: &Path,
) -> anyhow::Result<T> {
    match first_failure(world, &local, |e| format!("{e:#}")) {
        None => local,
        Some((first, text)) => {
            local?;
            bail!("{text} (rank {first}; {})", subject.display())
        }
    }
}

/// Rank 0's files: the serial command's.
fn write(
    a: &RunArgs,
    study: &DistributedStudy<'_>,
    ev: &aeroshape::study::distributed::DistEvaluation,
    r: &aeroshape::study::distributed::RootEvaluation,
    (baseline, q0): (&mesh::Mesh, &[f64]),
    ranks: i32,
    t0: Instant,
) -> anyhow::Result<()> {
    let out = |name: &str| a.output.join(name);
    let rep = &r.report;
    let mut written = super::run::write_outputs(
        &a.output,
        rep.seconds,
        (baseline, study.geometry(), q0),
        (&r.grid, &ev.geometry, &r.cell_quality),
        !a.no_pictures,
    )?;
    let report_path = out("report.json");
    written.push(report_path.display().to_string());
    let rr = RunReport {
        case: a.case.display().to_string(),
        design_vector: a.dv.as_ref().map(|p| p.display().to_string()),
        ranks,
        setup: study.setup_report(),
        evaluation: rep,
        distributed: ev.distributed.as_ref(),
        outputs: written.clone(),
    };
    write_atomic(&report_path, |w| {
        serde_json::to_writer_pretty(&mut *w, &rr).map_err(std::io::Error::other)?;
        writeln!(w)
    })?;
    match &ev.distributed {
        Some(d) => outln!(
            "param {:.3} s; model update {:.3} s (control-point residual {:.2e} relative); surface grid {:.3} s ({} nodes moved); deform {:.3} s on {} ranks ({} + {} iterations, residual {:.1e}, {} ghost nodes, {} coarse aggregates)",
            rep.param.seconds,
            rep.model.seconds,
            rep.model.junction_residual_rel,
            rep.surface.seconds,
            rep.surface.moved_nodes,
            rep.deform.seconds,
            d.ranks,
            d.iterations,
            d.rotation_iterations,
            d.residual,
            d.ghost_nodes,
            d.coarse_aggregates
        ),
        None => outln!("no wall node moved: the baseline grid"),
    }
    outln!(
        "quality min {:.4} → {:.4}, mean {:.4} → {:.4}, inverted {} → {}",
        rep.quality_before.min,
        rep.quality_after.min,
        rep.quality_before.mean,
        rep.quality_after.mean,
        rep.quality_before.inverted,
        rep.quality_after.inverted
    );
    for w in &written {
        outln!("wrote {w}");
    }
    eprintln!("[run] done in {:.2} s", t0.elapsed().as_secs_f64());
    Ok(())
}
