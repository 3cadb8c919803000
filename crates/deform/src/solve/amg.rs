//! Smoothed-aggregation algebraic multigrid (Vaněk, Mandel, Brezina), used as a W-cycle
//! preconditioner for conjugate gradients on the spring matrix.
//!
//! Setup, per level: strength of connection |a_ij| ≥ θ √(a_ii a_jj); greedy aggregation in
//! three passes (root nodes whose strong neighbours are all free, then attachment of the
//! remaining nodes to a neighbouring aggregate, then leftover groups); tentative prolongator
//! P₀ piecewise constant on aggregates (the constant is the near-null space of the spring
//! Laplacian); smoothed prolongator P = (I − ω_P D⁻¹ A) P₀ with ω_P = c_P / ρ, ρ the
//! Gershgorin bound max_i (1 + Σ_j |a_ij| / a_ii) ≥ λ_max(D⁻¹A); Galerkin coarse matrix
//! A_c = Pᵀ A P. The coarsest level (≤ `max_coarse` unknowns) is solved by a dense Cholesky
//! factorisation.
//!
//! Cycle: damped Jacobi pre- and post-smoothing with ω = c_S / ρ (the same symmetric
//! smoother on both sides), three components at once; on every coarse level but the
//! coarsest, `coarse_cycles` cycles per visit (2: the W-cycle), each started from the
//! previous one's residual. With c_S < 2, ω λ_max(D⁻¹A) ≤ c_S < 2, so the smoother converges
//! in the A-norm, and a fixed number of cycles of a symmetric convergent iteration from a
//! zero start is a symmetric positive definite operator: the cycle is a valid
//! preconditioner for conjugate gradients. Every kernel is deterministic for any thread
//! count.

use std::sync::Mutex;

use rayon::prelude::*;

use super::csr::{Entry, SymMatrix, build_rows};
use super::pcg::{Preconditioner, Weights};
use super::vecops::{CHUNK, V3, axpy, chunked_sum, row_chunks};
use crate::error::{Error, Result};

/// Multigrid setup options.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AmgOptions {
    /// Strength threshold θ on the finest level, halved on each coarser level (0 keeps every
    /// connection: aggregates of ~20 nodes, cheapest setup; measured faster overall than 0.08
    /// on the benchmark grids, see docs/performance.md).
    pub strength: f64,
    /// Stop coarsening when a level has at most this many unknowns.
    pub max_coarse: usize,
    /// Maximum number of levels.
    pub max_levels: usize,
    /// Jacobi sweeps before and after the coarse-grid correction.
    pub sweeps: usize,
    /// Cycles on each coarse level that is not the coarsest, per visit: 1 is the V-cycle,
    /// 2 (default) the W-cycle. The coarse levels are ~25× smaller than the finest, so the
    /// second cycle costs little, and it cuts the PCG iterations by a third on the
    /// wing-in-box grids (22 → 17 at 309k nodes, 27 → 18 at 1M; docs/performance.md).
    pub coarse_cycles: usize,
    /// c_S: the Jacobi smoother's damping is ω = c_S / ρ, ρ the Gershgorin bound of
    /// λ_max(D⁻¹A). Must lie in (0, 2): then ω λ_max ≤ c_S < 2 and the cycle is symmetric
    /// positive definite whatever the true λ_max. Default 1.8: ρ overestimates λ_max on tet
    /// grids (ρ ≈ 2 for a spring Laplacian), so the classical 4/3 under-damps; 1.8 took the
    /// PCG iterations from 17 to 13 at 309k nodes and from 18 to 13 at 1M
    /// (docs/performance.md).
    pub smoother_damping: f64,
    /// c_P: the prolongator smoothing's damping is ω_P = c_P / ρ (the classical choice is
    /// 4 / (3 λ_max), which is 4 / 3 here only if λ_max = ρ). Any value gives a valid
    /// hierarchy (A_c = Pᵀ A P stays symmetric positive definite); default 1.6.
    pub prolongator_damping: f64,
}

