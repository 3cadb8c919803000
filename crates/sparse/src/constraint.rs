//! Per-unknown linear constraints (sliding on a plane or along a line) and the right-hand
//! side projected on them: what the projected iterations of [`crate::pcg()`] and
//! [`crate::stationary`] work with.

use rayon::prelude::*;

use crate::operator::LinearOperator;
use crate::vec3::{CHUNK, V3, norm, ordered_sum};

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

/// The right-hand side `b` projected on the constraints, without a projected copy of `b`:
/// the constrained unknowns (stably sorted by index, so each unknown's constraints apply in
/// the order of [`Constraints::items`], as [`Constraints::project`] does) are projected when
/// they are read. Every result is bit for bit that of the same computation on a projected
/// copy.
pub(crate) struct ProjectedRhs<'b> {
    b: &'b [V3],
    items: Vec<(u32, Constraint)>,
}

impl<'b> ProjectedRhs<'b> {
    pub(crate) fn new(b: &'b [V3], cons: &Constraints) -> Self {
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
    pub(crate) fn norm(&self) -> f64 {
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
    pub(crate) fn residual<A: LinearOperator + ?Sized>(
        &self,
        a: &A,
        x: &[V3],
        r: &mut [V3],
    ) -> f64 {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn projected_rhs_equals_a_projected_copy_bit_for_bit() {
        let (a, b) = crate::generate::spring_grid(20, 19, 18); // 4896 unknowns: 2 chunks
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
