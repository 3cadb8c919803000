//! The spring analogy (paper §4.1–4.2, Eqs. 14–26) on unstructured grids, with the boundary
//! conditions of [`crate::bc`], an incremental quality guard and a report.
//!
//! For the unknown nodes i (interior and sliding), Eq. 21 in the deviations Δx:
//! Σ_j K_ij (Δx_j − Δx_i) = Σ_j K_ij (R_ij − I)(x⁰_j − x⁰_i), with the prescribed Δx_j of
//! moving and fixed nodes moved to the right-hand side: A Δx = b with a_ii = Σ_j K_ij,
//! a_ij = −K_ij (one scalar matrix, three components). Sliding nodes are constrained to their
//! plane (or seam line) and the system is solved by projected conjugate gradients, which is
//! the exact constrained minimum of the spring energy (Eq. 18) — no outer iteration is needed
//! for planes.
//!
//! R (Eqs. 25–26): per moving skin element (see [`crate::rotation`]), averaged to skin nodes
//! as unit quaternions (area-weighted sum, normalised, scalar part w ≥ 0), propagated by
//! Eq. 26 solved for the quaternions' vector part u (one three-component solve) with the skin
//! values and R = I (u = 0) on fixed nodes held, starting from R = I; each node's rotation is
//! the unit quaternion with that vector part, w = √(1 − |u|²) (|u| ≤ 1 by the discrete maximum
//! principle, A being an M-matrix; clamped against round-off). This replaces a second solve for
//! w followed by normalisation: both are exact for a uniform rotation and differ by O(θ³) for
//! angles θ in between. R_ij is the normalised sum of the two end nodes' quaternions — the
//! geodesic midpoint of R_i and R_j, a proper rotation, at the cost of a few flops per edge
//! instead of an SVD per edge.

use std::time::Instant;

use mesh::{Adjacency, Mesh};
use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use rayon::prelude::*;
use serde::Serialize;

use crate::bc::{BoundaryConditions, Classified, NodeRole, PlaneInfo, classify};
use crate::error::{Error, Result};
use crate::rotation::{frame, rotation_from_frame};
use crate::solve::order::inverse;
use crate::solve::vecops::{CHUNK, V3, norm, row_chunks};
use crate::solve::{
    Amg, AmgInfo, AmgOptions, Constraints, Csr, Jacobi, SolveOptions, SolveReport, SymMatrix, pcg,
    point_iteration,
};
use crate::support::{SupKind, Support, Supports, place, point, tangent_constraint};

/// With `DEFORM_TRACE` set: prints the seconds since `t` and the resident / peak memory
/// (Linux /proc) for the set-up step `label` on stderr; restarts `t`.
fn tr(label: &str, t: &mut Instant) {
    if std::env::var_os("DEFORM_TRACE").is_some() {
        let st = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
        let g = |k: &str| {
            st.lines()
                .find(|l| l.starts_with(k))
                .unwrap_or("")
                .to_string()
        };
        eprintln!(
            "TRACE {label}: {:.3} s  {} {}",
            t.elapsed().as_secs_f64(),
            g("VmRSS"),
            g("VmHWM")
        );
    }
    *t = Instant::now();
}

/// Spring stiffness K_ij of the edge ij (lengths and volumes of the grid at the start of the
/// increment).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Stiffness {
    /// K = 1 / l.
    InverseLength,
    /// K = 1 / l².
    InverseLengthSquared,
    /// K = (1 / l²) · (V̄ / V_ij): V_ij the smaller of the end nodes' mean adjacent cell volumes,
    /// V̄ the mean cell volume; stiffens the small cells near walls.
    Volume,
    /// K = (1 / l²) · (1 + (ℓ / d_ij)²): d_ij the distance of the edge's midpoint to the
    /// moving boundary (mean of the end nodes' shortest paths along grid edges, ≥ l/2), ℓ =
    /// 0.2 × the diagonal of the moving boundary's bounding box; stiffens a layer around
    /// moving bodies so that it moves almost rigidly (with R) on any grid, graded or not.
    WallDistance,
}

/// The linear solver.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum SolverKind {
    /// Conjugate gradients with the smoothed-aggregation multigrid W-cycle.
    PcgMultigrid,
    /// Conjugate gradients with the Jacobi preconditioner.
    PcgJacobi,
    /// The paper's point iteration (Eq. 22), Jacobi form.
    PointIteration,
}

/// Options of [`deform`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct DeformOptions {
    /// Spring stiffness.
    pub stiffness: Stiffness,
    /// Use the adaptation matrices R (Eqs. 18–26); `false` gives the plain spring system.
    pub adapt_rotation: bool,
    /// Linear solver.
    pub solver: SolverKind,
    /// Relative residual |b − A Δx| / |b| at which a solve stops.
    pub rel_tol: f64,
    /// Iteration limit of one solve.
    pub max_iters: usize,
    /// The point iteration also stops when the largest node update (Eq. 24) is below this
    /// fraction of the largest boundary displacement of the increment.
    pub step_rel_tol: f64,
    /// Quality guard: the motion is split into increments when a cell has q ≤ 0 or when the
    /// minimum quality falls below this fraction of the initial minimum.
    pub min_quality_ratio: f64,
    /// Largest number of increments tried (1, 2, 4, … up to this).
    pub max_increments: usize,
    /// Return an inverted grid instead of an error (the report says so).
    pub allow_inverted: bool,
    /// Planarity tolerance of sliding markers, relative to the bounding-box diagonal.
    pub plane_rel_tol: f64,
    /// Renumber the grid internally, along a Morton curve and then in breadth-first order
    /// ([`level_order`]), the unknowns in that order (the result is returned in the input
    /// numbering).
    pub renumber: bool,
    /// Sliding on geometry supports (Eqs. 27–33): the outer iteration stops when the largest
    /// node update of an iteration is ≤ this fraction of the largest boundary displacement of
    /// the increment (a length criterion: with 1e-9 and a 0.1 m motion, 1e-10 m).
    pub slide_rel_tol: f64,
    /// Largest number of outer iterations of the sliding on supports per increment.
    pub max_slide_iters: usize,
}

impl Default for DeformOptions {
    fn default() -> Self {
        Self {
            stiffness: Stiffness::InverseLengthSquared,
            adapt_rotation: true,
            solver: SolverKind::PcgMultigrid,
            rel_tol: 1e-8,
            max_iters: 20_000,
            step_rel_tol: 1e-10,
            min_quality_ratio: 0.2,
            max_increments: 16,
            allow_inverted: false,
            plane_rel_tol: 1e-6,
            renumber: true,
            slide_rel_tol: 1e-9,
            max_slide_iters: 50,
        }
    }
}

/// Seconds per phase.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct PhaseTimes {
    /// Node classification, adjacency, renumbering.
    pub setup: f64,
    /// Matrix and right-hand side assembly (all increments).
    pub assemble: f64,
    /// Preconditioner setup (multigrid hierarchy).
    pub precond: f64,
    /// R on the skin and its propagation (Eq. 26).
    pub rotation: f64,
    /// Linear solves of Eq. 21.
    pub solve: f64,
    /// Quality checks.
    pub quality: f64,
}

/// Quality summary (DESIGN.md measure).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct QualitySummary {
    /// Smallest value.
    pub min: f64,
    /// Mean value.
    pub mean: f64,
    /// 1st percentile.
    pub p1: f64,
    /// Cells with q ≤ 0.
    pub inverted: usize,
    /// Cells measured (tetrahedra, triangles).
    pub measured: usize,
}

impl QualitySummary {
    /// Summary of a quality field (NaN entries ignored).
    pub fn of(q: &[f64]) -> Self {
        let s = mesh::quality::summary(q);
        Self {
            min: s.min,
            mean: s.mean,
            p1: s.p1,
            inverted: s.n_nonpositive,
            measured: s.measured,
        }
    }
}

/// What [`deform`] did.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DeformReport {
    /// Nodes of the grid.
    pub nodes: usize,
    /// Cells of the grid.
    pub cells: usize,
    /// Unknown nodes (interior + sliding).
    pub unknowns: usize,
    /// Sliding nodes (constrained to a plane or a seam line).
    pub sliding: usize,
    /// Nodes sliding on geometry support curves and surfaces (Eqs. 27–33).
    pub sliding_on_supports: usize,
    /// Outer iterations of the sliding on supports, summed over the increments of the last
    /// attempt (0 without such nodes).
    pub slide_iterations: usize,
    /// Largest node update of the last outer iteration, relative to the largest boundary
    /// displacement of its increment (the convergence measure of the outer iteration).
    pub slide_update: f64,
    /// Nodes with prescribed motion (moving markers and displacements).
    pub moving: usize,
    /// Planes fitted to sliding markers.
    pub planes: Vec<PlaneInfo>,
    /// Increments used (1 unless the guard split the motion).
    pub increments: usize,
    /// Attempts made by the guard (increments tried, in order).
    pub attempts: Vec<usize>,
    /// Iterations of the Eq. 21 solves, summed over the increments of the last attempt.
    pub iterations: usize,
    /// Iterations of the Eq. 26 (R) solves, summed.
    pub rotation_iterations: usize,
    /// Largest final relative residual of the Eq. 21 solves.
    pub residual: f64,
    /// Solver used.
    pub solver: SolverKind,
    /// Multigrid hierarchy of the last increment (when used).
    pub multigrid: Option<AmgInfo>,
    /// Quality before.
    pub quality_before: QualitySummary,
    /// Quality after.
    pub quality_after: QualitySummary,
    /// Seconds per phase (all attempts).
    pub seconds: PhaseTimes,
    /// Messages of the guard (increments, inverted cells allowed).
    pub notes: Vec<String>,
}

