//! Preconditioned conjugate gradients on (I₃ ⊗ A) Δx = b, the three components sharing the
//! scalar matrix A, with optional per-node linear constraints (sliding on a plane or a line)
//! enforced by projection: the iteration runs in the subspace where every constrained node's
//! vector lies in its plane / on its line (projected CG, exact for linear constraints).

use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;

use super::csr::{Entry, SymMatrix};
use super::vecops::{CHUNK, V3, axpy, axpy_xpby, chunked_sum, dot, norm, ordered_sum};

/// A linear constraint on one unknown's 3-vector.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Constraint {
    /// The vector must be orthogonal to this unit normal (node sliding on a plane).
    Plane([f64; 3]),
    /// The vector must be parallel to this unit direction (node sliding on a straight line).
    Line([f64; 3]),
}

impl Constraint {
    /// Projects `v` onto the allowed subspace.
    #[inline]
    pub fn project(&self, v: &mut V3) {
        match self {
            Constraint::Plane(n) => {
                let d = v[0] * n[0] + v[1] * n[1] + v[2] * n[2];
                for k in 0..3 {
                    v[k] -= d * n[k];
                }
            }
            Constraint::Line(t) => {
                let d = v[0] * t[0] + v[1] * t[1] + v[2] * t[2];
                for k in 0..3 {
                    v[k] = d * t[k];
                }
            }
        }
    }
}

/// Constraints of the unknowns (sorted by unknown index).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Constraints {
    /// (unknown index, constraint).
    pub items: Vec<(u32, Constraint)>,
}

impl Constraints {
    /// Projects every constrained entry of `v`.
    pub fn project(&self, v: &mut [V3]) {
        for (i, c) in &self.items {
            c.project(&mut v[*i as usize]);
        }
    }

    /// True when there is no constraint.
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }
}

/// Damped-Jacobi weights w_i = ω / d_i, formed on use (the same division as a stored weight
/// vector, bit for bit; one vector less to hold and to read): the multigrid's smoother, and
/// the first pass a preconditioner may leave to PCG ([`Preconditioner::first_pass`]).
#[derive(Debug, Clone, Copy)]
pub struct Weights<'a> {
    /// The damping ω.
    pub omega: f64,
    /// The diagonal d.
    pub diag: &'a [f64],
}

impl Weights<'_> {
    /// w_i = ω / d_i.
    #[inline]
    pub fn at(self, i: usize) -> f64 {
        self.omega / self.diag[i]
    }
}

/// A preconditioner z = M⁻¹ r (symmetric positive definite), applied to the three components.
pub trait Preconditioner: Sync {
    /// z ← M⁻¹ r.
    fn apply(&self, r: &[V3], z: &mut [V3]);
    /// z ← M⁻¹ r, with `work` (same length as r, contents ignored and overwritten) as
    /// scratch the preconditioner may use instead of its own (the result is the same as
    /// [`Preconditioner::apply`]'s). The default ignores it.
    fn apply_with(&self, r: &[V3], z: &mut [V3], work: &mut [V3]) {
        let _ = work;
        self.apply(r, z);
    }
    /// [`Preconditioner::apply_with`], returning r · z (bit for bit [`dot`]`(r, z)`: the
    /// default computes it so; a preconditioner may fuse it into its last pass).
    fn apply_dot(&self, r: &[V3], z: &mut [V3], work: &mut [V3]) -> f64 {
        self.apply_with(r, z, work);
        dot(r, z)
    }
    /// The weights W of a first pass x = W r the preconditioner starts with, if it has one.
    /// PCG then forms W r in its residual update, in `work`, and calls
    /// [`Preconditioner::apply_dot_prescaled`]: one pass over r less per iteration.
    fn first_pass(&self) -> Option<Weights<'_>> {
        None
    }
    /// [`Preconditioner::apply_dot`] with `work` already holding W r (see
    /// [`Preconditioner::first_pass`]); bit for bit the same result. The default ignores
    /// `work`'s contents.
    fn apply_dot_prescaled(&self, r: &[V3], z: &mut [V3], work: &mut [V3]) -> f64 {
        self.apply_dot(r, z, work)
    }
    /// Short name for reports.
    fn name(&self) -> &'static str;
    /// Bytes held.
    fn bytes(&self) -> usize {
        0
    }
}

