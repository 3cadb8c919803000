//! Preconditioned conjugate gradients on (I₃ ⊗ A) Δx = b, the three components sharing the
//! scalar matrix A, with optional per-node linear constraints (sliding on a plane or a line)
//! enforced by projection: the iteration runs in the subspace where every constrained node's
//! vector lies in its plane / on its line (projected CG, exact for linear constraints).

use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;

use crate::constraint::{Constraints, ProjectedRhs};
use crate::operator::LinearOperator;
use crate::precond::{Preconditioner, Weights};
use crate::vec3::{CHUNK, V3, axpy, axpy_xpby, chunked_sum, dot, ordered_sum};

/// Stopping rule and limits of an iterative solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolveOptions {
    /// Stop when |b − A x| ≤ rel_tol · |b| (norms over all nodes and components).
    pub rel_tol: f64,
    /// Iteration limit.
    pub max_iters: usize,
}

impl Default for SolveOptions {
    fn default() -> Self {
        Self {
            rel_tol: 1e-8,
            max_iters: 5000,
        }
    }
}

/// What an iterative solve did.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SolveReport {
    /// Solver name.
    pub solver: String,
    /// Iterations done.
    pub iterations: usize,
    /// Final relative residual |b − A x| / |b| (recomputed from scratch at the end).
    pub rel_residual: f64,
    /// True when `rel_residual ≤ rel_tol`.
    pub converged: bool,
    /// Seconds spent in the iterations.
    pub seconds: f64,
}

/// Solves A x = b (three components) by preconditioned CG from the initial guess in `x`,
/// in the subspace of `cons` (b, x and the search directions are projected; the preconditioned
/// residual too). `a` is any symmetric [`LinearOperator`] (a [`crate::SymMatrix`], or one with
/// 3×3 blocks added, [`crate::WithBlocks`]). Deterministic for any thread count.
///
/// Safeguards, so that any right-hand side converges (issue 44: single-entry adjoint seeds):
/// - a zero (projected) right-hand side returns x = 0 at once, the exact solution;
/// - an initial guess whose residual exceeds |b| (the residual of x = 0), e.g. the solution
///   of another right-hand side, is replaced by zero;
/// - when the recurrence's residual has reached the tolerance but the true residual
///   |b − A x| (recomputed) has not — round-off drift, largest when the solution is large
///   against b —, CG restarts from x with the true residual, up to [`RESTARTS`] times and
///   within `max_iters` in all.
pub fn pcg<P: Preconditioner + ?Sized, A: LinearOperator + ?Sized>(
    a: &A,
    b: &[V3],
    x: &mut [V3],
    m: &P,
    cons: &Constraints,
    opts: &SolveOptions,
) -> SolveReport {
    let t0 = Instant::now();
    let n = a.n();
    let bp = ProjectedRhs::new(b, cons);
    cons.project(x);
    let bnorm = bp.norm();
    let report = |it: usize, res: f64, t0: Instant| SolveReport {
        solver: format!("pcg-{}", m.name()),
        iterations: it,
        rel_residual: res,
        converged: res <= opts.rel_tol,
        seconds: t0.elapsed().as_secs_f64(),
    };
    if bnorm == 0.0 {
        x.fill([0.0; 3]);
        return report(0, 0.0, t0);
    }
    let mut r = vec![[0.0; 3]; n];
    let mut rr = true_residual(&bp, a, x, cons, &mut r);
    if rr > bnorm * bnorm {
        x.fill([0.0; 3]);
        rr = true_residual(&bp, a, x, cons, &mut r);
    }
    let tol = opts.rel_tol * bnorm;
    let mut it = 0;
    let mut restarts = 0;
    loop {
        if rr.sqrt() <= tol {
            break;
        }
        let before = rr.sqrt();
        it += cg_run(a, x, &mut r, rr, m, cons, tol, opts.max_iters - it);
        // The true residual (the recurrence's r drifts from it by round-off).
        rr = true_residual(&bp, a, x, cons, &mut r);
        // Restart only while it pays: iterations left and the run reduced the residual.
        if it >= opts.max_iters || restarts == RESTARTS || rr.sqrt() >= 0.5 * before {
            break;
        }
        restarts += 1;
    }
    report(it, rr.sqrt() / bnorm, t0)
}

