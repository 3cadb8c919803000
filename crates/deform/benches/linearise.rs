//! The linearisation's cost (issue 22): one reverse product (`Linearisation::vjp`, the
//! gradient for every prescribed node) against one evaluation (`Deformer::deform`) on the
//! same set-up, and the forward product and `Deformer::linearise` beside them.
//!
//! Case: [`deform::generate::wing_in_box`] with the wing's nodes displaced by the 5° pitch
//! of [`deform::generate::wing_pitch_conditions`] given as node displacements (as the chain
//! gives the wall's), the symmetry plane sliding, the far field fixed; default options (R
//! on, 1/l², multigrid PCG, `rel_tol` 1e-8; the products solve to the same tolerance).
//!
//! "1st vjp s" is the first reverse product after `linearise`, which also builds the
//! constrained multigrid of the linearised solves (docs/crates/deform.md, "The constrained
//! multigrid"); "vjp s" the best of the next ones.
//!
//! `DEFORM_BENCH_LINEARISE=1 cargo bench -p deform --bench deform` prints the figures for the
//! sizes in `DEFORM_LIN_SIZES` (cubes per side, default "46"; 126 gives ~1M nodes: a few
//! GB) and runs the criterion group `linearise` at n = 30 (~15k nodes).

use std::hint::black_box;
use std::time::Instant;

use criterion::Criterion;
use deform::{BoundaryConditions, DeformOptions, Deformer, MarkerRole};
use mesh::Mesh;

/// The case at size `n` and the wing nodes' displacements.
fn case(n: usize) -> (Mesh, BoundaryConditions, Vec<[f64; 3]>) {
    let m = deform::generate::wing_in_box(n);
    let pitch = deform::generate::wing_pitch_conditions();
    let MarkerRole::Rigid(motion) = pitch.markers[0].1 else {
        unreachable!("the benchmark motion is a rigid pitch")
    };
    let mut nodes: Vec<u32> = m
        .marker("wing")
        .expect("the wing marker")
        .elements
        .node_set()
        .into_iter()
        .collect();
    nodes.sort_unstable();
    let values = nodes
        .iter()
        .map(|&v| {
            let (p, q) = (
                m.coords[v as usize],
                motion.apply(m.coords[v as usize], 1.0),
            );
            [q[0] - p[0], q[1] - p[1], q[2] - p[2]]
        })
        .collect();
    let bc = BoundaryConditions {
        markers: vec![("y_m".into(), MarkerRole::SlidePlane)],
        displacements: nodes.iter().map(|&v| (v, [0.0; 3])).collect(),
    };
    (m, bc, values)
}

/// Output weights X̄: a smooth field over the nodes (a stand-in for dJ/dX).
fn weights(m: &Mesh) -> Vec<[f64; 3]> {
    m.coords
        .iter()
        .map(|p| [(p[0] + p[2]).sin(), (p[1] * 2.0).cos(), (p[0] * p[2]).sin()])
        .collect()
}

/// Seconds of `f`, best of `reps` runs, and its last result.
fn best<T>(reps: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut out = None;
    let mut t = f64::INFINITY;
    for _ in 0..reps {
        let s = Instant::now();
        let r = f();
        t = t.min(s.elapsed().as_secs_f64());
        out = Some(r);
    }
    (t, out.expect("at least one run"))
}