/// The deformed coordinates (same numbering as the input) and the report.
#[derive(Debug, Clone)]
pub struct Deformed {
    /// New node coordinates.
    pub coords: Vec<[f64; 3]>,
    /// Final supports and parameters of the nodes that slid on geometry supports (input
    /// numbering; empty without [`crate::MarkerRole::SlideOnSupport`]).
    pub supports: Vec<(u32, Support)>,
    /// Signed quality of every cell at `coords` ([`cell_quality`], canonical order): the
    /// field the guard checked.
    pub cell_quality: Vec<f64>,
    /// What was done.
    pub report: DeformReport,
    /// The solver state of this result, the warm start of a later [`Deformer::deform`].
    state: SolverState,
}

/// The unknowns of a solved deformation in the set-up's own numbering: what a warm start
/// (see [`Deformer::deform`]) begins from.
#[derive(Debug, Clone, Default)]
struct SolverState {
    /// Nodes and unknowns of the set-up that produced it (a check on reuse).
    shape: (usize, usize),
    /// Δx of Eq. 21 per unknown (empty when nothing was solved).
    dx: Vec<V3>,
    /// The Eq. 26 solution per unknown: the quaternion's vector part as solved (before the
    /// clamp to |u| ≤ 1; empty without R). The scalar part is derived from it.
    qv: Vec<V3>,
    /// Parameters of the nodes sliding on supports (classification order).
    params: Vec<[f64; 2]>,
}

/// Signed quality of every cell (canonical order; NaN for kinds without a measure) for the
/// grid's connectivity at coordinates `x`.
pub fn cell_quality(mesh: &Mesh, x: &[[f64; 3]]) -> Vec<f64> {
    mesh::quality::cell_quality_at(mesh, x)
}

/// The `k` worst cells as "id (q = …)".
fn worst_cells(q: &[f64], k: usize) -> String {
    let mut idx: Vec<usize> = (0..q.len()).filter(|&i| !q[i].is_nan()).collect();
    idx.sort_by(|&a, &b| q[a].total_cmp(&q[b]).then(a.cmp(&b)));
    idx.iter()
        .take(k)
        .map(|&i| format!("cell {i} (q = {:.3e})", q[i]))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Unknown numbering and the solver's view of the grid.
struct System {
    /// Unknown index of each node (u32::MAX for prescribed nodes).
    unk_of: Vec<u32>,
    /// Node of each unknown, in solver order.
    node_of: Vec<u32>,
    cons: Constraints,
    /// Unknown index of each entry of [`Classified::supports`] (u32::MAX: not an unknown).
    sup_unk: Vec<u32>,
}

/// The unknowns in node order: with `opts.renumber` the grid is in breadth-first order
/// (see [`Deformer`]), and so are the unknowns, with the rows' neighbours close in memory.
fn build_system(cls: &Classified, adj: &Adjacency) -> System {
    let n = cls.roles.len();
    let is_unk = |r: &NodeRole| {
        matches!(
            r,
            NodeRole::Free | NodeRole::Sliding(_) | NodeRole::OnSupport(_)
        )
    };
    let mut node_of: Vec<u32> = Vec::new();
    for (i, r) in cls.roles.iter().enumerate() {
        // A node without edges (unused by the cells) cannot move: it is left where it is.
        if is_unk(r) && !adj.neighbours(i).is_empty() {
            node_of.push(i as u32);
        }
    }
    let mut unk_of = vec![u32::MAX; n];
    for (k, &i) in node_of.iter().enumerate() {
        unk_of[i as usize] = k as u32;
    }
    let mut items = Vec::new();
    for (k, &i) in node_of.iter().enumerate() {
        if let NodeRole::Sliding(c) = cls.roles[i as usize] {
            items.push((k as u32, c));
        }
    }
    let sup_unk = cls
        .supports
        .iter()
        .map(|s| unk_of[s.node as usize])
        .collect();
    System {
        unk_of,
        node_of,
        cons: Constraints { items },
        sup_unk,
    }
}

/// Spring stiffness evaluator on a grid state.
///
/// The stiffness is scaled by a power of two (exact) that makes it dimensionless, then rounded
/// to single precision: the matrix stores it in f32 (a product reads 8 instead of 12 bytes per
/// entry), and the diagonal, the couplings to prescribed nodes and the R term use the same
/// rounded value, so the system solved is exactly the spring system of the rounded springs
/// (stiffness changed by ≤ 6e-8 relative; the solution does not depend on the scale).
struct Springs<'a> {
    x: &'a [[f64; 3]],
    kind: Stiffness,
    /// 2^e ≈ 1 / (diagonal of the baseline grid's bounding box)^p, p the power of the length
    /// in K.
    scale: f64,
    /// For [`Stiffness::Volume`]: V̄ / V_node per node; for [`Stiffness::WallDistance`]:
    /// the distance d_node to the moving boundary.
    vol_factor: Vec<f64>,
    /// ℓ of [`Stiffness::WallDistance`].
    wall_len: f64,
}

impl Springs<'_> {
    /// K_ij, scaled and rounded to single precision (see [`Springs`]).
    #[inline]
    fn k(&self, i: usize, j: usize) -> f64 {
        f64::from((self.scale * self.k_exact(i, j)) as f32)
    }

    /// K_ij in f64, unscaled.
    #[inline]
    fn k_exact(&self, i: usize, j: usize) -> f64 {
        let (a, b) = (self.x[i], self.x[j]);
        let l2 = (b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2) + (b[2] - a[2]).powi(2);
        match self.kind {
            Stiffness::InverseLength => 1.0 / l2.sqrt(),
            Stiffness::InverseLengthSquared => 1.0 / l2,
            Stiffness::Volume => self.vol_factor[i].max(self.vol_factor[j]) / l2,
            Stiffness::WallDistance => {
                // Distance of the edge's midpoint, ≥ l / 2 next to the wall.
                let d = 0.5 * (self.vol_factor[i] + self.vol_factor[j]);
                let r = self.wall_len / d;
                (1.0 + r * r) / l2
            }
        }
    }
}

/// ℓ / (diagonal of the moving boundary's bounding box) of [`Stiffness::WallDistance`]
/// (0.1–0.2 measured best on the wing-in-box benchmark, docs/performance.md).
const WALL_SCALE: f64 = 0.2;

/// Distance of every node to the nodes flagged `source`, along grid edges (Dijkstra; ∞ where
/// unreachable). The result does not depend on the order in which nodes of equal distance
/// are settled (a node's distance is the smallest of its settled neighbours' d + l, and a
/// neighbour at the same distance cannot lower it), so the monotone [`RadixHeap`] gives the
/// distances of a binary heap bit for bit.
fn edge_distance(adj: &Adjacency, x: &[[f64; 3]], source: &[bool]) -> Vec<f64> {
    let n = x.len();
    let mut d = vec![f64::INFINITY; n];
    let mut heap = RadixHeap::default();
    for i in 0..n {
        if source[i] {
            d[i] = 0.0;
            heap.push(0, i as u32);
        }
    }
    while let Some((key, i)) = heap.pop() {
        let i = i as usize;
        let di = f64::from_bits(key);
        if di > d[i] {
            continue;
        }
        let a = x[i];
        for &j in adj.neighbours(i) {
            let j = j as usize;
            let b = x[j];
            let l = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2) + (b[2] - a[2]).powi(2)).sqrt();
            let dj = di + l;
            if dj < d[j] {
                d[j] = dj;
                // Non-negative f64 bit patterns order like the values.
                heap.push(dj.to_bits(), j as u32);
            }
        }
    }
    d
}

/// Monotone priority queue on u64 keys (radix heap): every pushed key must be ≥ the last
/// popped one, as in Dijkstra's algorithm. Bucket k holds the keys whose highest bit that
/// differs from the last popped key is bit k − 1 (bucket 0: equal to it); popping refills
/// from the first non-empty bucket, so each entry moves O(64) times at most and typically
/// once or twice.
struct RadixHeap {
    last: u64,
    len: usize,
    buckets: [Vec<(u64, u32)>; 65],
}

impl Default for RadixHeap {
    fn default() -> Self {
        Self {
            last: 0,
            len: 0,
            buckets: std::array::from_fn(|_| Vec::new()),
        }
    }
}

impl RadixHeap {
    #[inline]
    fn bucket(last: u64, key: u64) -> usize {
        (64 - (key ^ last).leading_zeros()) as usize
    }

    #[inline]
    fn push(&mut self, key: u64, v: u32) {
        debug_assert!(key >= self.last);
        self.buckets[Self::bucket(self.last, key)].push((key, v));
        self.len += 1;
    }

    /// A smallest (key, value) entry (among equal keys, any).
    fn pop(&mut self) -> Option<(u64, u32)> {
        if self.len == 0 {
            return None;
        }
        if self.buckets[0].is_empty() {
            let k = (1..65).find(|&k| !self.buckets[k].is_empty())?;
            let items = std::mem::take(&mut self.buckets[k]);
            self.last = items.iter().map(|e| e.0).min()?;
            for &(key, v) in &items {
                self.buckets[Self::bucket(self.last, key)].push((key, v));
            }
            // Keep the allocation of the emptied bucket.
            let mut items = items;
            items.clear();
            self.buckets[k] = items;
        }
        self.len -= 1;
        self.buckets[0].pop()
    }
}

