//! The distributed linear solve of Eqs. 21 and 26: the matrix rows of a rank's owned
//! unknowns ([`DistOperator`], assembled by deform's own `assemble` on the local grid) kept
//! as the owned–owned block (the serial solver's matrix, which the block multigrid holds)
//! and the few ghost columns of the boundary rows; the product A_own x computed by the
//! serial kernel while the ghost unknowns travel, then the ghost columns added; and
//! projected conjugate gradients with all-reduced dot products and the serial solver's
//! fused updates, preconditioned by a block-Jacobi of per-rank multigrid (or Jacobi) with
//! the coarse-grid correction across the ranks.

use std::time::Instant;

use sparse::vec3::{V3, axpy, axpy_xpby, dot};
use sparse::{Constraints, Csr, Jacobi, Preconditioner, SolveReport, SymMatrix};

use super::coarse::{CoarseOp, Correction};
use super::comm::{Comm, agree, max, sum, sum_n};
use super::halo::Halo;
use super::interface::{Interface, Ops, Scratch};
use crate::assembly::{System, assemble, couplings};
use crate::error::Result;
use crate::options::{DeformOptions, SolverKind};
use crate::solve::held::held_mask;
use crate::solve::{Amg, AmgOptions};
use crate::stiffness::Springs;

/// The preconditioner of a rank's block.
enum Block {
    /// The serial multigrid; it owns the owned–owned block.
    Amg(Box<Amg<'static, f32>>),
    /// The serial multigrid on the block extended by the ghost unknowns (one layer of
    /// overlap), beside the owned–owned block, and the weight 1/√m of each extended
    /// unknown, m the number of blocks that hold it.
    Overlap(Box<Amg<'static, f32>>, SymMatrix<f32>, Vec<f64>),
    /// The diagonal, with the owned–owned block beside it.
    Jacobi(Jacobi, SymMatrix<f32>),
}

/// What the block extended by the ghost unknowns needs (see [`DistOperator::new`]).
pub(crate) struct Overlap<'a> {
    pub comm: &'a Comm,
    /// The halo of the unknowns.
    pub halo: &'a Halo,
    /// Local node of every local unknown (owned, then ghosts).
    pub unk_node: &'a [u32],
    /// The interface smoother around the blocks ([`super::interface`]).
    pub sweep: bool,
}

/// Eq. 21's matrix on a rank: rows of the owned unknowns, columns of the local unknowns
/// (owned, then ghosts), the couplings to prescribed nodes and the block preconditioner.
pub(crate) struct DistOperator {
    n_own: usize,
    /// The owned–owned block and its preconditioner.
    block: Block,
    /// The ghost columns of the owned rows (column: local unknown ≥ `n_own`).
    ghost: Csr,
    /// The owned rows that have a ghost column.
    ghost_rows: Vec<u32>,
    /// The ranks' blocks overlap: every application exchanges through the halo.
    overlap_halo: bool,
    /// The interface smoother before and after the blocks (with the overlap, when asked
    /// for; on every rank alike, with a band or not).
    interface: Option<Interface>,
    /// The springs from each owned unknown to its prescribed neighbours.
    pub couplings: Csr,
    /// The coarse-grid correction across the ranks (none on one rank).
    pub coarse: Option<CoarseOp>,
    /// The block multigrid is the constrained one on some rank ([`DistOperator::swap`]; the
    /// same on every rank).
    held: bool,
}

/// A block multigrid beside the one in place ([`DistOperator::held`], [`DistOperator::swap`]):
/// the constrained one of Eq. 21 while the free one serves Eq. 26, and the other way round.
pub(crate) struct Held {
    /// The other multigrid (None: this rank's block is the same for both).
    amg: Option<Box<Amg<'static, f32>>>,
    /// The `-held` flag that goes with it (the same on every rank).
    any: bool,
}

/// The vectors of one solve, allocated once.
struct Work {
    /// The preconditioner's scratch (the multigrid's finest iterate).
    work: Vec<V3>,
    /// The residual and the correction on the extended block (overlap; else empty).
    r_ext: Vec<V3>,
    z_ext: Vec<V3>,
    /// The interface smoother's vectors (when there is one).
    sweep: Option<Scratch>,
}

impl DistOperator {
    /// Assembles at the springs `sp` on the local system `sys` (rows: owned unknowns; the
    /// unknown numbering of `sys` covers the ghost unknowns too).
    ///
    /// With `overlap` (multigrid only; collective), the block preconditioner is the
    /// weighted symmetric additive Schwarz one of one layer of overlap,
    /// B = Σ_i R_iᵀ W_i B_i W_i R_i: B_i the multigrid on rank i's owned and ghost unknowns,
    /// whose ghost rows hold their springs to the rank's local unknowns and their owners'
    /// diagonals (the ghosts' neighbours beyond the layer held at zero), R_i the restriction
    /// to them (the ghosts' values brought by the halo), R_iᵀ the ghosts' corrections added
    /// to their owners', W_i the weights 1/√m of the unknowns held by m blocks (Σ_i R_iᵀ
    /// W_i² R_i = I). Without the weights the unknowns at a junction of several ranks were
    /// over-corrected: at 98k nodes, -n 4 took 46 iterations against 42 without overlap
    /// and 30 with the weights (docs/perf-log/2026-12-03-mpi-round2.md).
    pub fn new(
        sys: &System,
        adj: &mesh::Adjacency,
        sp: &Springs,
        n_own: usize,
        opts: &DeformOptions,
        overlap: Option<Overlap>,
    ) -> Result<Self> {
        let a = assemble(sys, adj, sp);
        // The extended block is collective: the ranks agree on a failure before it.
        let a = match &overlap {
            Some(o) => agree(o.comm, a)?,
            None => a?,
        };
        let couplings = couplings(sys, adj, sp);
        let n_all = overlap.as_ref().map_or(n_own, |o| o.unk_node.len());
        // The ghost columns (the rows' columns are sorted: owned ones first).
        let ghost = Csr::from_rows(n_own, n_all, |k, row| {
            let (c, v) = a.row(k);
            let at = c.partition_point(|&c| (c as usize) < n_own);
            row.extend(
                c[at..]
                    .iter()
                    .zip(&v[at..])
                    .map(|(&c, &v)| (c, f64::from(v))),
            );
        });
        let ghost_rows: Vec<u32> = (0..n_own)
            .filter(|&k| ghost.offsets[k + 1] > ghost.offsets[k])
            .map(|k| k as u32)
            .collect();
        let overlap_halo = overlap.is_some() && opts.solver == SolverKind::PcgMultigrid;
        let sweep = overlap_halo && overlap.as_ref().is_some_and(|o| o.sweep);
        // The owned–owned block: `a` without its ghost columns.
        let own = (!ghost.cols.is_empty()).then(|| {
            let mut own = SymMatrix {
                diag: a.diag.clone(),
                offsets: Vec::with_capacity(n_own + 1),
                cols: Vec::with_capacity(a.cols.len() - ghost.cols.len()),
                vals: Vec::with_capacity(a.cols.len() - ghost.cols.len()),
            };
            own.offsets.push(0);
            for k in 0..n_own {
                let (c, v) = a.row(k);
                let at = c.partition_point(|&c| (c as usize) < n_own);
                own.cols.extend_from_slice(&c[..at]);
                own.vals.extend_from_slice(&v[..at]);
                own.offsets.push(own.cols.len());
            }
            own
        });
        // The extended block takes over `a`'s rows (no copy of them); collective, so made
        // on a rank without owned unknowns too.
        let (own, ext) = match &overlap {
            Some(o) if opts.solver == SolverKind::PcgMultigrid => {
                let own = own.unwrap_or_else(|| a.clone());
                let ext = extended(o, sys, adj, sp, a);
                (own, Some(ext).filter(|_| n_own > 0))
            }
            _ => (own.unwrap_or(a), None),
        };
        let interface = sweep.then(|| Interface::new(&own, &ghost, &ghost_rows));
        let block = match opts.solver {
            _ if ext.is_some() => {
                let (ext, wt) = ext.expect("the extended block");
                Block::Overlap(
                    Box::new(Amg::new_owned(ext, &AmgOptions::default())?),
                    own,
                    wt,
                )
            }
            SolverKind::PcgMultigrid if n_own > 0 => {
                Block::Amg(Box::new(Amg::new_owned(own, &AmgOptions::default())?))
            }
            _ => Block::Jacobi(Jacobi::new(&own), own),
        };
        Ok(Self {
            n_own,
            block,
            ghost,
            ghost_rows,
            overlap_halo,
            interface,
            couplings,
            coarse: None,
            held: false,
        })
    }