impl Default for AmgOptions {
    fn default() -> Self {
        Self {
            strength: 0.0,
            max_coarse: 400,
            max_levels: 12,
            sweeps: 1,
            coarse_cycles: 2,
            smoother_damping: 1.8,
            prolongator_damping: 1.6,
        }
    }
}

struct Level {
    /// Prolongator from the next coarser level.
    p: Transfer,
    /// Smoother damping ω (the weights ω / a_ii are formed when used: no stored vector).
    omega: f64,
}

/// A smoothed-aggregation multigrid hierarchy over a borrowed ([`Amg::new`]) or owned
/// ([`Amg::new_owned`], kept for reuse across solves) fine matrix, whose values are stored
/// as `T`; the coarse matrices are f64.
pub struct Amg<'a, T: Entry = f64> {
    fine: std::borrow::Cow<'a, SymMatrix<T>>,
    levels: Vec<Level>,
    /// Coarse matrices A_1 … A_L (A_0 is `fine`).
    coarse: Vec<SymMatrix>,
    chol: DenseCholesky,
    sweeps: usize,
    coarse_cycles: usize,
    scratch: Mutex<Vec<Scratch>>,
}

/// Vectors of one coarse level of the cycle (the finest level uses the caller's vectors):
/// `b` and `out` are the level's right-hand side and result, `x` the iterate (empty on the
/// coarsest level). The residual is never stored (it is restricted as it is computed);
/// with more than one sweep, `out` is the sweeps' scratch until the last sweep writes the
/// result there.
struct Scratch {
    b: Vec<V3>,
    out: Vec<V3>,
    x: Vec<V3>,
    /// Residual and correction of the repeated cycles (empty with one cycle).
    r: Vec<V3>,
    d: Vec<V3>,
    /// The restriction's [`LANES`] partial sums of this level's right-hand side.
    lanes: Vec<Vec<V3>>,
}

/// Summary of a hierarchy.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct AmgInfo {
    /// Unknowns per level, finest first.
    pub sizes: Vec<usize>,
    /// Stored off-diagonal entries per level.
    pub nnz: Vec<usize>,
    /// Operator complexity Σ nnz(A_l) / nnz(A_0) (diagonals included).
    pub operator_complexity: f64,
}

impl<'a, T: Entry> Amg<'a, T> {
    /// Builds the hierarchy for `a` (symmetric positive definite, positive diagonal).
    pub fn new(a: &'a SymMatrix<T>, opts: &AmgOptions) -> Result<Self> {
        Self::build(std::borrow::Cow::Borrowed(a), opts)
    }

