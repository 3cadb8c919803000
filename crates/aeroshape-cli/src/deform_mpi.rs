//! `mpirun -n N aeroshape deform ...` (cargo feature `mpi`): the same flags as the serial
//! command; rank 0 reads the grid, the deformation runs distributed
//! (`deform::distributed`, the partition made on rank 0), and rank 0 writes the gathered
//! grid in one file (and the report). Every rank reports an error, and exits 1, alike.

use std::time::Instant;

use anyhow::{Context, bail};
use deform::distributed::{self, Deformer, all_ok, mpi};
use deform::{BoundaryConditions, Request};
use mpi::traits::*;
use serde::Serialize;

use crate::deform::{DeformArgs, add_displacements};

/// True when the program was started by an MPI launcher (Open MPI's or a PMI one).
pub fn launched() -> bool {
    ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"]
        .iter()
        .any(|v| std::env::var_os(v).is_some())
}

#[derive(Serialize)]
struct Report<'a> {
    input: String,
    output: String,
    cells: usize,
    quality_before: mesh::quality::Summary,
    quality_after: mesh::quality::Summary,
    seconds_read: f64,
    seconds_write: f64,
    seconds_total: f64,
    distributed: &'a distributed::DistReport,
}

/// The grid and boundary conditions, read on rank 0: the request's, with the displacements
/// of the flags on this grid (as the serial command makes them).
fn read(args: &DeformArgs, request: &Request) -> anyhow::Result<(mesh::Mesh, BoundaryConditions)> {
    if args.geometry.is_some() {
        bail!("--geometry: sliding on geometry supports is not distributed yet (docs/mpi.md)");
    }
    let m = mesh::io::read_path(&args.mesh)?;
    let mut request = request.clone();
    add_displacements(args, &m, &mut request)?;
    let bc = request.boundary_conditions(&m, None);
    Ok((m, bc))
}

/// Runs the distributed deformation of `request` (its displacements made on rank 0 from the
/// flags) on the world communicator.
pub fn run(args: &DeformArgs, request: Request) -> anyhow::Result<()> {
    let opts = request.options();
    let t_all = Instant::now();
    let universe = mpi::initialize().context("MPI could not be initialised")?;
    let world = universe.world();
    let root = world.rank() == 0;
    let format = mesh::io::Format::from_path(&args.output)
        .ok_or_else(|| anyhow::anyhow!("{}: unknown output format", args.output.display()))?;
    let t = Instant::now();
    let input = if root {
        Some(read(args, &request))
    } else {
        None
    };
    let read_ok = !matches!(input, Some(Err(_)));
    if !all_ok(&world, read_ok) {
        return match input {
            Some(Err(e)) => Err(e.context(format!("{}", args.mesh.display()))),
            _ => bail!("{}: rank 0 could not read the input", args.mesh.display()),
        };
    }
    let input = input.transpose()?;
    let seconds_read = t.elapsed().as_secs_f64();
    let whole = input.as_ref().map(|(m, bc)| (m, bc));
    let d = Deformer::from_root(&world, whole, &opts)
        .with_context(|| format!("{}", args.mesh.display()))?
        .coarse_parts(args.coarse_parts);
    let out = d
        .deform()
        .with_context(|| format!("{}", args.mesh.display()))?;
    let gathered = d.gather(&out.coords);
    let written = match (input, gathered) {
        (Some((m, _)), Some(coords)) => {
            write(args, format, m, coords, &out.report, seconds_read, t_all)
        }
        _ => Ok(()),
    };
    if !all_ok(&world, written.is_ok()) {
        written?;
        bail!(
            "{}: rank 0 could not write the output",
            args.output.display()
        );
    }
    Ok(())
}

fn write(
    args: &DeformArgs,
    format: mesh::io::Format,
    m: mesh::Mesh,
    coords: Vec<[f64; 3]>,
    rep: &distributed::DistReport,
    seconds_read: f64,
    t_all: Instant,
) -> anyhow::Result<()> {
    let t = Instant::now();
    let before = mesh::quality::summary(&mesh::quality::cell_quality(&m));
    let after = mesh::quality::summary(&mesh::quality::cell_quality_at(&m, &coords));
    let mut out = m;
    out.coords = coords;
    aeroshape::fsio::write_atomic(&args.output, |w| mesh::io::write(&out, format, w))?;
    if let Some(path) = &args.report {
        let r = Report {
            input: args.mesh.display().to_string(),
            output: args.output.display().to_string(),
            cells: out.cells.len(),
            quality_before: before,
            quality_after: after,
            seconds_read,
            seconds_write: t.elapsed().as_secs_f64(),
            seconds_total: t_all.elapsed().as_secs_f64(),
            distributed: rep,
        };
        aeroshape::fsio::write_atomic(path, |w| {
            serde_json::to_writer_pretty(&mut *w, &r).map_err(std::io::Error::other)?;
            writeln!(w)
        })?;
    }
    Ok(())
}
