//! Tests of the multigrid: the cycle as a CG preconditioner, its kernels against plain
//! references, thread-count independence.

use sparse::csr::{Csr, build_rows, merge_row};
use sparse::generate::spring_grid;
use sparse::vec3::{self, V3};
use sparse::{Constraint, Constraints, Jacobi, Preconditioner, SolveOptions, SymMatrix, pcg};

use super::coarsen::{aggregate, gershgorin, smoothed_prolongator};
use super::galerkin::{Acc, galerkin};
use super::transfer::Transfer;
use super::*;

fn flat(v: &[V3]) -> Vec<f64> {
    v.iter().flat_map(|a| a.iter().copied()).collect()
}

/// The bits of every component, for bit-for-bit comparisons.
pub(super) fn bits(v: &[V3]) -> Vec<u64> {
    v.iter().flatten().map(|x| x.to_bits()).collect()
}

/// The solution of `a x = b` by Jacobi-PCG to 1e-13.
fn reference(a: &SymMatrix, b: &[V3]) -> Vec<V3> {
    let mut x = vec![[0.0; 3]; a.n()];
    let so = SolveOptions {
        rel_tol: 1e-13,
        max_iters: 20_000,
    };
    assert!(pcg(a, b, &mut x, &Jacobi::new(a), &Constraints::default(), &so).converged);
    x
}

#[test]
fn single_precision_fine_matrix_gives_the_iterates_of_its_f64_copy() {
    // The coarse levels are f64 in both.
    let (a, b) = spring_grid(21, 17, 15);
    let a32 = a.to_entries::<f32>();
    let a64 = a32.to_entries::<f64>();
    let so = SolveOptions::default();
    let none = Constraints::default();
    let (mut x32, mut x64) = (vec![[0.0; 3]; a.n()], vec![[0.0; 3]; a.n()]);
    let m32 = Amg::new(&a32, &AmgOptions::default()).unwrap();
    let m64 = Amg::new(&a64, &AmgOptions::default()).unwrap();
    let s32 = pcg(&a32, &b, &mut x32, &m32, &none, &so);
    let s64 = pcg(&a64, &b, &mut x64, &m64, &none, &so);
    assert!(s32.converged && s32.iterations == s64.iterations);
    assert_eq!(s32.rel_residual.to_bits(), s64.rel_residual.to_bits());
    assert_eq!(bits(&x32), bits(&x64));
}

#[test]
fn multigrid_cycles_are_symmetric_positive_definite() {
    // Three levels (the middle one repeated by the W-cycle): u · M v = v · M u, u · M u > 0.
    let (a, _) = spring_grid(21, 17, 15);
    let vec_of = |seed: f64| -> Vec<V3> {
        (0..a.n())
            .map(|i| {
                let t = seed * (i as f64 + 1.0);
                [t.sin(), (1.3 * t).cos(), (0.7 * t).sin() * (0.2 * t).cos()]
            })
            .collect()
    };
    let (u, v) = (vec_of(0.37), vec_of(1.91));
    // The most oscillating vector: the one a too weakly damped smoother would amplify.
    let w: Vec<V3> = (0..a.n())
        .map(|i| {
            if i % 2 == 0 {
                [1.0, -1.0, 0.5]
            } else {
                [-1.0, 1.0, -0.5]
            }
        })
        .collect();
    // The default damping, and one at the edge of the allowed range (0, 2).
    for (cycles, damping) in [(1, 1.8), (2, 1.8), (3, 1.8), (2, 1.99)] {
        let opts = AmgOptions {
            max_coarse: 10,
            coarse_cycles: cycles,
            smoother_damping: damping,
            ..Default::default()
        };
        let m = Amg::new(&a, &opts).unwrap();
        assert!(m.info().sizes.len() >= 3, "{:?}", m.info().sizes);
        assert_eq!(m.info().setup.len(), m.info().sizes.len() - 1);
        let (mut mu, mut mv, mut mw) = (
            vec![[0.0; 3]; a.n()],
            vec![[0.0; 3]; a.n()],
            vec![[0.0; 3]; a.n()],
        );
        m.apply(&u, &mut mu);
        m.apply(&v, &mut mv);
        m.apply(&w, &mut mw);
        let (umv, vmu) = (vec3::dot(&u, &mv), vec3::dot(&v, &mu));
        let scale = vec3::norm(&u) * vec3::norm(&mv);
        assert!(
            (umv - vmu).abs() <= 1e-12 * scale,
            "{cycles}, {damping}: {umv} vs {vmu}"
        );
        for (x, mx) in [(&u, &mu), (&v, &mv), (&w, &mw)] {
            assert!(vec3::dot(x, mx) > 0.0, "{cycles}, {damping}");
        }
    }
}

