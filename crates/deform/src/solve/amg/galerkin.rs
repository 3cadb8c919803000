//! The Galerkin coarse matrix A_c = Pᵀ A P, as two row-parallel sparse products with a
//! dense accumulator.

use std::sync::Mutex;

use rayon::prelude::*;
use sparse::vec3::CHUNK;
use sparse::{Entry, SymMatrix};

use super::transfer::Transfer;

/// Dense accumulator for sparse row products (per task scratch). An entry belongs to the
/// current row when its mark equals the row's stamp, so starting a row costs nothing: no
/// flag is cleared entry by entry.
pub(super) struct Acc {
    val: Vec<f64>,
    mark: Vec<u32>,
    pub(super) stamp: u32,
    list: Vec<u32>,
}

impl Acc {
    pub fn new(n: usize) -> Self {
        Self {
            val: vec![0.0; n],
            mark: vec![u32::MAX; n],
            stamp: 0,
            list: Vec::new(),
        }
    }
    #[inline]
    pub fn add(&mut self, c: u32, v: f64) {
        let ci = c as usize;
        if self.mark[ci] != self.stamp {
            self.mark[ci] = self.stamp;
            self.val[ci] = v;
            self.list.push(c);
        } else {
            self.val[ci] += v;
        }
    }
    /// Appends the row's entries to `out_c` / `out_v`, sorted by column when `sorted`
    /// (otherwise in first-touch order), and starts the next row.
    pub fn drain(&mut self, out_c: &mut Vec<u32>, out_v: &mut Vec<f64>, sorted: bool) -> usize {
        if sorted {
            self.list.sort_unstable();
        }
        out_c.extend_from_slice(&self.list);
        out_v.extend(self.list.iter().map(|&c| self.val[c as usize]));
        let n = self.list.len();
        self.list.clear();
        self.stamp += 1;
        if self.stamp == u32::MAX {
            // Every stamp used (never on a real grid: one per row): clear the marks.
            self.mark.fill(u32::MAX);
            self.stamp = 0;
        }
        n
    }
}

/// Rows of a sparse matrix computed by `row(i, acc)` into a dense accumulator over `ncols`
/// columns, row-parallel over blocks of [`CHUNK`] rows. A row's columns come sorted when
/// `sorted`, otherwise in first-touch order. Every row is summed by one task in the order
/// `row` adds its terms, so the result does not depend on the thread count.
///
/// Each task takes a scratch from a pool (an accumulator, whose fresh pages would cost more
/// than the rows summed into it, and a [`RowStore`]), appends its blocks' rows to the
/// store, and gives the scratch back; the blocks remember which store holds them. A store
/// starts with room for `reserve` entries: few large buffers instead of one per block,
/// which the C allocator maps on their own and returns to the system when dropped (at 1M
/// nodes glibc kept all 113 MB of A P's per-block buffers after they were freed).
fn accumulated_rows<F>(nrows: usize, ncols: usize, sorted: bool, reserve: usize, row: F) -> Rows
where
    F: Fn(usize, &mut Acc) + Sync,
{
    struct Task {
        id: usize,
        acc: Acc,
        store: RowStore,
    }
    let pool: Mutex<(Vec<Task>, usize)> = Mutex::new((Vec::new(), 0));
    let blocks = (0..nrows.div_ceil(CHUNK))
        .into_par_iter()
        .map(|b| {
            let mut st = {
                let mut guard = pool.lock().unwrap_or_else(|e| e.into_inner());
                match guard.0.pop() {
                    Some(st) => st,
                    None => {
                        guard.1 += 1;
                        Task {
                            id: guard.1 - 1,
                            acc: Acc::new(ncols),
                            store: RowStore {
                                cols: Vec::with_capacity(reserve),
                                vals: Vec::with_capacity(reserve),
                            },
                        }
                    }
                }
            };
            let lo = b * CHUNK;
            let hi = (lo + CHUNK).min(nrows);
            let mut offsets = Vec::with_capacity(hi - lo + 1);
            offsets.push(st.store.cols.len());
            for i in lo..hi {
                row(i, &mut st.acc);
                let RowStore { cols, vals } = &mut st.store;
                st.acc.drain(cols, vals, sorted);
                offsets.push(cols.len());
            }
            let id = st.id;
            pool.lock().unwrap_or_else(|e| e.into_inner()).0.push(st);
            (id, offsets)
        })
        .collect();
    let mut tasks = pool.into_inner().unwrap_or_else(|e| e.into_inner()).0;
    tasks.sort_unstable_by_key(|st| st.id);
    Rows {
        blocks,
        stores: tasks.into_iter().map(|st| st.store).collect(),
    }
}

