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

//!
//! Files: this one holds the options, the hierarchy, the cycle and its smoother;
//! `coarsen` one coarsening step (aggregation, prolongator); `transfer` the transfer
//! operators and the restriction; `galerkin` the coarse matrix Pᵀ A P; `dense` the
//! coarsest level's factorisation. It stays in `deform`, on `sparse`'s types, because it
//! pays: see docs/crates/deform.md, "Multigrid".

mod coarsen;
mod dense;
mod galerkin;
mod transfer;

#[cfg(test)]
mod held_tests;
#[cfg(test)]
mod tests;

use std::sync::Mutex;

use rayon::prelude::*;
use serde::Serialize;
use sparse::vec3::{CHUNK, V3, axpy, chunked_sum};
use sparse::{Entry, Preconditioner, SymMatrix, Weights};

use crate::error::{Error, Result};
use coarsen::coarsen;
use dense::DenseCholesky;
use transfer::{LANES, Transfer, restrict_residual, spmv_csr_add};

/// Multigrid setup options.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AmgOptions {
    /// Strength threshold θ on the finest level, halved on each coarser level (0 keeps every
    /// connection: aggregates of ~20 nodes, cheapest setup; measured faster overall than 0.08
    /// on the benchmark grids: docs/crates/deform.md, "Multigrid strength threshold").
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
    /// wing-in-box grids (22 → 17 at 309k nodes, 27 → 18 at 1M; docs/crates/deform.md,
    /// "W-cycle").
    pub coarse_cycles: usize,
    /// c_S: the Jacobi smoother's damping is ω = c_S / ρ, ρ the Gershgorin bound of
    /// λ_max(D⁻¹A). Must lie in (0, 2): then ω λ_max ≤ c_S < 2 and the cycle is symmetric
    /// positive definite whatever the true λ_max. Default 1.8: ρ overestimates λ_max on tet
    /// grids (ρ ≈ 2 for a spring Laplacian), so the classical 4/3 under-damps; 1.8 took the
    /// PCG iterations from 17 to 13 at 309k nodes and from 18 to 13 at 1M
    /// (docs/crates/deform.md, "Multigrid damping").
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
    /// What building the next coarser level took.
    setup: LevelSetup,
    /// The rows of this level held in some component, and those components (bit c): empty
    /// unless the hierarchy was built with [`Amg::new_held`].
    held: Vec<(u32, u8)>,
}

/// What one coarsening step of the set-up took (see [`AmgInfo::setup`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LevelSetup {
    /// Stored entries of the prolongator P.
    pub prolongator_entries: usize,
    /// Seconds of the aggregation.
    pub aggregate: f64,
    /// Seconds building the smoothed prolongator P.
    pub prolongator: f64,
    /// Seconds forming R = Pᵀ.
    pub transpose: f64,
    /// Seconds of the Galerkin product Pᵀ A P.
    pub galerkin: f64,
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
    /// The coarsest level's held rows and factorisations ([`Amg::new_held`]; None when
    /// nothing is held there).
    coarsest_held: Option<Box<CoarsestHeld>>,
    sweeps: usize,
    coarse_cycles: usize,
    scratch: Mutex<Vec<Scratch>>,
}

/// The coarsest level's held rows, and per component held there, the factorisation of the
/// coarsest matrix with those rows and columns decoupled.
struct CoarsestHeld {
    rows: Vec<(u32, u8)>,
    chol: [Option<DenseCholesky>; 3],
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
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AmgInfo {
    /// Unknowns per level, finest first.
    pub sizes: Vec<usize>,
    /// Stored off-diagonal entries per level.
    pub nnz: Vec<usize>,
    /// Operator complexity Σ nnz(A_l) / nnz(A_0) (diagonals included).
    pub operator_complexity: f64,
    /// Per coarsening step (level l → l + 1), what its set-up took.
    pub setup: Vec<LevelSetup>,
}

impl<'a, T: Entry> Amg<'a, T> {
    /// Builds the hierarchy for `a` (symmetric positive definite, positive diagonal).
    pub fn new(a: &'a SymMatrix<T>, opts: &AmgOptions) -> Result<Self> {
        Self::build(std::borrow::Cow::Borrowed(a), opts, None)
    }