#[test]
fn multigrid_damping_outside_its_range_is_refused() {
    let (a, _) = spring_grid(6, 5, 4);
    for (s, p) in [
        (2.0, 1.6),
        (0.0, 1.6),
        (f64::NAN, 1.6),
        (1.8, -0.1),
        (1.8, f64::INFINITY),
    ] {
        let opts = AmgOptions {
            smoother_damping: s,
            prolongator_damping: p,
            ..Default::default()
        };
        let e = Amg::new(&a, &opts).err().expect("refused");
        assert!(e.to_string().contains("damping"), "{e}");
    }
}

#[test]
fn fused_preconditioner_dot_equals_the_separate_dot_bit_for_bit() {
    let (a, b) = spring_grid(21, 17, 15);
    let amg = Amg::new(&a, &AmgOptions::default()).unwrap();
    let (mut z1, mut z2, mut work) = (
        vec![[0.0; 3]; a.n()],
        vec![[0.0; 3]; a.n()],
        vec![[0.0; 3]; a.n()],
    );
    amg.apply(&b, &mut z1);
    let rz = amg.apply_dot(&b, &mut z2, &mut work);
    assert_eq!(z1, z2);
    assert_eq!(rz.to_bits(), vec3::dot(&b, &z1).to_bits());
}

#[test]
fn pcg_with_the_first_pass_in_its_update_equals_the_plain_cycle_bit_for_bit() {
    // The multigrid offers its first smoothing pass to PCG's residual update; a wrapper
    // that does not (the trait's defaults) must give the same iterates, bit for bit,
    // with and without sliding constraints.
    struct Plain<'a>(&'a Amg<'a>);
    impl Preconditioner for Plain<'_> {
        fn apply(&self, r: &[V3], z: &mut [V3]) {
            self.0.apply(r, z);
        }
        fn apply_dot(&self, r: &[V3], z: &mut [V3], work: &mut [V3]) -> f64 {
            self.0.apply_dot(r, z, work)
        }
        fn name(&self) -> &'static str {
            "plain"
        }
    }
    let (a, b) = spring_grid(14, 13, 12);
    let amg = Amg::new(&a, &AmgOptions::default()).unwrap();
    assert!(amg.first_pass().is_some());
    assert!(Plain(&amg).first_pass().is_none());
    let n = [0.6f64, 0.0, 0.8];
    let sliding = Constraints {
        items: (0..a.n() as u32)
            .step_by(7)
            .map(|i| (i, Constraint::Plane(n)))
            .collect(),
    };
    let opts = SolveOptions {
        rel_tol: 1e-10,
        max_iters: 500,
    };
    for cons in [Constraints::default(), sliding] {
        let (mut x, mut y) = (vec![[0.0; 3]; a.n()], vec![[0.0; 3]; a.n()]);
        let r1 = pcg(&a, &b, &mut x, &amg, &cons, &opts);
        let r2 = pcg(&a, &b, &mut y, &Plain(&amg), &cons, &opts);
        assert!(r1.converged && r1.iterations > 3, "{r1:?}");
        assert_eq!(r1.iterations, r2.iterations);
        assert_eq!(r1.rel_residual.to_bits(), r2.rel_residual.to_bits());
        assert_eq!(bits(&x), bits(&y));
    }
}

#[test]
fn multigrid_with_lent_scratch_equals_own_scratch_bit_for_bit() {
    let (a, b) = spring_grid(16, 15, 14);
    let amg = Amg::new(&a, &AmgOptions::default()).unwrap();
    assert!(amg.info().sizes.len() >= 2);
    let (mut z1, mut z2) = (vec![[0.0; 3]; a.n()], vec![[0.0; 3]; a.n()]);
    amg.apply(&b, &mut z1);
    let mut work = vec![[f64::NAN; 3]; a.n()];
    amg.apply_with(&b, &mut z2, &mut work);
    assert_eq!(bits(&z1), bits(&z2));
    assert!(flat(&z1).iter().all(|v| v.is_finite()));
}

