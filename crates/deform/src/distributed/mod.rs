//! Distributed deformation over MPI (feature `mpi`): the grid that lives on the ranks of an
//! MPI job deforms where it lives. See docs/mpi.md and docs/crates/deform.md, "Distributed".
//!
//! - [`partition`]: a rank's part of the grid ([`LocalGrid`]: owned nodes with global ids,
//!   then ghosts, and the cells around the owned nodes) and its validated form
//!   ([`Partition`]: one owner per node, ghost layer complete, node halo built once); a bad
//!   part gives the same error on every rank, never a hang.
//! - [`mod@metis`]: METIS's k-way partition of a whole grid's node graph on rank 0, with
//!   [`mod@rcb`] (recursive coordinate bisection) as its fallback and alternative; `rcb` also
//!   makes the parts of the whole grid.
//! - `scatter`: each rank's share of the problem (its part and the roles of its nodes),
//!   given by the caller or made on rank 0 and sent.
//! - `halo`: the non-blocking exchange of ghost values; `comm`: the all-reduces, the
//!   agreement on errors and the variable all-to-all.
//! - `solve`: Eq. 21's rows on each rank (deform's own assembly), the product overlapped
//!   with the halo exchange, PCG with all-reduced dots and a block preconditioner of
//!   per-rank multigrid; `rfield`: the R field (Eqs. 25–26) over the ranks.
//! - `slide`: sliding on the geometry's supports (Eqs. 27–33), each owner its own sliding
//!   nodes; `wall`: the grid-wide fields of the volume and wall-distance stiffnesses (the
//!   mean cell volume, the distance from the moving boundary along grid edges).
//! - [`deformer`]: [`Deformer`] (takes a communicator), the increments and the quality
//!   guard with all-reduced counts, the gather on rank 0; `report`: what it gives back
//!   ([`DistDeformed`], [`DistReport`], [`DistSeconds`]).
//! - `cores`: rank 0's thread pool on the cores of the ranks of its node ([`root_pool`]),
//!   for its serial part of a partition made there, while the others wait asleep
//!   ([`wait_idle`]).

mod coarse;
mod comm;
mod cores;
pub mod deformer;
mod halo;
mod interface;
pub mod metis;
pub mod partition;
mod quality;
pub mod rcb;
mod report;
mod rfield;
mod scatter;
mod slide;
mod solve;
mod wall;

pub use comm::{Comm, first_failure};
pub use cores::{on_root, root_pool, wait_idle};
pub use deformer::{COARSE_PARTS, Deformer, DistDeformed, DistReport, DistSeconds, OnSupports};
pub use metis::{Cut, Partitioner};
/// The MPI bindings (rsmpi) the distributed deformation is built on, for the caller's
/// `mpi::initialize()` and communicators.
pub use mpi;
pub use partition::{LocalGrid, Partition};
pub use rcb::rcb;

/// True on every rank when `ok` is true on every rank (collective): how a caller makes the
/// ranks agree on a failure of its own (a file rank 0 could not read) before it goes on.
pub fn all_ok(comm: &Comm, ok: bool) -> bool {
    comm::min(comm, f64::from(u8::from(ok))) > 0.0
}
