//! Benchmarks of `deform`: SpMV against a STREAM-triad bandwidth measured in the same run,
//! PCG (Jacobi and multigrid) on the spring system, and the whole deformation of a
//! wing-like block in a box pitched by 5° with the symmetry plane sliding and the far field
//! fixed, at ~50k, ~300k and ~1M nodes.
//!
//! `cargo bench -p deform --bench deform` runs the criterion groups on the 50k grid and, first,
//! prints a table of figures for the sizes in `DEFORM_BENCH_SIZES` (cubes per side, default
//! "46,84" for ~50k and ~300k nodes; add 126 for ~1M nodes). The linear systems are solved
//! with the unknowns in `deform`'s internal order; `DEFORM_BENCH_ORDERS` also prints the
//! SpMV with the unknowns in other orders (generator, Morton, Morton + RCM).
//! `DEFORM_AMG_CYCLES`, `DEFORM_AMG_STRENGTH` and `DEFORM_AMG_DAMPING=cS,cP` override the
//! multigrid options of the solve figures; `DEFORM_BENCH_NO_JACOBI` skips the Jacobi-PCG
//! solve and `DEFORM_BENCH_SOLVES_ONLY` the whole deformations; `DEFORM_BENCH_SETUP_REPS=N`
//! times N multigrid set-ups in a row instead of the solves; `DEFORM_BENCH_TRACE` prints the
//! seconds of every set-up step of the whole deformations and of every multigrid level.
//! `DEFORM_BENCH_LINEARISE` runs the linearisation's figures and group instead (module
//! `linearise`).

mod linearise;

use std::hint::black_box;
use std::time::Instant;

use criterion::{Criterion, Throughput};
use deform::solve::{Amg, AmgOptions};
use deform::{BoundaryConditions, DeformOptions, MarkerRole, SolverKind, deform};
use mesh::Mesh;
use rayon::prelude::*;
use sparse::order;
use sparse::{Constraints, Entry, Jacobi, SolveOptions, SymMatrix, V3, pcg};

/// The wing-like case ([`deform::generate::wing_in_box`], pitched 5°).
fn case(n: usize) -> (Mesh, BoundaryConditions) {
    (
        deform::generate::wing_in_box(n),
        deform::generate::wing_pitch_conditions(),
    )
}

/// CPU seconds (user + system, all threads) of this process so far, from /proc/self/stat
/// (clock ticks of 1/100 s): on a machine shared with other jobs, CPU time / threads is the
/// wall time the run would take with the cores to itself.
fn cpu_s() -> f64 {
    std::fs::read_to_string("/proc/self/stat")
        .ok()
        .and_then(|s| {
            let rest = s.rsplit(')').next()?.split_whitespace().collect::<Vec<_>>();
            let u: f64 = rest.get(11)?.parse().ok()?;
            let k: f64 = rest.get(12)?.parse().ok()?;
            Some((u + k) / 100.0)
        })
        .unwrap_or(f64::NAN)
}

fn peak_rss_mb() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines().find(|l| l.starts_with("VmHWM:")).and_then(|l| {
                l.split_whitespace()
                    .nth(1)
                    .and_then(|v| v.parse::<f64>().ok())
            })
        })
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

/// The arrays of a STREAM triad a = b + s c over `len` 3-vectors.
struct Triad {
    a: Vec<V3>,
    b: Vec<V3>,
    c: Vec<V3>,
}

impl Triad {
    fn new(len: usize) -> Self {
        Self {
            a: vec![[0.0; 3]; len],
            b: (0..len).map(|i| [i as f64, 1.0, 2.0]).collect(),
            c: (0..len).map(|i| [1.0, i as f64, 3.0]).collect(),
        }
    }

    /// Bytes one pass moves (24 per 3-vector of each array, STREAM's count).
    fn bytes(&self) -> f64 {
        (self.a.len() * 3 * 24) as f64
    }

    /// Seconds of one pass.
    fn pass(&mut self) -> f64 {
        let t = Instant::now();
        self.a
            .par_chunks_mut(4096)
            .zip(self.b.par_chunks(4096).zip(self.c.par_chunks(4096)))
            .for_each(|(ca, (cb, cc))| {
                for ((x, y), z) in ca.iter_mut().zip(cb).zip(cc) {
                    for k in 0..3 {
                        x[k] = y[k] + 3.0 * z[k];
                    }
                }
            });
        let s = t.elapsed().as_secs_f64();
        black_box(&self.a);
        s
    }
}

