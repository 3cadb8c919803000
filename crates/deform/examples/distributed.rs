//! The distributed deformation on a partition given by the caller, as a CFD solver hands
//! it over: every rank makes the wing-in-box grid, cuts it by coordinate bisection, keeps its
//! own part and deforms it with `deform::distributed::Deformer::new`; rank 0 then compares
//! the gathered grid with the serial `deform::deform`.
//!
//! `mpirun -n N distributed [CELLS] [ok|missing-ghost|duplicate-id]`: `missing-ghost` drops a
//! ghost node (and its cells) from rank 1's part, `duplicate-id` gives rank 1's first owned
//! node the global id of rank 0's; both must fail on every rank with one clear line and exit
//! status 1, never hang. Prints `max deviation ... relative` and fails when it exceeds 1e-8.
//! In `ok` mode, the report's far field must be the serial one, and a second set-up with a
//! reach of R (each owner finding the moving boundary among its nodes) must lie within 1e-8
//! of the serial result with the same reach, which must differ from the full R's.
//!
//! `mpirun -n N distributed CELLS reuse`: one set-up, two designs, as an optimiser's loop
//! has them: the wing's nodes displaced (a pitch of -2°, then of -5°, as node
//! displacements), every other marker fixed. On the partition made on rank 0 and on a given
//! one, the second design through `Deformer::deform_with` on the first design's set-up
//! must equal a new set-up's result bit for bit, differ from the first design, and lie
//! within 1e-8 of the serial result; a list of the wrong length must fail on every rank.
//! Warm started (`Deformer::deform_from`) from the second design, a third one near it (a
//! pitch of -5.1°) must lie within 1e-8 of its cold start in fewer iterations, the same
//! design again from it must take no iteration, and a warm start given on rank 0 alone must
//! fail on every rank.
//!
//! `mpirun -n N distributed GRID.su2 [DEG]`: the same on a grid file, timed. Every rank reads
//! the grid and cuts it by METIS (the cut is the same on every rank), keeps its part and
//! deforms it: the markers `wing` and `fuselage` rotate by DEG degrees (2 by default) about
//! the axis through (5, 0, 0) along y, every other marker is fixed, `rel_tol` 1e-11. Rank 0
//! prints the seconds of `Deformer::new`, `deform` and a second `deform` on the same set-up
//! (an optimiser's next design; largest over the ranks), then, once the other ranks are
//! done, those of the serial `deform::Deformer::new` and `deform` of the whole grid on two
//! threads, and the deviation of the gathered result from the serial one.
//!
//! `mpirun -n N distributed GRID.su2 DEG warm`: an optimiser's step on a grid file. The
//! partition made as above; the nodes of `wing` and `fuselage` displaced by the pitch of
//! DEG degrees (node displacements, so that a design changes them), every other marker
//! fixed. Rank 0 prints the seconds and iterations of the first design, of a design 5 %
//! further (pitch 1.05 DEG) from zero (`deform_with`) and from the first design's
//! solutions (`deform_from`), and the deviation of the two, relative to the largest
//! displacement.

use std::process::ExitCode;

use deform::distributed::mpi::traits::*;
use deform::distributed::{Deformer, LocalGrid, mpi, rcb};
use deform::{BoundaryConditions, DeformOptions, MarkerRole};
use mesh::Mesh;

/// The reach of R of the `ok` mode's second run (the wing-in-box's chord is 1).
const REACH: f64 = 0.5;

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

