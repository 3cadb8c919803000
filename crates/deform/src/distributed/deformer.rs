//! The distributed deformation ([`Deformer`]): a rank's unknowns (owned first, ghosts after,
//! by owner), the increments of the motion with the serial guard's rule (1, 2, 4, …
//! increments until no cell is inverted and the minimum quality holds), each one assembling
//! Eq. 21 on the rank's cells, solving R (Eq. 26) and the spring system over the ranks, and
//! bringing the ghosts' new positions from their owners; the result gathered on rank 0.

use std::collections::HashMap;
use std::time::Instant;

use mesh::quality::Summary;
use mesh::{Elements, Marker, Mesh};
use mpi::traits::*;
use sparse::{Constraints, V3};

use super::coarse::{CoarseOp, CoarseSpace};
use super::comm::{Comm, agree, max, min, sum_n, sum_u64};
use super::halo::Halo;
use super::metis::Partitioner;
use super::partition::{LocalGrid, Partition, Start, locality_order};
use super::report::DistState;
pub use super::report::{DistDeformed, DistReport, DistSeconds};
use super::rfield::{Ctx, rotations};
use super::scatter::Local;
use super::slide::{self, Slide};
use super::solve::{DistOperator, Held, Overlap};
use crate::assembly::{System, rhs};
use crate::bc::{BoundaryConditions, NodeRole};
use crate::error::{Error, Result};
use crate::operator::check_converged;
use crate::options::{DeformOptions, SolverKind, reach_weight};
use crate::sliding::SlideOutcome;
use crate::stiffness::{Stiffness, length_scale, springs};
use crate::support::{Support, Supports};

/// What rank 0 gives [`Deformer::from_root_on_supports`]: the whole grid, its boundary
/// conditions, and the supports of its classified nodes ([`Supports::nodes`]).
pub type OnSupports<'a> = (&'a Mesh, &'a BoundaryConditions, &'a [(u32, Support)]);

/// What one increment did ([`Deformer::increment`]; all zero and empty when nothing moved).
#[derive(Default)]
struct Increment {
    /// Eq. 21 iterations, the sliding corrections' included.
    iterations: usize,
    /// Eq. 26 iterations.
    rotation_iterations: usize,
    /// The final relative residual of Eq. 21.
    residual: f64,
    /// What the sliding on supports did.
    slide: SlideOutcome,
    /// The Eq. 21 solver's name.
    solver: String,
    /// The Eq. 21 and Eq. 26 solutions per owned unknown (empty when nothing moved).
    dx: Vec<V3>,
    qv: Vec<V3>,
}

/// The least aggregates per rank of the coarse-grid correction by default
/// ([`Deformer::coarse_parts`]): iterations at 1, 2 and 4 ranks in docs/mpi.md,
/// "Coarse-grid correction".
pub const COARSE_PARTS: usize = 256;

/// The distributed deformation set-up on a communicator.
pub struct Deformer<'c> {
    comm: &'c Comm,
    local: Local,
    opts: DeformOptions,
    sys: System,
    /// Local node of every local unknown (owned unknowns, then ghost unknowns).
    unk_node: Vec<u32>,
    unk_halo: Halo,
    setup: f64,
    /// Seconds of the set-up until the partition was in place, and of it each rank's own
    /// work on its part (largest over the ranks).
    partition: [f64; 2],
    /// Rank 0's threads for the partition (the same on every rank).
    partition_threads: usize,
    /// The springs' scale of the whole grid (a rank's own grid would give its rows another
    /// power of two than its neighbours' and the matrix over the ranks would not be
    /// symmetric).
    scale: f64,
    /// Aggregates per rank of the coarse-grid correction (0: none).
    coarse_parts: usize,
    /// One layer of overlap in the blocks of the preconditioner.
    overlap: bool,
    /// The interface smoother around the overlapping blocks.
    sweep: bool,
    /// The nodes sliding on geometry supports (None without).
    slide: Option<Slide>,
    /// The weight φ of R per local node (the reach of R; empty: 1 everywhere).
    reach: Vec<f64>,
    /// The distance of every local node from the moving boundary along grid edges on the
    /// baseline grid, for the far-field report (the same `Some` or `None` on every rank).
    wall_distance: Option<Vec<f64>>,
    /// Deformations run on this set-up.
    runs: std::cell::Cell<usize>,
    /// The coarse space, made at the first deformation and kept (it depends on the
    /// baseline grid and the unknowns only).
    coarse: std::cell::OnceCell<Option<CoarseSpace>>,
    /// The cells this rank counts ([`counted_cells`]) and the baseline grid's quality over
    /// the ranks (summary, least quality, inverted cells): every deformation's "before",
    /// made at the first and kept.
    baseline: std::cell::OnceCell<(Mesh, (Summary, f64, u64))>,
    /// Eq. 21's operator on the baseline grid with its free block multigrid (Eq. 26's) in
    /// place and the constrained one (Eq. 21's) beside it: what every first increment
    /// builds, kept from the last one (the serial `Deformer` keeps its baseline operator
    /// too). Taken while an increment uses it: an error leaves it out, and the next first
    /// increment builds it again, on every rank alike.
    base: std::cell::RefCell<Option<(DistOperator, Held)>>,
}

