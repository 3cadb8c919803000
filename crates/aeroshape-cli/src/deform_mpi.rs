//! `mpirun -n N aeroshape deform ...` (cargo feature `mpi`): the same flags as the serial
//! command; rank 0 reads the grid, every rank the geometry of `--geometry` (the nodes
//! sliding on its supports are iterated by their owners), the deformation runs distributed
//! (`deform::distributed`, the partition made on rank 0), and rank 0 writes the gathered
//! grid in one file (and the report), or, for an output `NAME.pvtu`, every rank writes its
//! piece `NAME/NAME_<rank>.vtu` and rank 0 the index naming them. Every rank reports an
//! error, and exits 1, alike.

use std::time::Instant;

use anyhow::{Context, bail};
use deform::distributed::{self, Deformer, all_ok, mpi};
use deform::{BoundaryConditions, Request, Support, Supports};
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
    /// The whole grid's cell quality before and after, summarised over the ranks.
    quality_before: mesh::quality::Summary,
    quality_after: mesh::quality::Summary,
    /// The pieces of a `.pvtu` output.
    pieces: Vec<String>,
    seconds_read: f64,
    seconds_write: f64,
    seconds_total: f64,
    distributed: &'a distributed::DistReport,
}

/// The grid, the boundary conditions and the supports of the grid's classified nodes on
/// `geometry` (when given), read on rank 0: the request's, with the displacements of the
/// flags on this grid (as the serial command makes them).
type Input = (mesh::Mesh, BoundaryConditions, Vec<(u32, Support)>);

/// Reads the grid and makes the boundary conditions on rank 0 (see [`Input`]).
fn read(
    args: &DeformArgs,
    request: &Request,
    geometry: Option<&geom_db::GeomDb>,
) -> anyhow::Result<Input> {
    let m = mesh::io::read_path(&args.mesh)?;
    let supports = geometry
        .map(|db| Supports::from_classes(&m, db))
        .transpose()?;
    let mut request = request.clone();
    add_displacements(args, &m, &mut request)?;
    crate::deform::slide_symmetry_planes(args, &m, &mut request)?;
    let bc = request.boundary_conditions(&m, supports.as_ref());
    Ok((m, bc, supports.map_or_else(Vec::new, |s| s.nodes)))
}

/// The geometry of `--geometry`, read on every rank (it is small).
fn read_geometry(path: &std::path::Path) -> anyhow::Result<geom_db::GeomDb> {
    let text = std::fs::read_to_string(path).with_context(|| format!("{}", path.display()))?;
    Ok(geom_db::GeomDb::from_ron_str(
        &text,
        &path.display().to_string(),
    )?)
}

/// Runs the distributed deformation of `request` (its displacements made on rank 0 from the
/// flags) on the world communicator.
///
/// A failure is printed here by every rank, in one write, and the ranks then wait for each
/// other before MPI is finalised and they exit (once one rank exits 1, mpirun kills the
/// others); the error returned is then [`Reported`].
pub fn run(args: &DeformArgs, request: Request) -> anyhow::Result<()> {
    let t_all = Instant::now();
    let universe = mpi::initialize().context("MPI could not be initialised")?;
    let world = universe.world();
    deform_on(&world, args, request, t_all).map_err(|e| reported(&world, &e))
}

/// Prints the failure `e` of this rank in one write, waits for the other ranks (which
/// print theirs), and gives [`Reported`]: the ranks agree on a failure before any blocking
/// exchange, so every rank comes here, and none exits (after which mpirun kills the
/// others) before all have printed.
pub fn reported(world: &distributed::Comm, e: &anyhow::Error) -> anyhow::Error {
    // One write of the whole line: the ranks' lines share mpirun's stderr, and
    // `eprintln!` writes the pieces of its format separately (they interleaved).
    let line = format!("error: {}\n", crate::one_line(e));
    let _ = std::io::Write::write_all(&mut std::io::stderr(), line.as_bytes());
    world.barrier();
    Reported.into()
}