#[test]
fn multigrid_pcg_matches_the_reference_solution_in_fewer_iterations() {
    let (a, b) = spring_grid(9, 8, 7);
    let exact = reference(&a, &b);
    let opts = SolveOptions {
        rel_tol: 1e-12,
        max_iters: 10_000,
    };
    let cons = Constraints::default();
    let mut x = vec![[0.0; 3]; a.n()];
    let rep = pcg(&a, &b, &mut x, &Jacobi::new(&a), &cons, &opts);
    let amg = Amg::new(
        &a,
        &AmgOptions {
            max_coarse: 20,
            ..Default::default()
        },
    )
    .unwrap();
    assert!(amg.info().sizes.len() >= 2);
    let mut y = vec![[0.0; 3]; a.n()];
    let rep2 = pcg(&a, &b, &mut y, &amg, &cons, &opts);
    assert!(rep2.converged, "{rep2:?}");
    assert!(
        rep2.iterations < rep.iterations,
        "{} vs {}",
        rep2.iterations,
        rep.iterations
    );
    testkit::assert_close!(flat(&y), flat(&exact), rel = 1e-9, abs = 1e-11);
}

#[test]
fn results_identical_for_any_thread_count() {
    let (a, b) = spring_grid(24, 20, 18);
    let run = |threads: usize| {
        testkit::with_threads(threads, || {
            let amg = Amg::new(&a, &AmgOptions::default()).unwrap();
            let mut x = vec![[0.0; 3]; a.n()];
            let rep = pcg(
                &a,
                &b,
                &mut x,
                &amg,
                &Constraints::default(),
                &SolveOptions::default(),
            );
            (bits(&x), rep.iterations)
        })
    };
    assert_eq!(run(1), run(3));
}

#[test]
fn constrained_multigrid_solution_equals_the_jacobi_one() {
    let (nx, ny, nz) = (8, 7, 6);
    let (a, b) = spring_grid(nx, ny, nz);
    let m = (nx - 2) * (ny - 2);
    let cons = Constraints {
        items: (0..m as u32)
            .map(|i| (i, Constraint::Plane([0.0, 0.0, 1.0])))
            .collect(),
    };
    let so = SolveOptions {
        rel_tol: 1e-12,
        max_iters: 5000,
    };
    let mut x = vec![[0.0; 3]; a.n()];
    assert!(pcg(&a, &b, &mut x, &Jacobi::new(&a), &cons, &so).converged);
    let amg = Amg::new(
        &a,
        &AmgOptions {
            max_coarse: 30,
            ..Default::default()
        },
    )
    .unwrap();
    let mut y = vec![[0.0; 3]; a.n()];
    let rep2 = pcg(&a, &b, &mut y, &amg, &cons, &so);
    assert!(rep2.converged, "{rep2:?}");
    assert!(y.iter().take(m).all(|v| v[2] == 0.0));
    testkit::assert_close!(flat(&y), flat(&x), rel = 1e-8, abs = 1e-11);
}

#[test]
fn accumulator_restarts_its_stamps_when_they_run_out() {
    // Rows across the wrap of the stamp; row k adds to column k, new in that row (the
    // untouched marks hold u32::MAX, the stamp the counter would reach next).
    let mut acc = Acc::new(4);
    acc.stamp = u32::MAX - 2;
    let (mut c, mut v) = (Vec::new(), Vec::new());
    for k in 0..4u32 {
        acc.add(k, 1.0);
        acc.add(k, 0.5);
        assert_eq!(acc.drain(&mut c, &mut v, true), 1, "row {k}");
    }
    assert_eq!(c, [0, 1, 2, 3]);
    assert_eq!(v, [1.5; 4]);
}

#[test]
fn transpose_equals_the_dense_transpose_for_any_thread_count() {
    // 3001 × 40 with rows of 0 to 4 entries (a prolongator's shape), an empty column,
    // and columns whose rows span the whole matrix: every column range of the parallel
    // fill is exercised, with row ranges of every kind.
    let (nr, nc) = (3001, 40);
    let (offsets, entries) = build_rows(
        nr,
        |i, row| {
            let near = (i * nc / nr) as u32;
            for c in [near, near + 1, (i % 7) as u32 * 5 + 3, 39] {
                if c != 4 && (c as usize) < nc && i % 5 != 0 && !row.iter().any(|e| e.0 == c) {
                    row.push((c, (i as f64 + 0.25) * (c as f64 + 1.0)));
                }
            }
            row.sort_unstable_by_key(|e| e.0);
        },
        |(c, v)| (c, v as f32),
    );
    let m = Transfer {
        ncols: nc,
        offsets,
        entries,
    };
    let t1 = testkit::with_threads(1, || m.transpose());
    let t3 = testkit::with_threads(3, || m.transpose());
    assert_eq!(
        (t1.offsets.clone(), t1.entries.clone()),
        (t3.offsets, t3.entries)
    );
    assert_eq!((t1.nrows(), t1.ncols), (nc, nr));
    let mut dense = vec![vec![0.0f32; nr]; nc];
    for i in 0..nr {
        for &(c, v) in m.row(i) {
            dense[c as usize][i] = v;
        }
    }
    for (c, want) in dense.iter().enumerate() {
        let row = t1.row(c);
        assert!(
            row.windows(2).all(|w| w[0].0 < w[1].0),
            "column {c} in row order"
        );
        let mut got = vec![0.0f32; nr];
        for &(i, v) in row {
            got[i as usize] = v;
        }
        assert_eq!(&got, want, "column {c}");
    }
    assert!(t1.row(4).is_empty());
    let back = t1.transpose();
    assert_eq!((back.offsets, back.entries), (m.offsets, m.entries));
}

