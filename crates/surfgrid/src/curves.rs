//! Curve discretisation (§2.2): nodes on a curve component placed by equidistribution of
//! the metric length ∫ √(r′ᵀ T r′) dt (the arc length divided by the local size): the number
//! of segments is that integral rounded, and node k sits where the cumulative integral is k/n
//! of the total. Every curve component is discretised once; the surface components that
//! share it use the same nodes, so neighbouring surface grids conform.

use geom_db::eval::ParamCurve;
use geom_db::{CurveCompId, GeomDb};

use crate::error::{Error, Result};
use crate::spacing::SizeField;

/// Sub-intervals per unit of global curve parameter (one arc) for the length integral.
const SUB_PER_ARC: usize = 64;

/// Global support-curve parameters of the nodes of curve component `id`, from its start
/// (t0) to its end (t1) inclusive. At least one segment; at least three when the component
/// starts and ends at the same corner.
pub fn discretise_curve(db: &GeomDb, id: CurveCompId, field: &SizeField) -> Result<Vec<f64>> {
    let c = db.curve_component(id);
    let curve = db.curve(c.curve);
    let span = (c.t1 - c.t0).abs();
    let n_sub = ((span.ceil() as usize).max(1) * SUB_PER_ARC).max(SUB_PER_ARC);
    // 3-point Gauss–Legendre on each sub-interval of s ∈ [0, 1]
    let gx = [-(0.6f64.sqrt()), 0.0, 0.6f64.sqrt()];
    let gw = [5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0];
    let dtds = c.t1 - c.t0;
    let mut cum = Vec::with_capacity(n_sub + 1);
    cum.push(0.0);
    let mut total = 0.0;
    for i in 0..n_sub {
        let (s0, s1) = (i as f64 / n_sub as f64, (i + 1) as f64 / n_sub as f64);
        let mut acc = 0.0;
        for k in 0..3 {
            let s = 0.5 * (s0 + s1) + 0.5 * (s1 - s0) * gx[k];
            let d = curve.derivs(c.param_at(s));
            let tan = d.d1 * dtds;
            let t = field.metric_at(&d.point);
            acc += gw[k] * tan.dot(&(t * tan)).max(0.0).sqrt();
        }
        total += 0.5 * (s1 - s0) * acc;
        cum.push(total);
    }
    if !(total.is_finite() && total > 0.0) {
        return Err(Error::DegenerateCurve {
            curve: id,
            length: total,
        });
    }
    let min_seg = if c.start == c.end { 3 } else { 1 };
    let n = (total.round() as usize).max(min_seg);
    let mut ts = Vec::with_capacity(n + 1);
    ts.push(c.t0);
    let mut j = 0;
    for k in 1..n {
        let target = total * k as f64 / n as f64;
        while cum[j + 1] < target {
            j += 1;
        }
        let f = (target - cum[j]) / (cum[j + 1] - cum[j]);
        let s = (j as f64 + f) / n_sub as f64;
        ts.push(c.param_at(s));
    }
    ts.push(c.t1);
    Ok(ts)
}

/// Metric length of every segment between consecutive parameters (midpoint rule on a fine
/// subdivision); used by tests and reports.
pub fn segment_lengths(db: &GeomDb, id: CurveCompId, ts: &[f64]) -> Vec<f64> {
    let curve = db.curve(db.curve_component(id).curve);
    ts.windows(2)
        .map(|w| {
            let m = 32;
            (0..m)
                .map(|i| {
                    let a = w[0] + (w[1] - w[0]) * i as f64 / m as f64;
                    let b = w[0] + (w[1] - w[0]) * (i + 1) as f64 / m as f64;
                    (curve.point(b) - curve.point(a)).norm()
                })
                .sum()
        })
        .collect()
}
