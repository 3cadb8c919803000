//! Volume mesh deformation (paper §4): spring analogy with adaptation matrices
//! (Eqs. 14–24), propagation of R (Eqs. 25–26), boundary nodes sliding on planes and on the
//! support curves and surfaces of the geometry through their parametric coordinates (§4.3,
//! Eqs. 27–33), rigid motion of markers (Eqs. 34–35), the paper's point iteration
//! (Eqs. 22–24) and preconditioned conjugate-gradient solvers. See `docs/crates/deform.md`.
//!
//! Layer: depends on `sparse` and `mesh`, and on `geom-db` only to evaluate the support
//! that a sliding node lies on.
//!
//! For the unknown nodes i (interior and sliding), Eq. 21 in the deviations Δx:
//! Σ_j K_ij (Δx_j − Δx_i) = Σ_j K_ij (R_ij − I)(x⁰_j − x⁰_i), with the prescribed Δx_j of
//! moving and fixed nodes moved to the right-hand side: A Δx = b with a_ii = Σ_j K_ij,
//! a_ij = −K_ij (one scalar matrix, three components). Sliding nodes are constrained to their
//! plane (or seam line) and the system is solved by projected conjugate gradients, which is
//! the exact constrained minimum of the spring energy (Eq. 18) — no outer iteration is needed
//! for planes.
//!
//! One idea per module:
//! - [`options`]: [`DeformOptions`], [`SolverKind`]; [`stiffness`]: [`Stiffness`] and the
//!   springs K_ij (Eqs. 14–19); `wall_distance`: the distance to the moving boundary.
//! - `assembly`: the unknowns, the matrix A of Eq. 21, the couplings and right-hand sides;
//!   `operator`: A, its preconditioner and the solve, per grid state.
//! - `rfield`: the R field (Eqs. 25–26) from the skin rotations of [`rotation`] (element
//!   frames and the nearest rotation).
//! - [`bc`]: rigid motion (Eqs. 34–35), fixed and sliding markers, node precedence;
//!   [`support`]: sliding on geometry supports (Eqs. 27–33); `sliding`: the tangent
//!   constraints and the outer iteration.
//! - `increment`: one increment of the motion; `guard`: the quality guard and its
//!   increments; [`deformer`]: [`Deformer`] (the reusable set-up), [`Deformed`] and the free
//!   functions [`deform`], [`deform_on_supports`].
//! - [`linearise`]: [`Linearisation`] ([`Deformer::linearise`]), the forward and reverse
//!   products of the deformation (issue 22).
//! - [`report`]: [`DeformReport`]; [`solve`]: the multigrid preconditioner on `sparse`'s
//!   matrices and conjugate gradients; [`generate`]: test and benchmark grids.
//! - [`request`]: [`Request`], a deformation with the front ends' options (the program's
//!   `aeroshape deform` and Python's `deform()` call it).

mod assembly;
pub mod bc;
pub mod deformer;
#[cfg(feature = "mpi")]
pub mod distributed;
pub mod error;
pub mod generate;
mod guard;
mod increment;
pub mod linearise;
mod operator;
pub mod options;
pub mod report;
pub mod request;
mod rfield;
pub mod rotation;
mod sliding;
pub mod solve;
pub mod stiffness;
pub mod support;
mod wall_distance;

pub use bc::{BoundaryConditions, MarkerRole, RigidMotion};
pub use deformer::{
    Deformed, Deformer, StiffnessMatrix, deform, deform_on_supports,
    deform_on_supports_with_progress, deform_with_progress,
};
pub use error::{Error, Result};
pub use guard::cell_quality;
pub use linearise::{Linearisation, Product};
pub use options::{DeformOptions, SolverKind};
pub use report::{DeformReport, FarField, PhaseTimes, StepTime};
pub use request::Request;
pub use stiffness::Stiffness;
pub use support::{Support, Supports};
