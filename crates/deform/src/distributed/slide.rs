//! Sliding on the geometry's support curves and surfaces over the ranks (paper §4.3, Eqs.
//! 27–33): the geometry is on every rank (it is small), rank 0 classifies the sliding nodes
//! as the serial deformation does and hands each owner its own ([`Slide::new`]); each owner
//! then constrains its sliding unknowns to their tangent planes or lines, places them on
//! their supports and re-linearises there, the outer iteration's largest update all-reduced
//! so that every rank stops at the same iteration ([`Slide::iterate`]). The ghosts get the
//! placed positions through the node halo with the rest of the increment.

use std::collections::HashMap;

use geom_db::GeomDb;
use mpi::datatype::PartitionMut;
use mpi::traits::*;
use sparse::vec3::{axpy, dot};
use sparse::{Constraints, V3};

use super::comm::{Comm, agree, broadcast_vec, max, min, offsets, sum, sum_u64};
use super::halo::Halo;
use super::partition::Partition;
use super::solve::DistOperator;
use crate::assembly::System;
use crate::error::Result;
use crate::operator::check_converged;
use crate::options::DeformOptions;
use crate::sliding::{SlideOutcome, correction_tol, largest_update};
use crate::support::{SupKind, SupNode, Support, check_kind, place, point, tangent_constraint};

/// A sliding node as five floats: global id, kind (0 curve, 1 surface), entity id,
/// parameters.
fn encode(gid: u64, kind: SupKind, p: [f64; 2]) -> [f64; 5] {
    let (k, id) = match kind {
        SupKind::Curve(c) => (0.0, c.0),
        SupKind::Surface(s) => (1.0, s.0),
    };
    [gid as f64, k, f64::from(id), p[0], p[1]]
}

/// The inverse of [`encode`].
fn decode(v: &[f64]) -> (u64, SupKind, [f64; 2]) {
    let id = v[2] as u32;
    let kind = if v[1] == 0.0 {
        SupKind::Curve(geom_db::CurveId(id))
    } else {
        SupKind::Surface(geom_db::SurfaceId(id))
    };
    (v[0] as u64, kind, [v[3], v[4]])
}

/// A rank's nodes sliding on supports and the geometry they slide on.
pub(crate) struct Slide {
    db: GeomDb,
    /// The owned sliding unknowns: local node, support, baseline parameters.
    nodes: Vec<SupNode>,
    /// Their unknown indices (owned unknowns).
    unk: Vec<u32>,
    /// Their global ids (what errors and results name).
    gids: Vec<u64>,
    /// The whole grid's bounding-box diagonal (the placement's length scale, as serially).
    diag: f64,
    /// Sliding nodes over the ranks.
    pub total: u64,
}