    /// [`Amg::new`] taking the fine matrix by value (the hierarchy can then be stored and
    /// reused, e.g. by [`crate::Deformer`]).
    pub fn new_owned(a: SymMatrix<T>, opts: &AmgOptions) -> Result<Amg<'static, T>> {
        Amg::build(std::borrow::Cow::Owned(a), opts)
    }

    /// The fine matrix A_0.
    pub fn fine(&self) -> &SymMatrix<T> {
        &self.fine
    }

    fn build(fine: std::borrow::Cow<'a, SymMatrix<T>>, opts: &AmgOptions) -> Result<Self> {
        let a: &SymMatrix<T> = &fine;
        let c = opts.smoother_damping;
        if !(c > 0.0 && c < 2.0) {
            return Err(Error::BadOption {
                reason: format!(
                    "multigrid smoother damping {c} is not in (0, 2): the cycle would not be positive definite"
                ),
            });
        }
        if !(opts.prolongator_damping.is_finite() && opts.prolongator_damping >= 0.0) {
            return Err(Error::BadOption {
                reason: format!(
                    "multigrid prolongator damping {} is not a finite number ≥ 0",
                    opts.prolongator_damping
                ),
            });
        }
        let mut levels = Vec::new();
        let mut coarse: Vec<SymMatrix> = Vec::new();
        loop {
            let n = coarse.last().map_or(a.n(), |c| c.n());
            if n <= opts.max_coarse || levels.len() + 1 >= opts.max_levels {
                break;
            }
            let step = match coarse.last() {
                None => coarsen(a, opts, levels.len()),
                Some(c) => coarsen(c, opts, levels.len()),
            };
            let Some((level, ac)) = step else {
                break;
            };
            levels.push(level);
            coarse.push(ac);
        }
        let chol = match coarse.last() {
            Some(c) => DenseCholesky::new(c, levels.len())?,
            None => DenseCholesky::new(a, 0)?,
        };
        let nc = coarse.last().map_or(a.n(), |c| c.n());
        // Levels 1 … L (the finest level works in the caller's vectors).
        let mut scratch = Vec::new();
        let repeat = opts.coarse_cycles > 1;
        for c in coarse.iter().take(levels.len().saturating_sub(1)) {
            let n = c.n();
            let more = if repeat { n } else { 0 };
            scratch.push(Scratch {
                b: vec![[0.0; 3]; n],
                out: vec![[0.0; 3]; n],
                x: vec![[0.0; 3]; n],
                r: vec![[0.0; 3]; more],
                d: vec![[0.0; 3]; more],
                lanes: vec![vec![[0.0; 3]; n]; LANES],
            });
        }
        scratch.push(Scratch {
            b: vec![[0.0; 3]; nc],
            out: vec![[0.0; 3]; nc],
            x: Vec::new(),
            r: Vec::new(),
            d: Vec::new(),
            // Without coarse levels nothing is restricted.
            lanes: if levels.is_empty() {
                Vec::new()
            } else {
                vec![vec![[0.0; 3]; nc]; LANES]
            },
        });
        Ok(Self {
            fine,
            levels,
            coarse,
            chol,
            sweeps: opts.sweeps.max(1),
            coarse_cycles: opts.coarse_cycles.max(1),
            scratch: Mutex::new(scratch),
        })
    }

    /// Sizes and complexity of the hierarchy.
    pub fn info(&self) -> AmgInfo {
        let mut sizes = vec![self.fine.n()];
        let mut nnz = vec![self.fine.nnz_offdiag()];
        for c in &self.coarse {
            sizes.push(c.n());
            nnz.push(c.nnz_offdiag());
        }
        let tot: usize = sizes.iter().zip(&nnz).map(|(s, z)| s + z).sum();
        AmgInfo {
            operator_complexity: tot as f64 / (sizes[0] + nnz[0]) as f64,
            sizes,
            nnz,
        }
    }

    /// out ← cycle applied to `b` on level `l`, whose matrix is `a`; `x` is the level's
    /// iterate, `out` is scratch until the last sweep, `deeper` is the scratch of
    /// the coarser levels. Returns b · out (0 on the coarsest level).
    fn cycle<M: Entry>(
        &self,
        a: &SymMatrix<M>,
        l: usize,
        b: &[V3],
        out: &mut [V3],
        x: &mut [V3],
        deeper: &mut [Scratch],
        prescaled: bool,
    ) -> f64 {
        if l == self.levels.len() {
            self.chol.solve(b, out);
            return 0.0;
        }
        let lev = &self.levels[l];
        let w = Weights {
            omega: lev.omega,
            diag: &a.diag,
        };
        // Pre-smoothing from x = 0: x = W b (already in x when `prescaled`), then
        // x += W (b − A x).
        if !prescaled {
            x.par_chunks_mut(CHUNK)
                .zip(b.par_chunks(CHUNK))
                .enumerate()
                .for_each(|(c, (xs, bs))| {
                    let r0 = c * CHUNK;
                    for (k, (xi, bi)) in xs.iter_mut().zip(bs).enumerate() {
                        let wk = w.at(r0 + k);
                        *xi = [wk * bi[0], wk * bi[1], wk * bi[2]];
                    }
                });
        }
        for _ in 1..self.sweeps {
            jacobi_sweep(a, w, b, x, out);
        }
        // Restrict the residual, solve the coarse problem.
        let (next, rest) = deeper
            .split_first_mut()
            .expect("one scratch per level below the finest");
        restrict_residual(a, &lev.p, b, x, &mut next.b, &mut next.lanes);
        // coarse[l] is the matrix of level l + 1.
        let ac = &self.coarse[l];
        self.cycle(ac, l + 1, &next.b, &mut next.out, &mut next.x, rest, false);
        if l + 1 < self.levels.len() {
            // More cycles on the coarse level: out += V(b − A out).
            for _ in 1..self.coarse_cycles {
                ac.residual(&next.b, &next.out, &mut next.r);
                self.cycle(ac, l + 1, &next.r, &mut next.d, &mut next.x, rest, false);
                axpy(1.0, &next.d, &mut next.out);
            }
        }
        // Prolongate and correct; post-smoothing, the last sweep written straight to `out`.
        spmv_csr_add(&lev.p, &next.out, x);
        for _ in 1..self.sweeps {
            jacobi_sweep(a, w, b, x, out);
        }
        jacobi_sweep_into(a, w, b, x, out)
    }
}

