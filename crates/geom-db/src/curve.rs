//! Support curves (Eqs. 2–6): arcs of power-basis polynomials r(u) = A·U, u ∈ [0, 1] per arc,
//! any degree per arc, and the global parameter t ∈ [0, n_arcs] (arc ⌊t⌋, local u = t − ⌊t⌋,
//! last arc at t = n_arcs).

use serde::{Deserialize, Serialize};

use crate::control;
use crate::eval::{CurveDerivs, ParamCurve};
use crate::ids::{ControlNodeId, SurfaceId};
use crate::poly::{horner, horner_d2};
use crate::prelude::{Point3, Vector3};

/// One arc of a support curve: r(u) = a_0 + a_1 u + … + a_n u^n, u ∈ [0, 1] (Eq. 2).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Arc {
    /// Degree n (the paper's "rank").
    pub degree: usize,
    /// a_0 … a_n (Eq. 5); `coeffs.len() == degree + 1`.
    pub coeffs: Vec<Point3>,
}

impl Arc {
    /// The arc with the given power-basis coefficients (degree = `coeffs.len() - 1`).
    pub fn new(coeffs: Vec<Point3>) -> Self {
        Self {
            degree: coeffs.len().saturating_sub(1),
            coeffs,
        }
    }

    /// The straight segment from `a` to `b`.
    pub fn line(a: Point3, b: Point3) -> Self {
        Self::new(vec![a, Point3::from(b - a)])
    }

    /// r(u), local u ∈ [0, 1] (values outside extend the polynomial).
    #[inline]
    pub fn point(&self, u: f64) -> Point3 {
        Point3::from(horner(&self.coeffs, u))
    }

    /// r(u), r'(u), r''(u) with respect to the local parameter.
    #[inline]
    pub fn derivs(&self, u: f64) -> CurveDerivs {
        let (p, d1, d2) = horner_d2(&self.coeffs, u);
        CurveDerivs {
            point: Point3::from(p),
            d1,
            d2,
        }
    }

    /// The arc interpolating control points at the frozen nodes of degree `pts.len() - 1`
    /// (A = V⁻¹ R, Eq. 4, see [`control`]).
    ///
    /// # Panics
    /// If `pts` is empty or its degree exceeds [`control::MAX_DEGREE`].
    pub fn from_control_points(pts: &[Point3]) -> Self {
        Self::new(control::coeffs_from_points_1d(pts))
    }

    /// The arc of degree `degree` interpolating `f` at the frozen nodes of that degree
    /// (Chebyshev–Lobatto interpolation; exact when `f` is a polynomial of degree ≤ `degree`).
    ///
    /// # Panics
    /// If `degree` exceeds [`control::MAX_DEGREE`].
    pub fn interpolate(degree: usize, f: impl Fn(f64) -> Point3) -> Self {
        let pts: Vec<Point3> = control::nodes(degree).iter().map(|&x| f(x)).collect();
        Self::from_control_points(&pts)
    }

    /// The arc's control points r(x_i) at the frozen nodes of its degree (R = V A).
    pub fn control_points(&self) -> Vec<Point3> {
        control::nodes(self.degree)
            .iter()
            .map(|&x| self.point(x))
            .collect()
    }

    /// The same arc traversed backwards: r̃(u) = r(1 − u).
    pub fn reversed(&self) -> Self {
        // r(1-u) = Σ a_k (1-u)^k = Σ_j u^j Σ_{k≥j} a_k C(k,j) (-1)^j
        let n = self.degree;
        let mut out = vec![Vector3::zeros(); n + 1];
        for (k, a) in self.coeffs.iter().enumerate() {
            let mut c = 1.0;
            for j in 0..=k {
                // c = C(k, j) (-1)^j
                out[j] += a.coords * c;
                c = -c * (k - j) as f64 / (j + 1) as f64;
            }
        }
        Self::new(out.into_iter().map(Point3::from).collect())
    }
}

/// Control nodes of a support curve: `nodes[a]` lists the ids of the `degree + 1` control
/// nodes of arc a, in order of increasing local parameter (the nodes of
/// [`control::nodes`]). Empty when the curve has no control nodes.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct CurveControl {
    /// Per arc, its control node ids.
    pub nodes: Vec<Vec<ControlNodeId>>,
}

impl CurveControl {
    /// True when the curve carries no control nodes.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }
}

/// A support curve: arcs joined end to end, global parameter t ∈ [0, n_arcs].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SupportCurve {
    /// A name for messages and reports (may be empty).
    #[serde(default)]
    pub name: String,
    /// The arcs, in order of increasing t.
    pub arcs: Vec<Arc>,
    /// The support surfaces whose intersection this curve is (0, 1 or 2, §3.1).
    #[serde(default)]
    pub defining_surfaces: Vec<SurfaceId>,
    /// The control nodes of each arc (§3).
    #[serde(default, skip_serializing_if = "CurveControl::is_empty")]
    pub control: CurveControl,
}

impl SupportCurve {
    /// A curve without control nodes and defining surfaces.
    pub fn new(name: impl Into<String>, arcs: Vec<Arc>) -> Self {
        Self {
            name: name.into(),
            arcs,
            defining_surfaces: Vec::new(),
            control: CurveControl::default(),
        }
    }

    /// Number of arcs.
    pub fn n_arcs(&self) -> usize {
        self.arcs.len()
    }

    /// The arc index and local parameter of global t: arc ⌊t⌋ clamped to the arcs, local
    /// u = t − arc (outside [0, n] the end arcs are extended).
    #[inline]
    pub fn locate(&self, t: f64) -> (usize, f64) {
        locate(t, self.arcs.len())
    }

    /// Points at many global parameters (in parallel above a size threshold; the result does
    /// not depend on the number of threads).
    pub fn points(&self, ts: &[f64]) -> Vec<Point3> {
        crate::par_map(ts, |&t| ParamCurve::point(self, t))
    }
}

/// Cell index and local coordinate of a global parameter over `n` unit cells.
#[inline]
pub(crate) fn locate(t: f64, n: usize) -> (usize, f64) {
    let last = n.saturating_sub(1);
    // Truncation is floor for t ≥ 0 and avoids a libm call; `as usize` saturates, so
    // negative values and NaN give 0 and huge values the last cell.
    let i = (t as usize).min(last);
    (i, t - i as f64)
}

impl ParamCurve for SupportCurve {
    fn domain(&self) -> (f64, f64) {
        (0.0, self.arcs.len() as f64)
    }

    #[inline]
    fn point(&self, t: f64) -> Point3 {
        let (a, u) = self.locate(t);
        self.arcs[a].point(u)
    }

    #[inline]
    fn derivs(&self, t: f64) -> CurveDerivs {
        let (a, u) = self.locate(t);
        self.arcs[a].derivs(u)
    }

    fn breaks(&self) -> Vec<f64> {
        (1..self.arcs.len()).map(|i| i as f64).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn locate_global() {
        assert_eq!(locate(0.0, 3), (0, 0.0));
        assert_eq!(locate(2.5, 3), (2, 0.5));
        assert_eq!(locate(3.0, 3), (2, 1.0));
        assert_eq!(locate(-0.5, 3).0, 0);
        assert_eq!(locate(f64::NAN, 3).0, 0);
    }

    #[test]
    fn reversed_arc() {
        let a = Arc::new(vec![
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(0.5, 2.0, 0.0),
            Point3::new(0.0, -1.0, 3.0),
        ]);
        let r = a.reversed();
        for &u in &[0.0, 0.2, 0.7, 1.0] {
            assert!((a.point(u) - r.point(1.0 - u)).norm() < 1e-14);
        }
    }
}
