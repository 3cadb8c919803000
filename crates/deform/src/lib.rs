//! Volume mesh deformation (paper §4): spring analogy with adaptation matrices
//! (Eqs. 14–24), propagation of R (Eqs. 25–26), boundary nodes sliding on planes and on the
//! support curves and surfaces of the geometry through their parametric coordinates (§4.3,
//! Eqs. 27–33), rigid motion of markers (Eqs. 34–35), the paper's point iteration
//! (Eqs. 22–24) and preconditioned conjugate-gradient solvers. See `docs/crates/deform.md`.
//!
//! Layer: depends on `mesh`, and on `geom-db` only to evaluate the support that a sliding
//! node lies on.
//!
//! - [`spring`]: the spring system in deviations (Eq. 21) with stiffness choices, R from the
//!   skin (Eq. 25) propagated by Eq. 26, the quality guard with incremental deformation.
//! - [`support`]: sliding on geometry supports (Eqs. 27–33), node supports from a grid's
//!   classification.
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
pub mod support;

pub use bc::{BoundaryConditions, MarkerRole, RigidMotion};
pub use error::{Error, Result};
pub use spring::{
    DeformOptions, DeformReport, Deformed, Deformer, QualitySummary, SolverKind, Stiffness,
    cell_quality, deform, deform_on_supports, deform_on_supports_with_progress,
    deform_with_progress,
};
pub use support::{Support, Supports};
