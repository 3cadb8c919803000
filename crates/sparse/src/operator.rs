//! Linear operators on vectors of 3-vectors ([`LinearOperator`]): what [`crate::pcg()`]
//! multiplies by. A [`SymMatrix`] is one (one scalar matrix shared by the three components);
//! [`WithBlocks`] adds symmetric 3×3 blocks on the diagonal of some unknowns, which couple
//! their three components (the curvature terms of a linearised sliding constraint).

use crate::sym::{Entry, SymMatrix};
use crate::vec3::{V3, chunked_sum};

/// A symmetric linear operator on vectors of 3-vectors (one per unknown).
pub trait LinearOperator: Sync {
    /// Number of unknowns.
    fn n(&self) -> usize;
    /// y ← A x, returns xᵀ A x (deterministic for any thread count).
    fn mul_dot(&self, x: &[V3], y: &mut [V3]) -> f64;
    /// r ← b − A x, returns |r|² (deterministic for any thread count).
    fn residual(&self, b: &[V3], x: &[V3], r: &mut [V3]) -> f64;
    /// (A x)_i, bit for bit the entry i of [`LinearOperator::mul_dot`]'s y.
    fn row_mul(&self, i: usize, x: &[V3]) -> V3;
}

impl<T: Entry> LinearOperator for SymMatrix<T> {
    fn n(&self) -> usize {
        SymMatrix::n(self)
    }
    fn mul_dot(&self, x: &[V3], y: &mut [V3]) -> f64 {
        SymMatrix::mul_dot(self, x, y)
    }
    fn residual(&self, b: &[V3], x: &[V3], r: &mut [V3]) -> f64 {
        SymMatrix::residual(self, b, x, r)
    }
    fn row_mul(&self, i: usize, x: &[V3]) -> V3 {
        SymMatrix::row_mul(self, i, x)
    }
}

/// A symmetric 3×3 block (row-major).
pub type Block3 = [[f64; 3]; 3];

/// The operator (I₃ ⊗ A) + B, B block diagonal: `blocks` holds (unknown, symmetric 3×3
/// block) pairs, sorted by unknown, at most one per unknown; the other unknowns' blocks are
/// zero.
#[derive(Debug, Clone, Copy)]
pub struct WithBlocks<'a, T: Entry> {
    /// The scalar matrix A.
    pub a: &'a SymMatrix<T>,
    /// The blocks, sorted by unknown.
    pub blocks: &'a [(u32, Block3)],
}

#[inline]
fn block_mul(b: &Block3, x: V3) -> V3 {
    [
        b[0][0] * x[0] + b[0][1] * x[1] + b[0][2] * x[2],
        b[1][0] * x[0] + b[1][1] * x[1] + b[1][2] * x[2],
        b[2][0] * x[0] + b[2][1] * x[1] + b[2][2] * x[2],
    ]
}

impl<T: Entry> WithBlocks<'_, T> {
    /// Adds B x to `y` (every block's row), in block order.
    fn add_blocks(&self, x: &[V3], y: &mut [V3], sign: f64) {
        for (i, b) in self.blocks {
            let i = *i as usize;
            let v = block_mul(b, x[i]);
            for k in 0..3 {
                y[i][k] += sign * v[k];
            }
        }
    }
}

impl<T: Entry> LinearOperator for WithBlocks<'_, T> {
    fn n(&self) -> usize {
        self.a.n()
    }
    fn mul_dot(&self, x: &[V3], y: &mut [V3]) -> f64 {
        if self.blocks.is_empty() {
            return self.a.mul_dot(x, y);
        }
        self.a.mul(x, y);
        self.add_blocks(x, y, 1.0);
        chunked_sum(y, |r0, ys| {
            ys.iter()
                .zip(&x[r0..])
                .map(|(v, u)| v[0] * u[0] + v[1] * u[1] + v[2] * u[2])
                .sum()
        })
    }
    fn residual(&self, b: &[V3], x: &[V3], r: &mut [V3]) -> f64 {
        if self.blocks.is_empty() {
            return self.a.residual(b, x, r);
        }
        self.a.residual(b, x, r);
        self.add_blocks(x, r, -1.0);
        chunked_sum(r, |_, rs| {
            rs.iter()
                .map(|v| v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
                .sum()
        })
    }
    fn row_mul(&self, i: usize, x: &[V3]) -> V3 {
        let mut v = self.a.row_mul(i, x);
        if let Ok(p) = self.blocks.binary_search_by_key(&(i as u32), |e| e.0) {
            let w = block_mul(&self.blocks[p].1, x[i]);
            for k in 0..3 {
                v[k] += w[k];
            }
        }
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_add_to_the_matrix_product_and_residual() {
        let (a, b) = crate::generate::spring_grid(6, 5, 4);
        let n = a.n();
        let blocks = vec![
            (
                3u32,
                [[1.0, 0.5, 0.0], [0.5, 2.0, -0.25], [0.0, -0.25, 0.5]],
            ),
            (17u32, [[0.1, 0.0, 0.2], [0.0, 0.0, 0.0], [0.2, 0.0, -0.3]]),
        ];
        let op = WithBlocks {
            a: &a,
            blocks: &blocks,
        };
        let x: Vec<V3> = (0..n)
            .map(|i| [(i as f64).sin(), 0.3 * i as f64, (0.7 * i as f64).cos()])
            .collect();
        let mut y = vec![[0.0; 3]; n];
        let xay = LinearOperator::mul_dot(&op, &x, &mut y);
        let mut ay = vec![[0.0; 3]; n];
        a.mul(&x, &mut ay);
        let mut want = 0.0;
        for i in 0..n {
            let mut v = ay[i];
            if let Some((_, bl)) = blocks.iter().find(|e| e.0 as usize == i) {
                let w = block_mul(bl, x[i]);
                for k in 0..3 {
                    v[k] += w[k];
                }
            }
            assert_eq!(y[i], v, "row {i}");
            assert_eq!(op.row_mul(i, &x), v, "row_mul {i}");
            want += v[0] * x[i][0] + v[1] * x[i][1] + v[2] * x[i][2];
        }
        assert!((xay - want).abs() <= 1e-12 * want.abs());
        let mut r = vec![[0.0; 3]; n];
        let rr = LinearOperator::residual(&op, &b, &x, &mut r);
        let mut s = 0.0;
        for i in 0..n {
            for k in 0..3 {
                // (b − A x) − B x: the same as b − (A x + B x) up to round-off.
                let want = b[i][k] - y[i][k];
                assert!(
                    (r[i][k] - want).abs() <= 1e-14 * (b[i][k].abs() + y[i][k].abs()),
                    "row {i}: {} vs {want}",
                    r[i][k]
                );
                s += r[i][k] * r[i][k];
            }
        }
        assert!((rr - s).abs() <= 1e-12 * s);
    }
}