    /// The constrained block multigrid of `cons` ([`Amg::new_held`]: the unknowns' held
    /// components from their constraints, the ghosts' from their owners' through the halo),
    /// made beside the free one, which stays in place; [`DistOperator::swap`] exchanges
    /// them. Collective. A rank without held unknowns in its block keeps its free multigrid
    /// (the same hierarchy); should the set-up fail on a rank, that rank keeps its free
    /// multigrid too (a valid, slower preconditioner of the same system). The solver's name
    /// gets `-held` when some rank holds (docs/mpi.md, "Preconditioner").
    pub fn held(&self, comm: &Comm, halo: &Halo, cons: &Constraints) -> Held {
        let n_all = self.ghost.ncols;
        let mask = held_mask(self.n_own, cons);
        let ext_mask = self.overlap_halo.then(|| {
            let mut v = vec![[0.0f64; 1]; n_all];
            for (vk, &m) in v.iter_mut().zip(&mask) {
                vk[0] = f64::from(m);
            }
            halo.exchange(comm, &mut v);
            v.iter().map(|x| x[0] as u8).collect::<Vec<u8>>()
        });
        let opts = AmgOptions::default();
        let amg = match &self.block {
            // Nothing held on this rank: the free multigrid is the constrained one.
            Block::Amg(_) if mask.iter().all(|&m| m == 0) => None,
            Block::Overlap(..) if ext_mask.as_ref().is_none_or(|k| k.iter().all(|&m| m == 0)) => {
                None
            }
            Block::Amg(m) => Amg::new_held(m.fine().clone(), &opts, &mask).ok(),
            Block::Overlap(m, ..) => {
                let mask = ext_mask.expect("the extended block's mask");
                Amg::new_held(m.fine().clone(), &opts, &mask).ok()
            }
            Block::Jacobi(..) => None,
        };
        let any = max(comm, f64::from(u8::from(amg.is_some()))) > 0.0;
        Held {
            amg: amg.map(Box::new),
            any,
        }
    }