/// The stiffness evaluator at `x`; for [`Stiffness::WallDistance`], `distance` is the
/// wall distance when already computed ([`edge_distance`] of `adj`, `x`, `moving`).
fn springs<'a>(
    mesh: &Mesh,
    x: &'a [[f64; 3]],
    kind: Stiffness,
    adj: &Adjacency,
    moving: &[bool],
    distance: Option<Vec<f64>>,
) -> Springs<'a> {
    let mut vol_factor = Vec::new();
    let mut wall_len = 0.0;
    if kind == Stiffness::WallDistance {
        let scale = WALL_SCALE;
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for (p, &m) in x.iter().zip(moving) {
            if m {
                for k in 0..3 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
        }
        let diag =
            ((hi[0] - lo[0]).powi(2) + (hi[1] - lo[1]).powi(2) + (hi[2] - lo[2]).powi(2)).sqrt();
        wall_len = if diag.is_finite() { scale * diag } else { 0.0 };
        vol_factor = distance.unwrap_or_else(|| edge_distance(adj, x, moving));
    }
    if kind == Stiffness::Volume {
        let n = x.len();
        let mut sum = vec![0.0; n];
        let mut cnt = vec![0u32; n];
        let mut total = 0.0;
        let mut ncell = 0usize;
        for t in mesh.tets() {
            let v = mesh::quality::tet_volume([
                x[t[0] as usize],
                x[t[1] as usize],
                x[t[2] as usize],
                x[t[3] as usize],
            ])
            .abs();
            total += v;
            ncell += 1;
            for &i in t {
                sum[i as usize] += v;
                cnt[i as usize] += 1;
            }
        }
        for t in mesh.triangles() {
            let p = |i: u32| Vector3::from(x[i as usize]);
            let v = 0.5 * (p(t[1]) - p(t[0])).cross(&(p(t[2]) - p(t[0]))).norm();
            total += v;
            ncell += 1;
            for &i in t {
                sum[i as usize] += v;
                cnt[i as usize] += 1;
            }
        }
        let mean = if ncell > 0 { total / ncell as f64 } else { 1.0 };
        vol_factor = (0..n)
            .map(|i| {
                if cnt[i] > 0 && sum[i] > 0.0 {
                    mean / (sum[i] / cnt[i] as f64)
                } else {
                    1.0
                }
            })
            .collect();
    }
    // A power of two near 1 / diag^p (exact scaling; K is ~1 / length^p): the baseline
    // grid's size serves every state (any power of two would give the same solution).
    let diag = mesh.bbox_diagonal();
    let power = if kind == Stiffness::InverseLength {
        1
    } else {
        2
    };
    let scale = if diag.is_finite() && diag > 0.0 {
        2f64.powi(power * diag.log2().round() as i32)
    } else {
        1.0
    };
    Springs {
        x,
        kind,
        scale,
        vol_factor,
        wall_len,
    }
}

/// A = spring matrix on the unknowns (rows in solver order, parallel, deterministic).
///
/// Two passes over the rows, both in parallel: the row lengths (unknown neighbours), then,
/// per chunk of [`CHUNK`] rows, each row's entries written straight into its slice of the
/// output and sorted by column there (one scratch buffer per chunk, no allocation per row).
/// a_ii sums K_ij over the neighbours in adjacency order, whatever the thread count.
/// Fails, naming the spring of the lowest row, when a stiffness is not a normal positive f32
/// after scaling (coincident nodes, or lengths spanning ~19 orders of magnitude).
fn assemble(sys: &System, adj: &Adjacency, sp: &Springs) -> Result<SymMatrix<f32>> {
    let nu = sys.node_of.len();
    let is_unk = |j: u32| sys.unk_of[j as usize] != u32::MAX;
    let lens: Vec<usize> = sys
        .node_of
        .par_iter()
        .with_min_len(CHUNK)
        .map(|&i| {
            adj.neighbours(i as usize)
                .iter()
                .filter(|&&j| is_unk(j))
                .count()
        })
        .collect();
    let mut offsets = Vec::with_capacity(nu + 1);
    offsets.push(0usize);
    let mut total = 0;
    for l in lens {
        total += l;
        offsets.push(total);
    }
    let mut diag = vec![0.0; nu];
    let mut cols = vec![0u32; total];
    let mut vals = vec![0.0f32; total];
    // One (first row, diagonal, columns, values) piece per chunk of rows.
    let start = |r: usize| offsets[r];
    let pieces: Vec<_> = row_chunks(&mut diag, nu, CHUNK, |r| r)
        .into_iter()
        .zip(row_chunks(&mut cols, nu, CHUNK, start))
        .zip(row_chunks(&mut vals, nu, CHUNK, start))
        .enumerate()
        .map(|(k, ((d, c), v))| (k * CHUNK, d, c, v))
        .collect();
    // The first bad spring of each piece (pieces in row order: the first of them all).
    let bad = pieces.into_par_iter().find_map_first(|(lo, d, c, v)| {
        let base = offsets[lo];
        let mut bad = None;
        let mut row: Vec<(u32, f32)> = Vec::new();
        for (r, dk) in d.iter_mut().enumerate() {
            let k = lo + r;
            let i = sys.node_of[k] as usize;
            let mut s = 0.0;
            row.clear();
            for &j in adj.neighbours(i) {
                let kij = sp.k(i, j as usize);
                if !(kij as f32).is_normal() && bad.is_none() {
                    bad = Some((i, j, sp.scale * sp.k_exact(i, j as usize)));
                }
                s += kij;
                let u = sys.unk_of[j as usize];
                if u != u32::MAX {
                    row.push((u, -kij as f32));
                }
            }
            // Columns are distinct: the order is unique.
            row.sort_unstable_by_key(|e| e.0);
            *dk = s;
            let at = offsets[k] - base;
            for (q, &(cu, val)) in row.iter().enumerate() {
                c[at + q] = cu;
                v[at + q] = val;
            }
        }
        bad
    });
    if let Some((i, j, k)) = bad {
        return Err(Error::Stiffness {
            nodes: [i as u32, j],
            value: k,
        });
    }
    Ok(SymMatrix {
        diag,
        offsets,
        cols,
        vals,
    })
}

/// b_k = `extra(k, i)` + Σ_{j prescribed} K_ij v(j) for unknown k at node i, for a per-node
/// field v (the springs to prescribed nodes from [`couplings`]).
fn rhs<G, F>(sys: &System, cp: &Csr, v: G, extra: F) -> Vec<V3>
where
    G: Fn(usize) -> V3 + Sync,
    F: Fn(usize, usize) -> V3 + Sync,
{
    (0..sys.node_of.len())
        .into_par_iter()
        .with_min_len(CHUNK)
        .map(|k| {
            let mut s = extra(k, sys.node_of[k] as usize);
            let (nodes, kij) = cp.row(k);
            for (&j, &kij) in nodes.iter().zip(kij) {
                let vj = v(j as usize);
                for q in 0..3 {
                    s[q] += kij * vj[q];
                }
            }
            s
        })
        .collect()
}

/// The springs from each unknown to its prescribed neighbours (moving, fixed): row k (solver
/// order) holds the nodes j and K_ij, the coupling terms of the right-hand sides, evaluated
/// once per grid state. The springs between unknowns are A's off-diagonal entries
/// (a_ij = −K_ij).
fn couplings(sys: &System, adj: &Adjacency, sp: &Springs) -> Csr {
    Csr::from_rows(sys.node_of.len(), sys.unk_of.len(), |k, row| {
        let i = sys.node_of[k] as usize;
        for &j in adj.neighbours(i) {
            if sys.unk_of[j as usize] == u32::MAX {
                row.push((j, sp.k(i, j as usize)));
            }
        }
    })
}

/// (R − I) d for the rotation of the quaternion (u, w) scaled by any l > 0, l² = |u|² + w²
/// given: (2w (u×d) + 2 u×(u×d)) / l² — the unit quaternion's formula without the square
/// root of its normalisation.
#[inline]
fn rot_minus_id(u: [f64; 3], w: f64, l2: f64, d: [f64; 3]) -> V3 {
    let c = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let ud = c(u, d);
    let uud = c(u, ud);
    let f = 2.0 / l2;
    [
        f * (w * ud[0] + uud[0]),
        f * (w * ud[1] + uud[1]),
        f * (w * ud[2] + uud[2]),
    ]
}

/// Runs one linear solve with the chosen solver (preconditioner given for PCG).
fn solve_one(
    a: &SymMatrix<f32>,
    b: &[V3],
    x: &mut [V3],
    cons: &Constraints,
    pre: &Pre,
    opts: &DeformOptions,
    step_len: f64,
) -> SolveReport {
    solve_tol(a, b, x, cons, pre, opts, step_len, opts.rel_tol)
}

/// [`solve_one`] with the relative residual `rel_tol`.
#[allow(clippy::too_many_arguments)]
fn solve_tol(
    a: &SymMatrix<f32>,
    b: &[V3],
    x: &mut [V3],
    cons: &Constraints,
    pre: &Pre,
    opts: &DeformOptions,
    step_len: f64,
    rel_tol: f64,
) -> SolveReport {
    let so = SolveOptions {
        rel_tol,
        max_iters: opts.max_iters,
    };
    match pre {
        Pre::Amg(m) => pcg(a, b, x, m, cons, &so),
        Pre::Jacobi(m) => pcg(a, b, x, m, cons, &so),
        Pre::None => point_iteration(a, b, x, cons, 1.0, opts.step_rel_tol * step_len, &so),
    }
}

