//! The coarse-grid correction across the ranks: the second level of the distributed
//! preconditioner, so that the conjugate gradients' iterations do not grow with the number
//! of ranks as the block Jacobi of per-rank multigrid alone makes them.
//!
//! Coarse space ([`CoarseSpace`], made once per set-up): each rank cuts its free unknowns
//! (those without a sliding constraint) into `parts` aggregates by coordinate bisection,
//! more when they would hold over [`COARSE_SIZE`] unknowns each (up to [`COARSE_MAX`]
//! over the ranks); P₀ has, per aggregate and per component, the vector that is 1 on the
//! aggregate's unknowns and 0 elsewhere.
//! Coarse operator ([`CoarseOp`], per matrix): P = (I − ω D⁻¹ A) P₀, P₀ smoothed by one
//! damped Jacobi step of the matrix as the serial multigrid's prolongator (its rows of the
//! ghost unknowns come from their owners through the halo); the constrained unknowns keep
//! P's row 0, so that P lies in the range of the constraints' projection Π and the coarse
//! problem is that of the projected operator. The rows of A P on the owned unknowns, and
//! A_c = Pᵀ A P gathered on every rank and factorised there by the envelope Cholesky of
//! `sparse` in reverse Cuthill–McKee order.
//!
//! Preconditioner (A-DEF2 of Tang, Nabben, Vuik and Erlangga 2009): with Q = P A_c⁻¹ Pᵀ
//! and B the block preconditioner,
//! M = Q + (I − Q A) B,
//! applied as z = y + P A_c⁻¹ (Pᵀ r − (A P)ᵀ y), y = B r: one pass over the stored rows of
//! P and A P together, one all-reduce of 6 n_c values (with Pᵀ r, so that r · z = r · y +
//! (Pᵀ r) · c needs no pass over z), one coarse solve, and P c added in the conjugate
//! gradients' update of their search direction; no halo exchange. The conjugate gradients
//! start from x₀ + Q r₀ ([`CoarseOp::start`]), so that Pᵀ r₀ = 0; from such a start A-DEF2
//! gives the iterates of the balancing preconditioner (Mandel's BNN)
//! M = Q + (I − Q A) B (I − A Q) in exact arithmetic, at half its coarse work (BNN applies
//! A Q r and Pᵀ A y separately: two all-reduces, two coarse solves and four passes).
//! Measured: docs/perf-log/2026-12-03-mpi-adef2.md.

use std::sync::Arc;

use mpi::collective::SystemOperation;
use mpi::traits::*;
use sparse::csr::merge_row;
use sparse::envelope::EnvelopeCholesky;
use sparse::order::reverse_cuthill_mckee;
use sparse::{SymMatrix, V3};

