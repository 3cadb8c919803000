//! What a distributed deformation gives back: each rank's [`DistDeformed`] (its nodes' new
//! coordinates, its sliding nodes' supports, the quality over the ranks) and the
//! [`DistReport`] with its [`DistSeconds`], the same on every rank.

use mesh::quality::Summary;
use serde::Serialize;

use crate::support::Support;

/// What a distributed deformation did (the same figures on every rank).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct DistReport {
    /// Ranks.
    pub ranks: usize,
    /// Nodes over the ranks.
    pub nodes: u64,
    /// Unknowns over the ranks.
    pub unknowns: u64,
    /// The most owned unknowns of a rank over their mean (1: even): the ranks wait for the
    /// busiest at every product and dot.
    pub imbalance: f64,
    /// Ghost nodes over the ranks (the partition surface, counted on the receiving side).
    pub ghost_nodes: u64,
    /// How the parts were made: `given` (by the caller), `metis`, `rcb`, or
    /// `rcb (METIS failed)` (on rank 0).
    pub partitioner: String,
    /// The threads rank 0 made the parts with: its pool on the cores of the ranks of its
    /// node (`root_pool`), or its own threads; 0 for a given partition.
    pub partition_threads: usize,
    /// Increments of the last attempt and the increment counts tried.
    pub increments: usize,
    /// The increment counts tried.
    pub attempts: Vec<usize>,
    /// PCG iterations of the spring system (Eq. 21), summed over the increments.
    pub iterations: usize,
    /// PCG iterations of the R field (Eq. 26), summed over the increments.
    pub rotation_iterations: usize,
    /// Largest final relative residual of the Eq. 21 solves.
    pub residual: f64,
    /// The Eq. 21 solver of the last increment, e.g. `pcg-schwarz-amg-interface-coarse-held`:
    /// the block (`block-amg`, `schwarz-amg` with the overlap, `block-jacobi`), `-interface`
    /// with the interface sweep around the overlapping blocks, `-coarse` with
    /// the coarse-grid correction, `-held` when the block multigrid is the constrained one
    /// (docs/mpi.md, "Preconditioner"); empty when nothing moved.
    pub solver: String,
    /// Bytes sent by all ranks in one halo exchange of the unknowns (one product A p).
    pub bytes_per_iteration: u64,
    /// Aggregates of the coarse-grid correction over the ranks (0: none).
    pub coarse_aggregates: usize,
    /// Nodes sliding on geometry supports over the ranks (Eqs. 27–33; 0 without).
    pub sliding_on_supports: u64,
    /// Outer iterations of the sliding on supports, summed over the increments.
    pub slide_iterations: usize,
    /// The largest last update of those outer iterations relative to the boundary
    /// displacement.
    pub slide_update: f64,
    /// The largest distance a node sliding on a support moved.
    pub slide_max_move: f64,
    /// Minimum cell quality before and after.
    pub min_quality: [f64; 2],
    /// Cells with q ≤ 0 before and after.
    pub nonpositive: [u64; 2],
    /// Largest seconds over the ranks: set-up (partition checks, unknowns), assembly and
    /// preconditioner, R field, spring solve, quality.
    pub seconds: DistSeconds,
    /// Deformations run on this set-up, this one included
    /// ([`Deformer::deform_with`](super::Deformer::deform_with) reuses a set-up for new
    /// displacements: from the second on, the set-up and partition seconds are those of the
    /// first, not spent again).
    pub deformations: usize,
    /// The far field, as the serial report's (`DeformReport::far_field`; the node by its
    /// number in the whole grid: its global id on a given partition).
    pub far_field: Option<crate::report::FarField>,
}

/// Seconds per phase (largest over the ranks).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct DistSeconds {
    /// Unknowns and halo of the unknowns, with the partition before them (its part of it
    /// in [`DistSeconds::partition`]).
    pub setup: f64,
    /// Of the set-up: the partition in place on every rank (made on rank 0 and scattered,
    /// or given; its checks, adjacency and halo), before the deformation's own set-up.
    pub partition: f64,
    /// Of the partition: each rank's own work on its part once it has it (decoding it,
    /// its checks, adjacency, ordering and halo, its nodes' roles), what a partition given
    /// by the caller costs too; the rest of [`DistSeconds::partition`] is rank 0's read
    /// grid cut and sent.
    pub own_part: f64,
    /// Springs, assembly, block preconditioner.
    pub assemble: f64,
    /// The R field.
    pub rotation: f64,
    /// The Eq. 21 solve.
    pub solve: f64,
    /// Quality.
    pub quality: f64,
}

/// A rank's result: the new coordinates of its local nodes (owned, then ghosts) and the
/// report.
#[derive(Debug, Clone)]
pub struct DistDeformed {
    /// New coordinates of the local nodes (owned, then ghosts), in the caller's numbering
    /// of a given part ([`Deformer::local_ids`](super::Deformer::local_ids)).
    pub coords: Vec<[f64; 3]>,
    /// Final supports and parameters of the owned nodes that slid on geometry supports
    /// (global ids; empty without).
    /// [`Deformer::gather_supports`](super::Deformer::gather_supports) brings them to rank 0.
    pub supports: Vec<(u64, Support)>,
    /// The whole grid's cell quality before and after, summarised over the ranks (the
    /// same summary as [`mesh::quality::summary`] of the whole field, the mean summed in
    /// rank order).
    pub quality: [Summary; 2],
    /// What was done.
    pub report: DistReport,
    /// This rank's solutions, the warm start of a later deformation on the same set-up
    /// ([`Deformer::deform_from`](super::Deformer::deform_from)).
    pub(crate) state: DistState,
}

/// A rank's solutions of a deformation, per owned unknown of its set-up: what a warm start
/// begins from (empty when the deformation took more than one increment, or nothing moved).
#[derive(Debug, Clone, Default)]
pub(crate) struct DistState {
    /// Owned unknowns of the set-up that made it (a check on reuse).
    pub unknowns: usize,
    /// Δx of Eq. 21.
    pub dx: Vec<sparse::V3>,
    /// The Eq. 26 solution (the quaternions' vector part as solved, before the clamp).
    pub qv: Vec<sparse::V3>,
    /// The parameters of the owned nodes sliding on supports.
    pub params: Vec<[f64; 2]>,
}
