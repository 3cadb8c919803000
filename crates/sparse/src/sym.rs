//! Symmetric sparse matrices with the diagonal apart: the spring system's matrix.
//!
//! [`SymMatrix`] stores the diagonal apart and the off-diagonal entries of every row in full
//! (both triangles), so that the matrix–vector product runs row by row in parallel with no
//! write conflicts. One scalar matrix serves the three components: [`SymMatrix::mul`]
//! multiplies a vector of 3-vectors in one pass over the matrix.
//!
//! The off-diagonal values are stored as any [`Entry`] type: f64, or f32 for a matrix whose
//! values were rounded to single precision once, when they were computed (the diagonal and
//! every product stay f64; the matrix is then exactly the one of the rounded values, and a
//! product reads 8 instead of 12 bytes per entry).

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::madd::{self, Kernel, MulAdd};
use crate::vec3::{CHUNK, V3, chunked_sum};

/// The storage type of a [`SymMatrix`]'s off-diagonal values (f64 or f32); arithmetic is in
/// f64 whatever the storage.
pub trait Entry: Copy + Default + PartialEq + std::fmt::Debug + Send + Sync + 'static {
    /// The value as f64 (exact).
    fn get(self) -> f64;
    /// `v` rounded to the storage type (to nearest).
    fn of(v: f64) -> Self;
}

impl Entry for f64 {
    #[inline]
    fn get(self) -> f64 {
        self
    }
    #[inline]
    fn of(v: f64) -> Self {
        v
    }
}

impl Entry for f32 {
    #[inline]
    fn get(self) -> f64 {
        f64::from(self)
    }
    #[inline]
    fn of(v: f64) -> Self {
        v as f32
    }
}

/// Symmetric sparse matrix: diagonal apart (f64), off-diagonal rows in full, their values
/// stored as `T`.
#[derive(Debug, Clone, PartialEq)]
pub struct SymMatrix<T = f64> {
    /// Diagonal entries a_ii.
    pub diag: Vec<f64>,
    /// Row offsets into `cols` / `vals`, length n + 1.
    pub offsets: Vec<usize>,
    /// Column indices of the off-diagonal entries.
    pub cols: Vec<u32>,
    /// Off-diagonal values a_ij, i ≠ j.
    pub vals: Vec<T>,
}

impl<T: Entry> SymMatrix<T> {
    /// Checks the structure (lengths, index range, no diagonal in the off-diagonal part) and
    /// symmetry of the pattern and values to `rel_tol` relative.
    pub fn validate(&self, rel_tol: f64) -> Result<()> {
        let n = self.diag.len();
        if self.offsets.len() != n + 1
            || self.offsets[n] != self.cols.len()
            || self.cols.len() != self.vals.len()
        {
            return Err(Error::BadGraph {
                reason: "inconsistent matrix array lengths".into(),
            });
        }
        for i in 0..n {
            for p in self.offsets[i]..self.offsets[i + 1] {
                let j = self.cols[p] as usize;
                if j >= n || j == i {
                    return Err(Error::BadGraph {
                        reason: format!("row {i}: bad column {j}"),
                    });
                }
                let back = self.get(j, i);
                let a = self.vals[p].get();
                if (back - a).abs() > rel_tol * a.abs().max(back.abs()) {
                    return Err(Error::BadGraph {
                        reason: format!("not symmetric at ({i}, {j}): {a} vs {back}"),
                    });
                }
            }
        }
        Ok(())
    }

    /// Order of the matrix.
    pub fn n(&self) -> usize {
        self.diag.len()
    }

    /// Number of stored off-diagonal entries.
    pub fn nnz_offdiag(&self) -> usize {
        self.cols.len()
    }

    /// Entry (i, j) (zero when not stored; linear search in the row).
    pub fn get(&self, i: usize, j: usize) -> f64 {
        if i == j {
            return self.diag[i];
        }
        let r = self.offsets[i]..self.offsets[i + 1];
        self.cols[r.clone()]
            .iter()
            .position(|&c| c as usize == j)
            .map_or(0.0, |p| self.vals[r.start + p].get())
    }

    /// Bytes held by the matrix arrays.
    pub fn bytes(&self) -> usize {
        self.diag.len() * 8
            + self.offsets.len() * 8
            + self.cols.len() * 4
            + self.vals.len() * std::mem::size_of::<T>()
    }

    /// The same matrix with its off-diagonal values stored as `U` (rounded to nearest).
    pub fn to_entries<U: Entry>(&self) -> SymMatrix<U> {
        SymMatrix {
            diag: self.diag.clone(),
            offsets: self.offsets.clone(),
            cols: self.cols.clone(),
            vals: self.vals.iter().map(|&v| U::of(v.get())).collect(),
        }
    }

    /// The off-diagonal entries of row `i`: their columns and values.
    #[inline]
    pub fn row(&self, i: usize) -> (&[u32], &[T]) {
        let r = self.offsets[i]..self.offsets[i + 1];
        (&self.cols[r.clone()], &self.vals[r])
    }

