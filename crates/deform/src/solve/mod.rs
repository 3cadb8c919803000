//! The solvers of the spring systems: the smoothed-aggregation multigrid preconditioner
//! ([`amg`]), deform's own kernel, built on the `sparse` crate's matrices and conjugate
//! gradients; the `sparse` items it is used with are re-exported here.

pub mod amg;
pub(crate) mod held;

pub use amg::{Amg, AmgInfo, AmgOptions, LevelSetup};
pub use sparse::{
    Constraint, Constraints, Entry, Jacobi, Preconditioner, SolveOptions, SolveReport, SymMatrix,
    V3, pcg, point_iteration,
};
