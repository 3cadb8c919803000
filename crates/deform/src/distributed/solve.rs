//! The distributed linear solve of Eqs. 21 and 26: the matrix rows of a rank's owned
//! unknowns ([`DistOperator`], assembled by deform's own `assemble` on the local grid), the
//! product with the halo exchange of the ghost unknowns overlapped with the interior rows,
//! and projected conjugate gradients with all-reduced dot products, preconditioned by a
//! block-Jacobi of per-rank multigrid (or Jacobi) on the owned–owned block.

use std::time::Instant;

use rayon::prelude::*;
use sparse::vec3::{CHUNK, V3, dot};
use sparse::{Constraints, Csr, Jacobi, Preconditioner, SolveReport, SymMatrix};

use super::coarse::CoarseOp;
use super::comm::{Comm, sum, sum_n};
use super::halo::Halo;
use crate::assembly::{System, assemble, couplings};
use crate::error::Result;
use crate::options::{DeformOptions, SolverKind};
use crate::solve::{Amg, AmgOptions};
use crate::stiffness::Springs;

/// The preconditioner of a rank's block.
enum Block {
    Amg(Box<Amg<'static, f32>>),
    Jacobi(Jacobi),
    /// No owned unknown.
    Empty,
}

/// Eq. 21's matrix on a rank: rows of the owned unknowns, columns of the local unknowns
/// (owned, then ghosts), the couplings to prescribed nodes and the block preconditioner.
pub(crate) struct DistOperator {
    /// Rows of the owned unknowns; column indices ≥ `n_own` are ghost unknowns.
    a: SymMatrix<f32>,
    n_own: usize,
    /// Rows with a ghost column (computed once the halo has arrived).
    boundary: Vec<u32>,
    /// Rows without (computed while it travels).
    interior: Vec<u32>,
    block: Block,
    /// The springs from each owned unknown to its prescribed neighbours.
    pub couplings: Csr,
    /// The coarse-grid correction across the ranks (none on one rank).
    pub coarse: Option<CoarseOp>,
}

impl DistOperator {
    /// Assembles at the springs `sp` on the local system `sys` (rows: owned unknowns; the
    /// unknown numbering of `sys` covers the ghost unknowns too).
    pub fn new(
        sys: &System,
        adj: &mesh::Adjacency,
        sp: &Springs,
        n_own: usize,
        opts: &DeformOptions,
    ) -> Result<Self> {
        let a = assemble(sys, adj, sp)?;
        let couplings = couplings(sys, adj, sp);
        let (mut boundary, mut interior) = (Vec::new(), Vec::new());
        for k in 0..n_own {
            if a.row(k).0.iter().any(|&c| c as usize >= n_own) {
                boundary.push(k as u32);
            } else {
                interior.push(k as u32);
            }
        }
        // The owned–owned block.
        let mut own = SymMatrix {
            diag: a.diag.clone(),
            offsets: vec![0],
            cols: Vec::new(),
            vals: Vec::new(),
        };
        for k in 0..n_own {
            let (c, v) = a.row(k);
            for (&c, &v) in c.iter().zip(v) {
                if (c as usize) < n_own {
                    own.cols.push(c);
                    own.vals.push(v);
                }
            }
            own.offsets.push(own.cols.len());
        }
        let block = if n_own == 0 {
            Block::Empty
        } else {
            match opts.solver {
                SolverKind::PcgMultigrid => {
                    Block::Amg(Box::new(Amg::new_owned(own, &AmgOptions::default())?))
                }
                _ => Block::Jacobi(Jacobi::new(&own)),
            }
        };
        Ok(Self {
            a,
            n_own,
            boundary,
            interior,
            block,
            couplings,
            coarse: None,
        })
    }

    /// The rows of the owned unknowns.
    pub fn matrix(&self) -> &SymMatrix<f32> {
        &self.a
    }

    fn row(&self, k: usize, x: &[V3]) -> V3 {
        let (cols, vals) = self.a.row(k);
        let d = self.a.diag[k];
        let mut s = [d * x[k][0], d * x[k][1], d * x[k][2]];
        for (&c, &v) in cols.iter().zip(vals) {
            let (v, xc) = (f64::from(v), x[c as usize]);
            for q in 0..3 {
                s[q] += v * xc[q];
            }
        }
        s
    }