impl<T: Entry> Amg<'_, T> {
    /// One application, r · z returned; `prescaled`: `work` already holds the finest level's
    /// first pass W r (ignored with a single level, which has no such pass).
    fn apply_cycle(&self, r: &[V3], z: &mut [V3], work: &mut [V3], prescaled: bool) -> f64 {
        if self.levels.is_empty() {
            // A single level: the dense factorisation is the preconditioner.
            self.chol.solve(r, z);
            return super::vecops::dot(r, z);
        }
        let mut guard = self.scratch.lock().unwrap_or_else(|e| e.into_inner());
        self.cycle(&*self.fine, 0, r, z, work, &mut guard, prescaled)
    }
}

impl<T: Entry> Preconditioner for Amg<'_, T> {
    fn apply(&self, r: &[V3], z: &mut [V3]) {
        let mut own = Vec::new();
        if !self.levels.is_empty() {
            own = vec![[0.0; 3]; r.len()];
        }
        self.apply_with(r, z, &mut own);
    }
    /// The finest level's iterate is kept in `work` (no fine-level vector of its own).
    fn apply_with(&self, r: &[V3], z: &mut [V3], work: &mut [V3]) {
        self.apply_dot(r, z, work);
    }
    /// r · z from the last smoothing sweep.
    fn apply_dot(&self, r: &[V3], z: &mut [V3], work: &mut [V3]) -> f64 {
        self.apply_cycle(r, z, work, false)
    }
    /// The finest level's first smoothing pass, x = W r with W = ω D⁻¹.
    fn first_pass(&self) -> Option<Weights<'_>> {
        self.levels.first().map(|lev| Weights {
            omega: lev.omega,
            diag: &self.fine.diag,
        })
    }
    fn apply_dot_prescaled(&self, r: &[V3], z: &mut [V3], work: &mut [V3]) -> f64 {
        self.apply_cycle(r, z, work, true)
    }
    fn name(&self) -> &'static str {
        "amg"
    }
    fn bytes(&self) -> usize {
        let mut b = 0;
        for (l, lev) in self.levels.iter().enumerate() {
            b += lev.p.bytes();
            if l > 0 {
                b += self.coarse[l - 1].bytes();
            }
        }
        b + self.coarse.last().map_or(0, |c| c.bytes()) + self.chol.l.len() * 8
    }
}

/// One coarsening step of the set-up (level `depth` → `depth + 1`): aggregation, smoothed
/// prolongator, restriction and Galerkin product. `None` when the coarsening stalls.
fn coarsen<T: Entry>(
    cur: &SymMatrix<T>,
    opts: &AmgOptions,
    depth: usize,
) -> Option<(Level, SymMatrix)> {
    // The threshold halves on each coarser level (coarse operators have more, weaker
    // connections per row).
    let theta = opts.strength * 0.5f64.powi(depth as i32);
    let trace = std::env::var_os("DEFORM_AMG_TRACE").is_some();
    let t0 = std::time::Instant::now();
    let (agg, nagg) = aggregate(cur, theta);
    let t_agg = t0.elapsed().as_secs_f64();
    if nagg == 0 || nagg * 10 > cur.n() * 9 {
        // Coarsening stalled: stop here.
        return None;
    }
    let rho = gershgorin(cur);
    let omega = opts.smoother_damping / rho;
    // The prolongator is stored in single precision; the coarse matrix is the Galerkin
    // product of the rounded P, so the cycle stays a symmetric positive definite
    // preconditioner (every vector stays f64).
    let p = smoothed_prolongator(cur, &agg, nagg, opts.prolongator_damping / rho);
    let t_p = t0.elapsed().as_secs_f64();
    let r = p.transpose();
    let t_r = t0.elapsed().as_secs_f64();
    let ac = galerkin(cur, &p, &r);
    if trace {
        eprintln!(
            "amg level {depth}: n {} -> {nagg}, nnz(P) {}, nnz(A_c) {}, aggregate {t_agg:.3} s, P {:.3} s, Pt {:.3} s, RAP {:.3} s",
            cur.n(),
            p.entries.len(),
            ac.cols.len(),
            t_p - t_agg,
            t_r - t_p,
            t0.elapsed().as_secs_f64() - t_r
        );
    }
    let level = Level { p, omega };
    Some((level, ac))
}