/// True when this rank counts the element `e` of its local grid: it owns the element's node
/// of smallest global id (so each cell and boundary element is counted by one rank).
fn counts(part: &Partition, e: &[u32]) -> bool {
    let g = &part.grid;
    e.iter()
        .min_by_key(|&&v| g.global_ids[v as usize])
        .is_some_and(|&v| (v as usize) < g.n_owned)
}

/// The cells of the local grid this rank counts ([`counts`]).
fn counted_cells(part: &Partition) -> Mesh {
    let g = &part.grid;
    let mut m = Mesh::new(g.mesh.dim);
    for (kind, e) in g.mesh.cells.iter() {
        if counts(part, e) {
            m.cells.push(kind, e, None);
        }
    }
    m
}

impl<'c> Deformer<'c> {
    /// The set-up on a partition given by the caller (each rank its own part, as a CFD
    /// solver has it): `bc` names markers of the local grids (rigid or fixed) and node
    /// displacements in local numbering. Each rank's part must hold every boundary
    /// element of its owned nodes (its roles, the reach of R and the far field are found
    /// from them). Collective.
    pub fn new(
        comm: &'c Comm,
        grid: LocalGrid,
        bc: &BoundaryConditions,
        opts: &DeformOptions,
    ) -> Result<Self> {
        check_options(comm, opts)?;
        let t = Instant::now();
        let local = Local::given(comm, grid, bc, opts)?;
        Self::set_up(comm, local, opts, t).map(Self::with_reach)
    }

    /// The set-up from the whole grid on rank 0 (`whole`: `Some` on rank 0, `None` on the
    /// others), partitioned there by METIS (coordinate bisection when METIS fails) and
    /// scattered; the boundary conditions are those of the serial [`crate::deform`].
    /// Collective.
    pub fn from_root(
        comm: &'c Comm,
        whole: Option<(&Mesh, &BoundaryConditions)>,
        opts: &DeformOptions,
    ) -> Result<Self> {
        Self::from_root_with(comm, whole, opts, Partitioner::Metis)
    }

    /// [`Deformer::from_root`] with the partitioner of rank 0 chosen (`by` is read on rank 0).
    pub fn from_root_with(
        comm: &'c Comm,
        whole: Option<(&Mesh, &BoundaryConditions)>,
        opts: &DeformOptions,
        by: Partitioner,
    ) -> Result<Self> {
        check_options(comm, opts)?;
        let t = Instant::now();
        let local = Local::from_root(comm, whole, None, opts, by)?;
        Self::set_up(comm, local, opts, t).map(Self::with_reach)
    }

    /// The distance of the local nodes from the moving boundary along grid edges, as the
    /// serial set-up's, and from it the weights of the reach of R when the options give a
    /// finite one (collective). The moving boundary is the serial one: on a part made on
    /// rank 0, found there on the whole grid; on a given part, by each owner among its own
    /// nodes, from its own boundary elements.
    fn with_reach(mut self) -> Self {
        let t = Instant::now();
        let (comm, local) = (self.comm, &self.local);
        let part = &local.part;
        let d = super::wall::edge_distance(comm, part, &part.grid.mesh.coords, &local.boundary);
        if let Some(l) = self.opts.rotation_reach.filter(|l| l.is_finite()) {
            self.reach = d.iter().map(|&d| reach_weight(d, l)).collect();
        }
        self.wall_distance = Some(d);
        self.setup += max(comm, t.elapsed().as_secs_f64());
        self
    }

