//! General sparse matrices in compressed sparse row form (rectangular allowed), and the
//! parallel row builder that every CSR array of the workspace is made with.

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::vec3::CHUNK;

/// General sparse matrix in CSR (rectangular allowed; the diagonal is not special).
#[derive(Debug, Clone, PartialEq)]
pub struct Csr {
    /// Number of columns.
    pub ncols: usize,
    /// Row offsets, length rows + 1.
    pub offsets: Vec<usize>,
    /// Column indices, sorted within a row.
    pub cols: Vec<u32>,
    /// Values.
    pub vals: Vec<f64>,
}

impl Csr {
    /// Number of rows.
    pub fn nrows(&self) -> usize {
        self.offsets.len() - 1
    }

    /// Builds the matrix from rows computed independently in parallel (deterministic: each
    /// row by one task; [`build_rows`]).
    pub fn from_rows<F>(nrows: usize, ncols: usize, row: F) -> Self
    where
        F: Fn(usize, &mut Vec<(u32, f64)>) + Sync,
    {
        let (offsets, entries) = build_rows(nrows, row, |e| e);
        let (cols, vals) = entries.into_iter().unzip();
        Self {
            ncols,
            offsets,
            cols,
            vals,
        }
    }

    /// The entries of row `i`: their columns and values.
    #[inline]
    pub fn row(&self, i: usize) -> (&[u32], &[f64]) {
        let r = self.offsets[i]..self.offsets[i + 1];
        (&self.cols[r.clone()], &self.vals[r])
    }

    /// The matrix as a [`sprs::CsMat`] in CSR form (the workspace's public interchange type
    /// for sparse matrices). Fails on a malformed matrix (lengths, a column out of range or
    /// columns not increasing in a row).
    pub fn to_csmat(&self) -> Result<sprs::CsMat<f64>> {
        let indices = self.cols.iter().map(|&c| c as usize).collect();
        sprs::CsMat::try_new(
            (self.nrows(), self.ncols),
            self.offsets.clone(),
            indices,
            self.vals.clone(),
        )
        .map_err(|e| Error::BadGraph {
            reason: format!("{}", e.3),
        })
    }
}

/// The rows of a sparse matrix, computed in parallel blocks of [`CHUNK`] rows: `row(i, buf)`
/// fills row i's (column, value) pairs into an empty buffer and `put` turns each pair into a
/// stored entry. Returns the row offsets and the entries, the blocks copied into place in
/// parallel. Each row is computed by one task, so the result does not depend on the thread
/// count.
pub fn build_rows<E, F, P>(nrows: usize, row: F, put: P) -> (Vec<usize>, Vec<E>)
where
    E: Copy + Default + Send + Sync,
    F: Fn(usize, &mut Vec<(u32, f64)>) + Sync,
    P: Fn((u32, f64)) -> E + Sync,
{
    let blocks: Vec<(Vec<usize>, Vec<E>)> = (0..nrows.div_ceil(CHUNK))
        .into_par_iter()
        .map(|b| {
            let (lo, hi) = (b * CHUNK, ((b + 1) * CHUNK).min(nrows));
            let mut lens = Vec::with_capacity(hi - lo);
            let mut entries = Vec::new();
            let mut buf = Vec::new();
            for i in lo..hi {
                buf.clear();
                row(i, &mut buf);
                lens.push(buf.len());
                entries.extend(buf.iter().map(|&e| put(e)));
            }
            (lens, entries)
        })
        .collect();
    let mut offsets = Vec::with_capacity(nrows + 1);
    offsets.push(0usize);
    let mut last = 0;
    for l in blocks.iter().flat_map(|b| &b.0) {
        last += l;
        offsets.push(last);
    }
    let mut entries = vec![E::default(); last];
    let mut pieces = Vec::with_capacity(blocks.len());
    let mut rest = entries.as_mut_slice();
    for b in &blocks {
        let (piece, tail) = rest.split_at_mut(b.1.len());
        pieces.push(piece);
        rest = tail;
    }
    pieces
        .into_par_iter()
        .zip(&blocks)
        .for_each(|(piece, b)| piece.copy_from_slice(&b.1));
    (offsets, entries)
}

/// Sorts (column, value) pairs by column (stable) and sums duplicates in their order: a row
/// merge written plainly (the reference of faster merges in tests).
pub fn merge_row(buf: &mut Vec<(u32, f64)>) {
    buf.sort_by_key(|e| e.0);
    let mut w = 0;
    for r in 0..buf.len() {
        if w > 0 && buf[w - 1].0 == buf[r].0 {
            buf[w - 1].1 += buf[r].1;
        } else {
            buf[w] = buf[r];
            w += 1;
        }
    }
    buf.truncate(w);
}
