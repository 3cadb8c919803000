//! The interface smoother of the distributed preconditioner: a damped Jacobi sweep on the
//! owned rows near the partition's interface, before and after the block preconditioner.
//!
//! The blocks of the additive Schwarz preconditioner (`super::solve`) overlap by one layer:
//! each block's correction is cut off at its ghosts, and the weighted sum of two blocks'
//! corrections has a kink along the interface that the block multigrids cannot see. A
//! Jacobi sweep over the whole grid before and after the block preconditioner (the
//! symmetric multiplicative composition z₁ = S r, z₂ = z₁ + B (r − A z₁),
//! z = z₂ + S (r − A z₂)) smooths it: at 98k nodes on 2 ranks it took the Eq. 21 + Eq. 26
//! iterations from 25 + 23 to 20 + 17, for two more products with A per iteration. The
//! kink lies at the interface, and so does the sweep's gain: restricted to the owned rows
//! with a ghost column and their owned neighbours (two layers), the sweep gave 21 + 18,
//! and one layer 23 + 20 (docs/perf-log/2026-12-04-mpi-interface.md). Restricted, S is
//! zero away from the interface, and A z₁ and S A z₂ need A's rows on the band and next to
//! it only: two halo exchanges and a few percent of a product per iteration.
//!
//! S is the ℓ1-Jacobi smoother S_k = c / Σ_j |a_kj| (the row's absolute sum, diagonal and
//! ghost columns included) with c = 1.8, as the serial multigrid's smoother damping: every
//! row of S A then has absolute sum ≤ c < 2, so λ_max(S A) < 2, I − S A is a contraction
//! in the A-norm, and the composition is symmetric positive definite whenever B is: a valid
//! preconditioner for conjugate gradients, with no bound of λ_max to agree on over the ranks.

use sparse::{Csr, SymMatrix, V3};

/// c of the ℓ1-Jacobi weights c / Σ_j |a_kj| (below 2; the serial multigrid's smoother
/// damping).
const DAMPING: f64 = 1.8;

/// The rows the interface smoother works on, and its weights.
pub(crate) struct Interface {
    /// The owned rows within two layers of the ghosts (those with a ghost column, then
    /// their owned neighbours), increasing.
    band: Vec<u32>,
    /// The weight c / Σ_j |a_kj| of each row of `band`.
    weight: Vec<f64>,
    /// The owned rows where A v may be nonzero for v zero off the band and the ghosts (the
    /// band and its owned neighbours), increasing.
    near: Vec<u32>,
}

/// The scratch of one solve: vectors over the local unknowns (owned, then ghosts), zero off
/// the band between applications.
pub(crate) struct Scratch {
    /// z₁ = S r, its ghosts brought from their owners.
    z1: Vec<V3>,
    /// r − A z₁.
    r1: Vec<V3>,
    /// The ghosts of z₂ (its owned entries are the caller's z).
    z2: Vec<V3>,
    /// S (r − A z₂).
    s2: Vec<V3>,
}

impl Scratch {
    /// The scratch for `n_own` owned and `n_all` local unknowns.
    pub fn new(n_own: usize, n_all: usize) -> Self {
        Self {
            z1: vec![[0.0; 3]; n_all],
            r1: vec![[0.0; 3]; n_own],
            z2: vec![[0.0; 3]; n_all - n_own],
            s2: vec![[0.0; 3]; n_own],
        }
    }
}

impl Interface {
    /// The band of the owned block `own` (rows of the owned unknowns, owned columns) whose
    /// rows `ghost_rows` have the ghost columns `ghost`.
    pub fn new(own: &SymMatrix<f32>, ghost: &Csr, ghost_rows: &[u32]) -> Self {
        let n = own.n();
        let mut layer = vec![0u8; n];
        for &k in ghost_rows {
            layer[k as usize] = 1;
        }
        // Then the band's owned neighbours (layer 2), then theirs (`near`'s extra rows).
        for next in [2u8, 3] {
            for k in 0..n {
                if layer[k] == 0 && own.row(k).0.iter().any(|&c| layer[c as usize] == next - 1) {
                    layer[k] = next;
                }
            }
        }
        let band: Vec<u32> = (0..n as u32)
            .filter(|&k| matches!(layer[k as usize], 1 | 2))
            .collect();
        let near = (0..n as u32).filter(|&k| layer[k as usize] > 0).collect();
        let weight = band
            .iter()
            .map(|&k| {
                let k = k as usize;
                let (_, v) = own.row(k);
                let (_, g) = ghost.row(k);
                let sum = own.diag[k].abs()
                    + v.iter().map(|&v| f64::from(v).abs()).sum::<f64>()
                    + g.iter().map(|v| v.abs()).sum::<f64>();
                if sum > 0.0 { DAMPING / sum } else { 0.0 }
            })
            .collect();
        Self { band, weight, near }
    }

