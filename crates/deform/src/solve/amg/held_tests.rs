//! Tests of the constrained multigrid ([`Amg::new_held`]).

use sparse::generate::spring_grid;
use sparse::vec3::{self, V3};
use sparse::{Constraint, Constraints, Jacobi, Preconditioner, SolveOptions, SymMatrix, pcg};

use super::tests::bits;
use super::*;
use crate::solve::held::held_mask;

/// A smooth field with every component non-zero at every node.
fn field(n: usize, seed: f64) -> Vec<V3> {
    (0..n)
        .map(|i| {
            let t = seed * (i as f64 + 1.0) / n as f64;
            [
                (3.0 * t).sin() + 0.5,
                (2.0 * t).cos(),
                (5.0 * t).sin() - 0.7,
            ]
        })
        .collect()
}

/// The spring grid's first layer of unknowns (k = 1) slides on the plane of normal
/// `normal`, except its first row (j = 1), which slides on the line along x.
fn sliding_layer(nx: usize, ny: usize, normal: [f64; 3]) -> Constraints {
    let layer = (nx - 2) * (ny - 2);
    Constraints {
        items: (0..layer as u32)
            .map(|i| {
                if (i as usize) < nx - 2 {
                    (i, Constraint::Line([1.0, 0.0, 0.0]))
                } else {
                    (i, Constraint::Plane(normal))
                }
            })
            .collect(),
    }
}

/// |x − y| / |y|.
fn rel_diff(x: &[V3], y: &[V3]) -> f64 {
    let d: Vec<V3> = x
        .iter()
        .zip(y)
        .map(|(p, q)| [p[0] - q[0], p[1] - q[1], p[2] - q[2]])
        .collect();
    vec3::norm(&d) / vec3::norm(y)
}

fn solve(a: &SymMatrix, b: &[V3], m: &dyn Preconditioner, cons: &Constraints) -> (Vec<V3>, usize) {
    let so = SolveOptions {
        rel_tol: 1e-12,
        max_iters: 20_000,
    };
    let mut x = vec![[0.0; 3]; a.n()];
    let rep = pcg(a, b, &mut x, m, cons, &so);
    assert!(rep.converged, "{rep:?}");
    (x, rep.iterations)
}

/// The spring grid with its first layer of unknowns a free boundary, as a symmetry plane
/// is: the layer's couplings to the prescribed layer below it taken out of the diagonal
/// (row sums zero there).
fn free_layer(nx: usize, ny: usize, nz: usize) -> SymMatrix {
    let (mut a, _) = spring_grid(nx, ny, nz);
    for i in 0..(nx - 2) * (ny - 2) {
        let (_, v) = a.row(i);
        a.diag[i] = v.iter().map(|x| x.abs()).sum();
    }
    a
}

fn opts() -> AmgOptions {
    AmgOptions {
        max_coarse: 40,
        ..Default::default()
    }
}

#[test]
fn held_multigrid_with_nothing_held_is_the_free_one_bit_for_bit() {
    let (a, b) = spring_grid(16, 15, 14);
    let free = Amg::new_owned(a.clone(), &opts()).unwrap();
    let held = Amg::new_held(a.clone(), &opts(), &vec![0; a.n()]).unwrap();
    assert_eq!(free.info().sizes, held.info().sizes);
    let (mut z1, mut z2) = (vec![[0.0; 3]; a.n()], vec![[0.0; 3]; a.n()]);
    let mut work = vec![[0.0; 3]; a.n()];
    let d1 = free.apply_dot(&b, &mut z1, &mut work);
    let d2 = held.apply_dot(&b, &mut z2, &mut work);
    assert_eq!(bits(&z1), bits(&z2));
    assert_eq!(d1.to_bits(), d2.to_bits());
}

#[test]
fn held_multigrid_solves_a_sliding_plane_in_fewer_iterations_than_the_free_one() {
    // A z = const plane with a seam line, and weights with a z component everywhere: the
    // free multigrid treats the plane's z as free, the constrained one holds it.
    let (nx, ny, nz) = (30, 28, 26);
    let a = free_layer(nx, ny, nz);
    let b: Vec<V3> = field(a.n(), 7.0).iter().map(|v| [0.0, 0.0, v[2]]).collect();
    let cons = sliding_layer(nx, ny, [0.0, 0.0, 1.0]);
    let mask = held_mask(a.n(), &cons);
    assert!(mask.iter().filter(|&&m| m == 4).count() > 100);
    assert!(mask.iter().filter(|&&m| m == 6).count() > 10);
    let (exact, it_jacobi) = solve(&a, &b, &Jacobi::new(&a), &cons);
    let free = Amg::new_owned(a.clone(), &opts()).unwrap();
    let held = Amg::new_held(a.clone(), &opts(), &mask).unwrap();
    assert!(held.info().sizes.len() >= 3, "{:?}", held.info().sizes);
    let (x_free, it_free) = solve(&a, &b, &free, &cons);
    let (x_held, it_held) = solve(&a, &b, &held, &cons);
    for x in [&x_free, &x_held] {
        assert!(rel_diff(x, &exact) <= 1e-9);
    }
    // At least a fifth fewer (24 against 32 when written).
    assert!(
        5 * it_held <= 4 * it_free && it_free < it_jacobi,
        "held {it_held}, free {it_free}, Jacobi {it_jacobi}"
    );
    // The same iterates for any thread count.
    let run = |threads: usize| {
        testkit::with_threads(threads, || {
            let h = Amg::new_held(a.clone(), &opts(), &mask).unwrap();
            let (x, it) = solve(&a, &b, &h, &cons);
            (bits(&x), it)
        })
    };
    assert_eq!(run(1), run(3));
}

#[test]
fn held_multigrid_is_symmetric_positive_definite_for_a_tilted_plane() {
    // A plane not along an axis: the held component (z, n's largest) is an approximation;
    // the cycle must still be symmetric and positive on the constraints' subspace, and
    // the solve must reach the constrained solution.
    let (nx, ny, nz) = (18, 16, 14);
    let (a, _) = spring_grid(nx, ny, nz);
    let cons = sliding_layer(nx, ny, [0.6, 0.0, 0.8]);
    let mask = held_mask(a.n(), &cons);
    let held = Amg::new_held(a.clone(), &opts(), &mask).unwrap();
    let (mut u, mut v) = (field(a.n(), 3.0), field(a.n(), 11.0));
    cons.project(&mut u);
    cons.project(&mut v);
    let (mut mu, mut mv) = (vec![[0.0; 3]; a.n()], vec![[0.0; 3]; a.n()]);
    held.apply(&u, &mut mu);
    held.apply(&v, &mut mv);
    let (umv, vmu) = (vec3::dot(&u, &mv), vec3::dot(&v, &mu));
    assert!((umv - vmu).abs() <= 1e-12 * vec3::norm(&u) * vec3::norm(&mv));
    assert!(vec3::dot(&u, &mu) > 0.0 && vec3::dot(&v, &mv) > 0.0);
    // A vector in the subspace that lives only in the held component of one node.
    let mut e = vec![[0.0; 3]; a.n()];
    e[nx] = [-0.8, 0.0, 0.6];
    let mut me = vec![[0.0; 3]; a.n()];
    held.apply(&e, &mut me);
    assert!(vec3::dot(&e, &me) > 0.0);
    let b = field(a.n(), 5.0);
    let (exact, _) = solve(&a, &b, &Jacobi::new(&a), &cons);
    let (x, _) = solve(&a, &b, &held, &cons);
    assert!(rel_diff(&x, &exact) <= 1e-9);
}