    /// Exchanges the block multigrid in place with the one `h` holds, and the solver's
    /// `-held` flag with `h`'s: after [`DistOperator::held`], once puts the constrained
    /// multigrid in place, twice puts the free one back. Local.
    pub fn swap(&mut self, h: &mut Held) {
        if let Some(a) = h.amg.as_mut() {
            match &mut self.block {
                Block::Amg(m) | Block::Overlap(m, ..) => std::mem::swap(m, a),
                Block::Jacobi(..) => {}
            }
        }
        std::mem::swap(&mut self.held, &mut h.any);
    }

    /// The owned–owned block.
    fn own(&self) -> &SymMatrix<f32> {
        match &self.block {
            Block::Amg(m) => m.fine(),
            Block::Overlap(_, a, _) | Block::Jacobi(_, a) => a,
        }
    }

    /// The diagonal of the owned rows.
    pub fn diag(&self) -> &[f64] {
        &self.own().diag
    }

    /// Calls `f(column, a_kc)` for the off-diagonal entries of owned row `k` (owned
    /// columns in increasing order, then the ghost ones).
    #[inline]
    pub fn row_entries(&self, k: usize, mut f: impl FnMut(usize, f64)) {
        let (c, v) = self.own().row(k);
        for (&c, &v) in c.iter().zip(v) {
            f(c as usize, f64::from(v));
        }
        let (c, v) = self.ghost.row(k);
        for (&c, &v) in c.iter().zip(v) {
            f(c as usize, v);
        }
    }