    /// z = S r + B (r − A S r), then z += S (r − A z) (see the module's doc), each step
    /// projected: [`Interface::before`], `block(r₁, z)` (the block preconditioner),
    /// [`Interface::after`].
    pub fn apply<P, E, F>(
        &self,
        ops: &Ops<'_, P, E, F>,
        s: &mut Scratch,
        r: &[V3],
        z: &mut [V3],
        block: impl FnOnce(&[V3], &mut [V3]),
    ) where
        P: Fn(&mut [V3]),
        E: Fn(&mut [V3]),
        F: Fn(&[V3], &mut [V3]),
    {
        let mut r1 = std::mem::take(&mut s.r1);
        r1.copy_from_slice(r);
        self.before(ops, s, &mut r1);
        block(&r1, z);
        s.r1 = r1;
        (ops.project)(z);
        self.after(ops, s, r, z);
    }

    /// The sweep's first half: z₁ = S r on the band, projected (its ghosts brought by
    /// `ops.exchange`, collective), and `r1`, which holds r, becomes r − A z₁, projected:
    /// the block preconditioner's residual.
    pub fn before<P, E, F>(&self, ops: &Ops<'_, P, E, F>, s: &mut Scratch, r1: &mut [V3])
    where
        P: Fn(&mut [V3]),
        E: Fn(&mut [V3]),
    {
        let n = r1.len();
        for (&k, &w) in self.band.iter().zip(&self.weight) {
            let k = k as usize;
            s.z1[k] = r1[k].map(|v| w * v);
        }
        (ops.project)(&mut s.z1[..n]);
        (ops.exchange)(&mut s.z1);
        let (z1, z1_ghost) = s.z1.split_at(n);
        for &k in &self.near {
            let k = k as usize;
            let a = ops.row(k, z1, z1_ghost);
            for q in 0..3 {
                r1[k][q] -= a[q];
            }
        }
        (ops.project)(r1);
    }

    /// The sweep's second half: `z`, which holds the block's projected correction, becomes
    /// z₂ = z + z₁, then z₂ + S (r − A z₂), projected; `ops.exchange_from(z, ghosts)`
    /// brings the ghosts of z from their owners (collective).
    pub fn after<P, E, F>(&self, ops: &Ops<'_, P, E, F>, s: &mut Scratch, r: &[V3], z: &mut [V3])
    where
        P: Fn(&mut [V3]),
        F: Fn(&[V3], &mut [V3]),
    {
        let n = r.len();
        for &k in &self.band {
            let k = k as usize;
            for q in 0..3 {
                z[k][q] += s.z1[k][q];
            }
        }
        (ops.exchange_from)(z, &mut s.z2);
        for (&k, &w) in self.band.iter().zip(&self.weight) {
            let k = k as usize;
            let a = ops.row(k, z, &s.z2);
            s.s2[k] = [0, 1, 2].map(|q| w * (r[k][q] - a[q]));
        }
        (ops.project)(&mut s.s2);
        for &k in &self.band {
            let k = k as usize;
            for q in 0..3 {
                z[k][q] += s.s2[k][q];
            }
            s.z1[k] = [0.0; 3];
            s.s2[k] = [0.0; 3];
        }
        s.z1[n..].fill([0.0; 3]);
    }
}

/// What the sweep needs of its caller: the owned rows of A (`own`, the owned–owned block,
/// and `ghost`, their ghost columns), the constraints' projection, and the halo: `exchange`
/// fills a local vector's ghosts from their owners, `exchange_from(owned, ghosts)` those of
/// a vector held in two pieces (both collective).
pub(crate) struct Ops<'a, P, E, F> {
    /// The owned–owned block of A.
    pub own: &'a SymMatrix<f32>,
    /// The ghost columns of A's owned rows.
    pub ghost: &'a Csr,
    /// The constraints' projection.
    pub project: P,
    /// The halo exchange of a local vector.
    pub exchange: E,
    /// The halo exchange of a vector held in two pieces.
    pub exchange_from: F,
}

impl<P, E, F> Ops<'_, P, E, F> {
    /// (A x)_k for owned row `k`, `x` over the local unknowns held in two pieces: its owned
    /// entries `x_own`, then its ghost ones `x_ghost`.
    fn row(&self, k: usize, x_own: &[V3], x_ghost: &[V3]) -> V3 {
        let mut s = self.own.row_mul(k, x_own);
        let (c, v) = self.ghost.row(k);
        let n = x_own.len();
        for (&c, &v) in c.iter().zip(v) {
            for q in 0..3 {
                s[q] += v * x_ghost[c as usize - n][q];
            }
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sparse::{Constraint, Constraints};

    /// The spring Laplacian of an `m` × `m` grid of unknowns (4-neighbours, springs of
    /// varied stiffness, every diagonal also held by a spring to a prescribed node), and
    /// ghost columns on the rows of the last grid column (a neighbouring rank's nodes).
    fn problem(m: usize) -> (SymMatrix<f32>, Csr) {
        let n = m * m;
        let k = |i: usize, j: usize| 1.0 + ((i * 7 + j * 13) % 5) as f64;
        let mut a = SymMatrix {
            diag: vec![0.0; n],
            offsets: vec![0],
            cols: Vec::new(),
            vals: Vec::new(),
        };
        for i in 0..n {
            let (r, c) = (i / m, i % m);
            let mut nb = Vec::new();
            if r > 0 {
                nb.push(i - m);
            }
            if c > 0 {
                nb.push(i - 1);
            }
            if c + 1 < m {
                nb.push(i + 1);
            }
            if r + 1 < m {
                nb.push(i + m);
            }
            a.diag[i] = 0.5 + nb.iter().map(|&j| k(i.min(j), i.max(j))).sum::<f64>();
            for j in nb {
                a.cols.push(j as u32);
                a.vals.push(-k(i.min(j), i.max(j)) as f32);
            }
            a.offsets.push(a.cols.len());
        }
        let ghost = Csr::from_rows(n, n + m, |i, row| {
            if i % m == m - 1 {
                row.push(((n + i / m) as u32, -2.0));
            }
        });
        (a, ghost)
    }

    /// M r of the interface sweep around the block B r = D⁻¹ r, the ghosts' values zero
    /// (a neighbour whose vector is zero), projected by `cons`.
    fn apply(f: &Interface, a: &SymMatrix<f32>, g: &Csr, cons: &Constraints, r: &[V3]) -> Vec<V3> {
        let n = r.len();
        let mut s = Scratch::new(n, g.ncols);
        let mut z = vec![[0.0; 3]; n];
        let block = |r: &[V3], z: &mut [V3]| {
            for k in 0..n {
                z[k] = r[k].map(|v| v / a.diag[k]);
            }
        };
        let exchange = |v: &mut [V3]| v[n..].fill([0.0; 3]);
        let exchange_from = |_: &[V3], g: &mut [V3]| g.fill([0.0; 3]);
        let ops = Ops {
            own: a,
            ghost: g,
            project: |v: &mut [V3]| cons.project(v),
            exchange,
            exchange_from,
        };
        f.apply(&ops, &mut s, r, &mut z, block);
        // The scratch is zero off the band again.
        assert!(s.z1.iter().chain(&s.s2).all(|v| *v == [0.0; 3]));
        z
    }

    fn dot(u: &[V3], v: &[V3]) -> f64 {
        u.iter()
            .zip(v)
            .map(|(a, b)| a[0] * b[0] + a[1] * b[1] + a[2] * b[2])
            .sum()
    }

    #[test]
    fn the_band_is_two_layers_from_the_ghosts_and_the_sweep_symmetric_positive() {
        let m = 7;
        let (a, g) = problem(m);
        let ghost_rows: Vec<u32> = (0..m * m)
            .filter(|i| i % m == m - 1)
            .map(|i| i as u32)
            .collect();
        let f = Interface::new(&a, &g, &ghost_rows);
        let want: Vec<u32> = (0..m * m)
            .filter(|i| i % m >= m - 2)
            .map(|i| i as u32)
            .collect();
        assert_eq!(f.band, want);
        let near: Vec<u32> = (0..m * m)
            .filter(|i| i % m >= m - 3)
            .map(|i| i as u32)
            .collect();
        assert_eq!(f.near, near);
        // ℓ1 weights: 1.8 over the row's absolute sum, ghost columns included.
        let k = m - 1;
        let (_, v) = a.row(k);
        let sum = a.diag[k] + v.iter().map(|&v| f64::from(v).abs()).sum::<f64>() + 2.0;
        assert!(
            (f.weight[f.band.iter().position(|&b| b as usize == k).unwrap()] - 1.8 / sum).abs()
                < 1e-15
        );
        // A plane held at one node, a line at another.
        let cons = Constraints {
            items: vec![
                (k as u32, Constraint::Plane([0.0, 1.0, 0.0])),
                (5, Constraint::Line([0.6, 0.8, 0.0])),
            ],
        };
        let vec = |seed: usize| -> Vec<V3> {
            let mut v: Vec<V3> = (0..m * m)
                .map(|i| [0, 1, 2].map(|q| (((i * 31 + q * 17 + seed * 101) % 23) as f64) - 11.0))
                .collect();
            cons.project(&mut v);
            v
        };
        for (s, t) in [(1, 2), (3, 4), (5, 9)] {
            let (u, v) = (vec(s), vec(t));
            let (mu, mv) = (apply(&f, &a, &g, &cons, &u), apply(&f, &a, &g, &cons, &v));
            let (uv, vu) = (dot(&u, &mv), dot(&v, &mu));
            assert!(
                (uv - vu).abs() <= 1e-12 * uv.abs().max(1.0),
                "{uv} against {vu}"
            );
            assert!(dot(&v, &mv) > 0.0 && dot(&u, &mu) > 0.0);
        }
        // The sweep does change the block's answer on the band, and only there and next to it.
        let r = vec(7);
        let mut plain = vec![[0.0; 3]; m * m];
        for i in 0..m * m {
            plain[i] = r[i].map(|x| x / a.diag[i]);
        }
        cons.project(&mut plain);
        let swept = apply(&f, &a, &g, &cons, &r);
        let changed: Vec<usize> = (0..m * m).filter(|&i| swept[i] != plain[i]).collect();
        assert!(changed.iter().any(|&i| i % m == m - 1));
        assert!(changed.iter().all(|&i| i % m >= m - 3), "{changed:?}");
    }
}
