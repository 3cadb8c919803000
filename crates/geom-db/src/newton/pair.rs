//! The intersection point of two surfaces with one parameter frozen, Eq. (12):
//!
//! ```text
//! r₁(u₁, v₁) − r₂(u₂, v₂⁰) = 0                                         (Eq. 12)
//! ```
//!
//! solved as the least-squares problem f = ½|r₁ − r₂|² in the three free parameters of
//! y = [u₁, v₁, u₂, v₂] (any one of the four may be the frozen one) by the safeguarded
//! Newton of [`crate::newton`], with the Gauss–Newton Hessian JᵀJ. It serves the model
//! update of `intersect` (each control point of a support curve keeps its frozen parameter
//! from the initial model) and the import's junction rebuild (the curve's driving parameter
//! is frozen at the nodes of each arc).
//!
//! The conditioning of the frozen problem is measured by [`free_sines`]: the 3 × 3 Jacobian
//! has, up to sign, det J = (r₁,u × r₁,v) · r₂,w with w the free parameter of the frozen
//! parameter's surface (here surface 2), so it is well conditioned when that free direction
//! crosses the other surface's tangent plane.

use super::{Eval, Outcome, Problem, Settings, minimise};
use crate::eval::ParamSurface;
use crate::prelude::Vector3;
use nalgebra::SMatrix;

/// F(y) = r₁(u₁, v₁) − r₂(u₂, v₂) at the full parameters y = [u₁, v₁, u₂, v₂], the Jacobian
/// columns [r₁,u, r₁,v, −r₂,u, −r₂,v] and |r₁| + |r₂| (the magnitude that sets the round-off
/// level of F).
fn residual_and_jacobian<S1, S2>(s1: &S1, s2: &S2, y: &[f64; 4]) -> (Vector3, [Vector3; 4], f64)
where
    S1: ParamSurface + ?Sized,
    S2: ParamSurface + ?Sized,
{
    let d1 = s1.derivs(y[0], y[1]);
    let d2 = s2.derivs(y[2], y[3]);
    (
        d1.point - d2.point,
        [d1.du, d1.dv, -d2.du, -d2.dv],
        d1.point.coords.norm() + d2.point.coords.norm(),
    )
}

/// Eq. (12) with parameter `frozen` of y = [u₁, v₁, u₂, v₂] held at `value`: a
/// [`Problem<3>`] in the other three parameters, in their order in y.
///
/// f = ½|r₁ − r₂|², g = Jᵀ(r₁ − r₂), H = JᵀJ (Gauss–Newton), residual |r₁ − r₂| (length
/// units), round-off level of f 16 ε |r₁ − r₂| (|r₁| + |r₂|). A non-finite residual gives
/// f = residual = ∞, so the line search rejects the point.
///
/// ```
/// use geom_db::eval::{ParamSurface, SurfaceDerivs};
/// use geom_db::newton::{Settings, pair::Frozen};
/// use geom_db::prelude::{Point3, Vector3};
/// // the plane z = 0 and the plane x = 1 (r(u, v) = (1, u, v)): they meet along x = 1, z = 0
/// struct Plane(bool);
/// impl ParamSurface for Plane {
///     fn domain(&self) -> ([f64; 2], [f64; 2]) {
///         ([-2.0, 2.0], [-2.0, 2.0])
///     }
///     fn derivs(&self, u: f64, v: f64) -> SurfaceDerivs {
///         let z = Vector3::zeros();
///         let (point, du, dv) = if self.0 {
///             (Point3::new(1.0, u, v), Vector3::y(), Vector3::z())
///         } else {
///             (Point3::new(u, v, 0.0), Vector3::x(), Vector3::y())
///         };
///         SurfaceDerivs { point, du, dv, duu: z, duv: z, dvv: z }
///     }
/// }
/// let (s1, s2) = (Plane(false), Plane(true));
/// // freeze u₂ = 0.5: the intersection point is (1, 0.5, 0)
/// let prob = Frozen::new(&s1, &s2, 2, 0.5);
/// let (lo, hi) = ([-2.0; 4], [2.0; 4]);
/// let (y, o) = prob.solve(&[0.0, 0.0, 0.0, 0.3], &lo, &hi, Settings { tol: 1e-12, max_iters: 20 });
/// assert!(o.report.converged);
/// assert!((y[0] - 1.0).abs() < 1e-12 && (y[1] - 0.5).abs() < 1e-12);
/// assert_eq!(y[2], 0.5);
/// assert!(y[3].abs() < 1e-12);
/// ```
#[derive(Debug)]
pub struct Frozen<'s, S1: ?Sized, S2: ?Sized> {
    s1: &'s S1,
    s2: &'s S2,
    frozen: usize,
    value: f64,
}