/// Jacobi (diagonal) preconditioner.
#[derive(Debug, Clone)]
pub struct Jacobi {
    inv_diag: Vec<f64>,
}

impl Jacobi {
    /// From the matrix diagonal (must be positive).
    pub fn new<T: Entry>(a: &SymMatrix<T>) -> Self {
        Self {
            inv_diag: a.diag.iter().map(|d| 1.0 / d).collect(),
        }
    }
}

impl Preconditioner for Jacobi {
    fn apply(&self, r: &[V3], z: &mut [V3]) {
        self.apply_dot(r, z, &mut []);
    }
    /// z = D⁻¹ r and r · z in one pass.
    fn apply_dot(&self, r: &[V3], z: &mut [V3], _work: &mut [V3]) -> f64 {
        chunked_sum(z, |r0, zs| {
            let mut s = 0.0;
            for (k, zi) in zs.iter_mut().enumerate() {
                let d = self.inv_diag[r0 + k];
                let ri = r[r0 + k];
                *zi = [d * ri[0], d * ri[1], d * ri[2]];
                s += ri[0] * zi[0] + ri[1] * zi[1] + ri[2] * zi[2];
            }
            s
        })
    }
    fn name(&self) -> &'static str {
        "jacobi"
    }
    fn bytes(&self) -> usize {
        self.inv_diag.len() * 8
    }
}

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
/// residual too). Deterministic for any thread count.
pub fn pcg<P: Preconditioner + ?Sized, T: Entry>(
    a: &SymMatrix<T>,
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
    let mut r = vec![[0.0; 3]; n];
    let mut rr = bp.residual(a, x, &mut r);
    cons.project(&mut r);
    if !cons.is_empty() {
        rr = dot(&r, &r);
    }
    let report = |it: usize, res: f64, t0: Instant| SolveReport {
        solver: format!("pcg-{}", m.name()),
        iterations: it,
        rel_residual: res,
        converged: res <= opts.rel_tol,
        seconds: t0.elapsed().as_secs_f64(),
    };
    // With a zero right-hand side the tolerance is absolute (x = 0 returns at once).
    let scale = if bnorm > 0.0 { bnorm } else { 1.0 };
    if rr.sqrt() <= opts.rel_tol * scale {
        return report(0, rr.sqrt() / scale, t0);
    }
    let mut z = vec![[0.0; 3]; n];
    // q (A p) is dead while the preconditioner runs: it lends it as scratch.
    let mut q = vec![[0.0; 3]; n];
    // r · z before z is projected: r lies in the constraints' subspace and the projections
    // are orthogonal, so r · P z = P r · z = r · z.
    let mut rz = m.apply_dot(&r, &mut z, &mut q);
    cons.project(&mut z);
    let mut p = z.clone();
    let first = m.first_pass();
    let mut it = 0;
    while it < opts.max_iters {
        it += 1;
        let pq = a.mul_dot(&p, &mut q);
        cons.project(&mut q);
        if pq <= 0.0 || !pq.is_finite() {
            break;
        }
        let alpha = rz / pq;
        // q is dead once r is updated: it receives the preconditioner's first pass W r.
        rr = match first {
            Some(w) => update_residual_scaled(alpha, &mut q, &mut r, w),
            None => update_residual(alpha, &q, &mut r),
        };
        if rr.sqrt() <= opts.rel_tol * scale || it == opts.max_iters {
            axpy(alpha, &p, x);
            break;
        }
        let rz_new = if first.is_some() {
            m.apply_dot_prescaled(&r, &mut z, &mut q)
        } else {
            m.apply_dot(&r, &mut z, &mut q)
        };
        cons.project(&mut z);
        let beta = rz_new / rz;
        rz = rz_new;
        // x += α p and the next direction in one pass over p.
        axpy_xpby(alpha, x, &z, beta, &mut p);
    }
    // True residual (in z's storage: not needed any more).
    let rtrue = &mut z;
    bp.residual(a, x, rtrue);
    cons.project(rtrue);
    report(it, norm(rtrue) / scale, t0)
}