/// STREAM triad over `len` 3-vectors; returns GB/s (best of 10 passes).
fn triad_gbs(len: usize) -> f64 {
    let mut t = Triad::new(len);
    let best = (0..10).map(|_| t.pass()).fold(f64::INFINITY, f64::min);
    t.bytes() / best / 1e9
}

/// The SpMV's bandwidth as a fraction of the triad's, from `pairs` alternated passes (one
/// triad pass, then one product): the ratio of each pair, sorted. Both passes of a pair see
/// the machine in the same state, so the ratios are steadier than the ratio of two bests
/// measured apart on a machine whose bandwidth drifts.
fn paired_ratios<T: Entry>(a: &SymMatrix<T>, triad: &mut Triad, pairs: usize) -> Vec<f64> {
    let x = spmv_input(a.n());
    let mut y = vec![[0.0; 3]; a.n()];
    // One pass of each first, untimed: the first touches fresh pages.
    triad.pass();
    a.mul(&x, &mut y);
    let mut ratios: Vec<f64> = (0..pairs)
        .map(|_| {
            let tt = triad.pass();
            let t = Instant::now();
            a.mul(&x, &mut y);
            let ts = t.elapsed().as_secs_f64();
            black_box(&y);
            (spmv_bytes(a) / ts) / (triad.bytes() / tt)
        })
        .collect();
    ratios.sort_by(f64::total_cmp);
    ratios
}

/// The vector the SpMV figures multiply (n entries, all distinct in x).
fn spmv_input(n: usize) -> Vec<V3> {
    (0..n).map(|i| [i as f64, 1.0, -1.0]).collect()
}

/// Bytes one SpMV moves at least: matrix (values, columns, offsets, diagonal), x once, y.
fn spmv_bytes<T: Entry>(a: &SymMatrix<T>) -> f64 {
    (a.nnz_offdiag() * (4 + std::mem::size_of::<T>()) + a.n() * (8 + 8 + 24 + 24)) as f64
}

fn spmv_gbs<T: Entry>(a: &SymMatrix<T>) -> f64 {
    let x = spmv_input(a.n());
    let mut y = vec![[0.0; 3]; a.n()];
    let mut best = f64::INFINITY;
    for _ in 0..10 {
        let t = Instant::now();
        a.mul(&x, &mut y);
        best = best.min(t.elapsed().as_secs_f64());
        black_box(&y);
    }
    spmv_bytes(a) / best / 1e9
}

/// The assembled Eq. 21 system of the case (matrix in solver order and right-hand side), via
/// a deformation with an iteration limit of 0 is not possible, so rebuild it here: the spring
/// matrix with K = 1/l² (rounded to f32, as the library stores it) on interior + sliding
/// nodes, RHS from the rigid motion of the wing.
fn system(m: &Mesh, bc: &BoundaryConditions) -> (SymMatrix<f32>, Vec<V3>) {
    // Use the library's own path: deform with the point iteration limited to 0 iterations
    // would error; instead assemble a plain Laplacian system with the same pattern.
    let adj = mesh::Adjacency::build(m);
    let n = m.n_nodes();
    let mut on = vec![0u8; n]; // 1 fixed, 2 moving
    for mk in &m.markers {
        let tag = if mk.name == "wing" {
            2
        } else if mk.name == "y_m" {
            0
        } else {
            1
        };
        for v in mk.elements.node_set() {
            on[v as usize] = on[v as usize].max(tag);
        }
    }
    let motion = match bc.markers[0].1 {
        MarkerRole::Rigid(r) => r,
        _ => unreachable!(),
    };
    let mut num = vec![u32::MAX; n];
    let mut cnt = 0u32;
    for i in 0..n {
        if on[i] == 0 {
            num[i] = cnt;
            cnt += 1;
        }
    }
    let x = &m.coords;
    let mut diag = Vec::new();
    let mut offsets = vec![0usize];
    let mut cols = Vec::new();
    let mut vals = Vec::new();
    let mut b = Vec::new();
    for i in 0..n {
        if num[i] == u32::MAX {
            continue;
        }
        let mut d = 0.0;
        let mut bi = [0.0; 3];
        for &j in adj.neighbours(i) {
            let j = j as usize;
            let l2: f64 = (0..3).map(|k| (x[j][k] - x[i][k]).powi(2)).sum();
            let k = f64::from((1.0 / l2) as f32);
            d += k;
            if num[j] != u32::MAX {
                cols.push(num[j]);
                vals.push(-k as f32);
            } else if on[j] == 2 {
                let t = motion.apply(x[j], 1.0);
                for q in 0..3 {
                    bi[q] += k * (t[q] - x[j][q]);
                }
            }
        }
        diag.push(d);
        offsets.push(cols.len());
        b.push(bi);
    }
    (
        SymMatrix {
            diag,
            offsets,
            cols,
            vals,
        },
        b,
    )
}