enum Pre<'a> {
    Amg(Amg<'a, f32>),
    Jacobi(Jacobi),
    None,
}

/// Everything of Eqs. 21 and 26 that depends only on the grid state an increment starts
/// from, built once per state: the spring matrix, its preconditioner, the couplings to
/// prescribed nodes and the skin elements' initial frames.
struct Base {
    /// The matrix (None when the multigrid hierarchy owns it).
    a: Option<SymMatrix<f32>>,
    pre: Pre<'static>,
    /// [`couplings`] at this state.
    couplings: Csr,
    /// Per skin element: S̄⁻¹ of its initial frame (Eq. 25) and its size (the weight of its
    /// rotation at its nodes); None for a degenerate element.
    skin: Vec<Option<(Matrix3<f64>, f64)>>,
}

impl Base {
    /// Springs at `x`, assembly of A and its preconditioner; `distance`: the wall distance
    /// at `x` when already computed (see [`springs`]).
    #[allow(clippy::too_many_arguments)]
    fn new(
        mesh: &Mesh,
        cls: &Classified,
        sys: &System,
        adj: &Adjacency,
        x: &[[f64; 3]],
        opts: &DeformOptions,
        times: &mut PhaseTimes,
        distance: Option<Vec<f64>>,
    ) -> Result<Self> {
        let t = Instant::now();
        let moving: Vec<bool> = if opts.stiffness == Stiffness::WallDistance {
            cls.roles
                .iter()
                .map(|r| matches!(r, NodeRole::Rigid(_) | NodeRole::Displaced(_)))
                .collect()
        } else {
            Vec::new()
        };
        let mut tt = Instant::now();
        let sp = springs(mesh, x, opts.stiffness, adj, &moving, distance);
        tr("springs", &mut tt);
        let a = assemble(sys, adj, &sp)?;
        let couplings = couplings(sys, adj, &sp);
        tr("assemble", &mut tt);
        let skin = if opts.adapt_rotation {
            cls.skin
                .par_iter()
                .with_min_len(256)
                .map(|e| {
                    let p = skin_points(e, x);
                    let p = &p[..e.len().min(3)];
                    Some((frame(p)?.try_inverse()?, element_size(p)))
                })
                .collect()
        } else {
            Vec::new()
        };
        times.assemble += t.elapsed().as_secs_f64();
        let t = Instant::now();
        let (a, pre) = match opts.solver {
            SolverKind::PcgMultigrid => {
                (None, Pre::Amg(Amg::new_owned(a, &AmgOptions::default())?))
            }
            SolverKind::PcgJacobi => {
                let j = Jacobi::new(&a);
                (Some(a), Pre::Jacobi(j))
            }
            SolverKind::PointIteration => (Some(a), Pre::None),
        };
        times.precond += t.elapsed().as_secs_f64();
        tr("precond", &mut tt);
        Ok(Self {
            a,
            pre,
            couplings,
            skin,
        })
    }

    fn matrix(&self) -> &SymMatrix<f32> {
        match (&self.a, &self.pre) {
            (Some(a), _) => a,
            (None, Pre::Amg(m)) => m.fine(),
            (None, _) => unreachable!("the matrix is kept unless the hierarchy owns it"),
        }
    }
}

struct StepOut {
    /// Final Δx and Eq. 26 solutions (the warm start of a later call; empty when nothing
    /// was solved).
    dx: Vec<V3>,
    qv: Vec<V3>,
    iterations: usize,
    rot_iterations: usize,
    residual: f64,
    amg: Option<AmgInfo>,
    slide_iterations: usize,
    slide_update: f64,
}

/// The constraints of the solve: the planes and seam lines of `sys`, and the tangent plane
/// or line of every node sliding on a support at its parameters `params`.
fn constraints(
    cls: &Classified,
    sys: &System,
    sup: Option<&Supports>,
    params: &[[f64; 2]],
) -> Result<Constraints> {
    let mut cons = sys.cons.clone();
    if let Some(sp) = sup {
        for (k, s) in cls.supports.iter().enumerate() {
            let u = sys.sup_unk[k];
            if u != u32::MAX {
                cons.items
                    .push((u, tangent_constraint(sp.db, s.node, s.kind, params[k])?));
            }
        }
    }
    Ok(cons)
}