/// The largest distance between two node lists.
fn gap(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    let dist =
        |p: &[f64; 3], q: &[f64; 3]| (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt();
    a.iter().zip(b).map(|(p, q)| dist(p, q)).fold(0.0, f64::max)
}

/// The largest distance of `x` from `serial` over the largest displacement of `serial`
/// from `x0`.
fn deviation(x: &[[f64; 3]], serial: &[[f64; 3]], x0: &[[f64; 3]]) -> f64 {
    gap(x, serial) / gap(serial, x0)
}

/// The largest of `t` over the ranks.
fn largest(world: &deform::distributed::Comm, t: f64) -> f64 {
    let mut m = 0.0;
    world.all_reduce_into(&t, &mut m, mpi::collective::SystemOperation::max());
    m
}

/// The iterations of a result: Eq. 21's and Eq. 26's.
fn iterations(o: &deform::distributed::DistDeformed) -> (usize, usize) {
    (o.report.iterations, o.report.rotation_iterations)
}

/// The grid file `path`, read on every rank, and this rank's part of METIS's cut of it
/// (the same cut on every rank).
fn read_part(world: &deform::distributed::Comm, path: &str) -> Result<(Mesh, LocalGrid), String> {
    let whole =
        mesh::io::read_path(std::path::Path::new(path)).map_err(|e| format!("{path}: {e}"))?;
    let size = world.size() as usize;
    let cut =
        deform::distributed::metis::cut(&whole, size, deform::distributed::Partitioner::Metis);
    let grid = rcb::parts(&whole, &cut.part, size).swap_remove(world.rank() as usize);
    Ok((whole, grid))
}

/// The `warm` mode on a grid file (see the module's doc); errors are one line.
fn warm_file(world: &deform::distributed::Comm, path: &str, deg: f64) -> Result<(), String> {
    use std::time::Instant;
    let size = world.size() as usize;
    let (whole, grid) = read_part(world, path)?;
    // The owned nodes of the moving markers, in local numbering, and their pitch.
    let mut nodes: Vec<u32> = ["wing", "fuselage"]
        .iter()
        .filter_map(|m| grid.mesh.marker(m))
        .flat_map(|m| m.elements.node_set())
        .filter(|&v| (v as usize) < grid.n_owned)
        .collect();
    nodes.sort_unstable();
    nodes.dedup();
    let pitch = |deg: f64| -> Vec<[f64; 3]> {
        let motion = deform::RigidMotion {
            angle_deg: deg,
            axis_point: [5.0, 0.0, 0.0],
            axis_dir: [0.0, 1.0, 0.0],
            translation: [0.0; 3],
        };
        nodes
            .iter()
            .map(|&v| {
                let p = grid.mesh.coords[v as usize];
                let q = motion.apply(p, 1.0);
                [q[0] - p[0], q[1] - p[1], q[2] - p[2]]
            })
            .collect()
    };
    let bc = BoundaryConditions {
        markers: Vec::new(),
        displacements: nodes.iter().copied().zip(pitch(deg)).collect(),
    };
    let opts = DeformOptions {
        rel_tol: 1e-11,
        ..DeformOptions::default()
    };
    let e = |e: deform::Error| e.to_string();
    let near = pitch(1.05 * deg);
    let d = Deformer::new(world, grid.clone(), &bc, &opts).map_err(e)?;
    let timed = |f: &dyn Fn() -> deform::Result<deform::distributed::DistDeformed>| {
        let t = Instant::now();
        let out = f().map_err(e)?;
        Ok::<_, String>((largest(world, t.elapsed().as_secs_f64()), out))
    };
    let (t1, first) = timed(&|| d.deform())?;
    let (t_cold, cold) = timed(&|| d.deform_with(Some(&near)))?;
    let (t_warm, warm) = timed(&|| d.deform_from(Some(&near), Some(&first)))?;
    let (xc, xw) = (d.gather(&cold.coords), d.gather(&warm.coords));
    if let (Some(xc), Some(xw)) = (xc, xw) {
        let dev = deviation(&xw, &xc, &whole.coords);
        println!(
            "{size} ranks, warm start on {} nodes: first design {t1:.2} s {:?}; design 5 % further from zero {t_cold:.2} s {:?}, from the first's solutions {t_warm:.2} s {:?}; deviation {dev:.3e}",
            first.report.nodes,
            iterations(&first),
            iterations(&cold),
            iterations(&warm)
        );
    }
    Ok(())
}

/// The timed run on the grid file `path` (see the module's doc).
fn from_file(world: &deform::distributed::Comm, path: &str, deg: f64) -> ExitCode {
    use std::time::Instant;
    let (rank, size) = (world.rank(), world.size() as usize);
    let (whole, grid) = match read_part(world, path) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("error: {e}");
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
    world.barrier();
    // The seconds of Deformer::new and deform together, and the gathered grid on rank 0.
    let run = || -> deform::Result<Option<(f64, Vec<[f64; 3]>)>> {
        let t = Instant::now();
        let d = Deformer::new(world, grid, &bc, &opts)?;
        let t_new = largest(world, t.elapsed().as_secs_f64());
        let t = Instant::now();
        let out = d.deform()?;
        let t_deform = largest(world, t.elapsed().as_secs_f64());
        let t = Instant::now();
        d.deform_with(None)?;
        let t_again = largest(world, t.elapsed().as_secs_f64());
        if rank == 0 {
            println!(
                "{size} ranks, given partition: {} nodes, {} + {} iterations, Deformer::new {t_new:.2} s, deform {t_deform:.2} s, together {:.2} s; deform again on the set-up {t_again:.2} s",
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
    let mut t_serial = [0.0; 2];
    let serial = pool.map(|p| {
        p.install(|| {
            let t = Instant::now();
            let d = deform::Deformer::new(&whole, &bc, &opts)?;
            t_serial[0] = t.elapsed().as_secs_f64();
            let t = Instant::now();
            let out = d.deform(&[], None);
            t_serial[1] = t.elapsed().as_secs_f64();
            out
        })
    });
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
    let [t_new, t_deform] = t_serial;
    println!(
        "serial, 2 threads: {} iterations, Deformer::new {t_new:.2} s, deform {t_deform:.2} s, together {:.2} s; distributed / serial {:.2}; max deviation from the serial result: {:.3e} relative",
        serial.report.iterations,
        t_new + t_deform,
        t_dist / (t_new + t_deform),
        rel
    );
    ExitCode::SUCCESS
}

/// The wing's nodes of `whole` and their displacements for a pitch of `deg` degrees about
/// the benchmark's axis.
fn wing_pitch(whole: &Mesh, deg: f64) -> Vec<(u32, [f64; 3])> {
    let motion = deform::RigidMotion {
        angle_deg: deg,
        axis_point: [1.75, 0.0, 2.0],
        axis_dir: [0.0, 1.0, 0.0],
        translation: [0.0; 3],
    };
    let mut nodes: Vec<u32> = whole
        .marker("wing")
        .map(|m| m.elements.node_set().into_iter().collect())
        .unwrap_or_default();
    nodes.sort_unstable();
    nodes
        .into_iter()
        .map(|v| {
            let p = whole.coords[v as usize];
            let q = motion.apply(p, 1.0);
            (v, [q[0] - p[0], q[1] - p[1], q[2] - p[2]])
        })
        .collect()
}

/// The `reuse` mode (see the module's doc); errors are one line.
fn reuse(world: &deform::distributed::Comm, n: usize) -> Result<(), String> {
    let (rank, size) = (world.rank(), world.size() as usize);
    let whole = deform::generate::wing_in_box(n);
    let opts = DeformOptions {
        rel_tol: 1e-12,
        ..DeformOptions::default()
    };
    let bc = |d: Vec<(u32, [f64; 3])>| BoundaryConditions {
        markers: Vec::new(),
        displacements: d,
    };
    let (d1, d2) = (wing_pitch(&whole, -2.0), wing_pitch(&whole, -5.0));
    let values2: Vec<[f64; 3]> = d2.iter().map(|d| d.1).collect();
    let (bc1, bc2) = (bc(d1.clone()), bc(d2.clone()));
    let e = |e: deform::Error| e.to_string();
    let root = rank == 0;
    // Made on rank 0.
    let on_root = |b| root.then_some((&whole, b));
    let set_up = Deformer::from_root(world, on_root(&bc1), &opts).map_err(e)?;
    let first = set_up.deform().map_err(e)?;
    let second = set_up.deform_with(Some(&values2)).map_err(e)?;
    let fresh = Deformer::from_root(world, on_root(&bc2), &opts).map_err(e)?;
    let new = fresh.deform().map_err(e)?;
    let wrong = set_up.deform_with(Some(&values2[1..]));
    match wrong {
        Err(err) if err.to_string().contains("displacements given for the") => {}
        Err(err) => return Err(format!("wrong count: unexpected error: {err}")),
        Ok(_) => return Err(format!("rank {rank}: a list of the wrong length was taken")),
    }
    if second.report.deformations != 2 {
        return Err(format!(
            "the reused set-up counts {} deformations, not 2",
            second.report.deformations
        ));
    }
    let values3: Vec<[f64; 3]> = wing_pitch(&whole, -5.1).iter().map(|d| d.1).collect();
    let cold = set_up.deform_with(Some(&values3)).map_err(e)?;
    let warm = set_up
        .deform_from(Some(&values3), Some(&second))
        .map_err(e)?;
    let again = set_up.deform_from(Some(&values3), Some(&warm)).map_err(e)?;
    let (cold_it, warm_it, again_it) = (iterations(&cold), iterations(&warm), iterations(&again));
    if size > 1 {
        let one = set_up.deform_from(Some(&values2), root.then_some(&first));
        match one {
            Err(err) if err.to_string().contains("warm start and others none") => {}
            Err(err) => return Err(format!("warm start on one rank: unexpected error: {err}")),
            Ok(_) => {
                return Err(format!(
                    "rank {rank}: a warm start on rank 0 alone was taken"
                ));
            }
        }
    }
    let warm_x = set_up.gather(&warm.coords).zip(set_up.gather(&cold.coords));
    let made = [&first, &second, &new].map(|o| set_up.gather(&o.coords));
    // Given: each rank its part, its owned wing nodes' displacements in local numbering.
    let part = rcb(&whole.coords, size);
    let grid = deform::distributed::rcb::parts(&whole, &part, size).swap_remove(rank as usize);
    let local_bc = |d: &[(u32, [f64; 3])]| {
        let at: std::collections::HashMap<u64, u32> = grid.global_ids[..grid.n_owned]
            .iter()
            .enumerate()
            .map(|(i, &g)| (g, i as u32))
            .collect();
        bc(d.iter()
            .filter_map(|&(v, x)| at.get(&u64::from(v)).map(|&i| (i, x)))
            .collect())
    };
    let (g1, g2) = (local_bc(&d1), local_bc(&d2));
    let own2: Vec<[f64; 3]> = g2.displacements.iter().map(|d| d.1).collect();
    let set_up = Deformer::new(world, grid.clone(), &g1, &opts).map_err(e)?;
    let reused = set_up.deform_with(Some(&own2)).map_err(e)?;
    let fresh = Deformer::new(world, grid, &g2, &opts).map_err(e)?;
    let new_given = fresh.deform().map_err(e)?;
    let given = [&reused, &new_given].map(|o| set_up.gather(&o.coords));
    let ([Some(x1), Some(x2), Some(xn)], [Some(g2), Some(gn)], Some((xw, xc))) =
        (made, given, warm_x)
    else {
        return Ok(());
    };
    let serial = deform::deform(&whole, &bc2, &opts).map_err(e)?;
    let x0 = &whole.coords;
    let (made_gap, given_gap) = (gap(&x2, &xn), gap(&g2, &gn));
    let moved = gap(&x1, &x2);
    let dev = [&x2, &g2].map(|x| deviation(x, &serial.coords, x0));
    let warm_dev = deviation(&xw, &xc, x0);
    println!(
        "{size} ranks, warm start: third design {warm_dev:.3e} from its cold start, iterations (Eq. 21, Eq. 26) {warm_it:?} against {cold_it:?} cold; the same design again {again_it:?}"
    );
    if warm_dev.is_nan() || warm_dev > 1e-8 {
        return Err(format!(
            "the warm-started design is {warm_dev:.3e} from the cold one"
        ));
    }
    if warm_it.0 + warm_it.1 >= cold_it.0 + cold_it.1 {
        return Err(format!(
            "the warm start took {warm_it:?} iterations, the cold start {cold_it:?}"
        ));
    }
    if again_it != (0, 0) {
        return Err(format!(
            "the same design again took {again_it:?} iterations"
        ));
    }
    println!(
        "{size} ranks, reuse: made on rank 0: second design {made_gap:.3e} from a new set-up, {:.3e} from serial, {moved:.3e} from the first; given: {given_gap:.3e} from a new set-up, {:.3e} from serial; a list of the wrong length refused on every rank",
        dev[0], dev[1]
    );
    if made_gap != 0.0 || given_gap != 0.0 {
        return Err("the reused set-up's result differs from a new set-up's".into());
    }
    if moved == 0.0 {
        return Err("the second design did not move the grid from the first".into());
    }
    if !(dev[0] <= 1e-8 && dev[1] <= 1e-8) {
        return Err(format!("deviation from serial {dev:?} exceeds 1e-8"));
    }
    Ok(())
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
        if args.get(3).is_some_and(|m| m == "warm") {
            return match warm_file(&world, path, deg) {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => {
                    eprintln!("error: {e}");
                    ExitCode::from(1)
                }
            };
        }
        return from_file(&world, path, deg);
    }
    if mode == "reuse" {
        return match reuse(&world, n) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::from(1)
            }
        };
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
        let d = Deformer::new(&world, grid.clone(), &bc, &opts)?;
        let out = d.deform()?;
        // The reach of R on the given part: the moving boundary found by each owner.
        let reach = DeformOptions {
            rotation_reach: Some(REACH),
            ..opts
        };
        let near = Deformer::new(&world, grid, &bc, &reach)?.deform()?;
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
        let near_x = d.gather(&near.coords);
        let Some(x) = d.gather(&out.coords) else {
            return Ok(None);
        };
        let serial = deform::deform(&whole, &bc, &opts)?;
        let serial_near = deform::deform(&whole, &bc, &reach)?;
        let near_x = near_x.unwrap_or_default();
        let near_dev = deviation(&near_x, &serial_near.coords, &whole.coords);
        let effect = gap(&serial_near.coords, &serial.coords) / gap(&serial.coords, &whole.coords);
        let (fd, fs) = (out.report.far_field, serial.report.far_field);
        println!(
            "reach of R {REACH}: {near_dev:.3e} from serial (the reach moves the serial grid by {effect:.3e}); \
             far field {fd:?}, serial {fs:?}"
        );
        let far = fd.is_some_and(|f| {
            (f.distance, f.nodes, f.node) == (fs.distance, fs.nodes, fs.node)
                && (f.max_displacement - fs.max_displacement).abs()
                    <= 1e-8 * fs.wall_max_displacement
        });
        if !(near_dev <= 1e-8 && effect > 1e-6 && far && fs.nodes > 0) {
            eprintln!("error: the reach of R or the far field differ from serial");
            return Ok(Some(f64::INFINITY));
        }
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
