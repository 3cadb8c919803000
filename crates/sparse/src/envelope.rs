//! Envelope (skyline, profile) Cholesky factorisation A = L Lᵀ of a symmetric positive
//! definite sparse matrix in a given order: row p of L holds the columns from the first
//! nonzero of row p of A (in that order) to the diagonal, so the factorisation creates no
//! entry outside the envelope. With a bandwidth-reducing order
//! ([`crate::order::reverse_cuthill_mckee`]) this is the cheapest direct method for the
//! small, banded systems of the workspace (a surface component's harmonic map), factorised
//! once and solved many times.

use crate::error::{Error, Result};
use crate::order::inverse;
use crate::sym::{Entry, SymMatrix};
use crate::vec3::V3;

/// The envelope of a symmetric pattern under an order (the symbolic factorisation): what
/// the factor will hold and cost, before any value is computed.
#[derive(Debug, Clone, PartialEq)]
pub struct Envelope {
    /// Old index of each position (`order[new] = old`).
    order: Vec<u32>,
    /// First column of row p of L (in positions).
    first: Vec<usize>,
}

impl Envelope {
    /// The envelope of the `n`-node pattern `neighbours` renumbered by `perm`
    /// (`perm[old] = new`, the convention of [`crate::order`]).
    pub fn new<'a, F>(n: usize, neighbours: F, perm: &[u32]) -> Self
    where
        F: Fn(usize) -> &'a [u32],
    {
        let order = inverse(perm);
        let mut first: Vec<usize> = (0..n).collect();
        for (p, &i) in order.iter().enumerate() {
            for &j in neighbours(i as usize) {
                first[p] = first[p].min(perm[j as usize] as usize);
            }
        }
        Self { order, first }
    }

    /// Order of the matrix.
    pub fn n(&self) -> usize {
        self.order.len()
    }

    /// Estimated multiply–adds of the factorisation, Σ_p (p − first_p)² / 2.
    pub fn flops(&self) -> f64 {
        self.first
            .iter()
            .enumerate()
            .map(|(p, &f)| ((p - f) as f64).powi(2) / 2.0)
            .sum()
    }

    /// Entries of L (the envelope's size, diagonal included).
    pub fn entries(&self) -> usize {
        self.first.iter().enumerate().map(|(p, &f)| p - f + 1).sum()
    }
}

/// The envelope Cholesky factor L of A = L Lᵀ.
#[derive(Debug, Clone)]
pub struct EnvelopeCholesky {
    env: Envelope,
    /// Start of row p in `l` (row p holds columns first[p]..=p).
    start: Vec<usize>,
    l: Vec<f64>,
}

impl EnvelopeCholesky {
    /// Factorises `a` in the order `perm` (`perm[old] = new`).
    pub fn new<T: Entry>(a: &SymMatrix<T>, perm: &[u32]) -> Result<Self> {
        let env = Envelope::new(a.n(), |i| a.row(i).0, perm);
        Self::factor(env, a)
    }

    /// Factorises `a`, whose pattern gave `env`; fails, naming the position, at a pivot that
    /// is not positive (A not positive definite, e.g. a Laplacian part with no Dirichlet
    /// node).
    pub fn factor<T: Entry>(env: Envelope, a: &SymMatrix<T>) -> Result<Self> {
        let m = env.n();
        if a.n() != m {
            return Err(Error::BadGraph {
                reason: format!("envelope of order {m} for a matrix of order {}", a.n()),
            });
        }
        let (order, first) = (&env.order, &env.first);
        let mut pos = vec![0usize; m];
        for (p, &i) in order.iter().enumerate() {
            pos[i as usize] = p;
        }
        let mut start = vec![0usize; m + 1];
        for p in 0..m {
            start[p + 1] = start[p] + (p - first[p] + 1);
        }
        let mut l = vec![0.0; start[m]];
        for (p, &i) in order.iter().enumerate() {
            l[start[p] + (p - first[p])] = a.diag[i as usize];
            let (cols, vals) = a.row(i as usize);
            for (&j, &v) in cols.iter().zip(vals) {
                let q = pos[j as usize];
                if q < p {
                    l[start[p] + (q - first[p])] = v.get();
                }
            }
        }
        for p in 0..m {
            let fp = first[p];
            for q in fp..=p {
                let fq = first[q];
                let k0 = fp.max(fq);
                let mut s = l[start[p] + (q - fp)];
                let (rp, rq) = (&l[start[p] + (k0 - fp)..], &l[start[q] + (k0 - fq)..]);
                for k in 0..(q - k0) {
                    s -= rp[k] * rq[k];
                }
                if q == p {
                    if s <= 0.0 || !s.is_finite() {
                        return Err(Error::NotPositiveDefinite { index: p, pivot: s });
                    }
                    l[start[p] + (p - fp)] = s.sqrt();
                } else {
                    l[start[p] + (q - fp)] = s / l[start[q] + (q - fq)];
                }
            }
        }
        Ok(Self { env, start, l })
    }

