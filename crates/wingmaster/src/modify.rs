//! The section modification of Eq. (40):
//! q(t) = q*(t) + Σ_i (P_i − P_i*) B_i(t) + Σ_j Q_j B_j(t),
//! applied to the original section points q* (any coordinates; they need not lie on the
//! B-splines). Each original point is attached once to the fitted section: its thickness
//! parameter t, its surface (the thickness deviation is mirrored on the lower surface) and
//! its camber parameter u. A zero deviation returns q* bit for bit.

use crate::error::{Error, Result};
use crate::fit::SectionFit;
use crate::section::SectionParams;
use crate::thickness::{ThicknessParams, ThicknessPolygon};

/// Original points bound to a reference section (P*, Q*), ready for Eq. (40).
#[derive(Debug, Clone, PartialEq)]
pub struct SectionModifier {
    base: SectionParams,
    base_poly: ThicknessPolygon,
    camber_knots: geom_db::bspline::KnotVector,
    points: Vec<[f64; 2]>,
    t: Vec<f64>,
    sign: Vec<f64>,
    u: Vec<f64>,
}

/// `a + d`, keeping `a` unchanged (including the sign of zero) when `d` is exactly zero.
fn add(a: f64, d: f64) -> f64 {
    if d == 0.0 { a } else { a + d }
}

impl SectionModifier {
    /// Binds the fitted points (local coordinates) to the fitted section.
    pub fn from_fit(fit: &SectionFit) -> Result<Self> {
        Self::new(fit.params.clone(), fit.points.clone(), &fit.sigma)
    }

    /// Binds `points` (local coordinates) with their feet σ_i on the section `base`
    /// (σ > 0 upper surface, σ < 0 lower; t = |σ|).
    pub fn new(base: SectionParams, points: Vec<[f64; 2]>, sigma: &[f64]) -> Result<Self> {
        if sigma.len() != points.len() {
            return Err(Error::Modify {
                reason: format!("{} points but {} feet", points.len(), sigma.len()),
            });
        }
        let sec = base.build()?;
        let base_poly = sec.thickness().clone();
        let camber = sec.camber();
        let t: Vec<f64> = sigma.iter().map(|s| s.abs().min(1.0)).collect();
        let sign = sigma
            .iter()
            .map(|&s| if s >= 0.0 { 1.0 } else { -1.0 })
            .collect();
        let u = t
            .iter()
            .map(|&tt| camber.u_at_x(base_poly.point(tt)[0]))
            .collect();
        let camber_knots = camber.knots().clone();
        Ok(Self {
            base,
            base_poly,
            camber_knots,
            points,
            t,
            sign,
            u,
        })
    }

    /// The reference parameters (P*, Q*).
    pub fn base(&self) -> &SectionParams {
        &self.base
    }

    /// The original points q*.
    pub fn points(&self) -> &[[f64; 2]] {
        &self.points
    }

    /// Eq. (40): the points for new thickness parameters (giving P_i) and camber polygon
    /// deviations ΔQ_j (the Q_j of Eq. 40; one per camber control point of the base).
    pub fn apply(
        &self,
        thickness: &ThicknessParams,
        camber_deviation: &[[f64; 2]],
    ) -> Result<Vec<[f64; 2]>> {
        let poly = thickness.polygon()?;
        if poly.points().len() != self.base_poly.points().len() {
            return Err(Error::Modify {
                reason: format!(
                    "the thickness polygon has {} points, the reference {}: the number of \
                     extra points must not change",
                    poly.points().len(),
                    self.base_poly.points().len()
                ),
            });
        }
        if camber_deviation.len() != self.base.camber.len() {
            return Err(Error::Modify {
                reason: format!(
                    "{} camber deviations given for {} camber control points",
                    camber_deviation.len(),
                    self.base.camber.len()
                ),
            });
        }
        let dp: Vec<[f64; 2]> = poly
            .points()
            .iter()
            .zip(self.base_poly.points())
            .map(|(p, q)| [p[0] - q[0], p[1] - q[1]])
            .collect();
        Ok(self
            .points
            .iter()
            .zip(self.deviation(&dp, camber_deviation))
            .map(|(q, d)| [add(q[0], d[0]), add(q[1], d[1])])
            .collect())
    }

    /// The linear part of Eq. (40) at every bound point: Σ_i ΔP_i B_i(t) (its z mirrored on
    /// the lower surface) + Σ_j ΔQ_j B_j(u), for thickness polygon deviations `dp` (one per
    /// polygon point of the reference) and camber polygon deviations `dq`. Eq. (40) is
    /// linear in (ΔP, ΔQ), so this is also the derivative of the points along any
    /// direction (ΔP, ΔQ); the caller checks the lengths (see [`apply`](Self::apply)).
    pub fn deviation(&self, dp: &[[f64; 2]], dq: &[[f64; 2]]) -> Vec<[f64; 2]> {
        let camber_kv = &self.camber_knots;
        let kv = self.base_poly.knots();
        (0..self.points.len())
            .map(|i| {
                let d = kv.curve_point(dp, self.t[i]);
                let c = camber_kv.curve_point(dq, self.u[i]);
                [d[0] + c[0], self.sign[i] * d[1] + c[1]]
            })
            .collect()
    }

    /// The reference thickness polygon P*.
    pub fn base_polygon(&self) -> &ThicknessPolygon {
        &self.base_poly
    }
}