/// One increment: moves `cur` from the state of fraction `s0` to the prescribed state `s1`.
#[allow(clippy::too_many_arguments)]
fn step(
    mesh: &Mesh,
    cls: &Classified,
    bc: &BoundaryConditions,
    sys: &System,
    adj: &Adjacency,
    cur: &mut [[f64; 3]],
    s: f64,
    opts: &DeformOptions,
    times: &mut PhaseTimes,
    sup: Option<&Supports>,
    params: &mut [[f64; 2]],
    base: Option<&Base>,
    warm: Option<&SolverState>,
    exact: Option<&[[f64; 3]]>,
) -> Result<StepOut> {
    let x0 = &mesh.coords;
    let n = cur.len();
    // Prescribed targets and displacements of this increment.
    let mut target: Vec<[f64; 3]> = cur.to_vec();
    let mut max_disp = 0.0f64;
    for i in 0..n {
        let t = match cls.roles[i] {
            NodeRole::Rigid(m) => cls.motions[m].apply(x0[i], s),
            NodeRole::Displaced(k) => {
                let d = bc.displacements[k].1;
                if s == 1.0 {
                    exact.map_or([x0[i][0] + d[0], x0[i][1] + d[1], x0[i][2] + d[2]], |p| {
                        p[k]
                    })
                } else {
                    [
                        x0[i][0] + s * d[0],
                        x0[i][1] + s * d[1],
                        x0[i][2] + s * d[2],
                    ]
                }
            }
            _ => continue,
        };
        target[i] = t;
        // The displacement target − cur (recomputed, not stored, by the right-hand side).
        let d = [t[0] - cur[i][0], t[1] - cur[i][1], t[2] - cur[i][2]];
        max_disp = max_disp.max((d[0].powi(2) + d[1].powi(2) + d[2].powi(2)).sqrt());
    }
    let mut out = StepOut {
        dx: Vec::new(),
        qv: Vec::new(),
        iterations: 0,
        rot_iterations: 0,
        residual: 0.0,
        amg: None,
        slide_iterations: 0,
        slide_update: 0.0,
    };
    if max_disp == 0.0 {
        // Nothing moves: the grid is unchanged, bit for bit.
        return Ok(out);
    }
    if sys.node_of.is_empty() {
        // Every node is prescribed: nothing to solve.
        cur.copy_from_slice(&target);
        return Ok(out);
    }
    let owned;
    let base = match base {
        Some(b) => b,
        None => {
            owned = Base::new(mesh, cls, sys, adj, cur, opts, times, None)?;
            &owned
        }
    };
    let a = base.matrix();
    let pre = &base.pre;
    if let Pre::Amg(m) = pre {
        out.amg = Some(m.info());
    }

    // R: unit quaternions per node (vector part, scalar part); identity by default.
    let t = Instant::now();
    let mut qv: Vec<V3> = vec![[0.0; 3]; n];
    let mut qw: Vec<f64> = vec![1.0; n];
    let mut any_rot = false;
    if opts.adapt_rotation && !cls.skin.is_empty() {
        let mut acc: Vec<[f64; 4]> = vec![[0.0; 4]; n];
        let mut touched = vec![false; n];
        // Per element (in parallel; the sums below run in element order): its rotation as
        // a quaternion and its size as the weight.
        let cur_ro: &[[f64; 3]] = cur;
        let rots: Vec<Option<([f64; 4], f64)>> = cls
            .skin
            .par_iter()
            .zip(&base.skin)
            .with_min_len(256)
            .map(|(e, f)| {
                let (inv0, size) = (*f)?;
                let k = e.len().min(3);
                let (p0, p1) = (skin_points(e, cur_ro), skin_points(e, &target));
                let r = if p0 == p1 {
                    Matrix3::identity()
                } else {
                    rotation_from_frame(&inv0, &p1[..k])?
                };
                let mut q = quat(&r);
                if mesh.dim == 2 {
                    // Plane grids rotate about z only (drop the round-off of the SVD).
                    let l = (q[2] * q[2] + q[3] * q[3]).sqrt();
                    q = [0.0, 0.0, q[2] / l, q[3] / l];
                }
                Some((q, size))
            })
            .collect();
        for (e, rot) in cls.skin.iter().zip(&rots) {
            let Some((q, w)) = *rot else {
                continue;
            };
            for &v in e {
                let a = &mut acc[v as usize];
                for k in 0..4 {
                    a[k] += w * q[k];
                }
                touched[v as usize] = true;
            }
        }
        for i in 0..n {
            if touched[i] {
                let a = acc[i];
                let l = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2] + a[3] * a[3]).sqrt();
                if l > 0.0 && (a[0], a[1], a[2]) != (0.0, 0.0, 0.0) {
                    qv[i] = [a[0] / l, a[1] / l, a[2] / l];
                    qw[i] = a[3] / l;
                    any_rot = true;
                }
            }
        }
        if any_rot {
            // Eq. 26 for the quaternions' vector part u (one three-component solve); the
            // scalar part follows from it, w = √(1 − |u|²) ≥ 0 (the discrete maximum
            // principle keeps |u| ≤ 1 up to the solver tolerance: clamped), so no second
            // solve is needed (see the module doc).
            drop((acc, touched));
            let bv = rhs(sys, &base.couplings, |j| qv[j], |_, _| [0.0; 3]);
            let nu = sys.node_of.len();
            // u = 0 (R = I) as the start, or the previous solution when warm.
            let mut xv = match warm {
                Some(w) if w.qv.len() == nu => w.qv.clone(),
                _ => vec![[0.0; 3]; nu],
            };
            let rv = solve_one(a, &bv, &mut xv, &Constraints::default(), pre, opts, 1.0);
            drop(bv);
            out.rot_iterations = rv.iterations;
            for (k, &i) in sys.node_of.iter().enumerate() {
                let v = xv[k];
                let s2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
                let (u, w) = if s2 <= 1.0 {
                    (v, (1.0 - s2).sqrt())
                } else {
                    let l = s2.sqrt();
                    ([v[0] / l, v[1] / l, v[2] / l], 0.0)
                };
                qv[i as usize] = u;
                qw[i as usize] = w;
            }
            out.qv = xv;
        }
    }
    times.rotation += t.elapsed().as_secs_f64();

    // Eq. 21 right-hand side.
    let t = Instant::now();
    let cur_ro: &[[f64; 3]] = cur;
    let disp = |j: usize| {
        let (t, c) = (target[j], cur_ro[j]);
        [t[0] - c[0], t[1] - c[1], t[2] - c[2]]
    };
    // −Σ_j K_ij (R_ij − I)(x_j − x_i) over every neighbour j of node i: the unknown ones
    // from A's row k (a_kl = −K_ij), then the prescribed ones.
    let r_term = |i: usize, j: usize| {
        let u = [
            qv[i][0] + qv[j][0],
            qv[i][1] + qv[j][1],
            qv[i][2] + qv[j][2],
        ];
        let w = qw[i] + qw[j];
        let l2 = u[0] * u[0] + u[1] * u[1] + u[2] * u[2] + w * w;
        if l2 == 0.0 {
            return [0.0; 3];
        }
        let d = [
            cur_ro[j][0] - cur_ro[i][0],
            cur_ro[j][1] - cur_ro[i][1],
            cur_ro[j][2] - cur_ro[i][2],
        ];
        rot_minus_id(u, w, l2, d)
    };
    let b = rhs(sys, &base.couplings, disp, |k, i| {
        let mut s = [0.0; 3];
        if !any_rot {
            return s;
        }
        let (cols, vals) = a.row(k);
        for (&c, &akl) in cols.iter().zip(vals) {
            let akl = f64::from(akl);
            let r = r_term(i, sys.node_of[c as usize] as usize);
            for q in 0..3 {
                s[q] += akl * r[q];
            }
        }
        let (nodes, kij) = base.couplings.row(k);
        for (&j, &kij) in nodes.iter().zip(kij) {
            let r = r_term(i, j as usize);
            for q in 0..3 {
                s[q] -= kij * r[q];
            }
        }
        s
    });
    let mut b = b;
    if mesh.dim == 2 {
        // Plane grids stay in their plane.
        for v in b.iter_mut() {
            v[2] = 0.0;
        }
    }
    times.assemble += t.elapsed().as_secs_f64();

    let t = Instant::now();
    let nu = sys.node_of.len();
    let mut dx = match warm {
        Some(w) if w.dx.len() == nu => w.dx.clone(),
        _ => vec![[0.0; 3]; nu],
    };
    // The starting guess: the outer iteration of the sliding measures its updates from it.
    let dx0 = dx.clone();
    let sliding_on_supports = sup.is_some() && sys.sup_unk.iter().any(|&u| u != u32::MAX);
    let cons = if sliding_on_supports {
        constraints(cls, sys, sup, params)?
    } else {
        sys.cons.clone()
    };
    let rep = solve_one(a, &b, &mut dx, &cons, pre, opts, max_disp);
    let check = |rep: &SolveReport, what: &str| {
        let ok = match opts.solver {
            SolverKind::PointIteration => rep.iterations < opts.max_iters,
            _ => rep.converged,
        };
        if ok {
            Ok(())
        } else {
            Err(Error::NoConvergence {
                what: what.into(),
                solver: rep.solver.clone(),
                iterations: rep.iterations,
                residual: rep.rel_residual,
            })
        }
    };
    check(&rep, "spring system (Eq. 21)")?;
    out.iterations = rep.iterations;
    out.residual = rep.rel_residual;
    if let (true, Some(sp)) = (sliding_on_supports, sup) {
        // Outer iteration of the sliding on supports (Eqs. 27–33): place every sliding node
        // on its support nearest to its tentative position (parameters by Eq. 31 / 28),
        // re-linearise the constraints there and solve for the correction, until the largest
        // node update is ≤ slide_rel_tol × the largest boundary displacement.
        let scale = mesh.bbox_diagonal();
        let bnorm = norm(&b);
        let mut base = dx0;
        let mut converged = false;
        let mut update = f64::INFINITY;
        for outer in 1..=opts.max_slide_iters.max(1) {
            // Place the sliding nodes.
            for (k, sn) in cls.supports.iter().enumerate() {
                let u = sys.sup_unk[k];
                if u == u32::MAX {
                    continue;
                }
                let i = sn.node as usize;
                let d = dx[u as usize];
                let tgt = [cur[i][0] + d[0], cur[i][1] + d[1], cur[i][2] + d[2]];
                let p = place(sp.db, sn.node, sn.kind, params[k], tgt, 1e-14 * scale)?;
                params[k] = p;
                let r = point(sp.db, sn.kind, p);
                dx[u as usize] = [r[0] - cur[i][0], r[1] - cur[i][1], r[2] - cur[i][2]];
            }
            // Largest node update of this iteration.
            let mut upd = 0.0f64;
            for (d, b0) in dx.iter().zip(base.iter_mut()) {
                let e = ((d[0] - b0[0]).powi(2) + (d[1] - b0[1]).powi(2) + (d[2] - b0[2]).powi(2))
                    .sqrt();
                upd = upd.max(e);
                *b0 = *d;
            }
            update = upd / max_disp;
            out.slide_iterations = outer;
            if upd <= opts.slide_rel_tol * max_disp {
                converged = true;
                break;
            }
            // Correction: A δ = b − A Δx, δ in the tangent spaces at the new parameters.
            let cons = constraints(cls, sys, Some(sp), params)?;
            let mut r = vec![[0.0; 3]; nu];
            a.residual(&b, &dx, &mut r);
            let mut rp = r.clone();
            cons.project(&mut rp);
            let rn = norm(&rp);
            let tol = if rn > 0.0 {
                (opts.rel_tol * bnorm / rn).min(0.5)
            } else {
                0.5
            };
            let mut delta = vec![[0.0; 3]; nu];
            let rep = solve_tol(a, &r, &mut delta, &cons, pre, opts, max_disp, tol);
            check(&rep, "spring system (Eq. 21), sliding correction")?;
            out.iterations += rep.iterations;
            for (d, e) in dx.iter_mut().zip(&delta) {
                for q in 0..3 {
                    d[q] += e[q];
                }
            }
        }
        out.slide_update = update;
        if !converged {
            return Err(Error::NoConvergence {
                what: format!(
                    "sliding on supports (Eqs. 27–33): largest node update {update:.3e} × the boundary displacement after"
                ),
                solver: "outer iteration".into(),
                iterations: out.slide_iterations,
                residual: update,
            });
        }
    }
    times.solve += t.elapsed().as_secs_f64();
    for (k, &i) in sys.node_of.iter().enumerate() {
        let c = &mut cur[i as usize];
        for q in 0..3 {
            c[q] += dx[k][q];
        }
    }
    out.dx = dx;
    if let (true, Some(sp)) = (sliding_on_supports, sup) {
        // Exactly on the support.
        for (k, sn) in cls.supports.iter().enumerate() {
            if sys.sup_unk[k] != u32::MAX {
                cur[sn.node as usize] = point(sp.db, sn.kind, params[k]);
            }
        }
    }
    for i in 0..n {
        if matches!(cls.roles[i], NodeRole::Rigid(_) | NodeRole::Displaced(_)) {
            cur[i] = target[i];
        }
    }
    Ok(out)
}

/// The (up to three) nodes of skin element `e` at coordinates `x` (unused slots zero).
#[inline]
fn skin_points(e: &[u32], x: &[[f64; 3]]) -> [[f64; 3]; 3] {
    let mut p = [[0.0; 3]; 3];
    for (q, &v) in p.iter_mut().zip(e) {
        *q = x[v as usize];
    }
    p
}

fn element_size(p: &[[f64; 3]]) -> f64 {
    let v = |a: [f64; 3]| Vector3::from(a);
    if p.len() >= 3 {
        0.5 * (v(p[1]) - v(p[0])).cross(&(v(p[2]) - v(p[0]))).norm()
    } else {
        (v(p[1]) - v(p[0])).norm()
    }
}