    /// y = A x on the owned rows, and returns x · y over the owned unknowns (this rank's
    /// part); `x` holds the owned unknowns and receives the ghost ones from their owners
    /// while the owned–owned block's product is computed.
    pub fn mul_dot(&self, comm: &Comm, halo: &Halo, x: &mut [V3], y: &mut [V3]) -> f64 {
        let n = self.n_own;
        let mut xy = 0.0;
        halo.exchange_overlapped(comm, x, |x| xy = self.own().mul_dot(&x[..n], y));
        for &k in &self.ghost_rows {
            let k = k as usize;
            let (c, v) = self.ghost.row(k);
            let mut s = [0.0; 3];
            for (&c, &v) in c.iter().zip(v) {
                let xc = x[c as usize];
                for q in 0..3 {
                    s[q] += v * xc[q];
                }
            }
            for q in 0..3 {
                y[k][q] += s[q];
                xy += x[k][q] * s[q];
            }
        }
        xy
    }

    /// z = B r, B the block preconditioner (collective with overlap).
    fn block(&self, comm: &Comm, halo: &Halo, r: &[V3], z: &mut [V3], w: &mut Work) {
        match &self.block {
            Block::Amg(m) => {
                m.apply_dot(r, z, &mut w.work);
            }
            Block::Overlap(m, _, wt) => {
                w.r_ext[..self.n_own].copy_from_slice(r);
                Self::overlap_block(comm, halo, m, wt, w, z);
            }
            Block::Jacobi(m, _) => {
                m.apply_dot(r, z, &mut w.work);
                if self.overlap_halo {
                    // A rank without owned unknowns in an overlapping preconditioner: its
                    // neighbours exchange with it all the same.
                    let mut v = vec![[0.0; 3]; self.ghost.ncols];
                    halo.exchange(comm, &mut v);
                    halo.accumulate(comm, &mut v);
                }
            }
        }
    }

    /// z = Σ_i R_iᵀ W_i B_i W_i R_i r (see [`DistOperator::new`]), the owned r in
    /// `w.r_ext` (collective). W_i R_i r and the multigrid's first smoothing pass are one
    /// pass over the extended block, W_i's product and the copy to `z` another.
    fn overlap_block(
        comm: &Comm,
        halo: &Halo,
        m: &Amg<'static, f32>,
        wt: &[f64],
        w: &mut Work,
        z: &mut [V3],
    ) {
        let n = z.len();
        halo.exchange(comm, &mut w.r_ext);
        let scale = |v: &V3, c: f64| [c * v[0], c * v[1], c * v[2]];
        match m.first_pass() {
            Some(first) => {
                for (k, ((v, x), &c)) in w.r_ext.iter_mut().zip(&mut w.work).zip(wt).enumerate() {
                    *v = scale(v, c);
                    *x = scale(v, first.at(k));
                }
                m.apply_dot_prescaled(&w.r_ext, &mut w.z_ext, &mut w.work);
            }
            None => {
                for (v, &c) in w.r_ext.iter_mut().zip(wt) {
                    *v = scale(v, c);
                }
                m.apply_dot(&w.r_ext, &mut w.z_ext, &mut w.work);
            }
        }
        for ((zk, v), &c) in z.iter_mut().zip(&w.z_ext).zip(wt) {
            *zk = scale(v, c);
        }
        for (v, &c) in w.z_ext[n..].iter_mut().zip(&wt[n..]) {
            *v = scale(v, c);
        }
        halo.accumulate_into(comm, &w.z_ext[n..], n, z);
    }