/// Rows appended by the tasks of [`accumulated_rows`] (one store per task).
struct RowStore {
    cols: Vec<u32>,
    vals: Vec<f64>,
}

/// A matrix built by [`accumulated_rows`]: for each block of [`CHUNK`] rows, the store that
/// holds it and its rows' offsets there.
struct Rows {
    blocks: Vec<(usize, Vec<usize>)>,
    stores: Vec<RowStore>,
}

impl Rows {
    /// The columns and values of row `i`.
    #[inline]
    fn row(&self, i: usize) -> (&[u32], &[f64]) {
        let (s, offsets) = &self.blocks[i / CHUNK];
        let k = i % CHUNK;
        let st = &self.stores[*s];
        let span = offsets[k]..offsets[k + 1];
        (&st.cols[span.clone()], &st.vals[span])
    }

    /// Stored entries.
    fn nnz(&self) -> usize {
        self.stores.iter().map(|st| st.cols.len()).sum()
    }
}

/// The least reserve of a task's [`RowStore`] in a large Galerkin product, in entries: 36 MB
/// of column indices (and 72 MB of values), beyond glibc's largest threshold for mapping an
/// allocation on its own (32 MB). Only the pages written become resident.
const LARGE_STORE: usize = 9 << 20;

/// A_c = R A P with R = Pᵀ, returned with its diagonal apart.
///
/// First A P, row-parallel and never sorted (only the rows of A_c need their columns in
/// order); then the rows of R (A P), row-parallel. Both use a dense accumulator
/// ([`accumulated_rows`]). A P has ~2.5× the entries of P (~110 MB at 1M nodes), held only
/// during this product, before the solves' vectors exist.
pub(super) fn galerkin<T: Entry>(a: &SymMatrix<T>, p: &Transfer, r: &Transfer) -> SymMatrix {
    let nc = p.ncols;
    // Room for A P's entries in each task's store (~2.5 per entry of P; measured 2.44 at
    // 1M nodes): a large product reserves stores that are mapped on their own.
    let per_task = 5 * p.entries.len() / 2 / rayon::current_num_threads().max(1);
    let reserve = if per_task >= LARGE_STORE / 4 {
        per_task.max(LARGE_STORE)
    } else {
        per_task
    };
    let ap = accumulated_rows(a.n(), nc, false, reserve, |i, acc| {
        let d = a.diag[i];
        for &(c, w) in p.row(i) {
            acc.add(c, d * f64::from(w));
        }
        for k in a.offsets[i]..a.offsets[i + 1] {
            let j = a.cols[k] as usize;
            let v = a.vals[k].get();
            for &(c, w) in p.row(j) {
                acc.add(c, v * f64::from(w));
            }
        }
    });
    let rap = accumulated_rows(nc, nc, true, 0, |i, acc| {
        for &(f, w) in r.row(i) {
            let w = f64::from(w);
            let (cols, vals) = ap.row(f as usize);
            for (&c, &v) in cols.iter().zip(vals) {
                acc.add(c, w * v);
            }
        }
    });
    drop(ap);
    // Split off the diagonal. The product is symmetric up to round-off only; CG does not
    // need a_ij = a_ji to the last bit, so they are not averaged.
    let nnz = rap.nnz();
    let mut diag = vec![0.0; nc];
    let mut offsets = Vec::with_capacity(nc + 1);
    offsets.push(0usize);
    let mut cols = Vec::with_capacity(nnz.saturating_sub(nc));
    let mut vals = Vec::with_capacity(nnz.saturating_sub(nc));
    for (i, d) in diag.iter_mut().enumerate() {
        let (cs, vs) = rap.row(i);
        for (&c, &v) in cs.iter().zip(vs) {
            if c as usize == i {
                *d = v;
            } else {
                cols.push(c);
                vals.push(v);
            }
        }
        offsets.push(cols.len());
    }
    SymMatrix {
        diag,
        offsets,
        cols,
        vals,
    }
}