    /// x = A⁻¹ b (b and x in the matrix's own numbering).
    pub fn solve(&self, b: &[f64]) -> Vec<f64> {
        let m = b.len();
        let (order, first) = (&self.env.order, &self.env.first);
        // L y = b (in the factor's order).
        let mut y: Vec<f64> = order.iter().map(|&i| b[i as usize]).collect();
        for p in 0..m {
            let fp = first[p];
            let row = &self.l[self.start[p]..self.start[p + 1]];
            let mut s = y[p];
            for (k, lk) in row[..p - fp].iter().enumerate() {
                s -= lk * y[fp + k];
            }
            y[p] = s / row[p - fp];
        }
        // Lᵀ x = y (column sweep over the rows of L).
        for p in (0..m).rev() {
            let fp = first[p];
            let row = &self.l[self.start[p]..self.start[p + 1]];
            y[p] /= row[p - fp];
            let v = y[p];
            for (k, lk) in row[..p - fp].iter().enumerate() {
                y[fp + k] -= lk * v;
            }
        }
        let mut x = vec![0.0; m];
        for (p, &i) in order.iter().enumerate() {
            x[i as usize] = y[p];
        }
        x
    }

    /// Solves A x = b for the three components of `b` at once (one pass over the factor
    /// per sweep instead of three; each component's arithmetic is that of
    /// [`EnvelopeCholesky::solve`], so the results are the same bit for bit).
    pub fn solve3(&self, b: &[V3]) -> Vec<V3> {
        let m = b.len();
        let (order, first) = (&self.env.order, &self.env.first);
        let mut y: Vec<V3> = order.iter().map(|&i| b[i as usize]).collect();
        for p in 0..m {
            let fp = first[p];
            let row = &self.l[self.start[p]..self.start[p + 1]];
            let mut s = y[p];
            for (lk, yk) in row[..p - fp].iter().zip(&y[fp..p]) {
                for c in 0..3 {
                    s[c] -= lk * yk[c];
                }
            }
            let d = row[p - fp];
            y[p] = [s[0] / d, s[1] / d, s[2] / d];
        }
        for p in (0..m).rev() {
            let fp = first[p];
            let row = &self.l[self.start[p]..self.start[p + 1]];
            let d = row[p - fp];
            y[p] = [y[p][0] / d, y[p][1] / d, y[p][2] / d];
            let v = y[p];
            let (head, _) = y.split_at_mut(p);
            for (lk, yk) in row[..p - fp].iter().zip(&mut head[fp..]) {
                for c in 0..3 {
                    yk[c] -= lk * v[c];
                }
            }
        }
        let mut x = vec![[0.0; 3]; m];
        for (p, &i) in order.iter().enumerate() {
            x[i as usize] = y[p];
        }
        x
    }

    /// The symbolic part.
    pub fn envelope(&self) -> &Envelope {
        &self.env
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn envelope_cholesky_solves_the_spring_grid_in_any_order() {
        let (a, b) = crate::generate::spring_grid(7, 6, 5);
        let n = a.n();
        let b0: Vec<f64> = b.iter().map(|v| v[0]).collect();
        let rcm = crate::order::reverse_cuthill_mckee(n, |i| a.row(i).0);
        let ident: Vec<u32> = (0..n as u32).collect();
        let (f1, f2) = (
            EnvelopeCholesky::new(&a, &rcm).unwrap(),
            EnvelopeCholesky::new(&a, &ident).unwrap(),
        );
        assert!(f1.envelope().entries() <= f2.envelope().entries());
        for f in [&f1, &f2] {
            let x = f.solve(&b0);
            // Residual of A x = b, relative.
            let mut worst = 0.0f64;
            for i in 0..n {
                let (cols, vals) = a.row(i);
                let mut s = a.diag[i] * x[i];
                for (&c, &v) in cols.iter().zip(vals) {
                    s += v * x[c as usize];
                }
                worst = worst.max((s - b0[i]).abs());
            }
            let scale = b0.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            assert!(worst <= 1e-12 * scale, "{worst}");
        }
    }

    #[test]
    fn three_components_at_once_are_the_three_solves() {
        let (a, b) = crate::generate::spring_grid(6, 5, 4);
        let rcm = crate::order::reverse_cuthill_mckee(a.n(), |i| a.row(i).0);
        let f = EnvelopeCholesky::new(&a, &rcm).unwrap();
        let x3 = f.solve3(&b);
        for c in 0..3 {
            let bc: Vec<f64> = b.iter().map(|v| v[c]).collect();
            let xc = f.solve(&bc);
            for (p, q) in x3.iter().zip(&xc) {
                assert_eq!(p[c].to_bits(), q.to_bits());
            }
        }
    }
}
