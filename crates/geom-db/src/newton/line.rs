//! The intersection point of a straight line and a surface:
//!
//! ```text
//! r(u, v) − (p + t d) = 0
//! ```
//!
//! solved as the least-squares problem f = ½|r(u, v) − p − t d|² in x = [u, v, t] by the
//! safeguarded Newton of [`crate::newton`], with the Gauss–Newton Hessian JᵀJ (J = [r_u, r_v,
//! −d]). It serves the thickness constraints of `aeroshape` (the upper and lower surface
//! points on a line through a station).
//!
//! At a solution, the parameter t moves with a perturbation δr of the surface (the line held)
//! by dt = n·δr / n·d with n = r_u × r_v ([`LineSurface::dt_of`]): the Jacobian's first two
//! columns are orthogonal to n, so n·(r_u du + r_v dv − d dt + δr) = 0 leaves dt alone.

use super::{Eval, Outcome, Problem, Settings, minimise};
use crate::eval::ParamSurface;
use crate::prelude::{Point3, Vector3};
use nalgebra::SMatrix;

/// The line p + t d against surface `surf`: a [`Problem<3>`] in x = [u, v, t].
///
/// f = ½|r − p − t d|², g = Jᵀ(r − p − t d), H = JᵀJ, residual |r − p − t d| (length units),
/// round-off level of f 16 ε |r − p − t d| (|r| + |p| + |t d|). A non-finite residual gives
/// f = residual = ∞.
///
/// ```
/// use geom_db::eval::{ParamSurface, SurfaceDerivs};
/// use geom_db::newton::{Settings, line::LineSurface};
/// use geom_db::prelude::{Point3, Vector3};
/// // the plane z = 0.25 + 0.5 u (r(u, v) = (u, v, 0.25 + 0.5 u))
/// struct Plane;
/// impl ParamSurface for Plane {
///     fn domain(&self) -> ([f64; 2], [f64; 2]) {
///         ([-2.0, 2.0], [-2.0, 2.0])
///     }
///     fn derivs(&self, u: f64, v: f64) -> SurfaceDerivs {
///         let z = Vector3::zeros();
///         SurfaceDerivs { point: Point3::new(u, v, 0.25 + 0.5 * u), du: Vector3::new(1.0, 0.0, 0.5),
///             dv: Vector3::y(), duu: z, duv: z, dvv: z }
///     }
/// }
/// // the vertical line through (1, 0.5, 0) meets it at z = 0.75
/// let line = LineSurface::new(&Plane, Point3::new(1.0, 0.5, 0.0), Vector3::z());
/// let o = line.solve([0.0, 0.0, 0.0], 10.0, Settings { tol: 1e-12, max_iters: 20 });
/// assert!(o.report.converged);
/// assert!((o.x[2] - 0.75).abs() < 1e-12);
/// ```
#[derive(Debug)]
pub struct LineSurface<'s, S: ?Sized> {
    surf: &'s S,
    p: Point3,
    d: Vector3,
}

impl<'s, S: ParamSurface + ?Sized> LineSurface<'s, S> {
    /// The line through `p` along `d` (any length; t is in units of |d|) and the surface.
    pub fn new(surf: &'s S, p: Point3, d: Vector3) -> Self {
        Self { surf, p, d }
    }

    /// Solves from x0 = [u, v, t] inside the surface's domain, with t ∈ [−t_max, t_max].
    pub fn solve(&self, x0: [f64; 3], t_max: f64, s: Settings) -> Outcome<3> {
        let ([u0, u1], [v0, v1]) = self.surf.domain();
        minimise(self, x0, &[u0, v0, -t_max], &[u1, v1, t_max], s)
    }

    /// dt for a perturbation `dr` of the surface point at the solution (u, v) (the line held):
    /// n·δr / n·d, n = r_u × r_v; `None` where the line is tangent to the surface or the
    /// surface singular there.
    pub fn dt_of(&self, u: f64, v: f64, dr: &Vector3) -> Option<f64> {
        let e = self.surf.derivs(u, v);
        let n = e.du.cross(&e.dv);
        let nd = n.dot(&self.d);
        if nd.abs() <= 1e-12 * n.norm() * self.d.norm() || nd == 0.0 {
            None
        } else {
            Some(n.dot(dr) / nd)
        }
    }
}

impl<S: ParamSurface + ?Sized> Problem<3> for LineSurface<'_, S> {
    fn eval(&self, x: &[f64; 3], _active: &[bool; 3]) -> Eval<3> {
        let e = self.surf.derivs(x[0], x[1]);
        let q = self.p + self.d * x[2];
        let f = e.point - q;
        let mut j = SMatrix::<f64, 3, 3>::zeros();
        j.set_column(0, &e.du);
        j.set_column(1, &e.dv);
        j.set_column(2, &(-self.d));
        let g = j.transpose() * f;
        let h = j.transpose() * j;
        let r = f.norm();
        if !r.is_finite() {
            return Eval {
                f: f64::INFINITY,
                g,
                h,
                res: f64::INFINITY,
                fnoise: 0.0,
            };
        }
        let mag = e.point.coords.norm() + q.coords.norm();
        Eval {
            f: 0.5 * r * r,
            g,
            h,
            res: r,
            fnoise: 16.0 * f64::EPSILON * r * mag,
        }
    }
}