    /// [`Deformer::from_root_with`] with nodes sliding on the geometry's supports (as the
    /// serial [`crate::deform_on_supports`]): `db` is the geometry on every rank; `whole`
    /// holds, on rank 0, the grid, the boundary conditions (with
    /// [`crate::MarkerRole::SlideOnSupport`] markers) and the supports of the grid's
    /// classified nodes ([`Supports::nodes`], e.g. by [`Supports::from_classes`]). Rank 0
    /// classifies the sliding nodes as serially; each owner then iterates its own.
    /// Collective.
    pub fn from_root_on_supports(
        comm: &'c Comm,
        db: &geom_db::GeomDb,
        whole: Option<OnSupports<'_>>,
        opts: &DeformOptions,
        by: Partitioner,
    ) -> Result<Self> {
        check_options(comm, opts)?;
        let t = Instant::now();
        let sup = whole.map(|(_, _, nodes)| Supports {
            db,
            nodes: nodes.to_vec(),
        });
        let grid = whole.map(|(m, bc, _)| (m, bc));
        let local = Local::from_root(comm, grid, sup.as_ref(), opts, by)?;
        let mut d = Self::set_up(comm, local, opts, t).map(Self::with_reach)?;
        let s = Slide::new(comm, db, &d.local.root_supports, &d.local.part, &d.sys)?;
        d.slide = (s.total > 0).then_some(s);
        Ok(d)
    }

