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

use super::csr::{Csr, Entry, SymMatrix};
use super::pcg::{Preconditioner, Weights};
use super::vecops::{CHUNK, V3, axpy, chunked_sum};
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
    let mut p = smoothed_prolongator(cur, &agg, nagg, opts.prolongator_damping / rho);
    // The prolongator is stored in single precision; the coarse matrix is the Galerkin
    // product of the rounded P, so the cycle stays a symmetric positive definite
    // preconditioner (every vector stays f64).
    for v in &mut p.vals {
        *v = f64::from(*v as f32);
    }
    let t_p = t0.elapsed().as_secs_f64();
    let r = p.transpose();
    let t_r = t0.elapsed().as_secs_f64();
    let ac = galerkin(cur, &p, &r);
    if trace {
        eprintln!(
            "amg level {depth}: n {} -> {nagg}, nnz(P) {}, nnz(A_c) {}, aggregate {t_agg:.3} s, P {:.3} s, Pt {:.3} s, RAP {:.3} s",
            cur.n(),
            p.cols.len(),
            ac.cols.len(),
            t_p - t_agg,
            t_r - t_p,
            t0.elapsed().as_secs_f64() - t_r
        );
    }
    let level = Level {
        p: Transfer::from(p),
        omega,
    };
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

/// A multigrid prolongator P in CSR form with single-precision values (half the memory and
/// traffic of f64; products are formed in f64). The restriction uses it too, by rows
/// ([`restrict_residual`]).
struct Transfer {
    offsets: Vec<usize>,
    cols: Vec<u32>,
    vals: Vec<f32>,
}

impl From<Csr> for Transfer {
    fn from(m: Csr) -> Self {
        Self {
            vals: m.vals.iter().map(|&v| v as f32).collect(),
            offsets: m.offsets,
            cols: m.cols,
        }
    }
}