    /// One row's product (a_ii x_i + Σ_j a_ij x_j) for the three components, with the
    /// multiply–adds of `madd::run` (bit for bit the row's value in [`SymMatrix::mul`]).
    pub fn row_mul(&self, i: usize, x: &[V3]) -> V3 {
        struct Row<'a, T: Entry> {
            a: &'a SymMatrix<T>,
            i: usize,
            x: &'a [V3],
        }
        impl<T: Entry> Kernel for Row<'_, T> {
            type Output = V3;
            #[inline(always)]
            fn run<M: MulAdd>(self) -> V3 {
                self.a.row_mul_with::<M>(self.i, self.x)
            }
        }
        madd::run(Row { a: self, i, x })
    }

    #[inline(always)]
    fn row_mul_with<M: MulAdd>(&self, i: usize, x: &[V3]) -> V3 {
        let d = self.diag[i];
        let xi = x[i];
        let mut s = [d * xi[0], d * xi[1], d * xi[2]];
        let r = self.offsets[i]..self.offsets[i + 1];
        for (&c, &a) in self.cols[r.clone()].iter().zip(&self.vals[r]) {
            let a = a.get();
            let xj = x[c as usize];
            madd::mul_add3::<M>(a, xj, &mut s);
        }
        s
    }

    /// Calls `f(i, (A x)_i)` for the rows `lo..hi` in increasing order, the whole loop
    /// (`f` included) run by `madd::run`. Callers mark `f` `#[inline(always)]`: without
    /// it the compiler kept the restriction's and the smoother's per-row closures as a call
    /// per row (multigrid solve at 1M, one process, alternated: median 1.232 → 1.169 s in 16
    /// pairs, 1.158 → 1.145 s in 8).
    ///
    /// Rows are taken two at a time with their entries interleaved, so that the two rows'
    /// dependent chains of additions overlap in the processor; each row's own sum runs in the
    /// same order as [`SymMatrix::row_mul`], so the results are bit for bit those of row_mul.
    #[inline]
    pub fn rows_mul<F: FnMut(usize, V3)>(&self, lo: usize, hi: usize, x: &[V3], f: F) {
        struct Rows<'a, T: Entry, F> {
            a: &'a SymMatrix<T>,
            lo: usize,
            hi: usize,
            x: &'a [V3],
            f: F,
        }
        impl<T: Entry, F: FnMut(usize, V3)> Kernel for Rows<'_, T, F> {
            type Output = ();
            #[inline(always)]
            fn run<M: MulAdd>(self) {
                self.a
                    .rows_mul_with::<M, F>(self.lo, self.hi, self.x, self.f)
            }
        }
        madd::run(Rows {
            a: self,
            lo,
            hi,
            x,
            f,
        })
    }

    #[inline(always)]
    fn rows_mul_with<M: MulAdd, F: FnMut(usize, V3)>(
        &self,
        lo: usize,
        hi: usize,
        x: &[V3],
        mut f: F,
    ) {
        let off = &self.offsets[lo..=hi];
        let mut i = lo;
        while i + 1 < hi {
            let k = i - lo;

            let (p0, p1, p2) = (off[k], off[k + 1], off[k + 2]);
            let (c0, v0) = (&self.cols[p0..p1], &self.vals[p0..p1]);
            let (c1, v1) = (&self.cols[p1..p2], &self.vals[p1..p2]);
            let (d0, d1) = (self.diag[i], self.diag[i + 1]);
            let (x0, x1) = (x[i], x[i + 1]);
            let mut s = [d0 * x0[0], d0 * x0[1], d0 * x0[2]];
            let mut t = [d1 * x1[0], d1 * x1[1], d1 * x1[2]];
            let m = c0.len().min(c1.len());
            for ((&ca, &va), (&cb, &vb)) in c0[..m]
                .iter()
                .zip(&v0[..m])
                .zip(c1[..m].iter().zip(&v1[..m]))
            {
                let (va, vb) = (va.get(), vb.get());
                let xa = x[ca as usize];
                let xb = x[cb as usize];
                madd::mul_add3::<M>(va, xa, &mut s);
                madd::mul_add3::<M>(vb, xb, &mut t);
            }
            for (&ca, &va) in c0[m..].iter().zip(&v0[m..]) {
                let va = va.get();
                let xa = x[ca as usize];
                madd::mul_add3::<M>(va, xa, &mut s);
            }
            for (&cb, &vb) in c1[m..].iter().zip(&v1[m..]) {
                let vb = vb.get();
                let xb = x[cb as usize];
                madd::mul_add3::<M>(vb, xb, &mut t);
            }
            f(i, s);
            f(i + 1, t);
            i += 2;
        }
        if i < hi {
            f(i, self.row_mul_with::<M>(i, x));
        }
    }

    /// y ← A x for the three components in one pass over the matrix; rows in parallel,
    /// each row computed by one thread in a fixed order (deterministic).
    pub fn mul(&self, x: &[V3], y: &mut [V3]) {
        assert_eq!(x.len(), self.n());
        assert_eq!(y.len(), self.n());
        y.par_chunks_mut(CHUNK).enumerate().for_each(|(c, ys)| {
            let r0 = c * CHUNK;
            self.rows_mul(
                r0,
                r0 + ys.len(),
                x,
                #[inline(always)]
                |i, v| ys[i - r0] = v,
            );
        });
    }

    /// y ← A x and returns xᵀ A x (fused, deterministic chunked reduction).
    pub fn mul_dot(&self, x: &[V3], y: &mut [V3]) -> f64 {
        assert_eq!(x.len(), self.n());
        assert_eq!(y.len(), self.n());
        chunked_sum(y, |r0, ys| {
            let mut s = 0.0;
            self.rows_mul(
                r0,
                r0 + ys.len(),
                x,
                #[inline(always)]
                |i, v| {
                    ys[i - r0] = v;
                    s += v[0] * x[i][0] + v[1] * x[i][1] + v[2] * x[i][2];
                },
            );
            s
        })
    }

    /// r ← b − A x, returns |r|² (deterministic).
    pub fn residual(&self, b: &[V3], x: &[V3], r: &mut [V3]) -> f64 {
        chunked_sum(r, |r0, rs| {
            let mut s = 0.0;
            self.rows_mul(
                r0,
                r0 + rs.len(),
                x,
                #[inline(always)]
                |i, v| {
                    let ri = [b[i][0] - v[0], b[i][1] - v[1], b[i][2] - v[2]];
                    rs[i - r0] = ri;
                    s += ri[0] * ri[0] + ri[1] * ri[1] + ri[2] * ri[2];
                },
            );
            s
        })
    }

    /// The matrix with rows and columns renumbered by `perm` (old index i becomes `perm[i]`,
    /// the convention of [`crate::order`]); rows sorted by column.
    pub fn permuted(&self, perm: &[u32]) -> Self {
        let n = self.n();
        assert_eq!(perm.len(), n);
        let inv = perm;
        let perm = crate::order::inverse(perm);
        let mut offsets = vec![0usize; n + 1];
        for k in 0..n {
            let o = perm[k] as usize;
            offsets[k + 1] = offsets[k] + self.offsets[o + 1] - self.offsets[o];
        }
        let mut cols = vec![0u32; offsets[n]];
        let mut vals = vec![T::default(); offsets[n]];
        let mut diag = vec![0.0; n];
        for k in 0..n {
            let o = perm[k] as usize;
            diag[k] = self.diag[o];
            let mut row: Vec<(u32, T)> = (self.offsets[o]..self.offsets[o + 1])
                .map(|p| (inv[self.cols[p] as usize], self.vals[p]))
                .collect();
            row.sort_by_key(|e| e.0);
            for (q, (c, v)) in row.into_iter().enumerate() {
                cols[offsets[k] + q] = c;
                vals[offsets[k] + q] = v;
            }
        }
        Self {
            diag,
            offsets,
            cols,
            vals,
        }
    }

    /// The whole matrix (diagonal included, values as f64, columns sorted in each row) as a
    /// [`sprs::CsMat`] in CSR form: the workspace's public interchange type for sparse
    /// matrices. Fails on a malformed matrix (see [`SymMatrix::validate`]).
    pub fn to_csmat(&self) -> Result<sprs::CsMat<f64>> {
        let n = self.n();
        if self.offsets.len() != n + 1
            || self.offsets[n] != self.cols.len()
            || self.cols.len() != self.vals.len()
        {
            return Err(Error::BadGraph {
                reason: "inconsistent matrix array lengths".into(),
            });
        }
        let mut indptr = Vec::with_capacity(n + 1);
        let mut indices = Vec::with_capacity(self.cols.len() + n);
        let mut data = Vec::with_capacity(self.cols.len() + n);
        indptr.push(0);
        let mut row: Vec<(usize, f64)> = Vec::new();
        for i in 0..n {
            row.clear();
            row.push((i, self.diag[i]));
            let (cols, vals) = self.row(i);
            row.extend(cols.iter().zip(vals).map(|(&c, &v)| (c as usize, v.get())));
            row.sort_by_key(|e| e.0);
            for &(c, v) in &row {
                indices.push(c);
                data.push(v);
            }
            indptr.push(indices.len());
        }
        sprs::CsMat::try_new((n, n), indptr, indices, data).map_err(|e| Error::BadGraph {
            reason: format!("{}", e.3),
        })
    }

    /// Dense copy (tests and the coarsest multigrid level).
    pub fn to_dense(&self) -> Vec<Vec<f64>> {
        let n = self.n();
        let mut d = vec![vec![0.0; n]; n];
        for i in 0..n {
            d[i][i] = self.diag[i];
            for p in self.offsets[i]..self.offsets[i + 1] {
                d[i][self.cols[p] as usize] += self.vals[p].get();
            }
        }
        d
    }
}