/// The right-hand side `b` projected on the constraints, without a projected copy of `b`:
/// the constrained unknowns (stably sorted by index, so each unknown's constraints apply in
/// the order of [`Constraints::items`], as [`Constraints::project`] does) are projected when
/// they are read. Every result is bit for bit that of the same computation on a projected
/// copy.
struct ProjectedRhs<'b> {
    b: &'b [V3],
    items: Vec<(u32, Constraint)>,
}

impl<'b> ProjectedRhs<'b> {
    fn new(b: &'b [V3], cons: &Constraints) -> Self {
        let mut items = cons.items.clone();
        items.sort_by_key(|e| e.0);
        Self { b, items }
    }

    /// The projected b_i of the unknown `items[*t].0` (on entry), `t` moved past its items.
    #[inline]
    fn take(&self, t: &mut usize) -> V3 {
        let i = self.items[*t].0;
        let mut v = self.b[i as usize];
        while *t < self.items.len() && self.items[*t].0 == i {
            self.items[*t].1.project(&mut v);
            *t += 1;
        }
        v
    }

    /// |P b| (the chunked sums of [`norm`]).
    fn norm(&self) -> f64 {
        if self.items.is_empty() {
            return norm(self.b);
        }
        let parts: Vec<f64> = self
            .b
            .par_chunks(CHUNK)
            .enumerate()
            .map(|(c, cb)| {
                let lo = c * CHUNK;
                let mut t = self.items.partition_point(|e| (e.0 as usize) < lo);
                let mut s = 0.0;
                for (k, bk) in cb.iter().enumerate() {
                    let v = if t < self.items.len() && self.items[t].0 as usize == lo + k {
                        self.take(&mut t)
                    } else {
                        *bk
                    };
                    s += v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
                }
                s
            })
            .collect();
        ordered_sum(parts).sqrt()
    }

    /// r ← P b − A x; returns |r|² only without constraints (otherwise the caller projects r
    /// and sums it again).
    fn residual<T: Entry>(&self, a: &SymMatrix<T>, x: &[V3], r: &mut [V3]) -> f64 {
        let rr = a.residual(self.b, x, r);
        let mut t = 0;
        while t < self.items.len() {
            let i = self.items[t].0 as usize;
            let bi = self.take(&mut t);
            let v = a.row_mul(i, x);
            r[i] = [bi[0] - v[0], bi[1] - v[1], bi[2] - v[2]];
        }
        rr
    }
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
        let step = super::vecops::max_len(&r);
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn projected_rhs_equals_a_projected_copy_bit_for_bit() {
        let (a, b) = crate::solve::tests::grid_system(20, 19, 18); // 4896 unknowns: 2 chunks
        assert!(a.n() > CHUNK);
        let x: Vec<V3> = (0..a.n())
            .map(|i| [(i as f64).sin(), 0.1 * i as f64, (0.3 * i as f64).cos()])
            .collect();
        let s = 0.5f64.sqrt();
        // Unsorted, one unknown with two constraints, some in the second chunk.
        let cons = Constraints {
            items: vec![
                (4100, Constraint::Plane([0.0, s, s])),
                (7, Constraint::Plane([1.0, 0.0, 0.0])),
                (4095, Constraint::Line([s, 0.0, s])),
                (7, Constraint::Line([0.0, s, -s])),
                (0, Constraint::Plane([0.0, 0.0, 1.0])),
            ],
        };
        let mut bp = b.clone();
        cons.project(&mut bp);
        let rhs = ProjectedRhs::new(&b, &cons);
        assert_eq!(rhs.norm().to_bits(), norm(&bp).to_bits());
        let (mut r1, mut r2) = (vec![[0.0; 3]; a.n()], vec![[0.0; 3]; a.n()]);
        rhs.residual(&a, &x, &mut r1);
        a.residual(&bp, &x, &mut r2);
        assert!(
            r1.iter()
                .flatten()
                .zip(r2.iter().flatten())
                .all(|(p, q)| p.to_bits() == q.to_bits())
        );
        // Without constraints: b itself.
        let free = ProjectedRhs::new(&b, &Constraints::default());
        assert_eq!(free.norm().to_bits(), norm(&b).to_bits());
    }
}