    /// y = A x on the owned rows; `x` holds the owned unknowns and receives the ghost ones
    /// from their owners while the interior rows are computed.
    pub fn mul(&self, comm: &Comm, halo: &Halo, x: &mut [V3], y: &mut [V3]) {
        let rows = |list: &[u32], x: &[V3]| -> Vec<V3> {
            list.par_iter()
                .with_min_len(CHUNK)
                .map(|&k| self.row(k as usize, x))
                .collect()
        };
        let mut inner = Vec::new();
        halo.exchange_overlapped(comm, x, |x| inner = rows(&self.interior, x));
        let outer = rows(&self.boundary, x);
        for (&k, v) in self.interior.iter().zip(inner) {
            y[k as usize] = v;
        }
        for (&k, v) in self.boundary.iter().zip(outer) {
            y[k as usize] = v;
        }
    }

    fn block(&self, r: &[V3], z: &mut [V3]) {
        match &self.block {
            Block::Amg(m) => m.apply(r, z),
            Block::Jacobi(m) => m.apply(r, z),
            Block::Empty => {}
        }
    }

    /// z = M r (projected), M the block preconditioner B alone, or with the coarse-grid
    /// correction Q = P A_c⁻¹ Pᵀ: M = Q + (I − Q A) B (I − A Q) (collective).
    fn precondition(&self, comm: &Comm, cons: &Constraints, r: &[V3], z: &mut [V3]) {
        let Some(c) = &self.coarse else {
            self.block(r, z);
            cons.project(z);
            return;
        };
        let c1 = c.coarse_of(comm, r);
        let mut s = r.to_vec();
        c.sub_product(&c1, &mut s);
        cons.project(&mut s);
        self.block(&s, z);
        cons.project(z);
        let mut c2 = c.coarse_of_product(comm, z);
        for (a, b) in c2.iter_mut().zip(&c1) {
            for q in 0..3 {
                a[q] = b[q] - a[q];
            }
        }
        c.add_prolonged(&c2, z);
    }

    /// Projected PCG on A x = b over the ranks (owned unknowns of `b` and `x`; `x` holds the
    /// initial guess), to |b − A x| ≤ `rel_tol` |b| over all ranks.
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
        let mut full = vec![[0.0; 3]; n_all];
        let mut q = vec![[0.0; 3]; n];
        let residual = |x: &[V3], full: &mut Vec<V3>, out: &mut [V3]| {
            full[..n].copy_from_slice(x);
            self.mul(comm, halo, full, out);
            for k in 0..n {
                for c in 0..3 {
                    out[k][c] = bp[k][c] - out[k][c];
                }
            }
            cons.project(out);
        };
        let mut r = vec![[0.0; 3]; n];
        residual(x, &mut full, &mut r);
        let mut z = vec![[0.0; 3]; n];
        self.precondition(comm, cons, &r, &mut z);
        let [mut rr, mut rz] = sum_n(comm, [dot(&r, &r), dot(&r, &z)]);
        let name = match (&self.block, &self.coarse) {
            (Block::Amg(_), None) => "block-amg",
            (Block::Amg(_), Some(_)) => "block-amg-coarse",
            (_, None) => "block-jacobi",
            (_, Some(_)) => "block-jacobi-coarse",
        };
        let mut it = 0;
        if rr.sqrt() > rel_tol * scale {
            full[..n].copy_from_slice(&z);
            while it < opts.max_iters {
                it += 1;
                // full[..n] holds p.
                self.mul(comm, halo, &mut full, &mut q);
                cons.project(&mut q);
                let pq = sum(comm, dot(&full[..n], &q));
                if pq <= 0.0 || !pq.is_finite() {
                    break;
                }
                let alpha = rz / pq;
                for k in 0..n {
                    for c in 0..3 {
                        x[k][c] += alpha * full[k][c];
                        r[k][c] -= alpha * q[k][c];
                    }
                }
                self.precondition(comm, cons, &r, &mut z);
                let [rr_new, rz_new] = sum_n(comm, [dot(&r, &r), dot(&r, &z)]);
                rr = rr_new;
                if rr.sqrt() <= rel_tol * scale {
                    break;
                }
                let beta = rz_new / rz;
                rz = rz_new;
                for k in 0..n {
                    for c in 0..3 {
                        full[k][c] = z[k][c] + beta * full[k][c];
                    }
                }
            }
        }
        residual(x, &mut full, &mut r);
        let res = sum(comm, dot(&r, &r)).sqrt() / scale;
        SolveReport {
            solver: format!("pcg-{name}"),
            iterations: it,
            rel_residual: res,
            converged: res <= rel_tol,
            seconds: t0.elapsed().as_secs_f64(),
        }
    }
}
