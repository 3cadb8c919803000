//! Linear algebra of the spring system, independent of the grid: node graphs, the symmetric
//! sparse matrix shared by the three components, deterministic parallel kernels,
//! preconditioned conjugate gradients (Jacobi or smoothed-aggregation multigrid), the paper's
//! point iteration (Eq. 22) and reverse Cuthill–McKee renumbering.

pub mod amg;
pub mod csr;
pub mod madd;
pub mod order;
pub mod pcg;
pub mod vecops;

pub use amg::{Amg, AmgInfo, AmgOptions};
pub use csr::{Csr, Entry, Graph, SymMatrix};
pub use order::reverse_cuthill_mckee;
pub use pcg::{
    Constraint, Constraints, Jacobi, Preconditioner, SolveOptions, SolveReport, Weights, pcg,
    point_iteration,
};
pub use vecops::V3;

#[cfg(test)]
mod tests {
    use super::*;

    /// Spring matrix of a structured nx × ny × nz grid (spacings hx, hy, hz; 7-point stencil
    /// plus the face diagonals of a tetrahedral split), K = 1/length², boundary nodes
    /// prescribed (eliminated): returns the interior matrix and a right-hand side.
    pub(crate) fn grid_system(nx: usize, ny: usize, nz: usize) -> (SymMatrix, Vec<V3>) {
        let (hx, hy, hz) = (1.0, 0.7, 1.9);
        let id = |i: usize, j: usize, k: usize| (k * ny + j) * nx + i;
        let interior = |i: usize, j: usize, k: usize| {
            i > 0 && j > 0 && k > 0 && i + 1 < nx && j + 1 < ny && k + 1 < nz
        };
        let mut num = vec![u32::MAX; nx * ny * nz];
        let mut cnt = 0u32;
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    if interior(i, j, k) {
                        num[id(i, j, k)] = cnt;
                        cnt += 1;
                    }
                }
            }
        }
        let n = cnt as usize;
        let offs: [(i64, i64, i64); 18] = [
            (1, 0, 0),
            (-1, 0, 0),
            (0, 1, 0),
            (0, -1, 0),
            (0, 0, 1),
            (0, 0, -1),
            (1, 1, 0),
            (-1, -1, 0),
            (1, 0, 1),
            (-1, 0, -1),
            (0, 1, 1),
            (0, -1, -1),
            (1, -1, 0),
            (-1, 1, 0),
            (1, 0, -1),
            (-1, 0, 1),
            (0, 1, -1),
            (0, -1, 1),
        ];
        let mut diag = vec![0.0; n];
        let mut offsets = vec![0usize];
        let mut cols = Vec::new();
        let mut vals = Vec::new();
        let mut b = vec![[0.0; 3]; n];
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let r = num[id(i, j, k)];
                    if r == u32::MAX {
                        continue;
                    }
                    let mut row = Vec::new();
                    for &(di, dj, dk) in offs.iter().take(12) {
                        let (ii, jj, kk) = (i as i64 + di, j as i64 + dj, k as i64 + dk);
                        let l2 = (di as f64 * hx).powi(2)
                            + (dj as f64 * hy).powi(2)
                            + (dk as f64 * hz).powi(2);
                        let kij = 1.0 / l2;
                        diag[r as usize] += kij;
                        let c = num[id(ii as usize, jj as usize, kk as usize)];
                        if c == u32::MAX {
                            // Prescribed neighbour: its displacement goes to the right side.
                            let x = ii as f64 * hx;
                            let z = kk as f64 * hz;
                            let d = [0.1 * (x * 0.3).sin(), 0.05 * z, -0.02 * x * z];
                            for q in 0..3 {
                                b[r as usize][q] += kij * d[q];
                            }
                        } else {
                            row.push((c, -kij));
                        }
                    }
                    row.sort_by_key(|e| e.0);
                    for (c, v) in row {
                        cols.push(c);
                        vals.push(v);
                    }
                    offsets.push(cols.len());
                }
            }
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

    /// `a` with its values rounded to single precision, stored as f32 and as f64.
    fn rounded(a: &SymMatrix) -> (SymMatrix<f32>, SymMatrix) {
        let a32 = a.to_entries::<f32>();
        let a64 = a32.to_entries::<f64>();
        (a32, a64)
    }

    #[test]
    fn single_precision_storage_computes_the_f64_products_of_the_rounded_values() {
        let (a, b) = grid_system(21, 17, 15); // 4485 unknowns: more than one chunk
        let (a32, a64) = rounded(&a);
        let bits = |v: &[V3]| v.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
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
        // Multigrid-preconditioned CG: the same iterates (the coarse levels are f64 in both).
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
        assert!(a32.bytes() < a64.bytes());
    }

    #[test]
    fn multigrid_cycles_are_symmetric_positive_definite() {
        // Three levels (the middle one repeated by the W-cycle): u · M v = v · M u, u · M u > 0.
        let (a, _) = grid_system(21, 17, 15);
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
            let (mut mu, mut mv, mut mw) = (
                vec![[0.0; 3]; a.n()],
                vec![[0.0; 3]; a.n()],
                vec![[0.0; 3]; a.n()],
            );
            m.apply(&u, &mut mu);
            m.apply(&v, &mut mv);
            m.apply(&w, &mut mw);
            let (umv, vmu) = (vecops::dot(&u, &mv), vecops::dot(&v, &mu));
            let scale = vecops::norm(&u) * vecops::norm(&mv);
            assert!(
                (umv - vmu).abs() <= 1e-12 * scale,
                "{cycles}, {damping}: {umv} vs {vmu}"
            );
            for (x, mx) in [(&u, &mu), (&v, &mv), (&w, &mw)] {
                assert!(vecops::dot(x, mx) > 0.0, "{cycles}, {damping}");
            }
        }
    }

    #[test]
    fn multigrid_damping_outside_its_range_is_refused() {
        let (a, _) = grid_system(6, 5, 4);
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
        let (a, b) = grid_system(21, 17, 15);
        let amg = Amg::new(&a, &AmgOptions::default()).unwrap();
        let jac = Jacobi::new(&a);
        let pres: [&dyn Preconditioner; 2] = [&amg, &jac];
        for m in pres {
            let (mut z1, mut z2, mut work) = (
                vec![[0.0; 3]; a.n()],
                vec![[0.0; 3]; a.n()],
                vec![[0.0; 3]; a.n()],
            );
            m.apply(&b, &mut z1);
            let rz = m.apply_dot(&b, &mut z2, &mut work);
            assert_eq!(z1, z2, "{}", m.name());
            assert_eq!(rz.to_bits(), vecops::dot(&b, &z1).to_bits(), "{}", m.name());
        }
    }

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

    #[test]
    fn paired_row_products_equal_single_row_products_bit_for_bit() {
        // 75 unknowns (odd: the last row of a range is unpaired), rows of 6 to 12 entries.
        let (a, b) = grid_system(7, 7, 5);
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
        let (a, b) = grid_system(6, 7, 5);
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
        let (a, b) = grid_system(14, 13, 12);
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
            assert!(
                flat(&x)
                    .iter()
                    .zip(flat(&y))
                    .all(|(p, q)| p.to_bits() == q.to_bits())
            );
        }
    }

    #[test]
    fn multigrid_with_lent_scratch_equals_own_scratch_bit_for_bit() {
        let (a, b) = grid_system(16, 15, 14);
        let amg = Amg::new(&a, &AmgOptions::default()).unwrap();
        assert!(amg.info().sizes.len() >= 2);
        let (mut z1, mut z2) = (vec![[0.0; 3]; a.n()], vec![[0.0; 3]; a.n()]);
        amg.apply(&b, &mut z1);
        let mut work = vec![[f64::NAN; 3]; a.n()];
        amg.apply_with(&b, &mut z2, &mut work);
        assert!(
            flat(&z1)
                .iter()
                .zip(flat(&z2))
                .all(|(p, q)| p.to_bits() == q.to_bits())
        );
        assert!(flat(&z1).iter().all(|v| v.is_finite()));
    }

    #[test]
    fn grid_matrix_is_symmetric() {
        let (a, _) = grid_system(6, 5, 4);
        a.validate(1e-15).unwrap();
    }

    #[test]
    fn solvers_match_dense_solution() {
        let (a, b) = grid_system(9, 8, 7);
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
    fn results_identical_for_any_thread_count() {
        let (a, b) = grid_system(24, 20, 18);
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
                (flat(&x), rep.iterations)
            })
        };
        let (x1, i1) = run(1);
        let (x3, i3) = run(3);
        assert_eq!(i1, i3);
        assert!(x1.iter().zip(&x3).all(|(p, q)| p.to_bits() == q.to_bits()));
    }

    #[test]
    fn constrained_solution_stays_in_planes_and_matches_reduced_solve() {
        // Constrain every unknown of the plane k = 1 to slide in the plane z = const, and check
        // against the dense solve of the z component with those unknowns fixed at zero.
        let (nx, ny, nz) = (8, 7, 6);
        let (a, b) = grid_system(nx, ny, nz);
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
        // The multigrid preconditioner with the same constraints gives the same answer.
        let amg = Amg::new(
            &a,
            &AmgOptions {
                max_coarse: 30,
                ..Default::default()
            },
        )
        .unwrap();
        let mut y = vec![[0.0; 3]; a.n()];
        let rep2 = pcg(
            &a,
            &b,
            &mut y,
            &amg,
            &cons,
            &SolveOptions {
                rel_tol: 1e-12,
                max_iters: 5000,
            },
        );
        assert!(rep2.converged, "{rep2:?}");
        testkit::assert_close!(flat(&y), flat(&x), rel = 1e-8, abs = 1e-11);
    }

    #[test]
    fn permuted_system_gives_permuted_solution() {
        let (a, b) = grid_system(10, 9, 8);
        let n = a.n();
        let g = Graph {
            offsets: a.offsets.clone(),
            adj: a.cols.clone(),
        };
        let perm = reverse_cuthill_mckee(&g);
        let ap = a.permuted(&perm);
        ap.validate(1e-15).unwrap();
        let bp: Vec<V3> = perm.iter().map(|&o| b[o as usize]).collect();
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
        for (k, &o) in perm.iter().enumerate() {
            testkit::assert_close!(xp[k], x[o as usize], rel = 1e-9, abs = 1e-12);
        }
    }
}