/// Unit quaternion [x, y, z, w] of a rotation matrix, with w ≥ 0.
fn quat(r: &Matrix3<f64>) -> [f64; 4] {
    if *r == Matrix3::identity() {
        return [0.0, 0.0, 0.0, 1.0];
    }
    let q = UnitQuaternion::from_rotation_matrix(&nalgebra::Rotation3::from_matrix_unchecked(*r));
    let c = q.coords; // (i, j, k, w)
    let s = if c[3] < 0.0 { -1.0 } else { 1.0 };
    [s * c[0], s * c[1], s * c[2], s * c[3]]
}

/// Deforms the volume grid for the boundary conditions `bc` (Eqs. 14–26 and 34), with the
/// quality guard; returns the new coordinates (input numbering) and a report.
pub fn deform(mesh: &Mesh, bc: &BoundaryConditions, opts: &DeformOptions) -> Result<Deformed> {
    deform_with_progress(mesh, bc, opts, &mut |_, _, _| {})
}

/// Morton (Z-order) numbering of the nodes from their coordinates, 21 bits per axis over the
/// bounding box; returns `perm` with node `i` → new index `perm[i]` (ties by index, so the
/// order is deterministic).
pub fn spatial_order(coords: &[[f64; 3]]) -> Vec<u32> {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in coords {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let spread = |v: u64| {
        let mut x = v & 0x1f_ffff;
        x = (x | (x << 32)) & 0x1f_0000_0000_ffff;
        x = (x | (x << 16)) & 0x1f_0000_ff00_00ff;
        x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
        x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
        x = (x | (x << 2)) & 0x1249_2492_4924_9249;
        x
    };
    let mut keys: Vec<(u64, u32)> = coords
        .par_iter()
        .enumerate()
        .map(|(i, p)| {
            let mut code = 0u64;
            for k in 0..3 {
                let w = hi[k] - lo[k];
                let q = if w > 0.0 {
                    ((p[k] - lo[k]) / w * 2_097_151.0) as u64
                } else {
                    0
                };
                code |= spread(q) << k;
            }
            (code, i as u32)
        })
        .collect();
    keys.par_sort_unstable();
    let mut perm = vec![0u32; coords.len()];
    for (new, &(_, old)) in keys.iter().enumerate() {
        perm[old as usize] = new as u32;
    }
    perm
}

/// Breadth-first (Cuthill–McKee level-set, without its degree sort) numbering of the graph:
/// returns `perm` with node `i` → new index `perm[i]`; each connected component from its
/// lowest node, neighbours in increasing order. Applied to the Morton-ordered grid (whose
/// node 0 is at a corner of the domain), it keeps each node's neighbours within about two
/// level sets of it: at 1M nodes the spring matrix's product then takes about half the time
/// it takes in Morton order, whose jumps between the curve's blocks scatter the neighbours
/// (docs/performance.md).
pub fn level_order(adj: &Adjacency) -> Vec<u32> {
    let n = adj.n_nodes();
    let mut seen = vec![false; n];
    let mut order: Vec<u32> = Vec::with_capacity(n);
    for s0 in 0..n {
        if seen[s0] {
            continue;
        }
        seen[s0] = true;
        let mut head = order.len();
        order.push(s0 as u32);
        while head < order.len() {
            let i = order[head] as usize;
            head += 1;
            for &j in adj.neighbours(i) {
                if !seen[j as usize] {
                    seen[j as usize] = true;
                    order.push(j);
                }
            }
        }
    }
    inverse(&order)
}

/// The adjacency of the grid renumbered by `perm` (node `i` → `perm[i]`), rows sorted; the
/// same as [`Adjacency::build`] on the renumbered grid.
fn permuted_adjacency(adj: &Adjacency, perm: &[u32]) -> Adjacency {
    let n = adj.n_nodes();
    let old_of = inverse(perm);
    let mut offsets = Vec::with_capacity(n + 1);
    offsets.push(0usize);
    let mut total = 0;
    for &o in &old_of {
        total += adj.neighbours(o as usize).len();
        offsets.push(total);
    }
    let mut indices = vec![0u32; total];
    let pieces = row_chunks(&mut indices, n, CHUNK, |r| offsets[r]);
    pieces.into_par_iter().enumerate().for_each(|(k, piece)| {
        let (lo, hi) = (k * CHUNK, ((k + 1) * CHUNK).min(n));
        let base = offsets[lo];
        for r in lo..hi {
            let row = &mut piece[offsets[r] - base..offsets[r + 1] - base];
            for (d, &j) in row.iter_mut().zip(adj.neighbours(old_of[r] as usize)) {
                *d = perm[j as usize];
            }
            row.sort_unstable();
        }
    });
    Adjacency { offsets, indices }
}

/// Renumbers the set-up's grid, boundary conditions and support nodes: node `i` becomes
/// `perm[i]` (support entries of nodes outside the grid are dropped: classification has
/// refused them wherever supports are used).
fn renumber_set_up(
    m: &mut Mesh,
    bc: &mut BoundaryConditions,
    sup: &mut Option<Supports>,
    perm: &[u32],
) -> Result<()> {
    m.renumber_nodes(perm).map_err(|e| Error::BadGraph {
        reason: e.to_string(),
    })?;
    for (v, _) in &mut bc.displacements {
        *v = perm[*v as usize];
    }
    if let Some(sp) = sup {
        sp.nodes.retain(|(v, _)| (*v as usize) < perm.len());
        for (v, _) in &mut sp.nodes {
            *v = perm[*v as usize];
        }
    }
    Ok(())
}

/// [`deform`] calling `progress(phase, done, total)` as it goes.
///
/// With `opts.renumber`, the grid is first renumbered internally along a Morton curve (so a
/// randomly numbered input runs about as fast as a well-ordered one), then in breadth-first
/// order ([`level_order`]), and the unknowns keep that order; the result is returned in the
/// input numbering.
pub fn deform_with_progress(
    mesh: &Mesh,
    bc: &BoundaryConditions,
    opts: &DeformOptions,
    progress: &mut dyn FnMut(&str, usize, usize),
) -> Result<Deformed> {
    deform_driver(mesh, bc, None, opts, progress)
}

/// [`deform`] with nodes sliding on the support curves and surfaces of a geometry (paper
/// §4.3, Eqs. 27–33): the nodes of every [`crate::MarkerRole::SlideOnSupport`] marker slide
/// on the support `supports` gives them (corners frozen), by the precedence of
/// [`crate::bc`] (moving > sliding on a curve > sliding on a surface > fixed). The sliding
/// nodes end exactly on their supports; their final parameters are returned in
/// [`Deformed::supports`].
pub fn deform_on_supports(
    mesh: &Mesh,
    bc: &BoundaryConditions,
    supports: &Supports,
    opts: &DeformOptions,
) -> Result<Deformed> {
    deform_driver(mesh, bc, Some(supports), opts, &mut |_, _, _| {})
}

/// [`deform_on_supports`] calling `progress(phase, done, total)` as it goes.
pub fn deform_on_supports_with_progress(
    mesh: &Mesh,
    bc: &BoundaryConditions,
    supports: &Supports,
    opts: &DeformOptions,
    progress: &mut dyn FnMut(&str, usize, usize),
) -> Result<Deformed> {
    deform_driver(mesh, bc, Some(supports), opts, progress)
}

fn deform_driver(
    mesh: &Mesh,
    bc: &BoundaryConditions,
    sup: Option<&Supports>,
    opts: &DeformOptions,
    progress: &mut dyn FnMut(&str, usize, usize),
) -> Result<Deformed> {
    let d = Deformer::build(mesh, bc, sup, opts, progress)?;
    let values: Vec<[f64; 3]> = bc.displacements.iter().map(|e| e.1).collect();
    let mut out = d.run(Prescribed::Displacements(&values), None, progress)?;
    let s = &mut out.report.seconds;
    s.setup += d.setup.setup;
    s.assemble += d.setup.assemble;
    s.precond += d.setup.precond;
    s.quality += d.setup.quality;
    Ok(out)
}

/// The prescribed values given to [`Deformer`]: displacements or new positions.
#[derive(Clone, Copy)]
enum Prescribed<'a> {
    Displacements(&'a [[f64; 3]]),
    Positions(&'a [[f64; 3]]),
}

/// A reusable deformation set-up: everything that depends only on the baseline grid and on
/// the boundary-condition roles, built once by [`Deformer::new`] — node classification and
/// sliding-plane fits, adjacency, the renumbering (Morton, then [`level_order`]; also the
/// unknowns' order), the
/// spring stiffnesses at the baseline geometry, the matrix A of Eq. 21 and its
/// preconditioner (multigrid hierarchy or Jacobi diagonal), the baseline quality.
///
/// [`Deformer::deform`] then takes new values for the prescribed displacements (same nodes,
/// same order as the set-up's [`BoundaryConditions::displacements`]) and reuses all of it for
/// the first increment, which starts from the baseline grid — so the matrix there is exactly
/// the baseline one and the result is bit for bit that of the free [`deform`]. The rotation
/// field R (Eqs. 25–26) only changes the right-hand side of Eq. 21, never A, so nothing is
/// approximated. When the quality guard splits the motion into increments, the increments
/// after the first start from a deformed state and assemble their own A and preconditioner.
pub struct Deformer<'s> {
    /// The grid in solver numbering (renumbered with `opts.renumber`).
    mesh: Mesh,
    /// Input node → solver node (None without renumbering).
    perm: Option<Vec<u32>>,
    /// Solver node → input node (empty without renumbering).
    inv: Vec<u32>,
    /// The boundary conditions in solver numbering.
    bc: BoundaryConditions,
    sup: Option<Supports<'s>>,
    opts: DeformOptions,
    cls: Classified,
    adj: Adjacency,
    sys: System,
    before: QualitySummary,
    /// A and its preconditioner at the baseline (None when there is no unknown).
    base: Option<Base>,
    setup: PhaseTimes,
}

impl Deformer<'static> {
    /// Builds the set-up for `bc` on `mesh` (the displacement values of `bc` are not used;
    /// only which nodes are prescribed).
    pub fn new(mesh: &Mesh, bc: &BoundaryConditions, opts: &DeformOptions) -> Result<Self> {
        Deformer::build(mesh, bc, None, opts, &mut |_, _, _| {})
    }
}