/// Prints the figures for `DEFORM_LIN_SIZES`.
pub fn figures() {
    let sizes: Vec<usize> = std::env::var("DEFORM_LIN_SIZES")
        .unwrap_or_else(|_| "46".into())
        .split(',')
        .filter_map(|s| s.trim().parse().ok())
        .collect();
    let reps: usize = std::env::var("DEFORM_LIN_REPS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(3);
    println!(
        "linearise: threads {}, best of {reps}",
        rayon::current_num_threads()
    );
    println!(
        "{:>9} {:>7} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>8} {:>14}",
        "nodes",
        "inputs",
        "setup s",
        "eval s",
        "linear s",
        "1st vjp s",
        "vjp s",
        "jvp s",
        "vjp/eval",
        "iters e/v/j"
    );
    let mut warm_rows = Vec::new();
    for n in sizes {
        let (m, bc, values) = case(n);
        let opts = DeformOptions::default();
        let t = Instant::now();
        let d = Deformer::new(&m, &bc, &opts).expect("set-up");
        let setup = t.elapsed().as_secs_f64();
        let (te, res) = best(reps, || d.deform(&values, None).expect("deform"));
        let (tl, lin) = best(reps, || d.linearise(&res).expect("linearise"));
        let xbar = weights(&m);
        // The first product also builds the constrained multigrid of the linearised solves
        // (kept for the next ones).
        let s0 = Instant::now();
        lin.vjp(&xbar).expect("vjp");
        let tv1 = s0.elapsed().as_secs_f64();
        let (tv, v) = best(reps, || lin.vjp(&xbar).expect("vjp"));
        let (tj, j) = best(reps, || lin.jvp(&v.values).expect("jvp"));
        // An optimiser's next step: the motion 1 % larger, the weights changed by 1 %; the
        // evaluation warm-started from the last one, the reverse product from the last one's
        // adjoint solutions (and cold, for comparison).
        let values2: Vec<[f64; 3]> = values.iter().map(|v| v.map(|c| 1.01 * c)).collect();
        let (tew, res2) = best(reps, || d.deform(&values2, Some(&res)).expect("deform"));
        let lin2 = d.linearise(&res2).expect("linearise");
        let xbar2: Vec<[f64; 3]> = xbar
            .iter()
            .zip(m.coords.iter())
            .map(|(w, p)| std::array::from_fn(|c| w[c] * (1.0 + 0.01 * (p[c] + 0.3).sin())))
            .collect();
        let mut start = deform::AdjointStart::default();
        lin.vjp_from(&xbar, &mut start).expect("vjp");
        let (tvc, vc) = best(reps, || lin2.vjp(&xbar2).expect("vjp"));
        let mut tvw = f64::INFINITY;
        let mut vw = None;
        for _ in 0..reps {
            let mut st = start.clone();
            let s = Instant::now();
            let r = lin2.vjp_from(&xbar2, &mut st).expect("vjp");
            tvw = tvw.min(s.elapsed().as_secs_f64());
            vw = Some(r);
        }
        let vw = vw.expect("at least one run");
        warm_rows.push(format!(
            "{:>9} {:>9.3} {:>9.3} {:>9.3} {:>9.3} {:>9.2} {:>9.2} {:>12} {:>10.1e}",
            m.n_nodes(),
            te,
            tew,
            tvc,
            tvw,
            tvc / te,
            tvw / tew,
            format!(
                "{}+{}/{}/{}",
                res2.report.iterations,
                res2.report.rotation_iterations,
                vc.iterations,
                vw.iterations
            ),
            rel_diff(&vw.values, &vc.values),
        ));
        println!(
            "{:>9} {:>7} {:>9.3} {:>9.3} {:>9.3} {:>9.3} {:>9.3} {:>9.3} {:>8.2} {:>14}",
            m.n_nodes(),
            values.len(),
            setup,
            te,
            tl,
            tv1,
            tv,
            tj,
            tv / te,
            format!(
                "{}+{}/{}/{}",
                res.report.iterations, res.report.rotation_iterations, v.iterations, j.iterations
            )
        );
    }
    println!("next step (motion +1 %, weights ±1 %): evaluation and reverse product, cold / warm");
    println!(
        "{:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9} {:>12} {:>10}",
        "nodes",
        "eval s",
        "eval w s",
        "vjp s",
        "vjp w s",
        "cold",
        "warm",
        "iters e/v/w",
        "w vs cold"
    );
    for r in warm_rows {
        println!("{r}");
    }
}

/// |a − b| / |b| over all components.
fn rel_diff(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    let (mut d, mut n) = (0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        for c in 0..3 {
            d += (x[c] - y[c]) * (x[c] - y[c]);
            n += y[c] * y[c];
        }
    }
    (d / n).sqrt()
}

/// The criterion group `linearise` at ~15k nodes.
pub fn benches(c: &mut Criterion) {
    let (m, bc, values) = case(30);
    let d = Deformer::new(&m, &bc, &DeformOptions::default()).expect("set-up");
    let res = d.deform(&values, None).expect("deform");
    let lin = d.linearise(&res).expect("linearise");
    let xbar = weights(&m);
    let mut g = c.benchmark_group("linearise");
    g.sample_size(10);
    g.bench_function("evaluate_15k", |b| {
        b.iter(|| d.deform(black_box(&values), None).expect("deform"))
    });
    g.bench_function("linearise_15k", |b| {
        b.iter(|| d.linearise(black_box(&res)).expect("linearise"))
    });
    g.bench_function("vjp_15k", |b| {
        b.iter(|| lin.vjp(black_box(&xbar)).expect("vjp"))
    });
    g.finish();
}
