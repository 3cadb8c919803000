//! The distributed deformation on a partition given by the caller, as a CFD solver hands
//! it over: every rank makes the wing-in-box grid, cuts it by coordinate bisection, keeps its
//! own part and deforms it with `deform::distributed::Deformer::new`; rank 0 then compares
//! the gathered grid with the serial `deform::deform`.
//!
//! `mpirun -n N distributed [CELLS] [ok|missing-ghost|duplicate-id]`: `missing-ghost` drops a
//! ghost node (and its cells) from rank 1's part, `duplicate-id` gives rank 1's first owned
//! node the global id of rank 0's; both must fail on every rank with one clear line and exit
//! status 1, never hang. Prints `max deviation ... relative` and fails when it exceeds 1e-8.

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

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(20);
    let mode = args.get(2).map_or("ok", String::as_str);
    let universe = mpi::initialize().expect("MPI initialises");
    let world = universe.world();
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
        let (mut dev, mut disp) = (0.0f64, 0.0f64);
        for ((a, b), x0) in x.iter().zip(&serial.coords).zip(&whole.coords) {
            let d = (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt();
            let m = (0..3).map(|k| (b[k] - x0[k]).powi(2)).sum::<f64>().sqrt();
            dev = dev.max(d);
            disp = disp.max(m);
        }
        Ok(Some(dev / disp))
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