use super::comm::{Comm, all_gather_vec, max};
use super::halo::Halo;
use super::rcb::rcb;
use super::solve::DistOperator;
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
    /// at least `parts` aggregates ([`per_rank`]: more in parts of over [`COARSE_SIZE`]
    /// unknowns, fewer when there are fewer unknowns) and brings the ghost unknowns'
    /// aggregates from their owners (`halo` over `n_all` local unknowns). Collective.
    ///
    /// The R field (Eq. 26) uses the same space, though its sliding unknowns are free: a
    /// second space aggregating them too, with its own coarse operator, took the R field
    /// from 28 to 27 iterations at 1M nodes on 2 ranks for 0.3 s of set-up per increment,
    /// more than the iteration saved (docs/perf-log/2026-12-03-mpi-round4.md).
    pub fn new(
        comm: &Comm,
        halo: &Halo,
        coords: &[[f64; 3]],
        constrained: &[bool],
        n_all: usize,
        parts: usize,
    ) -> Self {
        let free: Vec<usize> = (0..coords.len()).filter(|&k| !constrained[k]).collect();
        let k = per_rank(parts, free.len(), comm.size() as usize);
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

/// Unknowns per aggregate above which a rank cuts more aggregates than asked: the coarse
/// space then keeps a fixed resolution as the ranks' parts grow (at 1M nodes on 2 ranks,
/// 256 aggregates per rank held ~2 000 unknowns each and left 55 + 34 iterations, 1 015
/// per rank 47 + 32; docs/perf-log/2026-12-03-mpi-round2.md).
pub(crate) const COARSE_SIZE: usize = 500;

/// Over the ranks, at most this many aggregates come from [`COARSE_SIZE`] (the coarse
/// matrix is factorised on every rank: 8 192 aggregates at 1M nodes took longer to
/// factorise and solve than their fewer iterations saved).
pub(crate) const COARSE_MAX: usize = 2048;

/// Aggregates of a rank with `free` free unknowns out of `p` ranks: at least `parts` (the
/// caller's count; 0 turns the coarse level off), more when they would hold over
/// [`COARSE_SIZE`] unknowns, up to [`COARSE_MAX`] / `p`; never more than `free`.
fn per_rank(parts: usize, free: usize, p: usize) -> usize {
    if parts == 0 {
        return 0;
    }
    let by_size = free.div_ceil(COARSE_SIZE).min(COARSE_MAX / p.max(1));
    parts.max(by_size).min(free)
}

/// Entries kept per row of the smoothed prolongator, which the halo brings to the ranks
/// that hold the row's unknown as a ghost (a fixed width: the halo's vectors are arrays).
/// A row of (I − ω D⁻¹ A) P₀ has the aggregates of its unknown's neighbours, ~2–5 with
/// aggregates of ~500 unknowns; beyond this width the smallest entries are dropped (on the
/// owner too: every rank holds the same row, and any P gives a valid coarse space).
const P_WIDTH: usize = 8;

/// c_P of the coarse space's smoothing: ω = c_P / ρ, ρ the Gershgorin bound of ρ(D⁻¹A)
/// over the ranks, as the serial multigrid's prolongator smoothing.
const P_DAMPING: f64 = 1.6;

/// The coarse operator of one matrix: the smoothed prolongator P = (I − ω D⁻¹ A) P₀ (P₀ the
/// aggregates' indicator) on the local unknowns, the owned rows of A P, and the factor of
/// A_c = Pᵀ A P.
pub(crate) struct CoarseOp {
    /// Aggregates over the ranks.
    n: usize,
    /// Row offsets of P (owned unknowns).
    p_off: Vec<usize>,
    /// Aggregates (columns) and values of P.
    p_col: Vec<u32>,
    p_val: Vec<f64>,
    /// Row offsets of P and A P together (owned unknowns): the union of their aggregates.
    off: Vec<usize>,
    /// Aggregates (columns) of the union.
    col: Vec<u32>,
    /// P's value at each entry of the union (0 where P's row lacks the aggregate).
    pv: Vec<f64>,
    /// A P's value at each entry of the union.
    apv: Vec<f64>,
    chol: EnvelopeCholesky,
}

impl CoarseOp {
    /// P smoothed by `a` (its ghost rows brought by `halo` from their owners), A P on the
    /// owned rows of `a` (`n_own` rows; columns: local unknowns), and A_c = Pᵀ A P gathered
    /// and factorised on every rank. Collective; an error (A_c not positive definite) is the
    /// same on every rank.
    ///
    /// The constrained (sliding) unknowns keep P's row 0, so that P stays in the range of
    /// the constraints' projection. Against the piecewise-constant P₀, smoothing took the
    /// Eq. 21 + Eq. 26 iterations at 98k nodes from 28 + 23, 30 + 26, 30 + 27 on 2, 3, 4
    /// ranks to 26 + 23, 24 + 23, 26 + 24, and at 1M nodes on 2 ranks from 47 + 32 to
    /// 38 + 28 (docs/perf-log/2026-12-03-mpi-round3.md).
    pub fn new(
        comm: &Comm,
        halo: &Halo,
        space: &CoarseSpace,
        a: &DistOperator,
        n_own: usize,
    ) -> Result<Self> {
        let agg = &space.agg;
        let diag = a.diag();
        // ω from the Gershgorin bound of D⁻¹A over the ranks.
        let mut rho = 0.0f64;
        for k in 0..n_own {
            let mut s = 0.0;
            a.row_entries(k, |_, v| s += v.abs());
            rho = rho.max(1.0 + s / diag[k]);
        }
        let rho = max(comm, rho);
        let omega = if rho > 0.0 { P_DAMPING / rho } else { 0.0 };
        // P's owned rows.
        let (mut p_off, mut p_col, mut p_val) = (vec![0], Vec::new(), Vec::new());
        let mut acc = RowAcc::new(space.n);
        for k in 0..n_own {
            if agg[k] != NONE {
                acc.clear();
                acc.add(agg[k], 1.0 - omega);
                let s = omega / diag[k];
                a.row_entries(k, |c, v| {
                    let g = agg[c];
                    if g != NONE {
                        acc.add(g, -s * v);
                    }
                });
                let buf = acc.take();
                if buf.len() > P_WIDTH {
                    // The largest entries (ties by aggregate), then back in aggregate order.
                    buf.sort_by(|x, y| y.1.abs().total_cmp(&x.1.abs()).then(x.0.cmp(&y.0)));
                    buf.truncate(P_WIDTH);
                    buf.sort_by_key(|e| e.0);
                }
                p_col.extend(buf.iter().map(|e| e.0));
                p_val.extend(buf.iter().map(|e| e.1));
            }
            p_off.push(p_col.len());
        }
        // The ghosts' rows from their owners, packed as (aggregate, value) pairs for the
        // rows sent only.
        let mut empty = [0.0f64; 2 * P_WIDTH];
        for e in 0..P_WIDTH {
            empty[2 * e] = f64::from(NONE);
        }
        let mut ghost_rows = vec![empty; agg.len() - n_own];
        let packed = |k: usize| {
            let mut row = empty;
            for (e, i) in (p_off[k]..p_off[k + 1]).enumerate() {
                row[2 * e] = f64::from(p_col[i]);
                row[2 * e + 1] = p_val[i];
            }
            row
        };
        halo.exchange_from(comm, packed, &mut ghost_rows, n_own);
        for row in &ghost_rows {
            for e in 0..P_WIDTH {
                let g = row[2 * e] as u32;
                if g != NONE {
                    p_col.push(g);
                    p_val.push(row[2 * e + 1]);
                }
            }
            p_off.push(p_col.len());
        }
        drop(ghost_rows);
        // A P on the owned rows.
        let (mut off, mut col, mut val) = (vec![0], Vec::new(), Vec::new());
        for k in 0..n_own {
            acc.clear();
            let d = diag[k];
            for e in p_off[k]..p_off[k + 1] {
                acc.add(p_col[e], d * p_val[e]);
            }
            a.row_entries(k, |c, v| {
                for e in p_off[c]..p_off[c + 1] {
                    acc.add(p_col[e], v * p_val[e]);
                }
            });
            for &(g, v) in acc.take().iter() {
                col.push(g);
                val.push(v);
            }
            off.push(col.len());
        }
        // Pᵀ A P's rows of this rank's owned unknowns: per aggregate I, Σ_k P_kI (A P)_k over
        // the owned rows k whose P has I (P transposed, then a dense accumulator per row).
        let n = space.n;
        let mut cnt = vec![0usize; n + 1];
        for &g in &p_col[..p_off[n_own]] {
            cnt[g as usize + 1] += 1;
        }
        for i in 0..n {
            cnt[i + 1] += cnt[i];
        }
        let mut at = cnt.clone();
        let mut pt = vec![(0u32, 0.0f64); p_off[n_own]];
        for k in 0..n_own {
            for e in p_off[k]..p_off[k + 1] {
                let g = p_col[e] as usize;
                pt[at[g]] = (k as u32, p_val[e]);
                at[g] += 1;
            }
        }
        let (mut ti, mut tj, mut tv) = (Vec::new(), Vec::new(), Vec::new());
        let mut acc = vec![0.0f64; n];
        let mut hit = vec![false; n];
        let mut touched: Vec<u32> = Vec::new();
        for i in 0..n {
            for &(k, p) in &pt[cnt[i]..cnt[i + 1]] {
                let k = k as usize;
                for e in off[k]..off[k + 1] {
                    let j = col[e] as usize;
                    if !hit[j] {
                        hit[j] = true;
                        touched.push(j as u32);
                    }
                    acc[j] += p * val[e];
                }
            }
            touched.sort_unstable();
            for &j in &touched {
                ti.push(i as u32);
                tj.push(j);
                tv.push(acc[j as usize]);
                acc[j as usize] = 0.0;
                hit[j as usize] = false;
            }
            touched.clear();
        }
        // Every rank's (I, J, value) lists, concatenated in rank order on every rank.
        let (ti, tj, tv) = (
            all_gather_vec(comm, &ti),
            all_gather_vec(comm, &tj),
            all_gather_vec(comm, &tv),
        );
        let ac = coarse_matrix(n, &ti, &tj, &tv);
        let perm = reverse_cuthill_mckee(ac.n(), |i| ac.row(i).0);
        let chol = EnvelopeCholesky::new(&ac, &perm).map_err(|e| Error::Distributed {
            rank: comm.rank(),
            reason: format!("coarse-grid matrix ({n} aggregates): {e}"),
        })?;
        p_off.truncate(n_own + 1);
        p_col.truncate(p_off[n_own]);
        p_val.truncate(p_off[n_own]);
        // P's and A P's rows merged (both in aggregate order), for the one pass of the
        // preconditioner over the two.
        let (mut u_off, mut u_col) = (vec![0], Vec::with_capacity(col.len()));
        let (mut pv, mut apv) = (Vec::with_capacity(col.len()), Vec::with_capacity(col.len()));
        for k in 0..n_own {
            let (mut i, mut j) = (p_off[k], off[k]);
            while i < p_off[k + 1] || j < off[k + 1] {
                let gi = if i < p_off[k + 1] { p_col[i] } else { NONE };
                let gj = if j < off[k + 1] { col[j] } else { NONE };
                let g = gi.min(gj);
                u_col.push(g);
                pv.push(if gi == g { p_val[i] } else { 0.0 });
                apv.push(if gj == g { val[j] } else { 0.0 });
                i += usize::from(gi == g);
                j += usize::from(gj == g);
            }
            u_off.push(u_col.len());
        }
        Ok(Self {
            n,
            p_off,
            p_col,
            p_val,
            off: u_off,
            col: u_col,
            pv,
            apv,
            chol,
        })
    }

    /// A_c⁻¹ t, the three components in one pass over the factor.
    fn solve(&self, t: &[f64]) -> Vec<V3> {
        let b: Vec<V3> = t.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        self.chol.solve3(&b)
    }

    /// Σ over the ranks of a coarse vector (3 n_c values).
    fn all_sum(comm: &Comm, t: Vec<f64>) -> Vec<f64> {
        let mut out = vec![0.0; t.len()];
        comm.all_reduce_into(&t[..], &mut out[..], SystemOperation::sum());
        out
    }

    /// A-DEF2's coarse correction of the residual `r` and the block's correction `y`,
    /// c = A_c⁻¹ Σ_k (P_k r_k − (A P)_k y_k) over the owned rows k of every rank, that is
    /// A_c⁻¹ (Pᵀ r − Pᵀ A y) (A symmetric), with what the conjugate gradients need of
    /// z = y + P c without forming z: r · P c over the ranks (Σ_I (Pᵀ r)_I · c_I, all-reduced
    /// with Pᵀ r − Pᵀ A y) and this rank's r · r and r · y, from the same pass over the rows
    /// of P and A P. [`CoarseOp::update`] then adds P c in the update of the search
    /// direction: one pass over the owned unknowns fewer per iteration (collective).
    pub fn correction(&self, comm: &Comm, r: &[V3], y: Option<&[V3]>) -> Correction {
        let n3 = 3 * self.n;
        // Pᵀ r − (A P)ᵀ y, then Pᵀ r.
        let mut t = vec![0.0; 2 * n3];
        let (mut rr, mut ry) = (0.0, 0.0);
        for (k, rk) in r.iter().enumerate() {
            let yk = y.map_or([0.0; 3], |y| y[k]);
            for q in 0..3 {
                rr += rk[q] * rk[q];
                ry += rk[q] * yk[q];
            }
            for e in self.off[k]..self.off[k + 1] {
                let (g, p, v) = (self.col[e] as usize, self.pv[e], self.apv[e]);
                for q in 0..3 {
                    t[3 * g + q] += p * rk[q] - v * yk[q];
                    t[n3 + 3 * g + q] += p * rk[q];
                }
            }
        }
        let t = Self::all_sum(comm, t);
        let c = self.solve(&t[..n3]);
        let r_pc = t[n3..]
            .chunks_exact(3)
            .zip(&c)
            .map(|(p, c)| p[0] * c[0] + p[1] * c[1] + p[2] * c[2])
            .sum();
        Correction {
            c,
            r_pc,
            dots: [rr, ry],
        }
    }

    /// The start of the conjugate gradients: x += P c and r −= Π A P c, c = A_c⁻¹ Pᵀ r, so
    /// that Pᵀ r = 0 after (`project` is Π; collective).
    pub fn start(&self, comm: &Comm, x: &mut [V3], r: &mut [V3], project: impl Fn(&mut [V3])) {
        let c = self.correction(comm, r, None).c;
        self.add_prolonged(&c, x);
        for (k, rk) in r.iter_mut().enumerate() {
            for e in self.off[k]..self.off[k + 1] {
                let (g, v) = (self.col[e] as usize, self.apv[e]);
                for q in 0..3 {
                    rk[q] -= v * c[g][q];
                }
            }
        }
        project(r);
    }

    /// The conjugate gradients' update with the preconditioned residual z = y + P c: x += α p,
    /// then p = y + P c + β p, in one pass over the owned unknowns (as `axpy_xpby`).
    pub fn update(&self, alpha: f64, x: &mut [V3], y: &[V3], c: &[V3], beta: f64, p: &mut [V3]) {
        for (k, ((xk, pk), yk)) in x.iter_mut().zip(p.iter_mut()).zip(y).enumerate() {
            let mut z = *yk;
            for e in self.p_off[k]..self.p_off[k + 1] {
                let (g, v) = (self.p_col[e] as usize, self.p_val[e]);
                for q in 0..3 {
                    z[q] += v * c[g][q];
                }
            }
            for q in 0..3 {
                xk[q] += alpha * pk[q];
                pk[q] = z[q] + beta * pk[q];
            }
        }
    }

    /// z += P c on the owned unknowns.
    pub fn add_prolonged(&self, c: &[V3], z: &mut [V3]) {
        for (k, zk) in z.iter_mut().enumerate() {
            for e in self.p_off[k]..self.p_off[k + 1] {
                let (g, p) = (self.p_col[e] as usize, self.p_val[e]);
                for q in 0..3 {
                    zk[q] += p * c[g][q];
                }
            }
        }
    }
}

/// What [`CoarseOp::correction`] gives.
pub(crate) struct Correction {
    /// c = A_c⁻¹ (Pᵀ r − Pᵀ A y), per aggregate.
    pub c: Vec<V3>,
    /// r · P c over the ranks.
    pub r_pc: f64,
    /// This rank's r · r and r · y.
    pub dots: [f64; 2],
}

/// A sparse row summed in a dense index over the aggregates: each entry added to the
/// first one of its aggregate in the order they come (the sums of a stable sort by
/// aggregate and a merge, without the sort of every product), read out by aggregate.
struct RowAcc {
    /// Place in `row` of each aggregate's entry ([`NONE`]: none yet).
    at: Vec<u32>,
    row: Vec<(u32, f64)>,
}

impl RowAcc {
    fn new(n: usize) -> Self {
        Self {
            at: vec![NONE; n],
            row: Vec::new(),
        }
    }

    #[inline]
    fn add(&mut self, g: u32, v: f64) {
        let at = &mut self.at[g as usize];
        if *at == NONE {
            *at = self.row.len() as u32;
            self.row.push((g, v));
        } else {
            self.row[*at as usize].1 += v;
        }
    }

    /// Starts a row.
    fn clear(&mut self) {
        self.row.clear();
    }

    /// The row in aggregate order (until the next [`RowAcc::clear`]).
    fn take(&mut self) -> &mut Vec<(u32, f64)> {
        for &(g, _) in &self.row {
            self.at[g as usize] = NONE;
        }
        self.row.sort_unstable_by_key(|e| e.0);
        &mut self.row
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn aggregates_per_rank_keep_their_size_up_to_the_cap() {
        // 98k nodes on 2 ranks: ~49k unknowns per rank, the caller's 256 hold fewer than
        // COARSE_SIZE each.
        assert_eq!(per_rank(256, 49_000, 2), 256);
        // 1M nodes on 2 ranks: 507 000 / 500 = 1 014.
        assert_eq!(per_rank(256, 507_000, 2), 1_014);
        // Capped at COARSE_MAX over the ranks, but never below the caller's count.
        assert_eq!(per_rank(256, 10_000_000, 4), COARSE_MAX / 4);
        assert_eq!(per_rank(256, 10_000_000, 64), 256);
        // Off, and never more aggregates than unknowns.
        assert_eq!(per_rank(0, 507_000, 2), 0);
        assert_eq!(per_rank(256, 100, 2), 100);
    }
}
