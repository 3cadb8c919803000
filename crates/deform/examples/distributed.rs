//! The distributed deformation on a partition given by the caller, as a CFD solver hands
//! it over: every rank makes the wing-in-box grid, cuts it by coordinate bisection, keeps its
//! own part and deforms it with `deform::distributed::Deformer::new`; rank 0 then compares
//! the gathered grid with the serial `deform::deform`.
//!
//! `mpirun -n N distributed [CELLS] [ok|missing-ghost|duplicate-id]`: `missing-ghost` drops a
//! ghost node (and its cells) from rank 1's part, `duplicate-id` gives rank 1's first owned
//! node the global id of rank 0's; both must fail on every rank with one clear line and exit
//! status 1, never hang. Prints `max deviation ... relative` and fails when it exceeds 1e-8.
//!
//! `mpirun -n N distributed GRID.su2 [DEG]`: the same on a grid file, timed. Every rank reads
//! the grid and cuts it by METIS (the cut is the same on every rank), keeps its part and
//! deforms it: the markers `wing` and `fuselage` rotate by DEG degrees (2 by default) about
//! the axis through (5, 0, 0) along y, every other marker is fixed, `rel_tol` 1e-11. Rank 0
//! prints the seconds of `Deformer::new` and `deform` (largest over the ranks), then, once
//! the other ranks are done, those of the serial `deform::deform` of the whole grid on two
//! threads, and the deviation of the gathered result from it.

use std::process::ExitCode;

use deform::distributed::mpi::traits::*;
use deform::distributed::{Deformer, LocalGrid, mpi, rcb};
use deform::{BoundaryConditions, DeformOptions, MarkerRole};
use mesh::Mesh;

/// The part of rank `r` with local node `v` and its cells removed.
fn drop_node(g: &mut LocalGrid, v: u32) {
    let mut m = Mesh::new(g.mesh.dim);
    m.coords = g.mesh.coords.clone();
    for (kind, e) in g.mesh.cells.iter() {
        if !e.contains(&v) {
            let e: Vec<u32> = e.iter().map(|&u| if u > v { u - 1 } else { u }).collect();
            m.cells.push(kind, &e, None);
        }
    }
    m.coords.remove(v as usize);
    g.global_ids.remove(v as usize);
    g.mesh = m;
}

