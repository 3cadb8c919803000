//! The multigrid's transfer operators (the prolongator P and, in the set-up, R = Pᵀ) in
//! single precision, the restriction of the residual and the prolongation.

use rayon::prelude::*;
use sparse::vec3::{CHUNK, V3, row_chunks};
use sparse::{Entry, SymMatrix};

/// A multigrid transfer operator in CSR form (the prolongator P; in the set-up, also its
/// transpose R = Pᵀ), each entry its column and its single-precision value side by side:
/// half the memory and traffic of f64 values, one stream to read, and a row of P (~4 entries
/// on the finest level) in one cache line, which matters when the Galerkin product gathers
/// the rows of a node's neighbours. Products are formed in f64. The restriction uses P too,
/// by rows ([`restrict_residual`]).
pub(super) struct Transfer {
    pub ncols: usize,
    pub offsets: Vec<usize>,
    pub entries: Vec<(u32, f32)>,
}

impl Transfer {
    pub fn nrows(&self) -> usize {
        self.offsets.len() - 1
    }

    /// The entries of row `i`.
    #[inline]
    pub fn row(&self, i: usize) -> &[(u32, f32)] {
        &self.entries[self.offsets[i]..self.offsets[i + 1]]
    }

    pub fn bytes(&self) -> usize {
        self.offsets.len() * 8 + self.entries.len() * 8
    }

    /// The transpose (a counting sort): each row of the result lists its entries in
    /// increasing column order, whatever the thread count.
    ///
    /// A serial pass counts each column's entries and finds the first and last rows that
    /// have one; then [`TRANSPOSE_PARTS`] ranges of columns are filled in parallel, each
    /// scanning in order only the rows between the first and last of its columns. The
    /// aggregates of the first pass are numbered in the order of the fine rows, so most
    /// ranges are short; those of the leftovers come last and span the grid (one scan).
    pub fn transpose(&self) -> Self {
        let (nr, nc) = (self.nrows(), self.ncols);
        let mut offsets = vec![0usize; nc + 1];
        let mut first = vec![usize::MAX; nc];
        let mut last = vec![0usize; nc];
        for i in 0..nr {
            for &(c, _) in self.row(i) {
                let c = c as usize;
                offsets[c + 1] += 1;
                first[c] = first[c].min(i);
                last[c] = i;
            }
        }
        for k in 0..nc {
            offsets[k + 1] += offsets[k];
        }
        let part = nc.div_ceil(TRANSPOSE_PARTS).max(1);
        let mut entries = vec![(0u32, 0.0f32); self.entries.len()];
        row_chunks(&mut entries, nc, part, |c| offsets[c])
            .into_par_iter()
            .enumerate()
            .for_each(|(k, out)| {
                let (lo, hi) = (k * part, ((k + 1) * part).min(nc));
                let r0 = first[lo..hi].iter().copied().min().unwrap_or(usize::MAX);
                let r1 = last[lo..hi].iter().copied().max().unwrap_or(0);
                let mut fill: Vec<usize> =
                    offsets[lo..hi].iter().map(|o| o - offsets[lo]).collect();
                for i in r0..=r1 {
                    for &(c, v) in self.row(i) {
                        let c = c as usize;
                        if (lo..hi).contains(&c) {
                            out[fill[c - lo]] = (i as u32, v);
                            fill[c - lo] += 1;
                        }
                    }
                }
            });
        Self {
            ncols: nr,
            offsets,
            entries,
        }
    }
}

/// Column ranges filled in parallel by [`Transfer::transpose`] (fixed: the result does not
/// depend on it anyway).
const TRANSPOSE_PARTS: usize = 16;

/// Fixed number of partial sums of the restriction (independent of the thread count).
pub(super) const LANES: usize = 4;

/// y ← Pᵀ (b − A x), without storing the residual nor Pᵀ: the fine rows are cut into
/// [`LANES`] fixed ranges (whole chunks of [`CHUNK`] rows); each range computes its residual
/// rows in order and adds P's row i times r_i into its own dense coarse vector of `lanes`;
/// y is the sum of the lanes in lane order. Every coarse entry sums its terms in a fixed
/// order, so the result does not depend on the thread count. The residual streams through
/// the fine rows once and P is read in its storage order (the gathers of a stored
/// restriction, whose rows reach across the aggregates' fine rows, were the slow part).
pub(super) fn restrict_residual<M: Entry>(
    a: &SymMatrix<M>,
    p: &Transfer,
    b: &[V3],
    x: &[V3],
    y: &mut [V3],
    lanes: &mut [Vec<V3>],
) {
    let n = a.n();
    let chunks = n.div_ceil(CHUNK);
    let nl = lanes.len();
    lanes.par_iter_mut().enumerate().for_each(|(k, acc)| {
        acc.fill([0.0; 3]);
        let lo = (k * chunks / nl) * CHUNK;
        let hi = (((k + 1) * chunks / nl) * CHUNK).min(n);
        if lo >= hi {
            return;
        }
        a.rows_mul(
            lo,
            hi,
            x,
            #[inline(always)]
            |i, v| {
                let r = [b[i][0] - v[0], b[i][1] - v[1], b[i][2] - v[2]];
                for &(col, w) in p.row(i) {
                    let w = f64::from(w);
                    let e = &mut acc[col as usize];
                    e[0] += w * r[0];
                    e[1] += w * r[1];
                    e[2] += w * r[2];
                }
            },
        );
    });
    let lanes = &*lanes;
    y.par_chunks_mut(CHUNK).enumerate().for_each(|(c, ys)| {
        let r0 = c * CHUNK;
        for (k, yi) in ys.iter_mut().enumerate() {
            let mut s = lanes[0][r0 + k];
            for lane in &lanes[1..] {
                let v = lane[r0 + k];
                s[0] += v[0];
                s[1] += v[1];
                s[2] += v[2];
            }
            *yi = s;
        }
    });
}

/// y ← y + M x.
pub(super) fn spmv_csr_add(m: &Transfer, x: &[V3], y: &mut [V3]) {
    y.par_chunks_mut(CHUNK).enumerate().for_each(|(c, ys)| {
        let r0 = c * CHUNK;
        for (k, yi) in ys.iter_mut().enumerate() {
            for &(col, v) in m.row(r0 + k) {
                let v = f64::from(v);
                let xj = x[col as usize];
                yi[0] += v * xj[0];
                yi[1] += v * xj[1];
                yi[2] += v * xj[2];
            }
        }
    });
}
