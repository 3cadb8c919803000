//! The geometric database of the paper (§2.1, §3).
//!
//! Layer: first of the geometry crates; depends only on `iges` (file format).
//!
//! * Support curves ([`SupportCurve`]): arcs of power-basis polynomials r(u) = A·U, any
//!   degree per arc (Eqs. 2–6), global parameter t ∈ [0, n_arcs].
//! * Support surfaces ([`SupportSurface`]): a regular grid of patches r(u, v) = U·A·V, degree
//!   n×m per patch (Eqs. 7–10), global parameters (u, v) ∈ [0, n_u] × [0, n_v].
//! * Evaluation of points, first and second derivatives, normals and the first fundamental
//!   form (Eq. 33) through the traits of [`eval`].
//! * Topology ([`topology`]): corners, curve components, surface components with oriented
//!   loops and the inward normal (§2.1).
//! * Control nodes (§3, [`control`]): Chebyshev–Lobatto parameter values, the solve of
//!   Eq. (4) / Eq. (9) for A ([`GeomDb::set_control_points`]) and its inverse.
//! * Basis conversions ([`convert`]): Bézier / B-spline ↔ power basis.
//! * The database as one serde type stored as RON ([`GeomDb`]), validated on load, and a
//!   check report ([`check`]).
//! * B-spline bases ([`bspline`]), shared by the parametrisation crates.
//! * The numerics every crate shares: the safeguarded box-constrained Newton ([`newton`]),
//!   point inversion — the foot of the normal, Eq. (11) — on curves and surfaces
//!   ([`invert`]), point merging within a tolerance ([`merge`]) and Gauss–Legendre rules
//!   ([`quadrature`]).

pub mod bspline;
pub mod check;
pub mod control;
pub mod convert;
pub mod curve;
pub mod db;
pub mod error;
pub mod eval;
pub mod ids;
pub mod import;
pub mod invert;
pub mod linearise;
pub mod merge;
pub mod newton;
pub mod poly;
pub mod prelude;
pub mod quadrature;
pub mod surface;
pub mod topology;

pub use check::{CheckOptions, CheckReport};
pub use curve::{Arc, CurveControl, SupportCurve};
pub use db::{FORMAT_VERSION, GeomDb, ModelTolerances, Tolerances};
pub use error::{Entity, Error, Result};
pub use ids::{ControlNodeId, CornerId, CurveCompId, CurveId, SurfCompId, SurfaceId};
pub use surface::{Patch, Side, SupportSurface, SurfaceControl};
pub use topology::{Corner, CurveComponent, Orientation, OrientedCurve, SurfaceComponent};

/// Maps `f` over `xs`, in parallel with rayon above a size threshold. Each output depends on
/// its input only, so the result is the same for any number of threads.
pub(crate) fn par_map<T: Sync, R: Send>(xs: &[T], f: impl Fn(&T) -> R + Sync + Send) -> Vec<R> {
    use rayon::prelude::*;
    const PAR_THRESHOLD: usize = 4096;
    if xs.len() < PAR_THRESHOLD {
        xs.iter().map(f).collect()
    } else {
        xs.par_iter().with_min_len(1024).map(f).collect()
    }
}