impl<'s> Deformer<'s> {
    /// [`Deformer::new`] with nodes sliding on geometry supports (as
    /// [`deform_on_supports`]).
    pub fn on_supports(
        mesh: &Mesh,
        bc: &BoundaryConditions,
        supports: &Supports<'s>,
        opts: &DeformOptions,
    ) -> Result<Self> {
        Deformer::build(mesh, bc, Some(supports), opts, &mut |_, _, _| {})
    }

    /// Seconds spent by the set-up (classification, ordering, assembly, preconditioner,
    /// baseline quality).
    pub fn setup_times(&self) -> PhaseTimes {
        self.setup
    }

    /// Number of prescribed displacements [`Deformer::deform`] expects.
    pub fn n_displacements(&self) -> usize {
        self.bc.displacements.len()
    }

    fn build(
        mesh: &Mesh,
        bc: &BoundaryConditions,
        sup: Option<&Supports<'s>>,
        opts: &DeformOptions,
        progress: &mut dyn FnMut(&str, usize, usize),
    ) -> Result<Self> {
        let mut times = PhaseTimes::default();
        let t = Instant::now();
        progress("setup", 0, 1);
        let renumber = opts.renumber && mesh.n_nodes() >= 2;
        let mut tt = Instant::now();
        let (mut m2, mut bc2, mut sup2) = (mesh.clone(), bc.clone(), sup.cloned());
        tr("clone", &mut tt);
        let (mut perm, moving) = if renumber {
            // Validate in the user's numbering first, so that errors name the user's nodes.
            let c1 = classify(mesh, bc, opts.plane_rel_tol, sup)?;
            tr("classify1", &mut tt);
            let perm = spatial_order(&mesh.coords);
            tr("morton", &mut tt);
            // The moving nodes (sources of the wall distance), in Morton numbering.
            let mut moving = Vec::new();
            if opts.stiffness == Stiffness::WallDistance {
                moving = vec![false; perm.len()];
                for (r, &p) in c1.roles.iter().zip(&perm) {
                    moving[p as usize] = matches!(r, NodeRole::Rigid(_) | NodeRole::Displaced(_));
                }
            }
            renumber_set_up(&mut m2, &mut bc2, &mut sup2, &perm)?;
            tr("renumber", &mut tt);
            (Some(perm), moving)
        } else {
            (None, Vec::new())
        };
        tt = Instant::now();
        let mut adj = Adjacency::try_build(&m2).map_err(|e| Error::BadGraph {
            reason: e.to_string(),
        })?;
        tr("adjacency", &mut tt);
        // The wall distance of the set-up's springs, when computed beside the level order.
        let mut distance = None;
        if let Some(perm) = perm.as_mut() {
            // Then breadth-first order (see `level_order`): node k → level[k]. The wall
            // distance (a sequential Dijkstra) runs beside it on the Morton-numbered grid: it
            // does not depend on the numbering (a node's distance is the smallest d + l of
            // its neighbours, the same sums in any order), so it is the one `springs` would
            // compute, permuted.
            let (d, (level, permuted)) = rayon::join(
                || (!moving.is_empty()).then(|| edge_distance(&adj, &m2.coords, &moving)),
                || {
                    let level = level_order(&adj);
                    let permuted = permuted_adjacency(&adj, &level);
                    (level, permuted)
                },
            );
            drop(moving);
            renumber_set_up(&mut m2, &mut bc2, &mut sup2, &level)?;
            adj = permuted;
            distance = d.map(|d| {
                let mut out = vec![0.0; d.len()];
                for (&l, v) in level.iter().zip(d) {
                    out[l as usize] = v;
                }
                out
            });
            for p in perm.iter_mut() {
                *p = level[*p as usize];
            }
            tr("level order", &mut tt);
        }
        // Solver node → input node.
        let inv = perm.as_deref().map_or_else(Vec::new, inverse);
        let cls = classify(&m2, &bc2, opts.plane_rel_tol, sup2.as_ref())?;
        tr("classify2", &mut tt);
        let sys = build_system(&cls, &adj);
        tr("build_system", &mut tt);
        times.setup = t.elapsed().as_secs_f64();
        let t = Instant::now();
        tt = Instant::now();
        let q0 = cell_quality(&m2, &m2.coords);
        tr("quality", &mut tt);
        let before = QualitySummary::of(&q0);
        tr("summary", &mut tt);
        times.quality += t.elapsed().as_secs_f64();
        let base = if sys.node_of.is_empty() {
            None
        } else {
            Some(
                Base::new(
                    &m2, &cls, &sys, &adj, &m2.coords, opts, &mut times, distance,
                )
                .map_err(|e| e.renumbered(&inv))?,
            )
        };
        Ok(Self {
            mesh: m2,
            perm,
            inv,
            bc: bc2,
            sup: sup2,
            opts: *opts,
            cls,
            adj,
            sys,
            before,
            base,
            setup: times,
        })
    }

    /// Deforms the grid for the prescribed displacements `displacements` (one per entry of
    /// the set-up's `bc.displacements`, same order), reusing the set-up. Report times exclude
    /// the set-up ([`Deformer::setup_times`]).
    ///
    /// `warm_start`: an earlier result of this set-up whose solution is the initial guess of
    /// the Eq. 26 solves (R), of the Eq. 21 solve and of the parameters of the nodes sliding
    /// on supports (single increment only). Without it every solve starts from zero (R = I,
    /// baseline parameters) and the answer is bit for bit that of [`deform`]; with it the
    /// answer agrees with that one to the solver tolerances (`rel_tol`, `slide_rel_tol`) and
    /// takes fewer iterations when the motions are close — the same motion again takes none.
    pub fn deform(
        &self,
        displacements: &[[f64; 3]],
        warm_start: Option<&Deformed>,
    ) -> Result<Deformed> {
        self.run(
            Prescribed::Displacements(displacements),
            warm_start,
            &mut |_, _, _| {},
        )
    }

    /// [`Deformer::deform`] with the prescribed nodes' new positions instead of their
    /// displacements (same order): the displacements are `positions − x⁰`, and the returned
    /// grid has these nodes exactly at `positions` (x⁰ + (p − x⁰) may differ from p by
    /// round-off), so that its cell quality is that of a grid whose boundary is exactly the
    /// caller's.
    pub fn deform_to(
        &self,
        positions: &[[f64; 3]],
        warm_start: Option<&Deformed>,
    ) -> Result<Deformed> {
        self.run(
            Prescribed::Positions(positions),
            warm_start,
            &mut |_, _, _| {},
        )
    }

    /// [`Deformer::deform`] calling `progress(phase, done, total)` as it goes.
    pub fn deform_with_progress(
        &self,
        displacements: &[[f64; 3]],
        warm_start: Option<&Deformed>,
        progress: &mut dyn FnMut(&str, usize, usize),
    ) -> Result<Deformed> {
        self.run(
            Prescribed::Displacements(displacements),
            warm_start,
            progress,
        )
    }

    fn run(
        &self,
        values: Prescribed,
        warm_start: Option<&Deformed>,
        progress: &mut dyn FnMut(&str, usize, usize),
    ) -> Result<Deformed> {
        // `exact`: the positions the prescribed nodes must end at, when given.
        let (given, what, exact) = match values {
            Prescribed::Displacements(d) => (d, "displacement", None),
            Prescribed::Positions(p) => (p, "position", Some(p)),
        };
        if given.len() != self.bc.displacements.len() {
            return Err(Error::BadMotion {
                reason: format!(
                    "{} {what}s given; the deformation set-up has {} prescribed nodes",
                    given.len(),
                    self.bc.displacements.len()
                ),
            });
        }
        let mut bc = self.bc.clone();
        for ((v, d), &new) in bc.displacements.iter_mut().zip(given) {
            if !new.iter().all(|x| x.is_finite()) {
                let v = self.perm.as_ref().map_or(*v, |_| self.inv[*v as usize]);
                return Err(Error::BadMotion {
                    reason: format!("node {v}: {what} {new:?} is not finite"),
                });
            }
            *d = if exact.is_some() {
                let x0 = self.mesh.coords[*v as usize];
                [new[0] - x0[0], new[1] - x0[1], new[2] - x0[2]]
            } else {
                new
            };
        }
        let shape = (self.mesh.n_nodes(), self.sys.node_of.len());
        let warm = match warm_start {
            Some(w) if w.state.shape != shape => {
                return Err(Error::BadMotion {
                    reason: format!(
                        "warm start from a deformation of {} nodes and {} unknowns; this set-up has {} and {}",
                        w.state.shape.0, w.state.shape.1, shape.0, shape.1
                    ),
                });
            }
            w => w.map(|w| &w.state),
        };
        let mut d = self
            .run_inner(&bc, warm, exact, progress)
            .map_err(|e| e.renumbered(&self.inv))?;
        if let Some(perm) = &self.perm {
            d.coords = perm.iter().map(|&p| d.coords[p as usize]).collect();
            for (v, _) in d.supports.iter_mut() {
                *v = self.inv[*v as usize];
            }
            d.supports.sort_by_key(|e| e.0);
        }
        Ok(d)
    }