    /// z = M r (projected), M the block preconditioner B alone, or with the coarse-grid
    /// correction Q = P A_c⁻¹ Pᵀ: M = Q + (I − Q A) B (A-DEF2, see [`super::coarse`];
    /// collective). Returns r · r and r · z on this rank's owned unknowns; with the
    /// coarse-grid correction, `z` holds y = B r and z = y + P c is left to the update
    /// ([`CoarseOp::update`]): the dots are r · r and r · y, and the correction carries c
    /// and r · P c over the ranks.
    fn precondition(
        &self,
        comm: &Comm,
        halo: &Halo,
        cons: &Constraints,
        r: &[V3],
        z: &mut [V3],
        w: &mut Work,
    ) -> ([f64; 2], Option<Correction>) {
        let n = self.n_own;
        let ops = Ops {
            own: self.own(),
            ghost: &self.ghost,
            project: |v: &mut [V3]| cons.project(v),
            exchange: |v: &mut [V3]| halo.exchange(comm, v),
            exchange_from: |v: &[V3], g: &mut [V3]| halo.exchange_from(comm, |e| v[e], g, n),
        };
        match (&self.interface, &self.block, w.sweep.take()) {
            // The block's residual formed in place in the extended block's.
            (Some(f), Block::Overlap(m, _, wt), Some(mut s)) => {
                w.r_ext[..n].copy_from_slice(r);
                f.before(&ops, &mut s, &mut w.r_ext[..n]);
                Self::overlap_block(comm, halo, m, wt, w, z);
                cons.project(z);
                f.after(&ops, &mut s, r, z);
                w.sweep = Some(s);
            }
            (Some(f), _, Some(mut s)) => {
                f.apply(&ops, &mut s, r, z, |r, z| self.block(comm, halo, r, z, w));
                w.sweep = Some(s);
            }
            _ => {
                self.block(comm, halo, r, z, w);
                cons.project(z);
            }
        }
        match &self.coarse {
            Some(coarse) => {
                let c = coarse.correction(comm, r, Some(z));
                (c.dots, Some(c))
            }
            None => ([dot(r, r), dot(r, z)], None),
        }
    }

    /// r = Π(b − A x) (`full[..n]` receives x); returns |r|² over the ranks.
    fn residual(
        &self,
        comm: &Comm,
        halo: &Halo,
        b: &[V3],
        x: &[V3],
        full: &mut [V3],
        cons: &Constraints,
        r: &mut [V3],
    ) -> f64 {
        let n = self.n_own;
        full[..n].copy_from_slice(x);
        self.mul_dot(comm, halo, full, r);
        for (rk, bk) in r.iter_mut().zip(b) {
            for q in 0..3 {
                rk[q] = bk[q] - rk[q];
            }
        }
        cons.project(r);
        sum(comm, dot(r, r))
    }

