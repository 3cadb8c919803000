//! Fast evaluation of the section B-splines: each is converted once by
//! `geom_db::convert::bspline_to_power` (Bézier extraction) into power-basis arcs, evaluated
//! by Horner's rule without allocation (`geom_db::poly::horner_d2`).

use geom_db::bspline::KnotVector;
use geom_db::convert::{PowerArc, bspline_to_power};
use geom_db::poly::horner_d2;
use geom_db::prelude::Point3;

use crate::error::Result;

/// A planar B-spline curve as power-basis arcs.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Piecewise {
    arcs: Vec<PowerArc>,
}

impl Piecewise {
    pub(crate) fn new(kv: &KnotVector, ctrl: &[[f64; 2]]) -> Result<Self> {
        let pts: Vec<Point3> = ctrl.iter().map(|c| Point3::new(c[0], c[1], 0.0)).collect();
        Ok(Self {
            arcs: bspline_to_power(kv, &pts)?,
        })
    }

    /// Point, first and second derivative with respect to the B-spline parameter t.
    #[inline]
    pub(crate) fn d2(&self, t: f64) -> [[f64; 2]; 3] {
        let k = self
            .arcs
            .partition_point(|a| a.t1 <= t)
            .min(self.arcs.len() - 1);
        let a = &self.arcs[k];
        let h = a.t1 - a.t0;
        let u = ((t - a.t0) / h).clamp(0.0, 1.0);
        let (p, d1, d2) = horner_d2(&a.arc.coeffs, u);
        [
            [p.x, p.y],
            [d1.x / h, d1.y / h],
            [d2.x / (h * h), d2.y / (h * h)],
        ]
    }
}