    /// [`Amg::new`] taking the fine matrix by value (the hierarchy can then be stored and
    /// reused, e.g. by [`crate::Deformer`]).
    pub fn new_owned(a: SymMatrix<T>, opts: &AmgOptions) -> Result<Amg<'static, T>> {
        Amg::build(std::borrow::Cow::Owned(a), opts, None)
    }

    /// The hierarchy of the constrained system: the fine matrix `a` with component c of
    /// node i held at zero where bit c of `mask[i]` is set (a node sliding on the plane
    /// y = 0 is held in y). Aggregates and prolongator rows never mix nodes of different
    /// masks, so on every level the held components live on their own aggregates; the
    /// cycle keeps them zero (its Galerkin coarse problems are those of the constrained
    /// system, for each component) and gives them Jacobi's D⁻¹ r on the finest level, so
    /// that it stays positive definite whatever the constraints' directions. An all-zero
    /// mask gives [`Amg::new_owned`]'s hierarchy, bit for bit. See
    /// docs/crates/deform.md, "The constrained multigrid".
    pub fn new_held(a: SymMatrix<T>, opts: &AmgOptions, mask: &[u8]) -> Result<Amg<'static, T>> {
        let mask = if mask.iter().any(|&m| m != 0) {
            Some(mask)
        } else {
            None
        };
        Amg::build(std::borrow::Cow::Owned(a), opts, mask)
    }

    /// The fine matrix A_0.
    pub fn fine(&self) -> &SymMatrix<T> {
        &self.fine
    }

    fn build(
        fine: std::borrow::Cow<'a, SymMatrix<T>>,
        opts: &AmgOptions,
        mask: Option<&[u8]>,
    ) -> Result<Self> {
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
        let mut masks: Vec<Vec<u8>> = mask.map(|m| vec![m.to_vec()]).unwrap_or_default();
        loop {
            let n = coarse.last().map_or(a.n(), |c| c.n());
            if n <= opts.max_coarse || levels.len() + 1 >= opts.max_levels {
                break;
            }
            let m = masks.last().map(Vec::as_slice);
            let step = match coarse.last() {
                None => coarsen(a, opts, levels.len(), m),
                Some(c) => coarsen(c, opts, levels.len(), m),
            };
            let Some((level, ac, mc)) = step else {
                break;
            };
            levels.push(level);
            coarse.push(ac);
            masks.extend(mc);
        }
        let chol = match coarse.last() {
            Some(c) => DenseCholesky::new(c, levels.len())?,
            None => DenseCholesky::new(a, 0)?,
        };
        let rows = coarsen::held_rows(masks.last().map(Vec::as_slice));
        let mut chol_held = [None, None, None];
        for (c, slot) in chol_held.iter_mut().enumerate() {
            let bit = 1u8 << c;
            if rows.iter().any(|h| h.1 & bit != 0) {
                let m = masks.last().map_or(&[][..], Vec::as_slice);
                let decoupled = match coarse.last() {
                    Some(ac) => decouple(ac, m, bit),
                    None => decouple(a, m, bit),
                };
                *slot = Some(DenseCholesky::new(&decoupled, levels.len())?);
            }
        }
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
            coarsest_held: (!rows.is_empty()).then(|| {
                Box::new(CoarsestHeld {
                    rows,
                    chol: chol_held,
                })
            }),
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
            setup: self.levels.iter().map(|l| l.setup).collect(),
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
            self.coarsest(b, out);
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
        // Held components stay zero (a no-op without held rows).
        zero_held(&lev.held, x);
        for _ in 1..self.sweeps {
            jacobi_sweep(a, w, b, x, out);
            zero_held(&lev.held, x);
        }
        // Restrict the residual, solve the coarse problem.
        let (next, rest) = deeper
            .split_first_mut()
            .expect("one scratch per level below the finest");
        restrict_residual(a, &lev.p, b, x, &mut next.b, &mut next.lanes);
        let next_held = match self.levels.get(l + 1) {
            Some(v) => &v.held[..],
            None => self.coarsest_held.as_ref().map_or(&[][..], |h| &h.rows[..]),
        };
        zero_held(next_held, &mut next.b);
        // coarse[l] is the matrix of level l + 1.
        let ac = &self.coarse[l];
        self.cycle(ac, l + 1, &next.b, &mut next.out, &mut next.x, rest, false);
        if l + 1 < self.levels.len() {
            // More cycles on the coarse level: out += V(b − A out).
            for _ in 1..self.coarse_cycles {
                ac.residual(&next.b, &next.out, &mut next.r);
                zero_held(next_held, &mut next.r);
                self.cycle(ac, l + 1, &next.r, &mut next.d, &mut next.x, rest, false);
                axpy(1.0, &next.d, &mut next.out);
            }
        }
        // Prolongate and correct (P keeps the held components zero); post-smoothing, the
        // last sweep written straight to `out`.
        spmv_csr_add(&lev.p, &next.out, x);
        for _ in 1..self.sweeps {
            jacobi_sweep(a, w, b, x, out);
            zero_held(&lev.held, x);
        }
        let mut s = jacobi_sweep_into(a, w, b, x, out);
        if !lev.held.is_empty() {
            // Held entries: 0 on coarse levels (their b is zero there); D⁻¹ b on the finest,
            // where b need not vanish in the held components (a plane not along an axis).
            for &(i, bits) in &lev.held {
                let i = i as usize;
                for c in 0..3 {
                    if (bits >> c) & 1 == 1 {
                        let v = if l == 0 { b[i][c] / a.diag[i] } else { 0.0 };
                        s += b[i][c] * (v - out[i][c]);
                        out[i][c] = v;
                    }
                }
            }
        }
        s
    }

    /// The coarsest level's solve: the factorisation of the coarsest matrix, and per held
    /// component that of the matrix with the held rows decoupled.
    fn coarsest(&self, b: &[V3], out: &mut [V3]) {
        self.chol.solve(b, out);
        let Some(held) = &self.coarsest_held else {
            return;
        };
        let mut t = vec![[0.0; 3]; b.len()];
        for (c, f) in held.chol.iter().enumerate() {
            if let Some(f) = f {
                f.solve(b, &mut t);
                for (o, v) in out.iter_mut().zip(&t) {
                    o[c] = v[c];
                }
            }
        }
        zero_held(&held.rows, out);
    }
}