    fn run_inner(
        &self,
        bc: &BoundaryConditions,
        warm: Option<&SolverState>,
        exact: Option<&[[f64; 3]]>,
        progress: &mut dyn FnMut(&str, usize, usize),
    ) -> Result<Deformed> {
        let (mesh, cls, sys, adj, opts) = (&self.mesh, &self.cls, &self.sys, &self.adj, &self.opts);
        let sup = self.sup.as_ref();
        let before = self.before;
        let mut times = PhaseTimes::default();
        let mut attempts = Vec::new();
        let mut notes = Vec::new();
        let mut inc = 1usize;
        loop {
            attempts.push(inc);
            let mut cur = mesh.coords.clone();
            let mut params: Vec<[f64; 2]> = match warm {
                Some(w) if inc == 1 && w.params.len() == cls.supports.len() => w.params.clone(),
                _ => cls.supports.iter().map(|s| s.param).collect(),
            };
            let mut state = SolverState {
                shape: (mesh.n_nodes(), sys.node_of.len()),
                ..SolverState::default()
            };
            let mut slide_iterations = 0;
            let mut slide_update = 0.0f64;
            let mut iterations = 0;
            let mut rot_iterations = 0;
            let mut residual = 0.0f64;
            let mut amg = None;
            for m in 1..=inc {
                progress("solve", m - 1, inc);
                let s = if m == inc { 1.0 } else { m as f64 / inc as f64 };
                let o = step(
                    mesh,
                    cls,
                    bc,
                    sys,
                    adj,
                    &mut cur,
                    s,
                    opts,
                    &mut times,
                    sup,
                    &mut params,
                    // The first increment starts from the baseline: its A is the set-up's.
                    if m == 1 { self.base.as_ref() } else { None },
                    if inc == 1 { warm } else { None },
                    exact,
                )?;
                slide_iterations += o.slide_iterations;
                slide_update = slide_update.max(o.slide_update);
                iterations += o.iterations;
                rot_iterations += o.rot_iterations;
                residual = residual.max(o.residual);
                if o.amg.is_some() {
                    amg = o.amg;
                }
                if inc == 1 {
                    // The solutions from the baseline (later increments start elsewhere).
                    (state.dx, state.qv) = (o.dx, o.qv);
                }
            }
            progress("quality", inc, inc);
            let t = Instant::now();
            let mut tt = Instant::now();
            let q1 = cell_quality(mesh, &cur);
            tr("quality after", &mut tt);
            let after = QualitySummary::of(&q1);
            tr("summary after", &mut tt);
            times.quality += t.elapsed().as_secs_f64();
            let low = after.min < opts.min_quality_ratio * before.min;
            let bad = after.inverted > before.inverted || low;
            if bad && inc < opts.max_increments {
                notes.push(format!(
                "{inc} increment(s): {} inverted cells, min quality {:.4} (initial {:.4}); retrying with {}",
                after.inverted,
                after.min,
                before.min,
                inc * 2
            ));
                inc *= 2;
                continue;
            }
            if after.inverted > before.inverted {
                let worst = worst_cells(&q1, 5);
                if !opts.allow_inverted {
                    return Err(Error::Inverted {
                        count: after.inverted,
                        increments: inc,
                        worst,
                    });
                }
                notes.push(format!(
                    "{} inverted cells kept (allowed); worst: {worst}",
                    after.inverted
                ));
            } else if low {
                notes.push(format!(
                    "minimum quality {:.4} is below {} × initial {:.4} after {inc} increments",
                    after.min, opts.min_quality_ratio, before.min
                ));
            }
            let nmov = cls
                .roles
                .iter()
                .filter(|r| matches!(r, NodeRole::Rigid(_) | NodeRole::Displaced(_)))
                .count();
            let report = DeformReport {
                nodes: mesh.n_nodes(),
                cells: mesh.cells.len(),
                unknowns: sys.node_of.len(),
                sliding: sys.cons.items.len(),
                sliding_on_supports: cls.supports.len(),
                slide_iterations,
                slide_update,
                moving: nmov,
                planes: cls.planes.clone(),
                increments: inc,
                attempts,
                iterations,
                rotation_iterations: rot_iterations,
                residual,
                solver: opts.solver,
                multigrid: amg,
                quality_before: before,
                quality_after: after,
                seconds: times,
                notes,
            };
            let supports = cls
                .supports
                .iter()
                .zip(&params)
                .map(|(sn, p)| {
                    let s = match sn.kind {
                        SupKind::Curve(curve) => Support::Curve { curve, t: p[0] },
                        SupKind::Surface(surface) => Support::Surface { surface, uv: *p },
                    };
                    (sn.node, s)
                })
                .collect();
            state.params = params;
            if inc > 1 {
                // Δx from the baseline of the whole motion.
                state.dx = sys
                    .node_of
                    .iter()
                    .map(|&i| {
                        let (p, q) = (cur[i as usize], mesh.coords[i as usize]);
                        [p[0] - q[0], p[1] - q[1], p[2] - q[2]]
                    })
                    .collect();
            }
            return Ok(Deformed {
                coords: cur,
                supports,
                cell_quality: q1,
                report,
                state,
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn level_order_keeps_neighbours_close_and_permutes_the_adjacency_exactly() {
        // A 20 × 18 × 16 box grid numbered at random, then Morton-ordered as `Deformer` does.
        let mut m = crate::generate::box_with_block(
            [20, 18, 16],
            [0.0; 3],
            [1.0, 0.9, 0.8],
            [8, 7, 6],
            [12, 11, 10],
        );
        mesh::generate::shuffle_nodes(&mut m, 11);
        m.renumber_nodes(&spatial_order(&m.coords)).unwrap();
        let adj = Adjacency::build(&m);
        let bandwidth = |a: &Adjacency| {
            (0..a.n_nodes())
                .flat_map(|i| a.neighbours(i).iter().map(move |&j| i.abs_diff(j as usize)))
                .max()
                .unwrap()
        };
        let level = level_order(&adj);
        let mut seen = vec![false; level.len()];
        for &p in &level {
            assert!(!std::mem::replace(&mut seen[p as usize], true));
        }
        let mut m2 = m.clone();
        m2.renumber_nodes(&level).unwrap();
        let permuted = permuted_adjacency(&adj, &level);
        assert_eq!(permuted, Adjacency::build(&m2));
        // Two level sets (diagonal sections from a corner) of the 20 × 18 × 16 grid hold at
        // most ~3 × 20 × 18 nodes; the Morton curve's jumps reach across most of the grid.
        let (before, after) = (bandwidth(&adj), bandwidth(&permuted));
        assert!(
            after < 3 * 20 * 18 && after * 4 < before,
            "{before} -> {after}"
        );
    }

    /// The textbook Dijkstra with a binary heap, ties by node index (the former
    /// `edge_distance`).
    fn binary_heap_distance(adj: &Adjacency, x: &[[f64; 3]], source: &[bool]) -> Vec<f64> {
        use std::cmp::Reverse;
        use std::collections::BinaryHeap;
        let mut d = vec![f64::INFINITY; x.len()];
        let mut heap = BinaryHeap::new();
        for (i, &s) in source.iter().enumerate() {
            if s {
                d[i] = 0.0;
                heap.push(Reverse((0u64, i as u32)));
            }
        }
        while let Some(Reverse((key, i))) = heap.pop() {
            let i = i as usize;
            let di = f64::from_bits(key);
            if di > d[i] {
                continue;
            }
            for &j in adj.neighbours(i) {
                let j = j as usize;
                let (a, b) = (x[i], x[j]);
                let l =
                    ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2) + (b[2] - a[2]).powi(2)).sqrt();
                if di + l < d[j] {
                    d[j] = di + l;
                    heap.push(Reverse(((di + l).to_bits(), j as u32)));
                }
            }
        }
        d
    }

    #[test]
    fn radix_heap_distances_equal_binary_heap_distances_bit_for_bit() {
        let mut m = mesh::generate::box_tets(14, 11, 9, [0.0; 3], [1.0, 0.8, 0.6]);
        for (i, p) in m.coords.iter_mut().enumerate() {
            let t = i as f64;
            p[0] += 0.01 * (t * 0.7).sin();
            p[1] += 0.01 * (t * 1.3).cos();
        }
        let adj = Adjacency::build(&m);
        let n = m.n_nodes();
        // Sources: a face, and one isolated corner node far from it.
        let source: Vec<bool> = (0..n)
            .map(|i| m.coords[i][2] <= 1e-12 || i == n - 1)
            .collect();
        let a = edge_distance(&adj, &m.coords, &source);
        let b = binary_heap_distance(&adj, &m.coords, &source);
        assert!(a.iter().all(|v| v.is_finite()));
        assert!(a.iter().zip(&b).all(|(p, q)| p.to_bits() == q.to_bits()));
        // No source: every distance is infinite.
        let none = edge_distance(&adj, &m.coords, &vec![false; n]);
        assert!(none.iter().all(|v| v.is_infinite()));
    }
}
