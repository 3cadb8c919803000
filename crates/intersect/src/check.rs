//! How well a support curve lies on its defining surfaces *between* its control points.
//!
//! Eq. (12) puts the control points on both surfaces; the arcs through them (Eq. 4) are
//! polynomials, so between control points the curve deviates from the true intersection by
//! the interpolation error. [`curve_surface_deviation`] samples the curve uniformly in each
//! arc and measures the distance of every sample to each defining surface (the foot of the
//! normal, Eq. 11, seeded by this crate's bounding-volume hierarchy). The model update and
//! `aeroshape geom check` use geom-db's measure of the same quantity
//! ([`geom_db::check::curve_surfaces_distance`]: ≥ 200 samples per arc, more where the curve
//! turns, continuation with a global re-check); this one serves tests on analytic shapes.

use crate::error::{Error, Result};
use crate::project::SurfaceProjector;
use geom_db::eval::{ParamCurve, ParamSurface};
use rayon::prelude::*;

/// Distance of a curve from its two defining surfaces at sample points.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DeviationReport {
    /// Number of sample points.
    pub samples: usize,
    /// Largest distance to surface 1 and to surface 2.
    pub max_distance: [f64; 2],
    /// Curve parameter where each maximum occurs.
    pub at_t: [f64; 2],
    /// Root mean square of the larger of the two distances over the samples.
    pub rms: f64,
}

impl DeviationReport {
    /// The larger of the two maxima.
    pub fn max(&self) -> f64 {
        self.max_distance[0].max(self.max_distance[1])
    }
}

/// Sample parameters: `per_arc` uniformly spaced values in each arc (arc borders from
/// [`ParamCurve::breaks`]), including both ends of the curve.
pub fn sample_parameters<C: ParamCurve + ?Sized>(curve: &C, per_arc: usize) -> Vec<f64> {
    let (lo, hi) = curve.domain();
    let mut e = vec![lo];
    let mut b: Vec<f64> = curve
        .breaks()
        .into_iter()
        .filter(|x| *x > lo && *x < hi)
        .collect();
    b.sort_by(f64::total_cmp);
    b.dedup();
    e.extend(b);
    e.push(hi);
    let k = per_arc.max(1);
    let mut out = Vec::with_capacity(k * (e.len() - 1) + 1);
    for w in e.windows(2) {
        for j in 0..k {
            out.push(w[0] + (w[1] - w[0]) * j as f64 / k as f64);
        }
    }
    out.push(hi);
    out
}

/// Measures the distance of `curve` from the surfaces of `s1` and `s2` at `per_arc` samples
/// per arc. Samples are projected in parallel; the maxima do not depend on the thread count.
pub fn curve_surface_deviation<C, S1, S2>(
    label: &str,
    curve: &C,
    s1: &SurfaceProjector<'_, S1>,
    s2: &SurfaceProjector<'_, S2>,
    per_arc: usize,
) -> Result<DeviationReport>
where
    C: ParamCurve + ?Sized,
    S1: ParamSurface + ?Sized,
    S2: ParamSurface + ?Sized,
{
    let ts = sample_parameters(curve, per_arc);
    let d: Vec<Result<(f64, f64)>> = ts
        .par_iter()
        .enumerate()
        .map(|(i, &t)| {
            let p = curve.point(t);
            if !p.iter().all(|c| c.is_finite()) {
                return Err(Error::NonFinitePoint {
                    entity: label.to_string(),
                    index: i,
                });
            }
            Ok((
                s1.project_indexed(&p, i)?.distance,
                s2.project_indexed(&p, i)?.distance,
            ))
        })
        .collect();
    let mut rep = DeviationReport {
        samples: ts.len(),
        max_distance: [0.0; 2],
        at_t: [ts[0]; 2],
        rms: 0.0,
    };
    let mut sum = 0.0;
    for (k, r) in d.into_iter().enumerate() {
        let (a, b) = r?;
        if a > rep.max_distance[0] {
            rep.max_distance[0] = a;
            rep.at_t[0] = ts[k];
        }
        if b > rep.max_distance[1] {
            rep.max_distance[1] = b;
            rep.at_t[1] = ts[k];
        }
        sum += a.max(b).powi(2);
    }
    rep.rms = (sum / ts.len() as f64).sqrt();
    Ok(rep)
}