impl Transfer {
    fn bytes(&self) -> usize {
        self.offsets.len() * 8 + self.cols.len() * 4 + self.vals.len() * 4
    }
}

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
                let span = p.offsets[i]..p.offsets[i + 1];
                for (&col, &w) in p.cols[span.clone()].iter().zip(&p.vals[span]) {
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
            let i = r0 + k;
            let span = m.offsets[i]..m.offsets[i + 1];
            for (&col, &v) in m.cols[span.clone()].iter().zip(&m.vals[span]) {
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
fn smoothed_prolongator<T: Entry>(a: &SymMatrix<T>, agg: &[u32], nagg: usize, omega: f64) -> Csr {
    Csr::from_rows(a.n(), nagg, |i, buf| {
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
    })
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

/// The scratch of one Galerkin task: the accumulator, the local index of the fine rows of
/// A P the block needs (`u32::MAX` elsewhere), their list, and the block's rows of A P.
/// Kept in a pool and reused from block to block: fresh buffers of this size cost more in
/// page faults than the products written into them.
struct GalerkinScratch {
    acc: Acc,
    loc: Vec<u32>,
    need: Vec<u32>,
    ap_off: Vec<usize>,
    ap_c: Vec<u32>,
    ap_v: Vec<f64>,
}

/// Coarse rows per task of the Galerkin product.
const GALERKIN_ROWS: usize = 4096;

/// A_c = R A P with R = Pᵀ, returned with its diagonal apart.
///
/// Row-parallel over blocks of [`GALERKIN_ROWS`] coarse rows; each block first computes the
/// rows of A P it needs (the fine rows in its rows of R), then its rows of R (A P), both with
/// a dense accumulator (the rows of A P are left unsorted: only the rows of A_c need their
/// columns in order). A P is never held whole (it has ~2× the entries of A: the largest
/// temporary of the set-up otherwise); the fine rows shared by neighbouring blocks are
/// computed once per block. Every row is computed by one task in a fixed order, so the
/// result does not depend on the thread count (nor on the block size, nor on which pooled
/// scratch a block gets).
fn galerkin<T: Entry>(a: &SymMatrix<T>, p: &Csr, r: &Csr) -> SymMatrix {
    let nc = p.ncols;
    let n = a.n();
    let ap_row = |i: usize, acc: &mut Acc| {
        let d = a.diag[i];
        for q in p.offsets[i]..p.offsets[i + 1] {
            acc.add(p.cols[q], d * p.vals[q]);
        }
        for k in a.offsets[i]..a.offsets[i + 1] {
            let j = a.cols[k] as usize;
            let v = a.vals[k].get();
            for q in p.offsets[j]..p.offsets[j + 1] {
                acc.add(p.cols[q], v * p.vals[q]);
            }
        }
    };
    let pool: Mutex<Vec<GalerkinScratch>> = Mutex::new(Vec::new());
    let blocks: Vec<(Vec<usize>, Vec<u32>, Vec<f64>)> = (0..nc.div_ceil(GALERKIN_ROWS))
        .into_par_iter()
        .map(|b| {
            let taken = pool.lock().unwrap_or_else(|e| e.into_inner()).pop();
            let mut st = taken.unwrap_or_else(|| GalerkinScratch {
                acc: Acc::new(nc),
                loc: vec![u32::MAX; n],
                need: Vec::new(),
                ap_off: Vec::new(),
                ap_c: Vec::new(),
                ap_v: Vec::new(),
            });
            let GalerkinScratch {
                acc,
                loc,
                need,
                ap_off,
                ap_c,
                ap_v,
            } = &mut st;
            let lo = b * GALERKIN_ROWS;
            let hi = (lo + GALERKIN_ROWS).min(nc);
            // The fine rows of A P this block needs, and A P on them.
            // Mark them, then collect them in increasing order over the marked range
            // (no sort of the ~100 entries per coarse row).
            const MARK: u32 = u32::MAX - 1;
            let (mut first, mut last) = (usize::MAX, 0);
            for &i in &r.cols[r.offsets[lo]..r.offsets[hi]] {
                loc[i as usize] = MARK;
                first = first.min(i as usize);
                last = last.max(i as usize);
            }
            need.clear();
            if first <= last {
                need.extend((first..=last).filter(|&i| loc[i] == MARK).map(|i| i as u32));
            }
            ap_off.clear();
            ap_c.clear();
            ap_v.clear();
            ap_off.push(0usize);
            for (k, &i) in need.iter().enumerate() {
                loc[i as usize] = k as u32;
                ap_row(i as usize, acc);
                acc.drain(ap_c, ap_v, false);
                ap_off.push(ap_c.len());
            }
            // Rows lo..hi of R (A P).
            let mut lens = Vec::with_capacity(hi - lo);
            let (mut cols, mut vals) = (Vec::new(), Vec::new());
            for i in lo..hi {
                for k in r.offsets[i]..r.offsets[i + 1] {
                    let l = loc[r.cols[k] as usize] as usize;
                    let v = r.vals[k];
                    for q in ap_off[l]..ap_off[l + 1] {
                        acc.add(ap_c[q], v * ap_v[q]);
                    }
                }
                lens.push(acc.drain(&mut cols, &mut vals, true));
            }
            for &i in need.iter() {
                loc[i as usize] = u32::MAX;
            }
            pool.lock().unwrap_or_else(|e| e.into_inner()).push(st);
            (lens, cols, vals)
        })
        .collect();
    let rap = Csr::from_blocks(nc, nc, blocks);
    // Split off the diagonal and symmetrise round-off: a_ij ← (a_ij + a_ji) / 2 is not
    // needed for CG's correctness, the product RAP is symmetric up to round-off only.
    let mut diag = vec![0.0; nc];
    let mut offsets = vec![0usize; nc + 1];
    let mut cols = Vec::with_capacity(rap.cols.len());
    let mut vals = Vec::with_capacity(rap.cols.len());
    for i in 0..nc {
        for q in rap.offsets[i]..rap.offsets[i + 1] {
            let c = rap.cols[q];
            if c as usize == i {
                diag[i] = rap.vals[q];
            } else {
                cols.push(c);
                vals.push(rap.vals[q]);
            }
        }
        offsets[i + 1] = cols.len();
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
    fn galerkin_product_equals_the_dense_product() {
        let (a, _) = crate::solve::tests::grid_system(9, 8, 7);
        let (agg, nagg) = aggregate(&a, 0.0);
        let p = smoothed_prolongator(&a, &agg, nagg, 1.6 / gershgorin(&a));
        let ac = galerkin(&a, &p, &p.transpose());
        ac.validate(1e-12).unwrap();
        // Dense Pᵀ A P.
        let ad = a.to_dense();
        let n = a.n();
        let mut pd = vec![vec![0.0; nagg]; n];
        for (i, row) in pd.iter_mut().enumerate() {
            let (cs, vs) = p.row(i);
            for (&c, &v) in cs.iter().zip(vs) {
                row[c as usize] = v;
            }
        }
        let ap: Vec<Vec<f64>> = (0..n)
            .map(|i| {
                (0..nagg)
                    .map(|c| (0..n).map(|k| ad[i][k] * pd[k][c]).sum())
                    .collect()
            })
            .collect();
        let acd = ac.to_dense();
        let scale = ac.diag.iter().fold(0.0f64, |m, d| m.max(d.abs()));
        for c in 0..nagg {
            for e in 0..nagg {
                let want: f64 = (0..n).map(|i| pd[i][c] * ap[i][e]).sum();
                assert!(
                    (acd[c][e] - want).abs() <= 1e-12 * scale,
                    "({c}, {e}): {} vs {want}",
                    acd[c][e]
                );
            }
        }
        // Rows sorted by column, as in every matrix of the hierarchy.
        for i in 0..nagg {
            assert!(ac.row(i).0.windows(2).all(|w| w[0] < w[1]), "row {i}");
        }
    }

    #[test]
    fn prolongator_rows_equal_sorted_merge_bit_for_bit() {
        for (a, _) in [
            crate::solve::tests::grid_system(12, 11, 10),
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
            assert_eq!(p.cols, reference.cols);
            assert!(
                p.vals
                    .iter()
                    .zip(&reference.vals)
                    .all(|(x, y)| x.to_bits() == y.to_bits())
            );
        }
    }
}
