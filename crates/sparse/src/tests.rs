//! Unit tests of the matrix kernels and solvers on the spring grid of [`crate::generate`].

use crate::generate::spring_grid;
use crate::vec3::{self, V3};
use crate::*;

fn dense_solve(a: &SymMatrix, b: &[V3]) -> Vec<V3> {
    let n = a.n();
    let mut m = a.to_dense();
    let mut x: Vec<V3> = b.to_vec();
    for c in 0..n {
        let piv = m[c][c];
        for r in c + 1..n {
            let f = m[r][c] / piv;
            if f != 0.0 {
                for k in c..n {
                    m[r][k] -= f * m[c][k];
                }
                for q in 0..3 {
                    x[r][q] -= f * x[c][q];
                }
            }
        }
    }
    for r in (0..n).rev() {
        for q in 0..3 {
            let mut s = x[r][q];
            for k in r + 1..n {
                s -= m[r][k] * x[k][q];
            }
            x[r][q] = s / m[r][r];
        }
    }
    x
}

fn flat(v: &[V3]) -> Vec<f64> {
    v.iter().flat_map(|a| a.iter().copied()).collect()
}

fn bits(v: &[V3]) -> Vec<u64> {
    v.iter().flatten().map(|x| x.to_bits()).collect()
}

#[test]
fn single_precision_storage_computes_the_f64_products_of_the_rounded_values() {
    let (a, b) = spring_grid(21, 17, 15); // 4485 unknowns: more than one chunk
    let a32 = a.to_entries::<f32>();
    let a64 = a32.to_entries::<f64>();
    let x: Vec<V3> = (0..a.n())
        .map(|i| {
            [
                (0.37 * i as f64).sin(),
                1e-3 * i as f64,
                (0.11 * i as f64).cos(),
            ]
        })
        .collect();
    let (mut y32, mut y64) = (vec![[0.0; 3]; a.n()], vec![[0.0; 3]; a.n()]);
    let d32 = a32.mul_dot(&x, &mut y32);
    let d64 = a64.mul_dot(&x, &mut y64);
    assert_eq!((d32.to_bits(), bits(&y32)), (d64.to_bits(), bits(&y64)));
    let r32 = a32.residual(&b, &x, &mut y32);
    let r64 = a64.residual(&b, &x, &mut y64);
    assert_eq!((r32.to_bits(), bits(&y32)), (r64.to_bits(), bits(&y64)));
    // Jacobi-preconditioned CG: the same iterates.
    let so = SolveOptions::default();
    let none = Constraints::default();
    let (mut x32, mut x64) = (vec![[0.0; 3]; a.n()], vec![[0.0; 3]; a.n()]);
    let s32 = pcg(&a32, &b, &mut x32, &Jacobi::new(&a32), &none, &so);
    let s64 = pcg(&a64, &b, &mut x64, &Jacobi::new(&a64), &none, &so);
    assert!(s32.converged && s32.iterations == s64.iterations);
    assert_eq!(s32.rel_residual.to_bits(), s64.rel_residual.to_bits());
    assert_eq!(bits(&x32), bits(&x64));
    assert!(a32.bytes() < a64.bytes());
}

#[test]
fn fused_jacobi_dot_equals_the_separate_dot_bit_for_bit() {
    let (a, b) = spring_grid(21, 17, 15);
    let m = Jacobi::new(&a);
    let (mut z1, mut z2, mut work) = (
        vec![[0.0; 3]; a.n()],
        vec![[0.0; 3]; a.n()],
        vec![[0.0; 3]; a.n()],
    );
    m.apply(&b, &mut z1);
    let rz = m.apply_dot(&b, &mut z2, &mut work);
    assert_eq!(z1, z2);
    assert_eq!(rz.to_bits(), vec3::dot(&b, &z1).to_bits());
}