impl<T: Entry> Amg<'_, T> {
    /// One application, r · z returned; `prescaled`: `work` already holds the finest level's
    /// first pass W r (ignored with a single level, which has no such pass).
    fn apply_cycle(&self, r: &[V3], z: &mut [V3], work: &mut [V3], prescaled: bool) -> f64 {
        if self.levels.is_empty() {
            // A single level: the dense factorisation is the preconditioner.
            self.coarsest(r, z);
            return sparse::vec3::dot(r, z);
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

/// Sets the held components of the held rows to zero.
fn zero_held(held: &[(u32, u8)], x: &mut [V3]) {
    for &(i, bits) in held {
        for c in 0..3 {
            if (bits >> c) & 1 == 1 {
                x[i as usize][c] = 0.0;
            }
        }
    }
}

/// `a` with the couplings of the rows held in component `bit` removed (diagonal kept).
fn decouple<M: Entry>(a: &SymMatrix<M>, mask: &[u8], bit: u8) -> SymMatrix {
    let held = |i: usize| mask.get(i).is_some_and(|m| m & bit != 0);
    let mut offsets = vec![0];
    let (mut cols, mut vals) = (Vec::new(), Vec::new());
    for i in 0..a.n() {
        let (c, v) = a.row(i);
        if !held(i) {
            for (&j, x) in c.iter().zip(v) {
                if !held(j as usize) {
                    cols.push(j);
                    vals.push(x.get());
                }
            }
        }
        offsets.push(cols.len());
    }
    SymMatrix {
        diag: a.diag.clone(),
        offsets,
        cols,
        vals,
    }
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
/// [`sparse::vec3::dot`], bit for bit).
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