/// The largest distance of `x` from `serial` over the largest displacement of `serial`
/// from `x0`.
fn deviation(x: &[[f64; 3]], serial: &[[f64; 3]], x0: &[[f64; 3]]) -> f64 {
    let dist =
        |a: &[f64; 3], b: &[f64; 3]| (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt();
    let (mut dev, mut disp) = (0.0f64, 0.0f64);
    for ((a, b), c) in x.iter().zip(serial).zip(x0) {
        dev = dev.max(dist(a, b));
        disp = disp.max(dist(b, c));
    }
    dev / disp
}

/// The timed run on the grid file `path` (see the module's doc).
fn from_file(world: &deform::distributed::Comm, path: &str, deg: f64) -> ExitCode {
    use std::time::Instant;
    let (rank, size) = (world.rank(), world.size() as usize);
    let whole = match mesh::io::read_path(std::path::Path::new(path)) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("error: {path}: {e}");
            return ExitCode::from(1);
        }
    };
    let motion = deform::RigidMotion {
        angle_deg: deg,
        axis_point: [5.0, 0.0, 0.0],
        axis_dir: [0.0, 1.0, 0.0],
        translation: [0.0; 3],
    };
    let bc = BoundaryConditions {
        markers: ["wing", "fuselage"]
            .map(|m| (m.to_string(), MarkerRole::Rigid(motion)))
            .to_vec(),
        displacements: Vec::new(),
    };
    let opts = DeformOptions {
        rel_tol: 1e-11,
        ..DeformOptions::default()
    };
    let cut =
        deform::distributed::metis::cut(&whole, size, deform::distributed::Partitioner::Metis);
    let grid = rcb::parts(&whole, &cut.part, size).swap_remove(rank as usize);
    world.barrier();
    let largest = |t: f64| {
        let mut m = 0.0;
        world.all_reduce_into(&t, &mut m, mpi::collective::SystemOperation::max());
        m
    };
    // The seconds of Deformer::new and deform together, and the gathered grid on rank 0.
    let run = || -> deform::Result<Option<(f64, Vec<[f64; 3]>)>> {
        let t = Instant::now();
        let d = Deformer::new(world, grid, &bc, &opts)?;
        let t_new = largest(t.elapsed().as_secs_f64());
        let t = Instant::now();
        let out = d.deform()?;
        let t_deform = largest(t.elapsed().as_secs_f64());
        if rank == 0 {
            println!(
                "{size} ranks, given partition: {} nodes, {} + {} iterations, Deformer::new {t_new:.2} s, deform {t_deform:.2} s, together {:.2} s",
                out.report.nodes,
                out.report.iterations,
                out.report.rotation_iterations,
                t_new + t_deform
            );
        }
        Ok(d.gather(&out.coords).map(|x| (t_new + t_deform, x)))
    };
    let (t_dist, x) = match run() {
        Ok(Some(tx)) => tx,
        Ok(None) => {
            // Wait for rank 0's serial run asleep (a blocking barrier, or MPI's finalize,
            // would poll and take a core from its two threads).
            let mut req = world.immediate_barrier();
            while let Err(r) = req.test() {
                req = r;
                std::thread::sleep(std::time::Duration::from_millis(5));
            }
            return ExitCode::SUCCESS;
        }
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(1);
        }
    };
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build();
    let t = Instant::now();
    let serial = pool.map(|p| p.install(|| deform::deform(&whole, &bc, &opts)));
    let t_serial = t.elapsed().as_secs_f64();
    let serial = match serial {
        Ok(Ok(s)) => s,
        Ok(Err(e)) => {
            eprintln!("error: serial: {e}");
            return ExitCode::from(1);
        }
        Err(e) => {
            eprintln!("error: thread pool: {e}");
            return ExitCode::from(1);
        }
    };
    let rel = deviation(&x, &serial.coords, &whole.coords);
    world.immediate_barrier().wait();
    println!(
        "serial deform::deform, 2 threads: {} iterations, {t_serial:.2} s; distributed / serial {:.2}; max deviation from the serial result: {:.3e} relative",
        serial.report.iterations,
        t_dist / t_serial,
        rel
    );
    ExitCode::SUCCESS
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(20);
    let mode = args.get(2).map_or("ok", String::as_str);
    let universe = mpi::initialize().expect("MPI initialises");
    let world = universe.world();
    if let Some(path) = args
        .get(1)
        .filter(|a| a.ends_with(".su2") || a.ends_with(".msh"))
    {
        let deg = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(2.0);
        return from_file(&world, path, deg);
    }
    let (rank, size) = (world.rank(), world.size() as usize);
    let whole = deform::generate::wing_in_box(n);
    // The benchmark's wing pitch, with every other marker fixed (a sliding plane needs the
    // whole marker: the partition made on rank 0 has it, a given one has not).
    let serial_bc = deform::generate::wing_pitch_conditions();
    let bc = BoundaryConditions {
        markers: serial_bc
            .markers
            .iter()
            .filter(|m| matches!(m.1, MarkerRole::Rigid(_)))
            .cloned()
            .collect(),
        displacements: Vec::new(),
    };
    let opts = DeformOptions {
        rel_tol: 1e-12,
        ..DeformOptions::default()
    };
    let part = rcb(&whole.coords, size);
    let mut grid = deform::distributed::rcb::parts(&whole, &part, size).swap_remove(rank as usize);
    if rank == 1 {
        match mode {
            "missing-ghost" => {
                let v = grid.n_owned as u32;
                drop_node(&mut grid, v);
            }
            "duplicate-id" => {
                grid.global_ids[0] = (0..whole.n_nodes() as u64)
                    .find(|&g| part[g as usize] == 0)
                    .unwrap_or(0);
            }
            _ => {}
        }
    }
    let run = || -> deform::Result<Option<f64>> {
        let d = Deformer::new(&world, grid, &bc, &opts)?;
        let out = d.deform()?;
        if rank == 0 {
            println!(
                "{} ranks: {} nodes, {} iterations (R: {}), {} bytes per iteration, {} ghost nodes",
                size,
                out.report.nodes,
                out.report.iterations,
                out.report.rotation_iterations,
                out.report.bytes_per_iteration,
                out.report.ghost_nodes
            );
        }
        let Some(x) = d.gather(&out.coords) else {
            return Ok(None);
        };
        let serial = deform::deform(&whole, &bc, &opts)?;
        Ok(Some(deviation(&x, &serial.coords, &whole.coords)))
    };
    match run() {
        Ok(Some(rel)) => {
            println!("max deviation from the serial result: {rel:.3e} relative");
            if rel <= 1e-8 {
                ExitCode::SUCCESS
            } else {
                eprintln!("error: deviation {rel:.3e} exceeds 1e-8");
                ExitCode::from(1)
            }
        }
        Ok(None) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(1)
        }
    }
}
