//! The coarsest multigrid level's dense Cholesky factorisation.

use sparse::{Entry, SymMatrix, V3};

use crate::error::{Error, Result};

/// Dense Cholesky factor of the coarsest matrix (row-major lower triangle).
pub(super) struct DenseCholesky {
    n: usize,
    pub l: Vec<f64>,
}

impl DenseCholesky {
    pub fn new<T: Entry>(a: &SymMatrix<T>, level: usize) -> Result<Self> {
        let n = a.n();
        let mut l = vec![0.0; n * n];
        for (i, row) in a.to_dense().into_iter().enumerate() {
            l[i * n..(i + 1) * n].copy_from_slice(&row);
        }
        let dmax = a.diag.iter().fold(0.0f64, |m, d| m.max(d.abs()));
        for j in 0..n {
            let mut d = l[j * n + j];
            for k in 0..j {
                d -= l[j * n + k] * l[j * n + k];
            }
            if d <= 1e-13 * dmax || !d.is_finite() {
                return Err(Error::NotPositiveDefinite {
                    level,
                    index: j,
                    pivot: d,
                });
            }
            let d = d.sqrt();
            l[j * n + j] = d;
            for i in j + 1..n {
                let mut s = l[i * n + j];
                for k in 0..j {
                    s -= l[i * n + k] * l[j * n + k];
                }
                l[i * n + j] = s / d;
            }
        }
        Ok(Self { n, l })
    }

    pub fn solve(&self, b: &[V3], x: &mut [V3]) {
        let n = self.n;
        let l = &self.l;
        for i in 0..n {
            let mut s = b[i];
            for k in 0..i {
                for d in 0..3 {
                    s[d] -= l[i * n + k] * x[k][d];
                }
            }
            for d in 0..3 {
                s[d] /= l[i * n + i];
            }
            x[i] = s;
        }
        for i in (0..n).rev() {
            let mut s = x[i];
            for k in i + 1..n {
                for d in 0..3 {
                    s[d] -= l[k * n + i] * x[k][d];
                }
            }
            for d in 0..3 {
                s[d] /= l[i * n + i];
            }
            x[i] = s;
        }
    }
}
