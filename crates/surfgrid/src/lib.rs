//! Surface grids tied to the geometry (paper §2.2–2.3, §3.3): curve discretisation,
//! advancing-front triangulation in the parametric plane, spacing control, grid update at
//! frozen parametric coordinates, classification of imported grids.
//!
//! Layer: depends on `geom-db`, `intersect` and `mesh`; the only crate that knows both the
//! geometry and the grid. Paper equations used: Eq. (33) (first fundamental form G, metric
//! M = G/h² of the parametric plane), Eq. (11) (foot of the normal, via `intersect`, for
//! boundary (u, v) and classification), Eqs. (2) and (7) (curve and surface evaluation at
//! frozen parameters in the update). Algorithms and limits: `docs/crates/surfgrid.md`.
//!
//! * [`spacing`]: the surface size field (§2.3): uniform size, point and line sources,
//!   background mesh with a metric T interpolated linearly; on a surface the parametric
//!   metric M = Jᵀ T J = G / h² (Eq. 33, G the first fundamental form).
//! * [`curves`]: curve discretisation by equidistribution of ∫ ds / h.
//! * [`generate`](mod@generate): advancing front in each surface component's parametric plane in the
//!   normalised space of M (desired size one), then swaps and smoothing.
//! * [`pole`]: degenerate sides of the parameter rectangle (poles) and the fan built there.
//! * [`grid`]: nodes with their support and parameters, per-component parametric grids,
//!   conversion to `mesh::Mesh` with Gmsh-like classification.
//! * [`classify`](mod@classify): an imported grid (SU2, no parameters) tied to the geometry by projection.
//! * [`linearise`]: forward and reverse products of the update for a perturbation of the
//!   updated model (issue 22).
//! * [`update`](mod@update): re-evaluation at frozen parameters after a model update, with a harmonic
//!   re-map of a component whose boundary moved in its parametric plane and smoothing (§3.3).

mod aft;
pub mod classify;
pub mod curves;
pub mod error;
pub mod generate;
pub mod grid;
pub mod harmonic;
pub mod linearise;
pub mod pole;
mod smooth;
pub mod spacing;
pub mod stats;
pub mod update;

pub use classify::{ClassifyOptions, ClassifyReport, classify, classify_wall};
pub use error::{Error, Result};
pub use generate::{GenerateOptions, generate};
pub use grid::{ComponentGrid, NodeSupport, PoleCopy, SurfaceGrid};
pub use linearise::SurfaceLinearisation;
pub use spacing::SizeField;
pub use stats::{GridStats, grid_stats};
pub use update::{UpdateOptions, UpdateRecord, UpdateReport, Updater, evaluate_frozen, update};