/// An error every rank has already printed: the program exits 1 without printing it again.
#[derive(Debug)]
pub struct Reported;

impl std::fmt::Display for Reported {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("the error was printed by every rank")
    }
}

impl std::error::Error for Reported {}

/// [`run`] on the world communicator `world`.
fn deform_on(
    world: &distributed::Comm,
    args: &DeformArgs,
    request: Request,
    t_all: Instant,
) -> anyhow::Result<()> {
    let opts = request.options();
    let format =
        if pieces(&args.output) {
            None
        } else {
            Some(mesh::io::Format::from_path(&args.output).ok_or_else(|| {
                anyhow::anyhow!("{}: unknown output format", args.output.display())
            })?)
        };
    let t = Instant::now();
    let geometry = args.geometry.as_deref().map(read_geometry).transpose();
    if !all_ok(world, geometry.is_ok()) {
        geometry?;
        bail!(
            "{}: another rank could not read the geometry",
            args.geometry
                .as_deref()
                .unwrap_or(args.mesh.as_path())
                .display()
        );
    }
    let geometry = geometry?;
    let input = distributed::on_root(world, || read(args, &request, geometry.as_ref()));
    // Every rank reports rank 0's error, so that all print the same line.
    let input = input.transpose();
    if let Some((_, e)) = distributed::first_failure(world, &input, |e| {
        format!("{}: {}", args.mesh.display(), crate::one_line(e))
    }) {
        bail!("{e}");
    }
    let input = input?;
    let seconds_read = t.elapsed().as_secs_f64();
    let d = match &geometry {
        Some(db) => {
            let whole = input.as_ref().map(|(m, bc, s)| (m, bc, &s[..]));
            Deformer::from_root_on_supports(world, db, whole, &opts, args.partition)
        }
        None => {
            let whole = input.as_ref().map(|(m, bc, _)| (m, bc));
            Deformer::from_root_with(world, whole, &opts, args.partition)
        }
    }
    .with_context(|| format!("{}", args.mesh.display()))?
    .coarse_parts(args.coarse_parts);
    let out = d
        .deform()
        .with_context(|| format!("{}", args.mesh.display()))?;
    let written = match format {
        Some(format) => {
            let gathered = d.gather(&out.coords);
            let supports = d.gather_supports(&out);
            let (quality, dist) = (out.quality, &out.report);
            distributed::on_root(world, move || match (input, gathered) {
                (Some((m, _, _)), Some(coords)) => {
                    let t = Instant::now();
                    let mut m = m;
                    m.coords = coords;
                    put_parameters(&mut m, supports.as_deref().unwrap_or_default());
                    crate::mesh::write_grid(&m, format, &args.output)
                        .and_then(|()| {
                            report(
                                args,
                                &m,
                                quality,
                                Vec::new(),
                                dist,
                                [seconds_read, t.elapsed().as_secs_f64()],
                                t_all,
                            )
                        })
                        .and_then(|()| summary(m.cells.len(), dist, quality, &args.output))
                }
                _ => Ok(()),
            })
            .unwrap_or(Ok(()))
        }
        None => write_pieces(world, &d, &out.coords, args).and_then(|sources| match &input {
            Some((m, _, _)) => {
                let t = Instant::now();
                aeroshape::fsio::write_atomic(&args.output, |w| {
                    mesh::pvtu::write(&sources, true, w)
                })?;
                report(
                    args,
                    m,
                    out.quality,
                    sources,
                    &out.report,
                    [seconds_read, t.elapsed().as_secs_f64()],
                    t_all,
                )?;
                summary(m.cells.len(), &out.report, out.quality, &args.output)
            }
            None => Ok(()),
        }),
    };
    if !all_ok(world, written.is_ok()) {
        written?;
        bail!(
            "{}: rank 0 could not write the output",
            args.output.display()
        );
    }
    Ok(())
}