/// The SpMV of the benchmark system with its unknowns in other orders (the unknowns sorted
/// by their node's index under a node numbering): the generator's, the Morton curve's, the
/// Morton curve's followed by `level_order` (what `deform` does) or by reverse Cuthill–McKee.
fn node_orders(m: &Mesh, a: &SymMatrix<f32>) {
    let report = |name: &str, node_perm: &[u32], secs: f64| {
        let ap = a.permuted(&unknowns_by(m, node_perm));
        let g = spmv_gbs(&ap);
        println!(
            "order {name} (computed in {secs:.3} s): SpMV {g:.2} GB/s, {:.2} ms",
            spmv_bytes(&ap) / g / 1e6
        );
    };
    let ident: Vec<u32> = (0..m.n_nodes() as u32).collect();
    report("generator", &ident, 0.0);
    let (morton, adj, t_morton) = morton_order(m);
    report("morton", &morton, t_morton);
    let t = Instant::now();
    let level = order::level_order(adj.n_nodes(), |i| adj.neighbours(i));
    let t_level = t.elapsed().as_secs_f64();
    report(
        "morton + level order (deform's)",
        &order::then(&morton, &level),
        t_morton + t_level,
    );
    let t = Instant::now();
    let rcm = order::reverse_cuthill_mckee(adj.n_nodes(), |i| adj.neighbours(i));
    let t_rcm = t.elapsed().as_secs_f64();
    report(
        "morton + RCM",
        &order::then(&morton, &rcm),
        t_morton + t_rcm,
    );
}

/// The Morton order of `m`'s nodes (node i → `perm[i]`), the adjacency of the grid so
/// renumbered, and the seconds the order took.
fn morton_order(m: &Mesh) -> (Vec<u32>, mesh::Adjacency, f64) {
    let t = Instant::now();
    let morton = order::morton_order(&m.coords);
    let secs = t.elapsed().as_secs_f64();
    let mut mm = m.clone();
    mm.renumber_nodes(&morton).unwrap();
    (morton, mesh::Adjacency::build(&mm), secs)
}

/// The unknowns of [`system`] (the nodes off the wing and far-field markers, in node order)
/// reordered by their nodes' indices under `node_perm` (node i → `node_perm[i]`), as a
/// permutation of the unknowns (`perm[old] = new`, `sparse::order`'s convention).
fn unknowns_by(m: &Mesh, node_perm: &[u32]) -> Vec<u32> {
    let mut unknown = vec![true; m.n_nodes()];
    for mk in &m.markers {
        if mk.name != "y_m" {
            for i in mk.elements.node_set() {
                unknown[i as usize] = false;
            }
        }
    }
    let nodes: Vec<usize> = (0..m.n_nodes()).filter(|&i| unknown[i]).collect();
    let mut new_to_old: Vec<u32> = (0..nodes.len() as u32).collect();
    new_to_old.sort_by_key(|&u| node_perm[nodes[u as usize]]);
    order::inverse(&new_to_old)
}

