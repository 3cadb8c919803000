//! Geometric measures of a model and their derivatives for a model perturbation (issue 46,
//! the constraints of `aeroshape`): thickness along a line through a station, volume enclosed
//! by support surfaces, area of support surfaces. Each is measured once on a model, which
//! gives a [`Measured`] whose [`tangent`](Measured::tangent) is the measure's derivative for a
//! [`ModelTangent`] of that model (e.g. [`crate::update::ModelLinearisation::jvp`]) and whose
//! [`add_cotangent`](Measured::add_cotangent) is its transpose. See docs/constraints.md for
//! the equations.
//!
//! - [`thickness`]: the outermost intersections of the line p + t d with the surfaces
//!   ([`geom_db::newton::line`]); thickness t_max − t_min, dt = n·δr / n·d (the line held);
//! - [`volume`]: V = Σ σ_s ∬ (r·m)(m·(r_u × r_v)) du dv (divergence theorem with F = (x·m) m,
//!   exact Gauss rules on the patches);
//! - [`area`]: A = Σ ∬ |r_u × r_v| du dv (Gauss rules on patches split until two levels
//!   agree to 1e-12).

use geom_db::linearise::ModelTangent;
use geom_db::{GeomDb, SurfaceId};

mod integral;
mod thickness;

pub use integral::{area, volume};
pub use thickness::{LineFailure, LineHit, Thickness, line_hits, thickness};

/// A measure taken on one model, with what its derivative needs.
#[derive(Debug, Clone)]
pub enum Measured {
    /// A thickness at one station.
    Thickness(Thickness),
    /// A volume: the surfaces with their outward signs σ, and the unit axis m.
    Volume {
        /// The value.
        value: f64,
        /// Surfaces and their signs σ (σ r_u × r_v points out of the body).
        surfaces: Vec<(SurfaceId, f64)>,
        /// The unit axis.
        axis: [f64; 3],
    },
    /// An area: the surfaces and the subdivision level [`area`] chose on each.
    Area {
        /// The value.
        value: f64,
        /// Surfaces and levels.
        surfaces: Vec<(SurfaceId, usize)>,
    },
}

impl Measured {
    /// A volume of `surfaces` (with outward signs) along the unit `axis`.
    pub fn volume(db: &GeomDb, surfaces: Vec<(SurfaceId, f64)>, axis: [f64; 3]) -> Self {
        Measured::Volume {
            value: volume(db, &surfaces, &axis),
            surfaces,
            axis,
        }
    }

    /// The area of `surfaces`.
    pub fn area(db: &GeomDb, surfaces: &[SurfaceId]) -> Self {
        let (value, levels) = area(db, surfaces);
        Measured::Area {
            value,
            surfaces: surfaces.iter().copied().zip(levels).collect(),
        }
    }

    /// The value (length, volume or area units).
    pub fn value(&self) -> f64 {
        match self {
            Measured::Thickness(th) => th.value(),
            Measured::Volume { value, .. } | Measured::Area { value, .. } => *value,
        }
    }

    /// True when `t` has the layout of `db` (one entry per control node).
    pub fn fits(db: &GeomDb, t: &ModelTangent) -> bool {
        t.nodes.len() == db.control_nodes.len()
    }

    /// The value's derivative for the perturbation `t` of the model `db` it was measured on
    /// (the caller checks [`fits`](Self::fits)).
    pub fn tangent(&self, db: &GeomDb, t: &ModelTangent) -> f64 {
        match self {
            Measured::Thickness(th) => th.tangent(db, t),
            Measured::Volume { surfaces, axis, .. } => {
                integral::volume_tangent(db, surfaces, axis, t)
            }
            Measured::Area { surfaces, .. } => integral::area_tangent(db, surfaces, t),
        }
    }

    /// The transpose of [`tangent`](Self::tangent): adds `bar` times the value's gradient
    /// with respect to the model to the cotangent `w`.
    pub fn add_cotangent(&self, db: &GeomDb, bar: f64, w: &mut ModelTangent) {
        match self {
            Measured::Thickness(th) => th.add_cotangent(db, bar, w),
            Measured::Volume { surfaces, axis, .. } => {
                integral::volume_cotangent(db, surfaces, axis, bar, w)
            }
            Measured::Area { surfaces, .. } => integral::area_cotangent(db, surfaces, bar, w),
        }
    }
}
