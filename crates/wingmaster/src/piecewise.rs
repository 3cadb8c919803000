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

/// The p + 1 non-zero basis functions at t into `out` (Cox–de Boor, the same arithmetic as
/// `KnotVector::basis_into`) without heap allocation for degrees below 16; returns the span.
#[inline]
pub(crate) fn basis_into(kv: &KnotVector, t: f64, out: &mut [f64]) -> usize {
    const N: usize = 16;
    let p = kv.degree();
    if p >= N {
        return kv.basis_into(t, out);
    }
    let s = kv.find_span(t);
    let t = t.clamp(kv.domain().0, kv.domain().1);
    let k = kv.knots();
    let mut left = [0.0; N];
    let mut right = [0.0; N];
    out[0] = 1.0;
    for j in 1..=p {
        left[j] = t - k[s + 1 - j];
        right[j] = k[s + j] - t;
        let mut saved = 0.0;
        for r in 0..j {
            let temp = out[r] / (right[r + 1] + left[j - r]);
            out[r] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        out[j] = saved;
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn basis_into_matches_geom_db_bit_for_bit() {
        let kv = KnotVector::clamped_uniform(4, 11).unwrap();
        let (mut a, mut b) = (vec![0.0; 5], vec![0.0; 5]);
        for i in 0..=200 {
            let t = i as f64 / 200.0;
            assert_eq!(basis_into(&kv, t, &mut a), kv.basis_into(t, &mut b));
            assert_eq!(a, b);
        }
    }
}
