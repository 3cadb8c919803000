//! Topology (§2.1): corners, curve components (a range of a support curve between two
//! corners) and surface components (a support surface bounded by oriented loops of curve
//! components), with the inward normal orientation.
//!
//! Loop convention: seen from the side the inward normal points to, an outer loop (the first)
//! runs counter-clockwise around the region and inner loops (holes) clockwise; equivalently
//! n × t points into the region (n the inward normal, t the loop's tangent). Two surface
//! components that share a curve component then traverse it in opposite directions (§2.1).
//! A patch edge that collapses to a point (a pole, e.g. the nose of a body of revolution)
//! carries no curve component: the loop passes through the corner at the pole.

use serde::{Deserialize, Serialize};

use crate::ids::{CornerId, CurveCompId, CurveId, SurfaceId};
use crate::prelude::Point3;

/// A corner: an end point of curve components.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Corner {
    /// Position.
    pub point: Point3,
    /// A name for messages and reports (may be empty).
    #[serde(default)]
    pub name: String,
}

/// A curve component: the part t ∈ [t0, t1] (or [t1, t0] when t1 < t0, traversed backwards)
/// of a support curve, from corner `start` (at t0) to corner `end` (at t1).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CurveComponent {
    /// A name for messages and reports (may be empty).
    #[serde(default)]
    pub name: String,
    /// The support curve.
    pub curve: CurveId,
    /// Global parameter of the start on the support curve.
    pub t0: f64,
    /// Global parameter of the end on the support curve.
    pub t1: f64,
    /// The corner at t0.
    pub start: CornerId,
    /// The corner at t1.
    pub end: CornerId,
}

impl CurveComponent {
    /// The global support-curve parameter at fraction s ∈ [0, 1] from start to end.
    #[inline]
    pub fn param_at(&self, s: f64) -> f64 {
        self.t0 + s * (self.t1 - self.t0)
    }
}

/// A curve component used in a loop, possibly traversed from `end` to `start`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OrientedCurve {
    /// The curve component.
    pub comp: CurveCompId,
    /// True when the loop runs from the component's `end` to its `start`.
    #[serde(default)]
    pub reversed: bool,
}

/// Which side of a support surface the region to be meshed lies on (§2.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Orientation {
    /// The inward normal is +r_u × r_v.
    Positive,
    /// The inward normal is −(r_u × r_v).
    Negative,
}

impl Orientation {
    /// +1 or −1.
    pub fn sign(self) -> f64 {
        match self {
            Orientation::Positive => 1.0,
            Orientation::Negative => -1.0,
        }
    }
}

/// A surface component: the part of a support surface bounded by loops of curve components.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceComponent {
    /// A name ("wing", "fuselage").
    #[serde(default)]
    pub name: String,
    /// The support surface.
    pub surface: SurfaceId,
    /// Boundary loops: the outer loop first, then holes (see the module doc for directions).
    pub loops: Vec<Vec<OrientedCurve>>,
    /// Direction of the inward normal.
    pub inward: Orientation,
}
