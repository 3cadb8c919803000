//! Preconditioners of the conjugate gradients: the trait, the damped-Jacobi weights a
//! preconditioner may leave to PCG's residual update, and the Jacobi (diagonal) one.

use crate::sym::{Entry, SymMatrix};
use crate::vec3::{V3, chunked_sum, dot};

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