#[test]
fn galerkin_product_equals_a_sparse_map_product() {
    use std::collections::BTreeMap;
    // 210 unknowns, and 4896 (A P in two blocks of rows).
    for (nx, ny, nz) in [(9, 8, 7), (20, 19, 18)] {
        let (a, _) = spring_grid(nx, ny, nz);
        let (agg, nagg) = aggregate(&a, 0.0, None);
        let p = smoothed_prolongator(&a, &agg, nagg, 1.6 / gershgorin(&a), None);
        let ac = galerkin(&a, &p, &p.transpose());
        ac.validate(1e-12).unwrap();
        // Pᵀ (A P) summed entry by entry in ordered maps.
        let n = a.n();
        assert_eq!(n, (nx - 2) * (ny - 2) * (nz - 2));
        let ap: Vec<BTreeMap<u32, f64>> = (0..n)
            .map(|i| {
                let mut row = BTreeMap::new();
                let (cols, vals) = a.row(i);
                let terms = std::iter::once((i, a.diag[i]))
                    .chain(cols.iter().zip(vals).map(|(&k, &v)| (k as usize, v)));
                for (k, v) in terms {
                    for &(c, w) in p.row(k) {
                        *row.entry(c).or_insert(0.0) += v * f64::from(w);
                    }
                }
                row
            })
            .collect();
        let mut want = vec![BTreeMap::<u32, f64>::new(); nagg];
        for (i, row) in ap.iter().enumerate() {
            for &(c, w) in p.row(i) {
                for (&e, &v) in row {
                    *want[c as usize].entry(e).or_insert(0.0) += f64::from(w) * v;
                }
            }
        }
        let scale = ac.diag.iter().fold(0.0f64, |m, d| m.max(d.abs()));
        for (c, row) in want.iter().enumerate() {
            let (cols, _) = ac.row(c);
            // Rows sorted by column, as in every matrix of the hierarchy.
            assert!(cols.windows(2).all(|w| w[0] < w[1]), "row {c}");
            assert_eq!(cols.len() + 1, row.len(), "row {c}: its pattern");
            for (&e, &v) in row {
                let got = ac.get(c, e as usize);
                assert!((got - v).abs() <= 1e-12 * scale, "({c}, {e}): {got} vs {v}");
            }
        }
    }
}

#[test]
fn prolongator_rows_equal_sorted_merge_bit_for_bit() {
    // 4896 unknowns (two blocks of rows), and 140.
    for (a, _) in [spring_grid(20, 19, 18), spring_grid(7, 9, 6)] {
        let (agg, nagg) = aggregate(&a, 0.0, None);
        let omega = 4.0 / (3.0 * gershgorin(&a));
        let p = smoothed_prolongator(&a, &agg, nagg, omega, None);
        let reference = Csr::from_rows(a.n(), nagg, |i, buf| {
            buf.push((agg[i], 1.0 - omega));
            let s = omega / a.diag[i];
            for q in a.offsets[i]..a.offsets[i + 1] {
                buf.push((agg[a.cols[q] as usize], -s * a.vals[q]));
            }
            merge_row(buf);
        });
        assert_eq!(p.offsets, reference.offsets);
        // The merged sums, rounded to single precision.
        let rounded: Vec<(u32, f32)> = (reference.cols.iter().zip(&reference.vals))
            .map(|(&c, &v)| (c, v as f32))
            .collect();
        assert_eq!(p.entries.len(), rounded.len());
        assert!(
            p.entries
                .iter()
                .zip(&rounded)
                .all(|(x, y)| x.0 == y.0 && x.1.to_bits() == y.1.to_bits())
        );
    }
}