/// Puts the sliding nodes' new parameters into the grid's classification, as the serial
/// command does (`deform::request::apply`).
fn put_parameters(m: &mut mesh::Mesh, supports: &[(u64, Support)]) {
    if let Some(classes) = m.classes.as_mut() {
        for &(v, s) in supports {
            let Some(c) = classes.get_mut(v as usize) else {
                continue;
            };
            match s {
                Support::Curve { t, .. } => c.param = [t, 0.0],
                Support::Surface { uv, .. } => c.param = uv,
                Support::Corner => {}
            }
        }
    }
}

/// True when `path` names a grid in pieces (`.pvtu`).
pub fn pieces(path: &std::path::Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("pvtu"))
}

/// Every rank writes its piece `DIR/NAME/NAME_<rank>.vtu` of the output `DIR/NAME.pvtu`
/// (the nodes it holds, the cells and boundary elements it counts; point data the
/// displacement); returns the pieces' paths relative to DIR once every rank has written
/// its own (collective).
fn write_pieces(
    world: &distributed::Comm,
    d: &Deformer<'_>,
    coords: &[[f64; 3]],
    args: &DeformArgs,
) -> anyhow::Result<Vec<String>> {
    let stem = args
        .output
        .file_stem()
        .and_then(|s| s.to_str())
        .ok_or_else(|| anyhow::anyhow!("{}: no file name", args.output.display()))?
        .to_string();
    let dir = args.output.with_extension("");
    let source = |r: i32| format!("{stem}/{stem}_{r}.vtu");
    let mine = (|| -> anyhow::Result<()> {
        std::fs::create_dir_all(&dir).with_context(|| format!("{}", dir.display()))?;
        let (piece, displacement) = d.piece(coords);
        let opts = mesh::vtu::VtuOptions::default().with_displacement(&displacement);
        let path = dir.join(format!("{stem}_{}.vtu", world.rank()));
        aeroshape::fsio::write_atomic(&path, |w| mesh::vtu::write(&piece, &opts, w))
            .with_context(|| format!("{}", path.display()))
    })();
    if !all_ok(world, mine.is_ok()) {
        mine?;
        bail!(
            "{}: another rank could not write its piece",
            args.output.display()
        );
    }
    Ok((0..world.size()).map(source).collect())
}

/// The summary printed by rank 0 on success, as the serial command's: sizes, ranks and
/// partition, solver work, cell quality before and after, the far field, the file written.
fn summary(
    cells: usize,
    r: &distributed::DistReport,
    q: [mesh::quality::Summary; 2],
    output: &std::path::Path,
) -> anyhow::Result<()> {
    outln!(
        "{} nodes, {cells} cells on {} ranks ({}, {} ghost nodes, unknowns {:.3} of the mean on the busiest); {} iterations ({} for R) in {} increment(s), residual {:.1e}",
        r.nodes,
        r.ranks,
        r.partitioner,
        r.ghost_nodes,
        r.imbalance,
        r.iterations,
        r.rotation_iterations,
        r.increments,
        r.residual
    );
    crate::deform::print_tail([&q[0], &q[1]], r.far_field.as_ref(), None, output)?;
    Ok(())
}

/// The report (rank 0), when asked for.
fn report(
    args: &DeformArgs,
    m: &mesh::Mesh,
    quality: [mesh::quality::Summary; 2],
    pieces: Vec<String>,
    rep: &distributed::DistReport,
    [seconds_read, t_write]: [f64; 2],
    t_all: Instant,
) -> anyhow::Result<()> {
    let Some(path) = &args.report else {
        return Ok(());
    };
    let r = Report {
        input: args.mesh.display().to_string(),
        output: args.output.display().to_string(),
        cells: m.cells.len(),
        quality_before: quality[0],
        quality_after: quality[1],
        pieces,
        seconds_read,
        seconds_write: t_write,
        seconds_total: t_all.elapsed().as_secs_f64(),
        distributed: rep,
    };
    aeroshape::fsio::write_atomic(path, |w| {
        serde_json::to_writer_pretty(&mut *w, &r).map_err(std::io::Error::other)?;
        writeln!(w)
    })?;
    Ok(())
}