/// x ← x + W (b − A x); `r` is scratch.
fn jacobi_sweep<M: Entry>(a: &SymMatrix<M>, w: Weights, b: &[V3], x: &mut [V3], r: &mut [V3]) {
    a.residual(b, x, r);
    x.par_chunks_mut(CHUNK)
        .zip(r.par_chunks(CHUNK))
        .enumerate()
        .for_each(|(c, (xs, rs))| {
            let r0 = c * CHUNK;
            for (k, (xi, ri)) in xs.iter_mut().zip(rs).enumerate() {
                let wk = w.at(r0 + k);
                for d in 0..3 {
                    xi[d] += wk * ri[d];
                }
            }
        });
}

/// out ← x + W (b − A x) (one Jacobi sweep written to another vector; the same arithmetic
/// as [`jacobi_sweep`], row by row); returns b · out (the chunked sums of
/// [`super::vecops::dot`], bit for bit).
fn jacobi_sweep_into<M: Entry>(
    a: &SymMatrix<M>,
    w: Weights,
    b: &[V3],
    x: &[V3],
    out: &mut [V3],
) -> f64 {
    chunked_sum(out, |r0, os| {
        let mut s = 0.0;
        a.rows_mul(
            r0,
            r0 + os.len(),
            x,
            #[inline(always)]
            |i, v| {
                let bi = b[i];
                let ri = [bi[0] - v[0], bi[1] - v[1], bi[2] - v[2]];
                let wk = w.at(i);
                let xi = x[i];
                let o = [xi[0] + wk * ri[0], xi[1] + wk * ri[1], xi[2] + wk * ri[2]];
                s += bi[0] * o[0] + bi[1] * o[1] + bi[2] * o[2];
                os[i - r0] = o;
            },
        );
        s
    })
}

/// A multigrid transfer operator in CSR form (the prolongator P; in the set-up, also its
/// transpose R = Pᵀ), each entry its column and its single-precision value side by side:
/// half the memory and traffic of f64 values, one stream to read, and a row of P (~4 entries
/// on the finest level) in one cache line, which matters when the Galerkin product gathers
/// the rows of a node's neighbours. Products are formed in f64. The restriction uses P too,
/// by rows ([`restrict_residual`]).
struct Transfer {
    ncols: usize,
    offsets: Vec<usize>,
    entries: Vec<(u32, f32)>,
}

impl Transfer {
    fn nrows(&self) -> usize {
        self.offsets.len() - 1
    }

    /// The entries of row `i`.
    #[inline]
    fn row(&self, i: usize) -> &[(u32, f32)] {
        &self.entries[self.offsets[i]..self.offsets[i + 1]]
    }

