//! Volume mesh deformation (paper §4): spring analogy with adaptation matrices
//! (Eqs. 14–24), propagation of R (Eqs. 25–26), boundary nodes sliding on planes (§4.3; the
//! parametric sliding on support curves and surfaces of Eqs. 27–33 is not implemented yet),
//! rigid motion of markers (Eqs. 34–35), the paper's point iteration (Eqs. 22–24) and
//! preconditioned conjugate-gradient solvers. See `docs/crates/deform.md`.
//!
//! Layer: depends on `mesh` only (`geom-db` will be needed for Eqs. 27–33, to evaluate the
//! support a sliding node lies on).
//!
//! - [`spring`]: the spring system in deviations (Eq. 21) with stiffness choices, R from the
//!   skin (Eq. 25) propagated by Eq. 26, the quality guard with incremental deformation.
//! - [`bc`]: rigid motion (Eq. 34–35), fixed and sliding markers, node precedence.
//! - [`rotation`]: element frames and the nearest rotation (polar decomposition).
//! - [`solve`]: the sparse matrix, deterministic parallel PCG (Jacobi, smoothed-aggregation
//!   multigrid), the paper's point iteration (Eqs. 22–24), reverse Cuthill–McKee.

pub mod bc;
pub mod error;
pub mod generate;
pub mod rotation;
pub mod solve;
pub mod spring;

pub use bc::{BoundaryConditions, MarkerRole, RigidMotion};
pub use error::{Error, Result};
pub use spring::{
    DeformOptions, DeformReport, Deformed, SolverKind, Stiffness, cell_quality, deform,
    deform_with_progress,
};
