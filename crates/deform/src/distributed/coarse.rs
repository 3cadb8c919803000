//! The coarse-grid correction across the ranks: the second level of the distributed
//! preconditioner, so that the conjugate gradients' iterations do not grow with the number
//! of ranks as the block Jacobi of per-rank multigrid alone makes them.
//!
//! Coarse space ([`CoarseSpace`], made once per set-up): each rank cuts its free unknowns
//! (those without a sliding constraint) into `parts` aggregates by coordinate bisection;
//! P has, per aggregate and per component, the vector that is 1 on the aggregate's unknowns
//! and 0 elsewhere. The constrained unknowns are left out, so that P lies in the range of
//! the constraints' projection Π and the coarse problem is that of the projected operator.
//! Coarse operator ([`CoarseOp`], per matrix): the rows of A P on the owned unknowns (the
//! ghosts' aggregates came once through the halo), A_c = Pᵀ A P gathered on every rank and
//! factorised there by the envelope Cholesky of `sparse` in reverse Cuthill–McKee order.
//!
//! Preconditioner (balancing, Mandel's BNN; Tang, Nabben, Vuik, Erlangga 2009): with
//! Q = P A_c⁻¹ Pᵀ and B the block preconditioner,
//! M = Q + (I − Q A) B (I − A Q),
//! symmetric positive definite; it costs two all-reduces of 3 n_c values and two coarse
//! solves per application, and no halo exchange (A Q r and Pᵀ A y come from the stored rows
//! of A P).

use std::sync::Arc;

use mpi::collective::SystemOperation;
use mpi::datatype::PartitionMut;
use mpi::traits::*;
use sparse::csr::merge_row;
use sparse::envelope::EnvelopeCholesky;
use sparse::order::reverse_cuthill_mckee;
use sparse::{SymMatrix, V3};

use super::comm::Comm;
use super::halo::Halo;
use super::rcb::rcb;
use crate::error::{Error, Result};

/// No aggregate (a constrained unknown).
const NONE: u32 = u32::MAX;

/// The aggregates of the local unknowns (owned, then ghosts) over the ranks.
pub(crate) struct CoarseSpace {
    /// Global aggregate of every local unknown, [`NONE`] for the constrained ones.
    agg: Arc<[u32]>,
    /// Aggregates over the ranks (n_c).
    n: usize,
}

impl CoarseSpace {
    /// Cuts this rank's free owned unknowns (`coords`, `constrained` per owned unknown) into
    /// `parts` aggregates (fewer when there are fewer unknowns) and brings the ghost unknowns'
    /// aggregates from their owners (`halo` over `n_all` local unknowns). Collective.
    pub fn new(
        comm: &Comm,
        halo: &Halo,
        coords: &[[f64; 3]],
        constrained: &[bool],
        n_all: usize,
        parts: usize,
    ) -> Self {
        let free: Vec<usize> = (0..coords.len()).filter(|&k| !constrained[k]).collect();
        let k = parts.min(free.len());
        let xs: Vec<[f64; 3]> = free.iter().map(|&i| coords[i]).collect();
        let part = rcb(&xs, k);
        let mut counts = vec![0u64; comm.size() as usize];
        comm.all_gather_into(&(k as u64), &mut counts[..]);
        let first: u64 = counts[..comm.rank() as usize].iter().sum();
        let n = counts.iter().sum::<u64>() as usize;
        let mut v = vec![[f64::from(NONE)]; n_all];
        for (&i, &p) in free.iter().zip(&part) {
            v[i] = [(first + u64::from(p)) as f64];
        }
        halo.exchange(comm, &mut v);
        let agg = v.iter().map(|a| a[0] as u32).collect();
        Self { agg, n }
    }

    /// Aggregates over the ranks.
    pub fn len(&self) -> usize {
        self.n
    }
}

/// The coarse operator of one matrix: the owned rows of A P and the factor of A_c.
pub(crate) struct CoarseOp {
    /// The space's aggregates.
    agg: Arc<[u32]>,
    /// Aggregates over the ranks.
    n: usize,
    /// Row offsets of A P (owned unknowns).
    off: Vec<usize>,
    /// Aggregates (columns) of A P.
    col: Vec<u32>,
    /// Values of A P.
    val: Vec<f64>,
    chol: EnvelopeCholesky,
}

impl CoarseOp {
    /// A P on the owned rows of `a` (`n_own` rows; columns: local unknowns), and A_c = Pᵀ A P
    /// gathered and factorised on every rank. Collective; an error (A_c not positive
    /// definite) is the same on every rank.
    pub fn new(comm: &Comm, space: &CoarseSpace, a: &SymMatrix<f32>, n_own: usize) -> Result<Self> {
        let agg = &space.agg;
        let (mut off, mut col, mut val) = (vec![0], Vec::new(), Vec::new());
        let mut buf: Vec<(u32, f64)> = Vec::new();
        // Pᵀ A P's entries of the owned rows: (I, J, value), merged per row.
        let (mut ti, mut tj, mut tv) = (Vec::new(), Vec::new(), Vec::new());
        for k in 0..n_own {
            buf.clear();
            if agg[k] != NONE {
                buf.push((agg[k], a.diag[k]));
            }
            let (cols, vals) = a.row(k);
            for (&c, &v) in cols.iter().zip(vals) {
                let g = agg[c as usize];
                if g != NONE {
                    buf.push((g, f64::from(v)));
                }
            }
            merge_row(&mut buf);
            for &(g, v) in &buf {
                col.push(g);
                val.push(v);
                if agg[k] != NONE {
                    ti.push(agg[k]);
                    tj.push(g);
                    tv.push(v);
                }
            }
            off.push(col.len());
        }
        let (ti, tj, tv) = gather_all(comm, &ti, &tj, &tv);
        let ac = coarse_matrix(space.n, &ti, &tj, &tv);
        let perm = reverse_cuthill_mckee(ac.n(), |i| ac.row(i).0);
        let chol = EnvelopeCholesky::new(&ac, &perm).map_err(|e| Error::Distributed {
            rank: comm.rank(),
            reason: format!("coarse-grid matrix ({} aggregates): {e}", space.n),
        })?;
        Ok(Self {
            agg: space.agg.clone(),
            n: space.n,
            off,
            col,
            val,
            chol,
        })
    }