/// At most this many restarts of CG from its iterate ([`pcg`]).
pub const RESTARTS: usize = 4;

/// r ← P (P b − A x); returns |r|².
fn true_residual<A: LinearOperator + ?Sized>(
    bp: &ProjectedRhs,
    a: &A,
    x: &[V3],
    cons: &Constraints,
    r: &mut [V3],
) -> f64 {
    bp.residual(a, x, r);
    cons.project(r);
    dot(r, r)
}

/// CG iterations from `x` with its residual `r` (|r|² = `rr`) until the recurrence's
/// residual is at most `tol`, the direction breaks down or `budget` iterations are done;
/// returns the iterations done (x updated; r is the recurrence's residual).
#[allow(clippy::too_many_arguments)]
fn cg_run<P: Preconditioner + ?Sized, A: LinearOperator + ?Sized>(
    a: &A,
    x: &mut [V3],
    r: &mut [V3],
    mut rr: f64,
    m: &P,
    cons: &Constraints,
    tol: f64,
    budget: usize,
) -> usize {
    let n = a.n();
    if budget == 0 || rr.sqrt() <= tol {
        return 0;
    }
    let mut z = vec![[0.0; 3]; n];
    // q (A p) is dead while the preconditioner runs: it lends it as scratch.
    let mut q = vec![[0.0; 3]; n];
    // r · z before z is projected: r lies in the constraints' subspace and the projections
    // are orthogonal, so r · P z = P r · z = r · z.
    let mut rz = m.apply_dot(r, &mut z, &mut q);
    cons.project(&mut z);
    let mut p = z.clone();
    let first = m.first_pass();
    let mut it = 0;
    while it < budget {
        it += 1;
        let pq = a.mul_dot(&p, &mut q);
        cons.project(&mut q);
        if pq <= 0.0 || !pq.is_finite() {
            break;
        }
        let alpha = rz / pq;
        // q is dead once r is updated: it receives the preconditioner's first pass W r.
        rr = match first {
            Some(w) => update_residual_scaled(alpha, &mut q, r, w),
            None => update_residual(alpha, &q, r),
        };
        if rr.sqrt() <= tol || it == budget {
            axpy(alpha, &p, x);
            break;
        }
        let rz_new = if first.is_some() {
            m.apply_dot_prescaled(r, &mut z, &mut q)
        } else {
            m.apply_dot(r, &mut z, &mut q)
        };
        cons.project(&mut z);
        let beta = rz_new / rz;
        rz = rz_new;
        // x += α p and the next direction in one pass over p.
        axpy_xpby(alpha, x, &z, beta, &mut p);
    }
    it
}

/// r ← r − α q, returns |r|².
fn update_residual(alpha: f64, q: &[V3], r: &mut [V3]) -> f64 {
    chunked_sum(r, |r0, cr| {
        let mut s = 0.0;
        for (ri, qi) in cr.iter_mut().zip(&q[r0..]) {
            for k in 0..3 {
                ri[k] -= alpha * qi[k];
            }
            s += ri[0] * ri[0] + ri[1] * ri[1] + ri[2] * ri[2];
        }
        s
    })
}

/// [`update_residual`], and q ← W r, in one pass.
fn update_residual_scaled(alpha: f64, q: &mut [V3], r: &mut [V3], w: Weights) -> f64 {
    let parts: Vec<f64> = r
        .par_chunks_mut(CHUNK)
        .zip(q.par_chunks_mut(CHUNK))
        .enumerate()
        .map(|(c, (cr, cq))| {
            let r0 = c * CHUNK;
            let mut s = 0.0;
            for (k, (ri, qi)) in cr.iter_mut().zip(cq.iter_mut()).enumerate() {
                for j in 0..3 {
                    ri[j] -= alpha * qi[j];
                }
                s += ri[0] * ri[0] + ri[1] * ri[1] + ri[2] * ri[2];
                let wk = w.at(r0 + k);
                *qi = [wk * ri[0], wk * ri[1], wk * ri[2]];
            }
            s
        })
        .collect();
    ordered_sum(parts)
}
