//! The camber line of §6.1: a B-spline whose polygon Q_j holds the design variables.
//!
//! The camber line is a B-spline curve (x(u), z_c(u)), u ∈ [0, 1], of degree min(3, m − 1)
//! on a clamped uniform knot vector. With the abscissae of Q_j at the Greville points
//! ξ_j = (u_{j+1} + … + u_{j+p}) / p the B-spline reproduces x(u) = u exactly (linear
//! precision), so z_c is a function of x evaluated without inversion; other abscissae are
//! allowed and inverted by safeguarded Newton.

use geom_db::bspline::KnotVector;

use crate::error::{Error, Result};

/// A camber line: control polygon Q_j and its B-spline basis.
#[derive(Debug, Clone, PartialEq)]
pub struct CamberLine {
    knots: KnotVector,
    points: Vec<[f64; 2]>,
    greville: bool,
}

/// The Greville abscissae of a knot vector.
pub fn greville(kv: &KnotVector) -> Vec<f64> {
    let p = kv.degree();
    let k = kv.knots();
    (0..kv.n_basis())
        .map(|j| {
            if p == 0 {
                k[j]
            } else {
                k[j + 1..=j + p].iter().sum::<f64>() / p as f64
            }
        })
        .collect()
}

/// The knot vector used for `m` camber control points.
pub fn camber_knots(m: usize) -> Result<KnotVector> {
    if m < 2 {
        return Err(Error::InvalidSection {
            parameter: "camber".into(),
            value: m as f64,
            reason: "at least 2 camber control points are needed".into(),
        });
    }
    Ok(KnotVector::clamped_uniform((m - 1).min(3), m)?)
}

impl CamberLine {
    /// A camber line from its polygon; abscissae must increase.
    pub fn new(points: Vec<[f64; 2]>) -> Result<Self> {
        let knots = camber_knots(points.len())?;
        for (j, q) in points.iter().enumerate() {
            if !(q[0].is_finite() && q[1].is_finite()) {
                return Err(Error::InvalidSection {
                    parameter: format!("camber point {j}"),
                    value: if q[0].is_finite() { q[1] } else { q[0] },
                    reason: "not finite".into(),
                });
            }
            if j > 0 && q[0] <= points[j - 1][0] {
                return Err(Error::InvalidSection {
                    parameter: format!("x of camber point {j}"),
                    value: q[0],
                    reason: "camber abscissae must increase".into(),
                });
            }
        }
        let g = greville(&knots);
        let greville = g.iter().zip(&points).all(|(a, q)| *a == q[0]);
        Ok(Self {
            knots,
            points,
            greville,
        })
    }

    /// The flat camber line z_c = 0 with `m` control points at the Greville abscissae.
    pub fn flat(m: usize) -> Result<Self> {
        let g = greville(&camber_knots(m)?);
        Self::new(g.into_iter().map(|x| [x, 0.0]).collect())
    }

    /// The control polygon Q_j.
    pub fn points(&self) -> &[[f64; 2]] {
        &self.points
    }

    /// The basis B_j(u).
    pub fn knots(&self) -> &KnotVector {
        &self.knots
    }

    /// The curve parameter u with x(u) = x.
    pub fn u_at_x(&self, x: f64) -> f64 {
        let (x0, x1) = (self.points[0][0], self.points[self.points.len() - 1][0]);
        if self.greville {
            return x.clamp(0.0, 1.0);
        }
        if x <= x0 {
            return 0.0;
        }
        if x >= x1 {
            return 1.0;
        }
        let (mut lo, mut hi) = (0.0, 1.0);
        let mut u = (x - x0) / (x1 - x0);
        for _ in 0..60 {
            let d = self.knots.curve_ders(&self.points, u, 1);
            let f = d[0][0] - x;
            if f > 0.0 {
                hi = u;
            } else {
                lo = u;
            }
            if f.abs() <= 1e-15 {
                break;
            }
            let mut un = u - f / d[1][0];
            if !(un > lo && un < hi && un.is_finite()) {
                un = 0.5 * (lo + hi);
            }
            if (un - u).abs() < 1e-16 {
                break;
            }
            u = un;
        }
        u
    }

    /// z_c(x) and its first two derivatives with respect to x.
    pub fn z_ders(&self, x: f64) -> [f64; 3] {
        let u = self.u_at_x(x);
        let d = self.knots.curve_ders(&self.points, u, 2);
        let (xu, zu) = (d[1][0], d[1][1]);
        let (xuu, zuu) = (d[2][0], d[2][1]);
        let z1 = zu / xu;
        let z2 = (zuu * xu - zu * xuu) / (xu * xu * xu);
        [d[0][1], z1, z2]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn greville_gives_linear_x() {
        let kv = camber_knots(7).unwrap();
        let g = greville(&kv);
        let pts: Vec<[f64; 2]> = g.iter().map(|&x| [x, 0.0]).collect();
        for i in 0..=20 {
            let u = i as f64 / 20.0;
            let p = kv.curve_point(&pts, u);
            assert!((p[0] - u).abs() < 1e-15);
        }
    }

    #[test]
    fn non_greville_inversion() {
        let c = CamberLine::new(vec![[0.0, 0.0], [0.2, 0.05], [0.7, 0.04], [1.0, 0.0]]).unwrap();
        for &x in &[0.01, 0.3, 0.77, 0.99] {
            let u = c.u_at_x(x);
            let p = c.knots().curve_point(c.points(), u);
            assert!((p[0] - x).abs() < 1e-13);
        }
    }
}