#[test]
fn paired_row_products_equal_single_row_products_bit_for_bit() {
    // 75 unknowns (odd: the last row of a range is unpaired), rows of 6 to 12 entries.
    let (a, b) = spring_grid(7, 7, 5);
    assert_eq!(a.n() % 2, 1);
    let x: Vec<V3> = b
        .iter()
        .enumerate()
        .map(|(i, v)| [v[0] + 0.3 * i as f64, v[1] - 1.7, (i as f64).sin()])
        .collect();
    for (lo, hi) in [(0, a.n()), (1, a.n()), (3, 4), (5, 5), (10, 41)] {
        let mut seen = Vec::new();
        a.rows_mul(lo, hi, &x, |i, v| {
            let w = a.row_mul(i, &x);
            assert!((0..3).all(|q| v[q].to_bits() == w[q].to_bits()), "row {i}");
            seen.push(i);
        });
        assert_eq!(seen, (lo..hi).collect::<Vec<_>>());
    }
    // The public kernels built on it.
    let mut y = vec![[0.0; 3]; a.n()];
    a.mul(&x, &mut y);
    assert!((0..a.n()).all(|i| y[i] == a.row_mul(i, &x)));
}

#[test]
fn products_round_as_the_processor_kind_says() {
    // Each row written out with the multiply–add `madd::fused` reports: fused where the
    // processor has FMA, a product then a sum elsewhere.
    let (a, b) = spring_grid(6, 7, 5);
    let x: Vec<V3> = b
        .iter()
        .enumerate()
        .map(|(i, v)| [v[0] / 3.0 + 0.1 * i as f64, (i as f64).cos(), v[2] - 0.7])
        .collect();
    let mut y = vec![[0.0; 3]; a.n()];
    a.mul(&x, &mut y);
    let row = |i: usize, fused: bool| {
        let d = a.diag[i];
        let mut s = [d * x[i][0], d * x[i][1], d * x[i][2]];
        let (cols, vals) = a.row(i);
        for (&c, &v) in cols.iter().zip(vals) {
            for q in 0..3 {
                let xq = x[c as usize][q];
                s[q] = if fused {
                    v.mul_add(xq, s[q])
                } else {
                    s[q] + v * xq
                };
            }
        }
        s
    };
    let fused = madd::fused();
    let same = |s: V3, t: V3| (0..3).all(|q| s[q].to_bits() == t[q].to_bits());
    for i in 0..a.n() {
        assert!(same(row(i, fused), y[i]), "row {i}");
    }
    // The two roundings differ on these data, so the check above tells them apart.
    assert!((0..a.n()).any(|i| !same(row(i, !fused), y[i])));
}

#[test]
fn grid_matrix_is_symmetric_and_exports_to_sprs() {
    let (a, b) = spring_grid(6, 5, 4);
    a.validate(1e-15).unwrap();
    // The sprs copy multiplies like the matrix itself (each component).
    let m = a.to_csmat().unwrap();
    assert_eq!(m.shape(), (a.n(), a.n()));
    assert_eq!(m.nnz(), a.n() + a.nnz_offdiag());
    let mut y = vec![[0.0; 3]; a.n()];
    a.mul(&b, &mut y);
    for q in 0..3 {
        let v: Vec<f64> = b.iter().map(|e| e[q]).collect();
        let w = &m * &sprs::CsVec::new(v.len(), (0..v.len()).collect(), v.clone());
        let dense = w.to_dense();
        for i in 0..a.n() {
            testkit::assert_close!(dense[i], y[i][q], rel = 1e-14, abs = 1e-14);
        }
    }
    let bad = SymMatrix::<f64> {
        diag: vec![1.0],
        offsets: vec![0, 1],
        cols: vec![3],
        vals: vec![1.0],
    };
    assert!(bad.to_csmat().is_err());
}

#[test]
fn solvers_match_dense_solution() {
    let (a, b) = spring_grid(9, 8, 7);
    let exact = dense_solve(&a, &b);
    let opts = SolveOptions {
        rel_tol: 1e-12,
        max_iters: 10_000,
    };
    let cons = Constraints::default();
    let mut x = vec![[0.0; 3]; a.n()];
    let rep = pcg(&a, &b, &mut x, &Jacobi::new(&a), &cons, &opts);
    assert!(rep.converged, "{rep:?}");
    testkit::assert_close!(flat(&x), flat(&exact), rel = 1e-9, abs = 1e-11);
    let mut z = vec![[0.0; 3]; a.n()];
    let rep3 = point_iteration(
        &a,
        &b,
        &mut z,
        &cons,
        1.0,
        0.0,
        &SolveOptions {
            rel_tol: 1e-10,
            max_iters: 50_000,
        },
    );
    assert!(rep3.rel_residual <= 1e-10, "{rep3:?}");
    testkit::assert_close!(flat(&z), flat(&exact), rel = 1e-7, abs = 1e-9);
}

