//! Evaluation traits for parametric curves and surfaces.
//!
//! Algorithms of the lower crates (`intersect`, `surfgrid`, `deform`) are written once against
//! these traits, so that they run on the database's power-basis curves and surfaces and, in
//! tests, on analytic shapes (planes, spheres, cylinders) whose answers are known exactly.
//!
//! Parameters are *global*: a support curve of n arcs has t ∈ [0, n] (arc ⌊t⌋, local u = t −
//! ⌊t⌋, Eq. 2), a support surface of n_u × n_v patches has (u, v) ∈ [0, n_u] × [0, n_v]
//! (Eq. 7). Derivatives are with respect to the global parameters.

use crate::prelude::{Matrix2, Point3, Vector3};

/// Point and derivatives of a curve at one parameter value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurveDerivs {
    /// r(t).
    pub point: Point3,
    /// dr/dt.
    pub d1: Vector3,
    /// d²r/dt².
    pub d2: Vector3,
}

/// Point and derivatives of a surface at one parameter pair.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceDerivs {
    /// r(u, v).
    pub point: Point3,
    /// ∂r/∂u.
    pub du: Vector3,
    /// ∂r/∂v.
    pub dv: Vector3,
    /// ∂²r/∂u².
    pub duu: Vector3,
    /// ∂²r/∂u∂v.
    pub duv: Vector3,
    /// ∂²r/∂v².
    pub dvv: Vector3,
}

impl SurfaceDerivs {
    /// The first fundamental matrix G = [r_u r_v]ᵀ[r_u r_v] (Eq. 33).
    pub fn first_fundamental_form(&self) -> Matrix2 {
        Matrix2::new(
            self.du.dot(&self.du),
            self.du.dot(&self.dv),
            self.dv.dot(&self.du),
            self.dv.dot(&self.dv),
        )
    }

    /// The unit normal r_u × r_v / |r_u × r_v|, or `None` where the surface is singular
    /// (|r_u × r_v| ≤ 1e-14 |r_u| |r_v|, e.g. a degenerate patch edge).
    pub fn unit_normal(&self) -> Option<Vector3> {
        let n = self.du.cross(&self.dv);
        let norm = n.norm();
        if norm > 1e-14 * self.du.norm() * self.dv.norm() && norm > 0.0 {
            Some(n / norm)
        } else {
            None
        }
    }
}

/// A parametric curve r(t), t in [`domain`](ParamCurve::domain).
pub trait ParamCurve: Sync {
    /// The parameter interval [t_min, t_max].
    fn domain(&self) -> (f64, f64);
    /// r(t).
    fn point(&self, t: f64) -> Point3 {
        self.derivs(t).point
    }
    /// r(t), dr/dt, d²r/dt².
    fn derivs(&self, t: f64) -> CurveDerivs;
    /// Parameter values inside the domain where the curve may be only C0 (arc borders);
    /// Newton iterations may need to stop or restart there.
    fn breaks(&self) -> Vec<f64> {
        Vec::new()
    }
}

/// A parametric surface r(u, v), (u, v) in [`domain`](ParamSurface::domain).
pub trait ParamSurface: Sync {
    /// The parameter rectangle ([u_min, u_max], [v_min, v_max]).
    fn domain(&self) -> ([f64; 2], [f64; 2]);
    /// r(u, v).
    fn point(&self, u: f64, v: f64) -> Point3 {
        self.derivs(u, v).point
    }
    /// r and its first and second partial derivatives.
    fn derivs(&self, u: f64, v: f64) -> SurfaceDerivs;
    /// Unit normal r_u × r_v / |r_u × r_v| (`None` where singular).
    fn normal(&self, u: f64, v: f64) -> Option<Vector3> {
        self.derivs(u, v).unit_normal()
    }
    /// Parameter lines (u values, v values) where the surface may be only C0 (patch borders).
    fn breaks(&self) -> (Vec<f64>, Vec<f64>) {
        (Vec::new(), Vec::new())
    }
}