impl<'s, S1, S2> Frozen<'s, S1, S2>
where
    S1: ParamSurface + ?Sized,
    S2: ParamSurface + ?Sized,
{
    /// Surfaces `s1` and `s2` with parameter `frozen` (0 to 3: u₁, v₁, u₂, v₂) at `value`.
    pub fn new(s1: &'s S1, s2: &'s S2, frozen: usize, value: f64) -> Self {
        debug_assert!(
            frozen < 4,
            "frozen parameter {frozen} is not one of u1, v1, u2, v2"
        );
        Self {
            s1,
            s2,
            frozen,
            value,
        }
    }

    /// The full parameters y of the free ones `x` (the frozen one at its value).
    pub fn full(&self, x: &[f64; 3]) -> [f64; 4] {
        let mut y = [0.0; 4];
        let mut k = 0;
        for (i, yi) in y.iter_mut().enumerate() {
            if i == self.frozen {
                *yi = self.value;
            } else {
                *yi = x[k];
                k += 1;
            }
        }
        y
    }

    /// The free parameters of full parameters `y` (the frozen one dropped).
    pub fn reduce(&self, y: &[f64; 4]) -> [f64; 3] {
        let mut x = [0.0; 3];
        let mut k = 0;
        for (i, &yi) in y.iter().enumerate() {
            if i != self.frozen {
                x[k] = yi;
                k += 1;
            }
        }
        x
    }

    /// Solves Eq. (12) by [`minimise`] from `y0` (its frozen entry is ignored) in the box
    /// `lo` ≤ y ≤ `hi` of the full parameters. Returns the full parameters at the end (the
    /// frozen one at its value) and the Newton's outcome in the free ones.
    pub fn solve(
        &self,
        y0: &[f64; 4],
        lo: &[f64; 4],
        hi: &[f64; 4],
        s: Settings,
    ) -> ([f64; 4], Outcome<3>) {
        let o = minimise(self, self.reduce(y0), &self.reduce(lo), &self.reduce(hi), s);
        (self.full(&o.x), o)
    }
}

impl<S1, S2> Problem<3> for Frozen<'_, S1, S2>
where
    S1: ParamSurface + ?Sized,
    S2: ParamSurface + ?Sized,
{
    fn eval(&self, x: &[f64; 3], _active: &[bool; 3]) -> Eval<3> {
        let y = self.full(x);
        let (f, cols, mag) = residual_and_jacobian(self.s1, self.s2, &y);
        let mut j = SMatrix::<f64, 3, 3>::zeros();
        let mut k = 0;
        for (i, c) in cols.iter().enumerate() {
            if i != self.frozen {
                j.set_column(k, c);
                k += 1;
            }
        }
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
        Eval {
            f: 0.5 * r * r,
            g,
            h,
            res: r,
            fnoise: 16.0 * f64::EPSILON * r * mag,
        }
    }
}