    fn bytes(&self) -> usize {
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
    fn transpose(&self) -> Self {
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
const LANES: usize = 4;

/// y ← Pᵀ (b − A x), without storing the residual nor Pᵀ: the fine rows are cut into
/// [`LANES`] fixed ranges (whole chunks of [`CHUNK`] rows); each range computes its residual
/// rows in order and adds P's row i times r_i into its own dense coarse vector of `lanes`;
/// y is the sum of the lanes in lane order. Every coarse entry sums its terms in a fixed
/// order, so the result does not depend on the thread count. The residual streams through
/// the fine rows once and P is read in its storage order (the gathers of a stored
/// restriction, whose rows reach across the aggregates' fine rows, were the slow part).
fn restrict_residual<M: Entry>(
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
fn spmv_csr_add(m: &Transfer, x: &[V3], y: &mut [V3]) {
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

/// Gershgorin bound of ρ(D⁻¹A).
fn gershgorin<T: Entry>(a: &SymMatrix<T>) -> f64 {
    (0..a.n())
        .into_par_iter()
        .with_min_len(CHUNK)
        .map(|i| {
            let s: f64 = a.vals[a.offsets[i]..a.offsets[i + 1]]
                .iter()
                .map(|v| v.get().abs())
                .sum();
            1.0 + s / a.diag[i]
        })
        .reduce(|| 0.0, f64::max)
}

/// Greedy aggregation; returns the aggregate of every node and the aggregate count.
fn aggregate<T: Entry>(a: &SymMatrix<T>, theta: f64) -> (Vec<u32>, usize) {
    const NONE: u32 = u32::MAX;
    let n = a.n();
    let strong = |i: usize, p: usize| {
        let j = a.cols[p] as usize;
        a.vals[p].get().abs() >= theta * (a.diag[i] * a.diag[j]).abs().sqrt()
    };
    let mut agg = vec![NONE; n];
    let mut nagg = 0u32;
    // Pass 1: roots whose strong neighbourhood is entirely unaggregated.
    for i in 0..n {
        if agg[i] != NONE {
            continue;
        }
        let mut any_strong = false;
        let mut free = true;
        for p in a.offsets[i]..a.offsets[i + 1] {
            if strong(i, p) {
                any_strong = true;
                if agg[a.cols[p] as usize] != NONE {
                    free = false;
                    break;
                }
            }
        }
        if any_strong && free {
            agg[i] = nagg;
            for p in a.offsets[i]..a.offsets[i + 1] {
                if strong(i, p) {
                    agg[a.cols[p] as usize] = nagg;
                }
            }
            nagg += 1;
        }
    }
    // Pass 2: attach to the strongest neighbouring pass-1 aggregate.
    let snapshot = agg.clone();
    for i in 0..n {
        if agg[i] != NONE {
            continue;
        }
        let mut best = (0.0, NONE);
        for p in a.offsets[i]..a.offsets[i + 1] {
            let g = snapshot[a.cols[p] as usize];
            if g != NONE && strong(i, p) && a.vals[p].get().abs() > best.0 {
                best = (a.vals[p].get().abs(), g);
            }
        }
        agg[i] = best.1;
    }
    // Pass 3: leftovers form aggregates with their unaggregated strong neighbours.
    for i in 0..n {
        if agg[i] != NONE {
            continue;
        }
        agg[i] = nagg;
        for p in a.offsets[i]..a.offsets[i + 1] {
            let j = a.cols[p] as usize;
            if agg[j] == NONE && strong(i, p) {
                agg[j] = nagg;
            }
        }
        nagg += 1;
    }
    (agg, nagg as usize)
}

/// P = (I − ω D⁻¹ A) P₀, P₀ the aggregate indicator.
///
/// A row of P has a few distinct aggregates (~4 on the finest level): each contribution is
/// added to its aggregate's entry found by a linear search, in the row's order — the sums of
/// a stable sort by column followed by merging (`merge_row`), bit for bit — and only the
/// distinct entries are sorted.
///
/// The values are rounded to single precision as they are stored ([`build_rows`]).
fn smoothed_prolongator<T: Entry>(
    a: &SymMatrix<T>,
    agg: &[u32],
    nagg: usize,
    omega: f64,
) -> Transfer {
    let (offsets, entries) = build_rows(
        a.n(),
        |i, buf| {
            let mut add = |c: u32, v: f64| match buf.iter_mut().find(|e| e.0 == c) {
                Some(e) => e.1 += v,
                None => buf.push((c, v)),
            };
            add(agg[i], 1.0 - omega);
            let s = omega / a.diag[i];
            for p in a.offsets[i]..a.offsets[i + 1] {
                add(agg[a.cols[p] as usize], -s * a.vals[p].get());
            }
            buf.sort_unstable_by_key(|e| e.0);
        },
        |(c, v)| (c, v as f32),
    );
    Transfer {
        ncols: nagg,
        offsets,
        entries,
    }
}

/// Dense accumulator for sparse row products (per task scratch). An entry belongs to the
/// current row when its mark equals the row's stamp, so starting a row costs nothing: no
/// flag is cleared entry by entry.
struct Acc {
    val: Vec<f64>,
    mark: Vec<u32>,
    stamp: u32,
    list: Vec<u32>,
}

impl Acc {
    fn new(n: usize) -> Self {
        Self {
            val: vec![0.0; n],
            mark: vec![u32::MAX; n],
            stamp: 0,
            list: Vec::new(),
        }
    }
    #[inline]
    fn add(&mut self, c: u32, v: f64) {
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
    fn drain(&mut self, out_c: &mut Vec<u32>, out_v: &mut Vec<f64>, sorted: bool) -> usize {
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
fn galerkin<T: Entry>(a: &SymMatrix<T>, p: &Transfer, r: &Transfer) -> SymMatrix {
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

/// Dense Cholesky factor of the coarsest matrix (row-major lower triangle).
struct DenseCholesky {
    n: usize,
    l: Vec<f64>,
}

impl DenseCholesky {
    fn new<T: Entry>(a: &SymMatrix<T>, level: usize) -> Result<Self> {
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

    fn solve(&self, b: &[V3], x: &mut [V3]) {
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

#[cfg(test)]
mod tests {
    use super::super::csr::Csr;
    use super::*;

    #[test]
    fn accumulator_restarts_its_stamps_when_they_run_out() {
        // Rows across the wrap of the stamp; row k adds to column k, new in that row (the
        // untouched marks hold u32::MAX, the stamp the counter would reach next).
        let mut acc = Acc::new(4);
        acc.stamp = u32::MAX - 2;
        let (mut c, mut v) = (Vec::new(), Vec::new());
        for k in 0..4u32 {
            acc.add(k, 1.0);
            acc.add(k, 0.5);
            assert_eq!(acc.drain(&mut c, &mut v, true), 1, "row {k}");
        }
        assert_eq!(c, [0, 1, 2, 3]);
        assert_eq!(v, [1.5; 4]);
    }

    #[test]
    fn transpose_equals_the_dense_transpose_for_any_thread_count() {
        // 3001 × 40 with rows of 0 to 4 entries (a prolongator's shape), an empty column,
        // and columns whose rows span the whole matrix: every column range of the parallel
        // fill is exercised, with row ranges of every kind.
        let (nr, nc) = (3001, 40);
        let (offsets, entries) = build_rows(
            nr,
            |i, row| {
                let near = (i * nc / nr) as u32;
                for c in [near, near + 1, (i % 7) as u32 * 5 + 3, 39] {
                    if c != 4 && (c as usize) < nc && i % 5 != 0 && !row.iter().any(|e| e.0 == c) {
                        row.push((c, (i as f64 + 0.25) * (c as f64 + 1.0)));
                    }
                }
                row.sort_unstable_by_key(|e| e.0);
            },
            |(c, v)| (c, v as f32),
        );
        let m = Transfer {
            ncols: nc,
            offsets,
            entries,
        };
        let t1 = testkit::with_threads(1, || m.transpose());
        let t3 = testkit::with_threads(3, || m.transpose());
        assert_eq!(
            (t1.offsets.clone(), t1.entries.clone()),
            (t3.offsets, t3.entries)
        );
        assert_eq!((t1.nrows(), t1.ncols), (nc, nr));
        let mut dense = vec![vec![0.0f32; nr]; nc];
        for i in 0..nr {
            for &(c, v) in m.row(i) {
                dense[c as usize][i] = v;
            }
        }
        for (c, want) in dense.iter().enumerate() {
            let row = t1.row(c);
            assert!(
                row.windows(2).all(|w| w[0].0 < w[1].0),
                "column {c} in row order"
            );
            let mut got = vec![0.0f32; nr];
            for &(i, v) in row {
                got[i as usize] = v;
            }
            assert_eq!(&got, want, "column {c}");
        }
        assert!(t1.row(4).is_empty());
        let back = t1.transpose();
        assert_eq!((back.offsets, back.entries), (m.offsets, m.entries));
    }

    #[test]
    fn galerkin_product_equals_a_sparse_map_product() {
        use std::collections::BTreeMap;
        // 210 unknowns, and 4896 (A P in two blocks of rows).
        for (nx, ny, nz) in [(9, 8, 7), (20, 19, 18)] {
            let (a, _) = crate::solve::tests::grid_system(nx, ny, nz);
            let (agg, nagg) = aggregate(&a, 0.0);
            let p = smoothed_prolongator(&a, &agg, nagg, 1.6 / gershgorin(&a));
            let ac = galerkin(&a, &p, &p.transpose());
            ac.validate(1e-12).unwrap();
            // Pᵀ (A P) summed entry by entry in ordered maps.
            let n = a.n();
            assert_eq!(n, (nx - 2) * (ny - 2) * (nz - 2));
            let ap: Vec<BTreeMap<u32, f64>> = (0..n)
                .map(|i| {
                    let mut row = BTreeMap::new();
                    let (cols, vals) = a.row(i);
                    let terms = std::iter::once((i, a.diag[i]))
                        .chain(cols.iter().zip(vals).map(|(&k, &v)| (k as usize, v)));
                    for (k, v) in terms {
                        for &(c, w) in p.row(k) {
                            *row.entry(c).or_insert(0.0) += v * f64::from(w);
                        }
                    }
                    row
                })
                .collect();
            let mut want = vec![BTreeMap::<u32, f64>::new(); nagg];
            for (i, row) in ap.iter().enumerate() {
                for &(c, w) in p.row(i) {
                    for (&e, &v) in row {
                        *want[c as usize].entry(e).or_insert(0.0) += f64::from(w) * v;
                    }
                }
            }
            let scale = ac.diag.iter().fold(0.0f64, |m, d| m.max(d.abs()));
            for (c, row) in want.iter().enumerate() {
                let (cols, _) = ac.row(c);
                // Rows sorted by column, as in every matrix of the hierarchy.
                assert!(cols.windows(2).all(|w| w[0] < w[1]), "row {c}");
                assert_eq!(cols.len() + 1, row.len(), "row {c}: its pattern");
                for (&e, &v) in row {
                    let got = ac.get(c, e as usize);
                    assert!((got - v).abs() <= 1e-12 * scale, "({c}, {e}): {got} vs {v}");
                }
            }
        }
    }

    #[test]
    fn prolongator_rows_equal_sorted_merge_bit_for_bit() {
        // 4896 unknowns (two blocks of rows), and 140.
        for (a, _) in [
            crate::solve::tests::grid_system(20, 19, 18),
            crate::solve::tests::grid_system(7, 9, 6),
        ] {
            let (agg, nagg) = aggregate(&a, 0.0);
            let omega = 4.0 / (3.0 * gershgorin(&a));
            let p = smoothed_prolongator(&a, &agg, nagg, omega);
            let reference = Csr::from_rows(a.n(), nagg, |i, buf| {
                buf.push((agg[i], 1.0 - omega));
                let s = omega / a.diag[i];
                for q in a.offsets[i]..a.offsets[i + 1] {
                    buf.push((agg[a.cols[q] as usize], -s * a.vals[q]));
                }
                super::super::csr::merge_row(buf);
            });
            assert_eq!(p.offsets, reference.offsets);
            // The merged sums, rounded to single precision.
            let rounded: Vec<(u32, f32)> = (reference.cols.iter().zip(&reference.vals))
                .map(|(&c, &v)| (c, v as f32))
                .collect();
            assert_eq!(p.entries.len(), rounded.len());
            assert!(
                p.entries
                    .iter()
                    .zip(&rounded)
                    .all(|(x, y)| x.0 == y.0 && x.1.to_bits() == y.1.to_bits())
            );
        }
    }
}