#[test]
fn jacobi_pcg_is_identical_for_any_thread_count() {
    let (a, b) = spring_grid(24, 20, 18);
    let run = |threads: usize| {
        testkit::with_threads(threads, || {
            let mut x = vec![[0.0; 3]; a.n()];
            let rep = pcg(
                &a,
                &b,
                &mut x,
                &Jacobi::new(&a),
                &Constraints::default(),
                &SolveOptions::default(),
            );
            (bits(&x), rep.iterations)
        })
    };
    assert_eq!(run(1), run(3));
}

#[test]
fn constrained_solution_stays_in_planes_and_matches_reduced_solve() {
    // Constrain every unknown of the plane k = 1 to slide in the plane z = const, and check
    // against the dense solve of the z component with those unknowns fixed at zero.
    let (nx, ny, nz) = (8, 7, 6);
    let (a, b) = spring_grid(nx, ny, nz);
    let m = (nx - 2) * (ny - 2);
    let cons = Constraints {
        items: (0..m as u32)
            .map(|i| (i, Constraint::Plane([0.0, 0.0, 1.0])))
            .collect(),
    };
    let mut x = vec![[0.0; 3]; a.n()];
    let rep = pcg(
        &a,
        &b,
        &mut x,
        &Jacobi::new(&a),
        &cons,
        &SolveOptions {
            rel_tol: 1e-12,
            max_iters: 5000,
        },
    );
    assert!(rep.converged, "{rep:?}");
    for v in x.iter().take(m) {
        assert_eq!(v[2], 0.0);
    }
    // x, y components are unconstrained: equal the dense solve.
    let exact = dense_solve(&a, &b);
    for i in 0..a.n() {
        testkit::assert_close!(
            [x[i][0], x[i][1]],
            [exact[i][0], exact[i][1]],
            rel = 1e-8,
            abs = 1e-11
        );
    }
    // z component: solve the reduced dense system.
    let keep: Vec<usize> = (m..a.n()).collect();
    let d = a.to_dense();
    let nk = keep.len();
    let red = SymMatrix {
        diag: keep.iter().map(|&i| d[i][i]).collect(),
        offsets: (0..=nk).map(|r| r * (nk - 1)).collect(),
        cols: (0..nk)
            .flat_map(|r| (0..nk).filter(move |&c| c != r).map(|c| c as u32))
            .collect(),
        vals: (0..nk)
            .flat_map(|r| (0..nk).filter(move |&c| c != r).map(move |c| (r, c)))
            .map(|(r, c)| d[keep[r]][keep[c]])
            .collect(),
    };
    let bz: Vec<V3> = keep.iter().map(|&i| [b[i][2], 0.0, 0.0]).collect();
    let xz = dense_solve(&red, &bz);
    for (r, &i) in keep.iter().enumerate() {
        testkit::assert_close!(x[i][2], xz[r][0], rel = 1e-8, abs = 1e-11);
    }
}

#[test]
fn permuted_system_gives_permuted_solution() {
    let (a, b) = spring_grid(10, 9, 8);
    let n = a.n();
    let perm = order::reverse_cuthill_mckee(n, |i| a.row(i).0);
    let ap = a.permuted(&perm);
    ap.validate(1e-15).unwrap();
    // perm[old] = new: the new vector gathers through the inverse.
    let inv = order::inverse(&perm);
    let bp: Vec<V3> = inv.iter().map(|&o| b[o as usize]).collect();
    let opts = SolveOptions {
        rel_tol: 1e-12,
        max_iters: 5000,
    };
    let mut x = vec![[0.0; 3]; n];
    pcg(
        &a,
        &b,
        &mut x,
        &Jacobi::new(&a),
        &Constraints::default(),
        &opts,
    );
    let mut xp = vec![[0.0; 3]; n];
    pcg(
        &ap,
        &bp,
        &mut xp,
        &Jacobi::new(&ap),
        &Constraints::default(),
        &opts,
    );
    for (old, &new) in perm.iter().enumerate() {
        testkit::assert_close!(xp[new as usize], x[old], rel = 1e-9, abs = 1e-12);
    }
}