    fn set_up(comm: &'c Comm, local: Local, opts: &DeformOptions, t: Instant) -> Result<Self> {
        let partition = [t.elapsed().as_secs_f64(), local.own_seconds].map(|v| max(comm, v));
        let part = &local.part;
        let (n, n_owned) = (part.grid.mesh.n_nodes(), part.grid.n_owned);
        let is_unk = |i: usize| {
            matches!(
                local.cls.roles[i],
                NodeRole::Free | NodeRole::Sliding(_) | NodeRole::OnSupport(_)
            ) && !part.adj.neighbours(i).is_empty()
        };
        let node_of: Vec<u32> = (0..n_owned)
            .filter(|&i| is_unk(i))
            .map(|i| i as u32)
            .collect();
        // A part made on rank 0 is numbered in locality order already (its unknowns keep
        // the nodes' order); a given part's unknowns are renumbered.
        let node_of = if part.in_order {
            node_of
        } else {
            locality_order(&node_of, &part.adj, &part.grid.mesh.coords, Start::Corner)
        };
        let mut ghost: Vec<u32> = (n_owned..n)
            .filter(|&i| is_unk(i))
            .map(|i| i as u32)
            .collect();
        let key = |i: &u32| (part.owner[*i as usize], part.grid.global_ids[*i as usize]);
        ghost.sort_unstable_by_key(key);
        let mut unk_of = vec![u32::MAX; n];
        let unk_node: Vec<u32> = node_of.iter().chain(&ghost).copied().collect();
        for (k, &i) in unk_node.iter().enumerate() {
            unk_of[i as usize] = k as u32;
        }
        // In unknown order, as `Constraints` keeps them.
        let items = node_of
            .iter()
            .enumerate()
            .filter_map(|(k, &i)| match local.cls.roles[i as usize] {
                NodeRole::Sliding(c) => Some((k as u32, c)),
                _ => None,
            })
            .collect();
        let ghosts: Vec<(u32, i32, u64)> = ghost
            .iter()
            .map(|&i| {
                let (o, g) = key(&i);
                (unk_of[i as usize], o, g)
            })
            .collect();
        let owned: HashMap<u64, u32> = node_of
            .iter()
            .enumerate()
            .map(|(k, &i)| (part.grid.global_ids[i as usize], k as u32))
            .collect();
        let unk_halo = agree(comm, Halo::build(comm, &ghosts, &owned))?;
        // The whole grid's bounding box, for the springs' scale.
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for p in &part.grid.mesh.coords[..n_owned] {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let (lo, hi) = (lo.map(|v| min(comm, v)), hi.map(|v| max(comm, v)));
        let diag = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
        let sys = System {
            unk_of,
            node_of,
            cons: Constraints { items },
            sup_unk: Vec::new(),
        };
        let setup = max(comm, t.elapsed().as_secs_f64());
        let partition_threads = max(comm, local.partition_threads as f64) as usize;
        Ok(Self {
            comm,
            local,
            opts: *opts,
            sys,
            unk_node,
            unk_halo,
            setup,
            partition,
            partition_threads,
            scale: length_scale(diag, opts.stiffness),
            coarse_parts: COARSE_PARTS,
            overlap: true,
            sweep: true,
            slide: None,
            reach: Vec::new(),
            wall_distance: None,
            runs: std::cell::Cell::new(0),
            coarse: std::cell::OnceCell::new(),
            baseline: std::cell::OnceCell::new(),
            base: std::cell::RefCell::new(None),
        })
    }

    /// Sets the least aggregates per rank of the coarse-grid correction (0: block
    /// preconditioner alone); a rank cuts more when they would hold over 500 unknowns each
    /// (at most 4 096 over the ranks). On one rank there is none: the block is the whole
    /// grid's multigrid.
    pub fn coarse_parts(mut self, parts: usize) -> Self {
        self.coarse_parts = parts;
        self.coarse = std::cell::OnceCell::new();
        self.base = std::cell::RefCell::new(None);
        self
    }

    /// Sets whether the blocks of the preconditioner overlap by one layer (the ghost
    /// unknowns: symmetric additive Schwarz; default) or not (block Jacobi). Multigrid
    /// blocks only; iterations of both in docs/mpi.md.
    pub fn overlap(mut self, on: bool) -> Self {
        self.overlap = on;
        self.base = std::cell::RefCell::new(None);
        self
    }

    /// Sets whether the overlapping blocks are wrapped in the interface smoother (a damped
    /// Jacobi sweep on the rows near the interface before and after them; default) or not.
    /// Iterations of both in docs/mpi.md.
    pub fn interface_sweep(mut self, on: bool) -> Self {
        self.sweep = on;
        self.base = std::cell::RefCell::new(None);
        self
    }

    /// The coarse space of the set-up's unknowns, when there is one (collective).
    fn coarse_space(&self) -> Option<CoarseSpace> {
        if self.comm.size() < 2 || self.coarse_parts == 0 {
            return None;
        }
        let x = &self.local.part.grid.mesh.coords;
        let coords: Vec<[f64; 3]> = self.sys.node_of.iter().map(|&i| x[i as usize]).collect();
        let mut constrained = vec![false; coords.len()];
        for &(k, _) in &self.sys.cons.items {
            constrained[k as usize] = true;
        }
        for &k in self.slide.as_ref().map_or(&[][..], Slide::unknowns) {
            constrained[k as usize] = true;
        }
        Some(CoarseSpace::new(
            self.comm,
            &self.unk_halo,
            &coords,
            &constrained,
            self.unk_node.len(),
            self.coarse_parts,
        ))
    }

    /// The deformations run on this set-up so far.
    pub fn deformations(&self) -> usize {
        self.runs.get()
    }

    /// This rank's partition, in the deformer's own numbering: a part given by the caller
    /// has its owned nodes renumbered for locality ([`Deformer::local_ids`] and
    /// [`DistDeformed::coords`] are in the caller's numbering).
    pub fn partition(&self) -> &Partition {
        &self.local.part
    }

    /// The global id of every local node in the numbering of [`DistDeformed::coords`]:
    /// the caller's for a given part, the partition's for one made on rank 0.
    pub fn local_ids(&self) -> Vec<u64> {
        let ids = &self.local.part.grid.global_ids;
        match &self.local.caller {
            Some(perm) => perm.iter().map(|&p| ids[p as usize]).collect(),
            None => ids.clone(),
        }
    }

    /// The quality summary over the ranks of the counted cells at the local coordinates
    /// `x`, and its minimum (+∞ when no cell is measured) and count of q ≤ 0.
    fn quality(&self, cells: &Mesh, x: &[[f64; 3]]) -> (Summary, f64, u64) {
        let s = super::quality::summary(self.comm, &mesh::quality::cell_quality_at(cells, x));
        let lo = if s.measured > 0 { s.min } else { f64::INFINITY };
        (s, lo, s.n_nonpositive as u64)
    }

    /// Deforms the grid for the prescribed motion of the set-up (collective).
    pub fn deform(&self) -> Result<DistDeformed> {
        self.run(&self.local.disp, None)
    }

    /// Deforms the grid for new values of the set-up's prescribed node displacements
    /// (`BoundaryConditions::displacements`, in the order the set-up was given them), the
    /// rest of the motion (rigid markers) as set up; `None`: those of the set-up, as
    /// [`Deformer::deform`]. The partition, the nodes' roles, the unknowns, their halos, the
    /// coarse space, the baseline grid's quality and its operator with its block multigrids
    /// are kept: an optimiser's loop, whose wall moves anew at each design, pays for them
    /// once. Which nodes are displaced is the set-up's: a node left out of it stays where
    /// its role holds it.
    ///
    /// For a set-up made on rank 0 ([`Deformer::from_root`]), `displacements` are read on
    /// rank 0 (the whole grid's list; the other ranks pass `None` or anything); for a given
    /// partition ([`Deformer::new`]), each rank passes its own list, and the ghosts take
    /// their owners' values. A list of another length than the set-up's, or a value that
    /// is not finite, fails on every rank with the same error. Collective.
    pub fn deform_with(&self, displacements: Option<&[[f64; 3]]>) -> Result<DistDeformed> {
        self.deform_from(displacements, None)
    }

    /// [`Deformer::deform_with`] from the solutions of an earlier result of this set-up,
    /// as the serial [`crate::Deformer::deform`]'s `warm_start`: `warm_start`'s Eq. 26
    /// solution starts the R field's solve, its Δx the Eq. 21 solve and its sliding nodes'
    /// parameters their iteration, when the deformation takes one increment (a guard's
    /// retry in more increments starts from the baseline). Without it every solve starts
    /// from zero and the answer is bit for bit [`Deformer::deform_with`]'s; with it the
    /// answer agrees with that one to the solver tolerances, and takes fewer iterations
    /// when the designs are close (the same motion again takes none). Every rank passes
    /// its own result of the same earlier deformation, or every rank none; a result of
    /// another set-up (another count of owned unknowns on some rank) fails on every rank.
    /// Collective.
    pub fn deform_from(
        &self,
        displacements: Option<&[[f64; 3]]>,
        warm_start: Option<&DistDeformed>,
    ) -> Result<DistDeformed> {
        // One all-reduce: the ranks that give a warm start, those whose warm start fits,
        // and (on a given partition, whose values are per rank) those that give values.
        let flag = |b: bool| f64::from(u8::from(b));
        let fits = warm_start.is_none_or(|w| w.state.unknowns == self.sys.node_of.len());
        let given = self.local.caller.is_some();
        let [has, fit, values] = sum_n(
            self.comm,
            [
                flag(warm_start.is_some()),
                flag(fits),
                flag(given && displacements.is_some()),
            ],
        );
        let all = f64::from(self.comm.size());
        let split = |n: f64| n != 0.0 && n != all;
        let mismatch = if split(has) {
            Some("some ranks gave a warm start and others none")
        } else if fit != all {
            Some("the warm start is a result of another set-up")
        } else if split(values) {
            Some("some ranks gave new displacements and others none")
        } else {
            None
        };
        if let Some(reason) = mismatch {
            return Err(Error::Distributed {
                rank: self.comm.rank(),
                reason: reason.into(),
            });
        }
        let warm = warm_start.map(|w| &w.state);
        let new = if given {
            values > 0.0
        } else {
            let mut on_root = u64::from(displacements.is_some());
            self.comm.process_at_rank(0).broadcast_into(&mut on_root);
            on_root > 0
        };
        if !new {
            return self.run(&self.local.disp, warm);
        }
        let disp = self
            .local
            .displacements(self.comm, displacements.unwrap_or(&[]))?;
        self.run(&disp, warm)
    }

    /// The deformation for the displacements `disp` of the local displaced nodes, from the
    /// solutions `warm` in one increment (collective).
    fn run(&self, disp: &[[f64; 3]], warm: Option<&DistState>) -> Result<DistDeformed> {
        let (comm, opts, part) = (self.comm, &self.opts, &self.local.part);
        self.runs.set(self.runs.get() + 1);
        let x0 = &part.grid.mesh.coords;
        let unknowns = sum_u64(comm, self.sys.node_of.len() as u64);
        let busiest = max(comm, self.sys.node_of.len() as f64);
        let mut rep = DistReport {
            ranks: comm.size() as usize,
            nodes: part.n_global,
            unknowns,
            imbalance: busiest * f64::from(comm.size()) / (unknowns.max(1) as f64),
            ghost_nodes: sum_u64(comm, (x0.len() - part.grid.n_owned) as u64),
            partitioner: self.local.made_by.to_string(),
            partition_threads: self.partition_threads,
            bytes_per_iteration: sum_u64(comm, self.unk_halo.bytes_sent(3) as u64),
            deformations: self.runs.get(),
            ..DistReport::default()
        };
        let t = Instant::now();
        // Collective when made: every rank's first deformation makes it.
        let coarse = self.coarse.get_or_init(|| self.coarse_space());
        rep.coarse_aggregates = coarse.as_ref().map_or(0, CoarseSpace::len);
        rep.seconds.setup = self.setup + max(comm, t.elapsed().as_secs_f64());
        [rep.seconds.partition, rep.seconds.own_part] = self.partition;
        let t = Instant::now();
        // Collective when made, as the coarse space.
        let (cells, (before, min0, bad0)) = self.baseline.get_or_init(|| {
            let cells = counted_cells(part);
            let q = self.quality(&cells, x0);
            (cells, q)
        });
        let (before, min0, bad0) = (*before, *min0, *bad0);
        rep.seconds.quality += t.elapsed().as_secs_f64();
        let mut inc = 1usize;
        let slide = self.slide.as_ref();
        loop {
            rep.attempts.push(inc);
            let mut cur = x0.clone();
            let warm = warm.filter(|_| inc == 1);
            let mut params = slide.map_or_else(Vec::new, Slide::initial_params);
            if let Some(w) = warm.filter(|w| w.params.len() == params.len()) {
                params.clone_from(&w.params);
            }
            let mut state = DistState {
                unknowns: self.sys.node_of.len(),
                ..DistState::default()
            };
            let (mut iterations, mut rot_iterations, mut residual) = (0, 0, 0.0f64);
            let (mut slide_iterations, mut slide_update) = (0, 0.0f64);
            let mut solver = String::new();
            for m in 1..=inc {
                let s = if m == inc { 1.0 } else { m as f64 / inc as f64 };
                let (c, sec) = (coarse.as_ref(), &mut rep.seconds);
                let o = self.increment(s, disp, &mut cur, &mut params, c, sec, warm)?;
                if inc == 1 {
                    (state.dx, state.qv) = (o.dx, o.qv);
                }
                iterations += o.iterations;
                rot_iterations += o.rotation_iterations;
                residual = residual.max(o.residual);
                slide_iterations += o.slide.iterations;
                slide_update = slide_update.max(o.slide.update);
                if !o.solver.is_empty() {
                    solver = o.solver;
                }
            }
            let t = Instant::now();
            let (after, min1, bad1) = self.quality(cells, &cur);
            rep.seconds.quality += t.elapsed().as_secs_f64();
            let low = min1 < opts.min_quality_ratio * min0;
            if (bad1 > bad0 || low) && inc < opts.max_increments {
                inc *= 2;
                continue;
            }
            if bad1 > bad0 && !opts.allow_inverted {
                return Err(Error::Inverted {
                    count: bad1 as usize,
                    increments: inc,
                    worst: super::quality::worst_cell(comm, cells, &cur, &part.grid.global_ids),
                });
            }
            rep.increments = inc;
            rep.iterations = iterations;
            rep.rotation_iterations = rot_iterations;
            rep.residual = max(comm, residual);
            rep.solver = solver;
            rep.min_quality = [min0, min1];
            rep.nonpositive = [bad0, bad1];
            let mut supports = Vec::new();
            if let Some(sl) = slide {
                rep.sliding_on_supports = sl.total;
                rep.slide_iterations = slide_iterations;
                rep.slide_update = slide_update;
                let mut moved = cur.clone();
                rep.slide_max_move = max(comm, sl.place(&mut moved, &params, x0));
                supports = sl.supports(&params);
            }
            if inc == 1 {
                state.params = params;
            }
            rep.far_field = self
                .wall_distance
                .as_ref()
                .map(|d| super::wall::far_field(comm, &self.local.part, d, &cur));
            let s = &mut rep.seconds;
            [s.assemble, s.rotation, s.solve, s.quality] =
                [s.assemble, s.rotation, s.solve, s.quality].map(|v| max(comm, v));
            if let Some(perm) = &self.local.caller {
                cur = perm.iter().map(|&p| cur[p as usize]).collect();
            }
            return Ok(DistDeformed {
                coords: cur,
                supports,
                quality: [before, after],
                report: rep,
                state,
            });
        }
    }

    /// One increment to the fraction `s` of the motion (`disp`: the displaced nodes'
    /// displacements), from `cur` (local nodes, ghosts up to date) and the sliding nodes'
    /// parameters `params`, the solves starting from `warm`'s solutions when given;
    /// returns what it did.
    #[allow(clippy::too_many_arguments)]
    fn increment(
        &self,
        s: f64,
        disp: &[[f64; 3]],
        cur: &mut [[f64; 3]],
        params: &mut [[f64; 2]],
        coarse: Option<&CoarseSpace>,
        sec: &mut DistSeconds,
        warm: Option<&DistState>,
    ) -> Result<Increment> {
        let (comm, opts, part, sys) = (self.comm, &self.opts, &self.local.part, &self.sys);
        let cls = &self.local.cls;
        let x0 = &part.grid.mesh.coords;
        let mut target = cur.to_vec();
        let mut max_disp = 0.0f64;
        for i in 0..cur.len() {
            let t = match cls.roles[i] {
                NodeRole::Rigid(m) => cls.motions[m].apply(x0[i], s),
                NodeRole::Displaced(k) => {
                    let d = disp[k];
                    if s == 1.0 {
                        [x0[i][0] + d[0], x0[i][1] + d[1], x0[i][2] + d[2]]
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
            let d = [t[0] - cur[i][0], t[1] - cur[i][1], t[2] - cur[i][2]];
            max_disp = max_disp.max((d[0].powi(2) + d[1].powi(2) + d[2].powi(2)).sqrt());
        }
        let max_disp = max(comm, max_disp);
        if max_disp == 0.0 {
            return Ok(Increment::default());
        }
        let t = Instant::now();
        // The first increment starts from the baseline grid: its operator and both block
        // multigrids are those of the last deformation's first increment, kept.
        let baseline = cur == x0.as_slice();
        let kept = if baseline {
            self.base.borrow_mut().take()
        } else {
            None
        };
        let (mut op, kept_held) = match kept {
            Some((op, held)) => (op, Some(held)),
            None => (self.operator(cur, coarse)?, None),
        };
        sec.assemble += t.elapsed().as_secs_f64();
        let t = Instant::now();
        let ctx = Ctx {
            comm,
            node_halo: &part.halo,
            unk_halo: &self.unk_halo,
            sys,
            n_all: self.unk_node.len(),
            n_owned_nodes: part.grid.n_owned,
            skin: &cls.skin,
            dim: part.grid.mesh.dim,
            opts,
            reach: &self.reach,
        };
        let rf = rotations(&ctx, &op, cur, &target, warm.map(|w| w.qv.as_slice()))?;
        sec.rotation += t.elapsed().as_secs_f64();
        let t = Instant::now();
        let op_ref = &op;
        let cur_ref: &[[f64; 3]] = cur;
        let unk_node = &self.unk_node;
        let disp = |j: usize| {
            let (t, c) = (target[j], cur_ref[j]);
            [t[0] - c[0], t[1] - c[1], t[2] - c[2]]
        };
        let mut b = rhs(sys, &op.couplings, disp, |k, i| {
            let mut s = [0.0; 3];
            if !rf.any {
                return s;
            }
            op_ref.row_entries(k, |c, akl| {
                let r = rf.minus_identity(i, unk_node[c] as usize, cur_ref);
                for q in 0..3 {
                    s[q] += akl * r[q];
                }
            });
            let (nodes, kij) = op.couplings.row(k);
            for (&j, &kij) in nodes.iter().zip(kij) {
                let r = rf.minus_identity(i, j as usize, cur_ref);
                for q in 0..3 {
                    s[q] -= kij * r[q];
                }
            }
            s
        });
        if part.grid.mesh.dim == 2 {
            for v in b.iter_mut() {
                v[2] = 0.0;
            }
        }
        sec.assemble += t.elapsed().as_secs_f64();
        let t = Instant::now();
        let nu = sys.node_of.len();
        let mut dx: Vec<V3> = match warm {
            Some(w) if w.dx.len() == nu => w.dx.clone(),
            _ => vec![[0.0; 3]; nu],
        };
        // The sliding's outer iteration measures its first update from the guess.
        let dx0 = if self.slide.is_some() {
            dx.clone()
        } else {
            Vec::new()
        };
        let cons = match &self.slide {
            Some(sl) => sl.constraints(comm, &sys.cons, params)?,
            None => sys.cons.clone(),
        };
        // Eq. 26 is solved: the block multigrid becomes the constrained one of Eq. 21.
        let mut held = match kept_held {
            Some(h) => h,
            None => op.held(comm, &self.unk_halo, &cons),
        };
        op.swap(&mut held);
        let r = op.solve(
            comm,
            &self.unk_halo,
            self.unk_node.len(),
            &b,
            &mut dx,
            &cons,
            opts,
            opts.rel_tol,
        );
        check_converged(&r, "spring system (Eq. 21)", opts)?;
        let mut so = SlideOutcome::default();
        if let Some(sl) = &self.slide {
            let n_all = self.unk_node.len();
            so = sl.iterate(
                comm,
                &op,
                &self.unk_halo,
                n_all,
                &sys.cons,
                cur,
                &b,
                &mut dx,
                dx0,
                params,
                opts,
                max_disp,
            )?;
        }
        for (k, &i) in sys.node_of.iter().enumerate() {
            for q in 0..3 {
                cur[i as usize][q] += dx[k][q];
            }
        }
        if let Some(sl) = &self.slide {
            sl.place(cur, params, x0);
        }
        for i in 0..cur.len() {
            if matches!(cls.roles[i], NodeRole::Rigid(_) | NodeRole::Displaced(_)) {
                cur[i] = target[i];
            }
        }
        part.halo.exchange(comm, cur);
        if baseline {
            op.swap(&mut held);
            *self.base.borrow_mut() = Some((op, held));
        }
        sec.solve += t.elapsed().as_secs_f64();
        let iterations = r.iterations + so.solver_iterations;
        Ok(Increment {
            iterations,
            rotation_iterations: rf.iterations,
            residual: r.rel_residual,
            slide: so,
            solver: r.solver,
            dx,
            qv: rf.solution,
        })
    }

    /// Eq. 21's operator at the local coordinates `cur` (springs, assembly, block
    /// multigrid, the coarse-grid correction on `coarse`); collective.
    fn operator(&self, cur: &[[f64; 3]], coarse: Option<&CoarseSpace>) -> Result<DistOperator> {
        let (comm, opts, part, sys) = (self.comm, &self.opts, &self.local.part, &self.sys);
        let mut sp = match opts.stiffness {
            Stiffness::Volume | Stiffness::WallDistance => {
                let roles = &self.local.cls.roles;
                super::wall::springs(comm, part, roles, cur, opts.stiffness, self.scale)
            }
            _ => springs(&part.grid.mesh, cur, opts.stiffness, &part.adj, &[], None),
        };
        sp.scale = self.scale;
        let overlap = (self.overlap && comm.size() > 1).then_some(Overlap {
            comm,
            halo: &self.unk_halo,
            unk_node: &self.unk_node,
            sweep: self.sweep,
        });
        let op = DistOperator::new(sys, &part.adj, &sp, sys.node_of.len(), opts, overlap);
        let mut op = agree(comm, op)?;
        if let Some(space) = coarse {
            let c = CoarseOp::new(comm, &self.unk_halo, space, &op, sys.node_of.len());
            op.coarse = Some(agree(comm, c)?);
        }
        Ok(op)
    }

    /// This rank's piece of the grid at its local coordinates `coords` (a result's
    /// [`DistDeformed::coords`]), for a grid written in pieces (one `.vtu` per rank): the
    /// local nodes (owned, then ghosts) at `coords`, the cells and the boundary elements
    /// (under every marker's name, in the same order on every rank) that this rank counts,
    /// each cell and element being in one piece; and the nodes' displacements.
    pub fn piece(&self, coords: &[[f64; 3]]) -> (Mesh, Vec<[f64; 3]>) {
        let part = &self.local.part;
        let mut m = counted_cells(part);
        m.coords = coords.to_vec();
        for mk in &part.grid.mesh.markers {
            let mut elements = Elements::new();
            for (kind, e) in mk.elements.iter() {
                if counts(part, e) {
                    elements.push(kind, e, None);
                }
            }
            m.markers.push(Marker {
                name: mk.name.clone(),
                tag: mk.tag,
                elements,
            });
        }
        let d = coords
            .iter()
            .zip(&part.grid.mesh.coords)
            .map(|(x, x0)| [x[0] - x0[0], x[1] - x0[1], x[2] - x0[2]])
            .collect();
        (m, d)
    }

    /// The final supports of every rank's sliding nodes (a result's
    /// [`DistDeformed::supports`]), gathered on rank 0 by global id (`None` on the other
    /// ranks). Collective.
    pub fn gather_supports(&self, out: &DistDeformed) -> Option<Vec<(u64, Support)>> {
        slide::gather(self.comm, &out.supports)
    }

    /// The owned nodes' coordinates of every rank (`coords` in the numbering of
    /// [`DistDeformed::coords`]), gathered on rank 0 in global-id order (`None` on the other
    /// ranks). Collective.
    pub fn gather(&self, coords: &[[f64; 3]]) -> Option<Vec<[f64; 3]>> {
        let no = self.local.part.grid.n_owned;
        let gids = self.local_ids();
        super::scatter::gather(self.comm, &gids[..no], &coords[..no])
    }
}

/// Refuses, on every rank alike, the options the distributed deformation does not have.
fn check_options(comm: &Comm, opts: &DeformOptions) -> Result<()> {
    let reason = if opts.solver == SolverKind::PointIteration {
        Some("the point iteration (jacobi) is not distributed; use pcg or pcg-jacobi".into())
    } else {
        opts.rotation_reach
            .filter(|l| l.is_nan() || *l < 0.0)
            .map(|l| format!("the reach of R must be a length ≥ 0 (or infinite), not {l}"))
    };
    match reason {
        Some(reason) => Err(Error::Distributed {
            rank: comm.rank(),
            reason,
        }),
        None => Ok(()),
    }
}