    /// Projected PCG on A x = b over the ranks (owned unknowns of `b` and `x`; `x` holds the
    /// initial guess), to |b − A x| ≤ `rel_tol` |b| over all ranks.
    #[allow(clippy::too_many_arguments)]
    pub fn solve(
        &self,
        comm: &Comm,
        halo: &Halo,
        n_all: usize,
        b: &[V3],
        x: &mut [V3],
        cons: &Constraints,
        opts: &DeformOptions,
        rel_tol: f64,
    ) -> SolveReport {
        let t0 = Instant::now();
        let n = self.n_own;
        let mut bp = b.to_vec();
        cons.project(&mut bp);
        cons.project(x);
        let bnorm = sum(comm, dot(&bp, &bp)).sqrt();
        let scale = if bnorm > 0.0 { bnorm } else { 1.0 };
        // full[..n] holds p, the ghosts receive theirs in the product.
        let mut full = vec![[0.0; 3]; n_all];
        let mut q = vec![[0.0; 3]; n];
        let mut r = vec![[0.0; 3]; n];
        let mut z = vec![[0.0; 3]; n];
        let n_ext = match &self.block {
            Block::Overlap(m, ..) => m.fine().n(),
            _ => 0,
        };
        let mut w = Work {
            work: vec![[0.0; 3]; n.max(n_ext)],
            r_ext: vec![[0.0; 3]; n_ext],
            z_ext: vec![[0.0; 3]; n_ext],
            sweep: self.interface.as_ref().map(|_| Scratch::new(n, n_all)),
        };
        let mut rr = self.residual(comm, halo, &bp, x, &mut full, cons, &mut r);
        if let Some(c) = &self.coarse {
            c.start(comm, x, &mut r, |v| cons.project(v));
            rr = sum(comm, dot(&r, &r));
        }
        let name = match (&self.block, &self.coarse) {
            (Block::Amg(_), None) => "block-amg",
            (Block::Amg(_), Some(_)) => "block-amg-coarse",
            (Block::Overlap(..), None) if self.interface.is_some() => "schwarz-amg-interface",
            (Block::Overlap(..), Some(_)) if self.interface.is_some() => {
                "schwarz-amg-interface-coarse"
            }
            (Block::Overlap(..), None) => "schwarz-amg",
            (Block::Overlap(..), Some(_)) => "schwarz-amg-coarse",
            (_, None) => "block-jacobi",
            (_, Some(_)) => "block-jacobi-coarse",
        };
        let name = if self.held {
            format!("{name}-held")
        } else {
            name.to_string()
        };
        let mut it = 0;
        if rr.sqrt() > rel_tol * scale {
            let (dots, c) = self.precondition(comm, halo, cons, &r, &mut z, &mut w);
            let mut rz = sum(comm, dots[1]) + c.as_ref().map_or(0.0, |c| c.r_pc);
            full[..n].copy_from_slice(&z);
            if let (Some(coarse), Some(c)) = (&self.coarse, &c) {
                coarse.add_prolonged(&c.c, &mut full[..n]);
            }
            while it < opts.max_iters {
                it += 1;
                let pq = sum(comm, self.mul_dot(comm, halo, &mut full, &mut q));
                if pq <= 0.0 || !pq.is_finite() {
                    break;
                }
                cons.project(&mut q);
                let alpha = rz / pq;
                axpy(-alpha, &q, &mut r);
                let (dots, c) = self.precondition(comm, halo, cons, &r, &mut z, &mut w);
                let [rr, rz_new] = sum_n(comm, dots);
                let rz_new = rz_new + c.as_ref().map_or(0.0, |c| c.r_pc);
                if rr.sqrt() <= rel_tol * scale || it == opts.max_iters {
                    axpy(alpha, &full[..n], x);
                    break;
                }
                let beta = rz_new / rz;
                rz = rz_new;
                // x += α p and the next direction in one pass over p.
                match (&self.coarse, &c) {
                    (Some(coarse), Some(c)) => {
                        coarse.update(alpha, x, &z, &c.c, beta, &mut full[..n]);
                    }
                    _ => axpy_xpby(alpha, x, &z, beta, &mut full[..n]),
                }
            }
        }
        let res = self
            .residual(comm, halo, &bp, x, &mut full, cons, &mut r)
            .sqrt()
            / scale;
        SolveReport {
            solver: format!("pcg-{name}"),
            iterations: it,
            rel_residual: res,
            converged: res <= rel_tol,
            seconds: t0.elapsed().as_secs_f64(),
        }
    }
}

/// The block of the owned and ghost unknowns: the owned rows of `a` (ghost columns
/// included), then per ghost unknown its springs to the local unknowns (in the local
/// adjacency: the edges of the cells around the owned nodes) and its owner's diagonal
/// (brought through the halo; collective). Symmetric: a spring is the same number from
/// either end.
fn extended(
    o: &Overlap,
    sys: &System,
    adj: &mesh::Adjacency,
    sp: &Springs,
    a: SymMatrix<f32>,
) -> (SymMatrix<f32>, Vec<f64>) {
    let (n_own, n_all) = (a.n(), o.unk_node.len());
    // The blocks that hold each unknown.
    let mut cnt = vec![[1.0f64]; n_all];
    o.halo.accumulate(o.comm, &mut cnt);
    o.halo.exchange(o.comm, &mut cnt);
    let wt = cnt.iter().map(|c| 1.0 / c[0].sqrt()).collect();
    let mut d = vec![[0.0f64; 1]; n_all];
    for (dk, &ak) in d.iter_mut().zip(&a.diag) {
        dk[0] = ak;
    }
    o.halo.exchange(o.comm, &mut d);
    let mut m = SymMatrix {
        diag: d.iter().map(|v| v[0]).collect(),
        offsets: a.offsets,
        cols: a.cols,
        vals: a.vals,
    };
    m.offsets.reserve(n_all - n_own);
    let mut row: Vec<(u32, f32)> = Vec::new();
    for k in n_own..n_all {
        let i = o.unk_node[k] as usize;
        row.clear();
        for &j in adj.neighbours(i) {
            let u = sys.unk_of[j as usize];
            if u != u32::MAX {
                row.push((u, -sp.k(i, j as usize) as f32));
            }
        }
        row.sort_unstable_by_key(|e| e.0);
        m.cols.extend(row.iter().map(|e| e.0));
        m.vals.extend(row.iter().map(|e| e.1));
        m.offsets.push(m.cols.len());
    }
    (m, wt)
}