impl Slide {
    /// The owned sliding nodes of this rank, from rank 0's classification `root` (whole-grid
    /// numbering, read on rank 0 only), broadcast to every rank as (global id, support,
    /// parameters): each rank keeps those it owns that are unknowns. Collective; fails alike
    /// on every rank when a support is not in `db`.
    pub fn new(
        comm: &Comm,
        db: &GeomDb,
        root: &[SupNode],
        part: &Partition,
        sys: &System,
    ) -> Result<Self> {
        let flat: Vec<f64> = if comm.rank() == 0 {
            root.iter()
                .flat_map(|s| encode(u64::from(s.node), s.kind, s.param))
                .collect()
        } else {
            Vec::new()
        };
        let flat = broadcast_vec(comm, 0, flat);
        let g = &part.grid;
        let local: HashMap<u64, u32> = g.global_ids[..g.n_owned]
            .iter()
            .enumerate()
            .map(|(i, &gid)| (gid, i as u32))
            .collect();
        let (mut nodes, mut unk, mut gids) = (Vec::new(), Vec::new(), Vec::new());
        let mut bad = Ok(());
        for v in flat.chunks_exact(5) {
            let (gid, kind, param) = decode(v);
            let Some(&i) = local.get(&gid) else { continue };
            let u = sys.unk_of[i as usize];
            if u == u32::MAX {
                continue;
            }
            if bad.is_ok() {
                bad = check_kind(db, gid as u32, kind);
            }
            nodes.push(SupNode {
                node: i,
                kind,
                param,
            });
            unk.push(u);
            gids.push(gid);
        }
        agree(comm, bad)?;
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for p in &g.mesh.coords[..g.n_owned] {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let (lo, hi) = (lo.map(|v| min(comm, v)), hi.map(|v| max(comm, v)));
        let diag = if lo[0] <= hi[0] {
            (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt()
        } else {
            0.0
        };
        let total = sum_u64(comm, nodes.len() as u64);
        Ok(Self {
            db: db.clone(),
            nodes,
            unk,
            gids,
            diag,
            total,
        })
    }

    /// The owned unknowns that slide on a support (for the coarse space, which leaves the
    /// constrained unknowns out).
    pub fn unknowns(&self) -> &[u32] {
        &self.unk
    }

    /// The baseline parameters of the owned sliding nodes (the start of every attempt).
    pub fn initial_params(&self) -> Vec<[f64; 2]> {
        self.nodes.iter().map(|s| s.param).collect()
    }

    /// The constraints of a solve: `base` (the planes and seams) and the tangent plane or
    /// line of every owned sliding node at its parameters `params` (collective: a singular
    /// support fails on every rank alike).
    pub fn constraints(
        &self,
        comm: &Comm,
        base: &Constraints,
        params: &[[f64; 2]],
    ) -> Result<Constraints> {
        let mut cons = base.clone();
        let made = (|| -> Result<()> {
            for (k, s) in self.nodes.iter().enumerate() {
                let c = tangent_constraint(&self.db, self.gids[k] as u32, s.kind, params[k])?;
                cons.items.push((self.unk[k], c));
            }
            Ok(())
        })();
        agree(comm, made)?;
        Ok(cons)
    }

    /// The outer iteration from the constrained solution `dx` of A Δx = `b` (owned unknowns,
    /// Δx from the state `cur`, updates measured from the solve's initial guess `dx0`), as the
    /// serial `Sliding::iterate`: place every owned sliding node on its support nearest to
    /// its tentative position (parameters in `params`), re-linearise the constraints there
    /// and solve for the correction over the ranks, until the largest node update over the
    /// ranks is ≤ `slide_rel_tol` × the largest boundary displacement `max_disp`.
    /// Collective.
    #[allow(clippy::too_many_arguments)]
    pub fn iterate(
        &self,
        comm: &Comm,
        op: &DistOperator,
        halo: &Halo,
        n_all: usize,
        base: &Constraints,
        cur: &[[f64; 3]],
        b: &[V3],
        dx: &mut [V3],
        dx0: Vec<V3>,
        params: &mut [[f64; 2]],
        opts: &DeformOptions,
        max_disp: f64,
    ) -> Result<SlideOutcome> {
        let n = dx.len();
        let bnorm = sum(comm, dot(b, b)).sqrt();
        let mut prev = dx0;
        let mut out = SlideOutcome::default();
        let mut converged = false;
        let mut update = f64::INFINITY;
        let tol = 1e-14 * self.diag;
        for outer in 1..=opts.max_slide_iters.max(1) {
            // Place the owned sliding nodes.
            let placed = (|| -> Result<()> {
                for (k, s) in self.nodes.iter().enumerate() {
                    let (u, i) = (self.unk[k] as usize, s.node as usize);
                    let d = dx[u];
                    let tgt = [cur[i][0] + d[0], cur[i][1] + d[1], cur[i][2] + d[2]];
                    let gid = self.gids[k] as u32;
                    let p = place(&self.db, gid, s.kind, params[k], tgt, tol)?;
                    params[k] = p;
                    let r = point(&self.db, s.kind, p);
                    dx[u] = [r[0] - cur[i][0], r[1] - cur[i][1], r[2] - cur[i][2]];
                }
                Ok(())
            })();
            agree(comm, placed)?;
            let upd = max(comm, largest_update(dx, &mut prev));
            update = upd / max_disp;
            out.iterations = outer;
            if upd <= opts.slide_rel_tol * max_disp {
                converged = true;
                break;
            }
            // Correction: A δ = b − A Δx, δ in the tangent spaces at the new parameters.
            let cons = self.constraints(comm, base, params)?;
            let mut full = vec![[0.0; 3]; n_all];
            full[..n].copy_from_slice(dx);
            let mut r = vec![[0.0; 3]; n];
            op.mul_dot(comm, halo, &mut full, &mut r);
            for (rk, bk) in r.iter_mut().zip(b) {
                for q in 0..3 {
                    rk[q] = bk[q] - rk[q];
                }
            }
            let mut rp = r.clone();
            cons.project(&mut rp);
            let rn = sum(comm, dot(&rp, &rp)).sqrt();
            let rel = correction_tol(opts, bnorm, rn);
            let mut delta = vec![[0.0; 3]; n];
            let rep = op.solve(comm, halo, n_all, &r, &mut delta, &cons, opts, rel);
            check_converged(&rep, "spring system (Eq. 21), sliding correction", opts)?;
            out.solver_iterations += rep.iterations;
            axpy(1.0, &delta, dx);
        }
        out.finish(update, converged)
    }

    /// Puts the owned sliding nodes of `cur` exactly on their supports at `params`; returns
    /// the largest distance they moved from the baseline `x0` (this rank's).
    pub fn place(&self, cur: &mut [[f64; 3]], params: &[[f64; 2]], x0: &[[f64; 3]]) -> f64 {
        let mut moved = 0.0f64;
        for (s, p) in self.nodes.iter().zip(params) {
            let i = s.node as usize;
            cur[i] = point(&self.db, s.kind, *p);
            let d = (0..3).map(|q| (cur[i][q] - x0[i][q]).powi(2)).sum::<f64>();
            moved = moved.max(d.sqrt());
        }
        moved
    }

    /// The final supports of the owned sliding nodes (global ids) at `params`.
    pub fn supports(&self, params: &[[f64; 2]]) -> Vec<(u64, Support)> {
        self.nodes
            .iter()
            .zip(params)
            .zip(&self.gids)
            .map(|((s, p), &g)| (g, support(s.kind, *p)))
            .collect()
    }
}

/// The [`Support`] of a sliding node at parameters `p`.
fn support(kind: SupKind, p: [f64; 2]) -> Support {
    match kind {
        SupKind::Curve(curve) => Support::Curve { curve, t: p[0] },
        SupKind::Surface(surface) => Support::Surface { surface, uv: p },
    }
}

/// Every rank's sliding nodes `mine` (global ids) gathered on rank 0, by global id
/// (`None` on the other ranks). Collective.
pub(crate) fn gather(comm: &Comm, mine: &[(u64, Support)]) -> Option<Vec<(u64, Support)>> {
    let flat: Vec<f64> = mine
        .iter()
        .filter_map(|&(g, s)| match s {
            Support::Curve { curve, t } => Some(encode(g, SupKind::Curve(curve), [t, 0.0])),
            Support::Surface { surface, uv } => Some(encode(g, SupKind::Surface(surface), uv)),
            Support::Corner => None,
        })
        .flatten()
        .collect();
    let root = comm.process_at_rank(0);
    let n = flat.len() as i32;
    if comm.rank() != 0 {
        root.gather_into(&n);
        root.gather_varcount_into(&flat[..]);
        return None;
    }
    let mut counts = vec![0i32; comm.size() as usize];
    root.gather_into_root(&n, &mut counts[..]);
    let displs = offsets(&counts);
    let total: usize = counts.iter().map(|&c| c as usize).sum();
    let mut all = vec![0.0f64; total];
    root.gather_varcount_into_root(
        &flat[..],
        &mut PartitionMut::new(&mut all[..], &counts[..], &displs[..]),
    );
    let mut out: Vec<(u64, Support)> = all
        .chunks_exact(5)
        .map(|v| {
            let (g, kind, p) = decode(v);
            (g, support(kind, p))
        })
        .collect();
    out.sort_by_key(|e| e.0);
    Some(out)
}