/// For each candidate frozen parameter k of y = [u₁, v₁, u₂, v₂], the sine that measures the
/// conditioning of Eq. (12) with k frozen: |n_other · r̂_free|, where `free` is the other
/// parameter of k's surface and `n_other` the other surface's unit normal. A zero normal or
/// a zero free derivative gives 0 (a degenerate point); a normal that is not zero is used as
/// it is, however small.
pub fn free_sines<S1, S2>(s1: &S1, s2: &S2, y: &[f64; 4]) -> [f64; 4]
where
    S1: ParamSurface + ?Sized,
    S2: ParamSurface + ?Sized,
{
    let d1 = s1.derivs(y[0], y[1]);
    let d2 = s2.derivs(y[2], y[3]);
    let unit = |v: Vector3| {
        let n = v.norm();
        if n > 0.0 { v / n } else { Vector3::zeros() }
    };
    let n1 = unit(d1.du.cross(&d1.dv));
    let n2 = unit(d2.du.cross(&d2.dv));
    let sine = |n: &Vector3, r: &Vector3| n.dot(&unit(*r)).abs();
    [
        sine(&n2, &d1.dv),
        sine(&n2, &d1.du),
        sine(&n1, &d2.dv),
        sine(&n1, &d2.du),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::SurfaceDerivs;
    use crate::prelude::Point3;

    /// The unit sphere r(u, v) = (cos u cos v, sin u cos v, sin v).
    struct Sphere;
    impl ParamSurface for Sphere {
        fn domain(&self) -> ([f64; 2], [f64; 2]) {
            ([-3.0, 3.0], [-1.5, 1.5])
        }
        fn derivs(&self, u: f64, v: f64) -> SurfaceDerivs {
            let (su, cu, sv, cv) = (u.sin(), u.cos(), v.sin(), v.cos());
            SurfaceDerivs {
                point: Point3::new(cu * cv, su * cv, sv),
                du: Vector3::new(-su * cv, cu * cv, 0.0),
                dv: Vector3::new(-cu * sv, -su * sv, cv),
                duu: Vector3::new(-cu * cv, -su * cv, 0.0),
                duv: Vector3::new(su * sv, -cu * sv, 0.0),
                dvv: Vector3::new(-cu * cv, -su * cv, -sv),
            }
        }
    }

    /// The plane x = c, r(u, v) = (c, u, v).
    struct PlaneX(f64);
    impl ParamSurface for PlaneX {
        fn domain(&self) -> ([f64; 2], [f64; 2]) {
            ([-2.0, 2.0], [-2.0, 2.0])
        }
        fn derivs(&self, u: f64, v: f64) -> SurfaceDerivs {
            let z = Vector3::zeros();
            SurfaceDerivs {
                point: Point3::new(self.0, u, v),
                du: Vector3::y(),
                dv: Vector3::z(),
                duu: z,
                duv: z,
                dvv: z,
            }
        }
    }

    /// Sphere ∩ plane x = 0.6 is the circle y² + z² = 0.64; with each parameter frozen in
    /// turn the solution lies on it, and the Jacobian agrees with central differences.
    #[test]
    fn sphere_plane_circle_with_each_parameter_frozen() {
        let (s1, s2) = (Sphere, PlaneX(0.6));
        let (lo, hi) = ([-3.0, -1.5, -2.0, -2.0], [3.0, 1.5, 2.0, 2.0]);
        let s = Settings {
            tol: 1e-13,
            max_iters: 50,
        };
        let y0 = [0.9, 0.3, 0.7, 0.25];
        for k in 0..4 {
            let prob = Frozen::new(&s1, &s2, k, y0[k]);
            let (y, o) = prob.solve(&y0, &lo, &hi, s);
            assert!(o.report.converged, "frozen {k}: {o:?}");
            assert_eq!(y[k], y0[k]);
            let p = s1.point(y[0], y[1]);
            assert!((p - s2.point(y[2], y[3])).norm() < 1e-12);
            assert!((p.x - 0.6).abs() < 1e-12 && (p.y * p.y + p.z * p.z - 0.64).abs() < 1e-12);
            // the gradient Jᵀ F against central differences of f
            let x = prob.reduce(&[0.8, 0.2, 0.5, 0.1]);
            let e = prob.eval(&x, &[false; 3]);
            for i in 0..3 {
                let hstep = 1e-6;
                let (mut xp, mut xm) = (x, x);
                xp[i] += hstep;
                xm[i] -= hstep;
                let fd =
                    (prob.eval(&xp, &[false; 3]).f - prob.eval(&xm, &[false; 3]).f) / (2.0 * hstep);
                assert!(
                    (fd - e.g[i]).abs() < 1e-8,
                    "frozen {k}, g[{i}]: {fd} vs {}",
                    e.g[i]
                );
            }
        }
    }

    /// The segment r(u, v) = (0, 0, v): r_u = 0, so it has no normal.
    struct Segment;
    impl ParamSurface for Segment {
        fn domain(&self) -> ([f64; 2], [f64; 2]) {
            ([-1.0, 1.0], [-1.0, 1.0])
        }
        fn derivs(&self, _u: f64, v: f64) -> SurfaceDerivs {
            let z = Vector3::zeros();
            SurfaceDerivs {
                point: Point3::new(0.0, 0.0, v),
                du: z,
                dv: Vector3::z(),
                duu: z,
                duv: z,
                dvv: z,
            }
        }
    }

    /// The sines on the sphere–plane pair against their closed forms, and 0 where a surface
    /// has no normal or a zero free derivative.
    #[test]
    fn free_sines_closed_form_and_degenerate() {
        let (s1, s2) = (Sphere, PlaneX(0.6));
        let (u, v) = (0.4_f64, 0.3_f64);
        let s = free_sines(&s1, &s2, &[u, v, 0.0, 0.0]);
        // n₂ = x̂: r̂₁,v = (−cos u sin v, …), r̂₁,u = (−sin u, cos u, 0)
        assert!((s[0] - u.cos() * v.sin()).abs() < 1e-14);
        assert!((s[1] - u.sin()).abs() < 1e-14);
        // n₁ = ±r₁ (the sphere's unit normal): r₂,v = ẑ, r₂,u = ŷ
        assert!((s[2] - v.sin()).abs() < 1e-14);
        assert!((s[3] - u.sin() * v.cos()).abs() < 1e-14);
        let d = free_sines(&s1, &Segment, &[u, v, 0.0, 0.5]);
        assert_eq!([d[0], d[1], d[3]], [0.0; 3]);
        assert!((d[2] - v.sin()).abs() < 1e-14);
    }
}
