//! Sparse linear algebra of the workspace, written once: compressed-sparse-row matrices and
//! graphs, deterministic parallel kernels on vectors of 3-vectors, projected conjugate
//! gradients and the stationary (point) iteration with per-unknown linear constraints, the
//! orderings (reverse Cuthill–McKee, breadth-first level sets, Morton) with one permutation
//! convention, and the envelope Cholesky factorisation. See `docs/crates/sparse.md`.
//!
//! Layer: the top of the workspace; depends on no workspace crate. `surfgrid` (the harmonic
//! re-map of §3.3) and `deform` (the spring systems of §4, whose multigrid is built on these
//! types) use it.
//!
//! - [`SymMatrix`]: symmetric matrix, diagonal apart, off-diagonal values stored as f64 or
//!   f32 ([`Entry`]); one scalar matrix shared by the three components of a displacement.
//! - [`Csr`], [`csr::build_rows`]: general CSR matrices built row-parallel; [`Graph`].
//! - [`vec3`]: dot products, norms and updates whose sums do not depend on the thread count.
//! - [`LinearOperator`]: what the conjugate gradients multiply by ([`SymMatrix`], or
//!   [`WithBlocks`]: a [`SymMatrix`] plus symmetric 3×3 blocks on some unknowns).
//! - [`pcg()`] with a [`Preconditioner`] ([`Jacobi`], or any other, e.g. deform's multigrid)
//!   and [`Constraints`]; [`stationary::point_iteration`].
//! - [`order`]: orderings and permutations. **Convention: `perm[old] = new`.**
//! - [`envelope`]: envelope Cholesky in a given order.
//! - [`SymMatrix::to_csmat`], [`Csr::to_csmat`]: [`sprs::CsMat`], the public interchange
//!   type for a sparse matrix that leaves a crate.
//!
//! Why by hand: sprs (used here as the interchange type) stores CSR matrices and multiplies
//! them, but has no product over three right-hand sides sharing one scalar matrix in one
//! pass, no reduction whose bits are independent of the thread count, no projected
//! (constrained) conjugate gradients, and no preconditioner hooks; its envelope and
//! Cholesky companions (sprs-ldl) are sequential and LDLᵀ. These kernels carry the volume
//! deformation's run time (docs/crates/deform.md, "Solvers").
//!
//! Determinism: every parallel loop works on fixed chunks of [`vec3::CHUNK`] rows or
//! entries; each row is computed by one task in a fixed order; every reduction sums fixed
//! chunks sequentially and adds the chunk sums in order. Results are bit-identical for any
//! thread count.

pub mod constraint;
pub mod csr;
pub mod envelope;
pub mod error;
pub mod generate;
pub mod graph;
pub mod madd;
pub mod operator;
pub mod order;
pub mod pcg;
pub mod precond;
pub mod stationary;
pub mod sym;
pub mod vec3;

#[cfg(test)]
mod tests;

pub use constraint::{Constraint, Constraints};
pub use csr::Csr;
pub use error::{Error, Result};
pub use graph::Graph;
pub use operator::{Block3, LinearOperator, WithBlocks};
pub use pcg::{SolveOptions, SolveReport, pcg};
pub use precond::{Jacobi, Preconditioner, Weights};
pub use stationary::point_iteration;
pub use sym::{Entry, SymMatrix};
pub use vec3::V3;
