//! The stationary (point) iteration: the paper's Eq. 22 in Jacobi form, with the projected
//! constraints of [`crate::constraint`].

use std::time::Instant;

use rayon::prelude::*;

use crate::constraint::{Constraints, ProjectedRhs};
use crate::pcg::{SolveOptions, SolveReport};
use crate::sym::{Entry, SymMatrix};
use crate::vec3::{CHUNK, V3, axpy, max_len, norm};

/// The paper's point iteration (Eqs. 22–24) in Jacobi form: Δx_i ← Δx_i + ω (b_i − (A Δx)_i)
/// / a_ii, i.e. RH_i of Eq. 23 scaled by the node's total stiffness Σ_j K_ij (the paper leaves
/// the scaling implicit; without it the iteration diverges for stiffness values ≫ 1). All
/// nodes are updated from the previous iterate (deterministic in parallel). Stops when the
/// largest node update |δx_i| (Eq. 24) is ≤ `step_tol` (a length), or when the relative
/// residual reaches `opts.rel_tol`.
pub fn point_iteration<T: Entry>(
    a: &SymMatrix<T>,
    b: &[V3],
    x: &mut [V3],
    cons: &Constraints,
    omega: f64,
    step_tol: f64,
    opts: &SolveOptions,
) -> SolveReport {
    let t0 = Instant::now();
    let n = a.n();
    let bp = ProjectedRhs::new(b, cons);
    cons.project(x);
    let bnorm = bp.norm();
    let scale = if bnorm > 0.0 { bnorm } else { 1.0 };
    let mut r = vec![[0.0; 3]; n];
    let mut it = 0;
    let mut rel = f64::INFINITY;
    while it < opts.max_iters {
        bp.residual(a, x, &mut r);
        cons.project(&mut r);
        rel = norm(&r) / scale;
        if rel <= opts.rel_tol {
            break;
        }
        it += 1;
        // δx_i = ω r_i / a_ii (Eq. 22–23), projected on the constraints.
        r.par_chunks_mut(CHUNK).enumerate().for_each(|(c, rs)| {
            let r0 = c * CHUNK;
            for (k, ri) in rs.iter_mut().enumerate() {
                let s = omega / a.diag[r0 + k];
                for v in ri.iter_mut() {
                    *v *= s;
                }
            }
        });
        cons.project(&mut r);
        let step = max_len(&r);
        axpy(1.0, &r, x);
        if step <= step_tol {
            bp.residual(a, x, &mut r);
            cons.project(&mut r);
            rel = norm(&r) / scale;
            break;
        }
    }
    SolveReport {
        solver: "point-jacobi".into(),
        iterations: it,
        rel_residual: rel,
        converged: rel <= opts.rel_tol || it < opts.max_iters,
        seconds: t0.elapsed().as_secs_f64(),
    }
}