/// The system in `deform`'s internal order (Morton curve, then `level_order`).
fn in_deform_order(m: &Mesh, a: &SymMatrix<f32>, b: &[V3]) -> (SymMatrix<f32>, Vec<V3>) {
    let (morton, adj, _) = morton_order(m);
    let level = order::level_order(adj.n_nodes(), |i| adj.neighbours(i));
    let perm = unknowns_by(m, &order::then(&morton, &level));
    let bp = order::inverse(&perm)
        .iter()
        .map(|&o| b[o as usize])
        .collect();
    (a.permuted(&perm), bp)
}

/// The environment variable `name` parsed, or `default` when unset or unparsable.
fn env_or<T: std::str::FromStr>(name: &str, default: T) -> T {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// `DEFORM_BENCH_TRACE`: print the set-up's steps and the multigrid's levels.
fn trace() -> bool {
    std::env::var_os("DEFORM_BENCH_TRACE").is_some()
}

/// `DEFORM_BENCH_STIFFNESS` = `l`, `l2` (default) or `volume`.
fn stiffness_from_env() -> deform::Stiffness {
    match std::env::var("DEFORM_BENCH_STIFFNESS").as_deref() {
        Ok("l") => deform::Stiffness::InverseLength,
        Ok("volume") => deform::Stiffness::Volume,
        Ok("wall") => deform::Stiffness::WallDistance,
        _ => deform::Stiffness::InverseLengthSquared,
    }
}

fn figures() {
    let sizes: Vec<usize> = std::env::var("DEFORM_BENCH_SIZES")
        .unwrap_or_else(|_| "46,84".into())
        .split(',')
        .filter_map(|s| s.trim().parse().ok())
        .collect();
    println!(
        "threads: {}, load average at start: {}",
        rayon::current_num_threads(),
        std::fs::read_to_string("/proc/loadavg")
            .unwrap_or_default()
            .trim()
    );
    for &n in &sizes {
        let t = Instant::now();
        let (m, bc) = case(n);
        let t_gen = t.elapsed().as_secs_f64();
        println!(
            "\n== n = {n}: {} nodes, {} tets (generated in {t_gen:.2} s)",
            m.n_nodes(),
            m.tets().len()
        );
        // Linear solves on the system in deform's internal order (`DEFORM_BENCH_ORDERS`:
        // first the SpMV in other orders).
        let (a, b) = system(&m, &bc);
        if std::env::var("DEFORM_BENCH_ORDERS").is_ok() {
            node_orders(&m, &a);
        }
        let (a, b) = in_deform_order(&m, &a, &b);
        let triad = triad_gbs(4_000_000);
        let spmv = spmv_gbs(&a);
        let t_spmv = spmv_bytes(&a) / spmv / 1e6;
        // The same matrix with f64 values, for comparison in the same run.
        let a64 = a.to_entries::<f64>();
        let spmv64 = spmv_gbs(&a64);
        let t_spmv64 = spmv_bytes(&a64) / spmv64 / 1e6;
        drop(a64);
        println!(
            "bandwidth: triad {triad:.2} GB/s, SpMV {spmv:.2} GB/s ({:.0} %, {t_spmv:.2} ms; with f64 values {spmv64:.2} GB/s, {:.0} %, {t_spmv64:.2} ms), nnz/row {:.1}",
            100.0 * spmv / triad,
            100.0 * spmv64 / triad,
            a.nnz_offdiag() as f64 / a.n() as f64
        );
        let ratios = paired_ratios(&a, &mut Triad::new(4_000_000), 21);
        println!(
            "SpMV / triad in 21 alternated pairs: median {:.0} %, quartiles {:.0}–{:.0} %, range {:.0}–{:.0} %",
            100.0 * ratios[10],
            100.0 * ratios[5],
            100.0 * ratios[15],
            100.0 * ratios[0],
            100.0 * ratios[20]
        );
        let so = SolveOptions {
            rel_tol: 1e-8,
            max_iters: 20_000,
        };
        let none = Constraints::default();
        if std::env::var("DEFORM_BENCH_NO_JACOBI").is_err() {
            let mut x = vec![[0.0; 3]; a.n()];
            let t = Instant::now();
            let c0 = cpu_s();
            let j = Jacobi::new(&a);
            let r = pcg(&a, &b, &mut x, &j, &none, &so);
            let tj = t.elapsed().as_secs_f64();
            let cj = cpu_s() - c0;
            println!(
                "pcg-jacobi: {} it, {tj:.3} s (cpu {cj:.2} s), {:.2} ms/it, residual {:.1e}",
                r.iterations,
                1e3 * tj / r.iterations.max(1) as f64,
                r.rel_residual
            );
        }
        // `DEFORM_BENCH_SETUP_REPS=N`: N multigrid set-ups in a row, each timed (with
        // `DEFORM_BENCH_TRACE`, per level), instead of the solves.
        if let Some(reps) = std::env::var("DEFORM_BENCH_SETUP_REPS")
            .ok()
            .and_then(|v| v.parse::<usize>().ok())
        {
            for _ in 0..reps {
                let t = Instant::now();
                let amg = Amg::new(&a, &AmgOptions::default()).unwrap();
                println!("multigrid set-up {:.3} s", t.elapsed().as_secs_f64());
                if trace() {
                    for (l, s) in amg.info().setup.iter().enumerate() {
                        println!(
                            "  level {l}: nnz(P) {}, aggregate {:.3} s, P {:.3} s, Pt {:.3} s, RAP {:.3} s",
                            s.prolongator_entries,
                            s.aggregate,
                            s.prolongator,
                            s.transpose,
                            s.galerkin
                        );
                    }
                }
                drop(amg);
            }
            continue;
        }
        let t = Instant::now();
        let c0 = cpu_s();
        let defaults = AmgOptions::default();
        // `DEFORM_AMG_DAMPING=cS,cP`: the smoother's and the prolongator's damping.
        let damping = std::env::var("DEFORM_AMG_DAMPING")
            .ok()
            .and_then(|v| {
                let (s, p) = v.split_once(',')?;
                Some((s.parse().ok()?, p.parse().ok()?))
            })
            .unwrap_or((defaults.smoother_damping, defaults.prolongator_damping));
        let amg = Amg::new(
            &a,
            &AmgOptions {
                strength: env_or("DEFORM_AMG_STRENGTH", defaults.strength),
                coarse_cycles: env_or("DEFORM_AMG_CYCLES", defaults.coarse_cycles),
                smoother_damping: damping.0,
                prolongator_damping: damping.1,
                ..Default::default()
            },
        )
        .unwrap();
        let setup = t.elapsed().as_secs_f64();
        let mut x = vec![[0.0; 3]; a.n()];
        let t = Instant::now();
        let r = pcg(&a, &b, &mut x, &amg, &none, &so);
        let ts = t.elapsed().as_secs_f64();
        let ca = cpu_s() - c0;
        let info = amg.info();
        println!(
            "pcg-amg: setup {setup:.3} s + {} it {ts:.3} s = {:.3} s (cpu {ca:.2} s), {:.2} ms/it, residual {:.1e}, levels {:?}, op. complexity {:.2}",
            r.iterations,
            setup + ts,
            1e3 * ts / r.iterations.max(1) as f64,
            r.rel_residual,
            info.sizes,
            info.operator_complexity
        );
        drop(amg);
        if std::env::var("DEFORM_BENCH_SOLVES_ONLY").is_ok() {
            continue;
        }
        // Whole deformation (`DEFORM_BENCH_QUICK`: multigrid only, no naive / numbering runs).
        let quick = std::env::var("DEFORM_BENCH_QUICK").is_ok();
        let solvers: &[(&str, SolverKind)] = if quick {
            &[("multigrid", SolverKind::PcgMultigrid)]
        } else {
            &[
                ("multigrid", SolverKind::PcgMultigrid),
                ("jacobi-pcg", SolverKind::PcgJacobi),
            ]
        };
        for &(name, solver) in solvers {
            let t = Instant::now();
            let c0 = cpu_s();
            let d = deform(
                &m,
                &bc,
                &DeformOptions {
                    solver,
                    stiffness: stiffness_from_env(),
                    ..Default::default()
                },
            )
            .unwrap();
            let tt = t.elapsed().as_secs_f64();
            let ct = cpu_s() - c0;
            let r = &d.report;
            if trace() {
                for st in &r.setup_steps {
                    println!("  set-up step {}: {:.3} s", st.step, st.seconds);
                }
            }
            println!(
                "deform [{name}]: {tt:.2} s total (cpu {ct:.2} s); it {} (+{} for R), increments {}; s: setup {:.2} assemble {:.2} precond {:.2} rotation {:.2} solve {:.2} quality {:.2}; q min {:.4} -> {:.4} ({:.1} %), p1 {:.4} -> {:.4}, inverted {}",
                r.iterations,
                r.rotation_iterations,
                r.increments,
                r.seconds.setup,
                r.seconds.assemble,
                r.seconds.precond,
                r.seconds.rotation,
                r.seconds.solve,
                r.seconds.quality,
                r.quality_before.min,
                r.quality_after.min,
                100.0 * r.quality_after.min / r.quality_before.min,
                r.quality_before.p1,
                r.quality_after.p1,
                r.quality_after.n_nonpositive
            );
        }
        if quick {
            print_memory_and_load();
            continue;
        }
        // Without R and with the symmetry plane fixed (the naive setup), for comparison.
        let naive = BoundaryConditions {
            markers: vec![bc.markers[0].clone()],
            displacements: vec![],
        };
        let d = deform(
            &m,
            &naive,
            &DeformOptions {
                adapt_rotation: false,
                max_increments: 1,
                allow_inverted: true,
                ..Default::default()
            },
        )
        .unwrap();
        println!(
            "naive (no R, plane fixed): q min {:.4}, inverted {}",
            d.report.quality_after.min, d.report.quality_after.n_nonpositive
        );
        // Random numbering.
        let mut shuffled = m.clone();
        mesh::generate::shuffle_nodes(&mut shuffled, 42);
        for (label, mm, renumber) in [
            ("ordered", &m, true),
            ("random, renumbered", &shuffled, true),
            ("random, not renumbered", &shuffled, false),
        ] {
            if m.n_nodes() > 500_000 && !renumber {
                continue;
            }
            let t = Instant::now();
            let d = deform(
                mm,
                &bc,
                &DeformOptions {
                    renumber,
                    ..Default::default()
                },
            )
            .unwrap();
            println!(
                "numbering {label}: {:.2} s (solve {:.2} s, {} it)",
                t.elapsed().as_secs_f64(),
                d.report.seconds.solve,
                d.report.iterations
            );
        }
        print_memory_and_load();
    }
}

/// Prints the process's peak RSS so far and the machine's load average.
fn print_memory_and_load() {
    println!(
        "peak RSS so far: {:.0} MB; load average: {}",
        peak_rss_mb(),
        std::fs::read_to_string("/proc/loadavg")
            .unwrap_or_default()
            .trim()
    );
}

fn benches(c: &mut Criterion) {
    let (m, bc) = case(46);
    let (a, b) = system(&m, &bc);
    let (a, b) = in_deform_order(&m, &a, &b);
    let x = spmv_input(a.n());
    let mut y = vec![[0.0; 3]; a.n()];
    let mut g = c.benchmark_group("kernels");
    g.throughput(Throughput::Elements(a.n() as u64));
    g.bench_function("spmv3_50k", |bch| bch.iter(|| a.mul(black_box(&x), &mut y)));
    g.sample_size(10);
    g.bench_function("pcg_amg_50k", |bch| {
        bch.iter(|| {
            let amg = Amg::new(&a, &AmgOptions::default()).unwrap();
            let mut x = vec![[0.0; 3]; a.n()];
            pcg(
                &a,
                &b,
                &mut x,
                &amg,
                &Constraints::default(),
                &SolveOptions::default(),
            )
        })
    });
    g.bench_function("deform_50k", |bch| {
        bch.iter(|| deform(&m, &bc, &DeformOptions::default()).unwrap())
    });
    g.finish();
}

fn main() {
    if std::env::var_os("DEFORM_BENCH_LINEARISE").is_some() {
        // The linearisation's figures and criterion group only (benches/linearise.rs).
        linearise::figures();
        if std::env::var("DEFORM_BENCH_FIGURES_ONLY").is_err() {
            let mut c = Criterion::default().configure_from_args();
            linearise::benches(&mut c);
            c.final_summary();
        }
        return;
    }
    figures();
    if std::env::var("DEFORM_BENCH_FIGURES_ONLY").is_err() {
        let mut c = Criterion::default().configure_from_args();
        benches(&mut c);
        c.final_summary();
    }
}
