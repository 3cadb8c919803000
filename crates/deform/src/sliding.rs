//! Sliding on the support curves and surfaces of the geometry (paper §4.3, Eqs. 27–33): the
//! tangent constraints of the solve, and the outer iteration that places every sliding node
//! on its support and re-linearises the constraints there.

use sparse::vec3::{axpy, norm};
use sparse::{Constraints, V3};

use crate::assembly::System;
use crate::bc::Classified;
use crate::error::{Error, Result};
use crate::operator::{Operator, check_converged};
use crate::options::DeformOptions;
use crate::support::{Supports, place, point, tangent_constraint};

/// The constraints of the solve: the planes and seam lines of `sys`, and the tangent plane
/// or line of every node sliding on a support at its parameters `params`.
pub(crate) fn constraints(
    cls: &Classified,
    sys: &System,
    sup: Option<&Supports>,
    params: &[[f64; 2]],
) -> Result<Constraints> {
    let mut cons = sys.cons.clone();
    if let Some(sp) = sup {
        for (k, s) in cls.supports.iter().enumerate() {
            let u = sys.sup_unk[k];
            if u != u32::MAX {
                cons.items
                    .push((u, tangent_constraint(sp.db, s.node, s.kind, params[k])?));
            }
        }
    }
    Ok(cons)
}

/// What one increment's sliding problem reads: the set-up, the operator of the state, and
/// the sizes its criteria are relative to.
pub(crate) struct Sliding<'a> {
    pub cls: &'a Classified,
    pub sys: &'a System,
    pub sup: &'a Supports<'a>,
    pub op: &'a Operator,
    pub opts: &'a DeformOptions,
    /// The grid's bounding-box diagonal (the placement's length scale).
    pub scale: f64,
    /// The largest boundary displacement of the increment.
    pub max_disp: f64,
}

/// What the outer iteration did.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct SlideOutcome {
    /// Outer iterations.
    pub iterations: usize,
    /// The last largest node update relative to the boundary displacement.
    pub update: f64,
    /// Iterations of the correction solves.
    pub solver_iterations: usize,
}

impl Sliding<'_> {
    /// The outer iteration from the constrained solution `dx` of A Δx = `b` (Δx from the
    /// state `cur`, updates measured from `start`, the solve's initial guess): place every
    /// sliding node on its support nearest to its tentative position (parameters by Eq. 31 /
    /// 28, in `params`), re-linearise the constraints there and solve for the correction,
    /// until the largest node update is ≤ `slide_rel_tol` × the largest boundary
    /// displacement.
    pub fn iterate(
        &self,
        cur: &[[f64; 3]],
        b: &[V3],
        dx: &mut [V3],
        start: Vec<V3>,
        params: &mut [[f64; 2]],
    ) -> Result<SlideOutcome> {
        let (cls, sys, sp, opts) = (self.cls, self.sys, self.sup, self.opts);
        let (scale, max_disp) = (self.scale, self.max_disp);
        let a = self.op.matrix();
        let nu = sys.node_of.len();
        let bnorm = norm(b);
        let mut base = start;
        let mut converged = false;
        let mut update = f64::INFINITY;
        let mut out = SlideOutcome {
            iterations: 0,
            update: 0.0,
            solver_iterations: 0,
        };
        for outer in 1..=opts.max_slide_iters.max(1) {
            // Place the sliding nodes.
            for (k, sn) in cls.supports.iter().enumerate() {
                let u = sys.sup_unk[k];
                if u == u32::MAX {
                    continue;
                }
                let i = sn.node as usize;
                let d = dx[u as usize];
                let tgt = [cur[i][0] + d[0], cur[i][1] + d[1], cur[i][2] + d[2]];
                let p = place(sp.db, sn.node, sn.kind, params[k], tgt, 1e-14 * scale)?;
                params[k] = p;
                let r = point(sp.db, sn.kind, p);
                dx[u as usize] = [r[0] - cur[i][0], r[1] - cur[i][1], r[2] - cur[i][2]];
            }
            // Largest node update of this iteration.
            let upd = largest_update(dx, &mut base);
            update = upd / max_disp;
            out.iterations = outer;
            if upd <= opts.slide_rel_tol * max_disp {
                converged = true;
                break;
            }
            // Correction: A δ = b − A Δx, δ in the tangent spaces at the new parameters.
            let cons = constraints(cls, sys, Some(sp), params)?;
            let mut r = vec![[0.0; 3]; nu];
            a.residual(b, dx, &mut r);
            let mut rp = r.clone();
            cons.project(&mut rp);
            let rn = norm(&rp);
            let tol = correction_tol(opts, bnorm, rn);
            let mut delta = vec![[0.0; 3]; nu];
            let rep = self.op.solve_to(&r, &mut delta, &cons, opts, max_disp, tol);
            check_converged(&rep, "spring system (Eq. 21), sliding correction", opts)?;
            out.solver_iterations += rep.iterations;
            axpy(1.0, &delta, dx);
        }
        out.finish(update, converged)
    }
}

/// The largest distance between `dx` and `prev` over the nodes (one outer iteration's
/// update), and `prev` set to `dx`.
pub(crate) fn largest_update(dx: &[V3], prev: &mut [V3]) -> f64 {
    let mut upd = 0.0f64;
    for (d, p) in dx.iter().zip(prev.iter_mut()) {
        let e = ((d[0] - p[0]).powi(2) + (d[1] - p[1]).powi(2) + (d[2] - p[2]).powi(2)).sqrt();
        upd = upd.max(e);
        *p = *d;
    }
    upd
}

/// The relative residual of a sliding correction's solve: the deformation's tolerance of
/// the right-hand side `bnorm` against the projected residual `rn`, at most 0.5.
pub(crate) fn correction_tol(opts: &DeformOptions, bnorm: f64, rn: f64) -> f64 {
    if rn > 0.0 {
        (opts.rel_tol * bnorm / rn).min(0.5)
    } else {
        0.5
    }
}

impl SlideOutcome {
    /// The outcome with its last update `update` (× the boundary displacement), or the
    /// failure of an outer iteration that did not get below its tolerance.
    pub(crate) fn finish(mut self, update: f64, converged: bool) -> Result<Self> {
        self.update = update;
        if converged {
            return Ok(self);
        }
        Err(Error::NoConvergence {
            what: format!(
                "sliding on supports (Eqs. 27–33): largest node update {update:.3e} × the boundary displacement after"
            ),
            solver: "outer iteration".into(),
            iterations: self.iterations,
            residual: update,
        })
    }
}
