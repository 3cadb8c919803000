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
//! How far R reaches (issue 20): R of Eq. 26 makes the near field turn with the body, which
//! keeps the cells at the wall intact but moves nodes far from the wall more than the wall
//! itself. [`DeformOptions::rotation_reach`] blends R to the identity with the distance from
//! the moving boundary (`None`, the default, keeps the full R: it gave the best near-wall
//! quality on the Gmsh-made wing grids), and [`DeformReport::far_field`] reports the largest
//! displacement far from the wall. Measured by `cargo run --release -p deform --example
//! rotation_reach`, the body pitched 5° (D: the moving nodes' bounding-box diagonal; the
//! picture is `docs/figures/rotation-reach.png`, the figures `docs/crates/deform.md`, "How
//! far R reaches"):
//!
//! | grid | far field (≥ D) max / wall max: no R, full R, reach D/2 | near-wall q min: before, no R, full R, reach D/2 |
//! |---|---|---|
//! | OCC split wing | 0.70, 4.79, 0.98 | 0.25870, 0.24919, 0.25868, 0.25779 |
//! | OCC wing-body | 0.64, 2.36, 0.87 | 0.37488, 0.36946, 0.37487, 0.37485 |
//! | ONERA M6 | 0.71, 4.25, 1.00 | 0.24519, 0.24310, 0.24515, 0.24406 |
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
pub mod layer;
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
pub use linearise::{AdjointStart, Linearisation, Product};
pub use options::{DeformOptions, SolverKind};
pub use report::{DeformReport, FarField, PhaseTimes, StepTime};
pub use request::Request;
pub use stiffness::Stiffness;
pub use support::{Support, Supports};