    /// A_c⁻¹ t, the three components solved apart.
    fn solve(&self, t: &[f64]) -> Vec<V3> {
        let n = self.n;
        let mut out = vec![[0.0; 3]; n];
        for q in 0..3 {
            let b: Vec<f64> = (0..n).map(|i| t[3 * i + q]).collect();
            for (o, v) in out.iter_mut().zip(self.chol.solve(&b)) {
                o[q] = v;
            }
        }
        out
    }

    /// Σ over the ranks of a coarse vector (3 n_c values).
    fn all_sum(comm: &Comm, t: Vec<f64>) -> Vec<f64> {
        let mut out = vec![0.0; t.len()];
        comm.all_reduce_into(&t[..], &mut out[..], SystemOperation::sum());
        out
    }

    /// A_c⁻¹ Pᵀ r (collective).
    pub fn coarse_of(&self, comm: &Comm, r: &[V3]) -> Vec<V3> {
        let mut t = vec![0.0; 3 * self.n];
        for (k, rk) in r.iter().enumerate() {
            let g = self.agg[k];
            if g != NONE {
                for q in 0..3 {
                    t[3 * g as usize + q] += rk[q];
                }
            }
        }
        self.solve(&Self::all_sum(comm, t))
    }

    /// A_c⁻¹ (A P)ᵀ y = A_c⁻¹ Pᵀ A y (A symmetric; collective).
    pub fn coarse_of_product(&self, comm: &Comm, y: &[V3]) -> Vec<V3> {
        let mut t = vec![0.0; 3 * self.n];
        for (k, yk) in y.iter().enumerate() {
            for e in self.off[k]..self.off[k + 1] {
                let (g, v) = (self.col[e] as usize, self.val[e]);
                for q in 0..3 {
                    t[3 * g + q] += v * yk[q];
                }
            }
        }
        self.solve(&Self::all_sum(comm, t))
    }

    /// s −= A P c on the owned rows.
    pub fn sub_product(&self, c: &[V3], s: &mut [V3]) {
        for (k, sk) in s.iter_mut().enumerate() {
            for e in self.off[k]..self.off[k + 1] {
                let (g, v) = (self.col[e] as usize, self.val[e]);
                for q in 0..3 {
                    sk[q] -= v * c[g][q];
                }
            }
        }
    }

    /// z += P c on the owned unknowns.
    pub fn add_prolonged(&self, c: &[V3], z: &mut [V3]) {
        for (k, zk) in z.iter_mut().enumerate() {
            let g = self.agg[k];
            if g != NONE {
                for q in 0..3 {
                    zk[q] += c[g as usize][q];
                }
            }
        }
    }
}

/// Every rank's (I, J, value) lists, concatenated in rank order on every rank.
fn gather_all(comm: &Comm, i: &[u32], j: &[u32], v: &[f64]) -> (Vec<u32>, Vec<u32>, Vec<f64>) {
    let p = comm.size() as usize;
    let mut counts = vec![0i32; p];
    comm.all_gather_into(&(i.len() as i32), &mut counts[..]);
    let displs: Vec<i32> = counts
        .iter()
        .scan(0, |a, &x| {
            let d = *a;
            *a += x;
            Some(d)
        })
        .collect();
    let total: usize = counts.iter().map(|&c| c as usize).sum();
    let (mut ai, mut aj, mut av) = (vec![0u32; total], vec![0u32; total], vec![0.0f64; total]);
    comm.all_gather_varcount_into(
        i,
        &mut PartitionMut::new(&mut ai[..], &counts[..], &displs[..]),
    );
    comm.all_gather_varcount_into(
        j,
        &mut PartitionMut::new(&mut aj[..], &counts[..], &displs[..]),
    );
    comm.all_gather_varcount_into(
        v,
        &mut PartitionMut::new(&mut av[..], &counts[..], &displs[..]),
    );
    (ai, aj, av)
}

/// A_c from its entries (duplicates summed in their order, the same on every rank).
fn coarse_matrix(n: usize, i: &[u32], j: &[u32], v: &[f64]) -> SymMatrix<f64> {
    let mut rows: Vec<Vec<(u32, f64)>> = vec![Vec::new(); n];
    for ((&i, &j), &v) in i.iter().zip(j).zip(v) {
        rows[i as usize].push((j, v));
    }
    let mut m = SymMatrix {
        diag: vec![0.0; n],
        offsets: vec![0],
        cols: Vec::new(),
        vals: Vec::new(),
    };
    for (r, mut row) in rows.into_iter().enumerate() {
        merge_row(&mut row);
        for (c, v) in row {
            if c as usize == r {
                m.diag[r] = v;
            } else {
                m.cols.push(c);
                m.vals.push(v);
            }
        }
        m.offsets.push(m.cols.len());
    }
    m
}
