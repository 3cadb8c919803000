//! Exact surfaces of the neutral model, their natural (untrimmed) domains with periodicity,
//! closed-form point inversion for the analytic ones, and their exact patches where they
//! are polynomial.

use std::f64::consts::{FRAC_PI_2, PI};

use super::curve::Curve;
use super::frame::{Affine, Frame};
use super::nurbs::NurbsSurface;
use crate::convert::bspline_surface_to_power;
use crate::prelude::{Point3, Vector3};
use crate::surface::{Patch, SupportSurface};

/// Which of u and v is the angle of a [`Surface::Revolution`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AngleParam {
    /// (θ, t): STEP and OpenCASCADE.
    U,
    /// (t, θ): IGES 120.
    V,
}

/// An exact surface. Parametrisations (frame (O, x, y, z)):
///
/// * plane O + u x + v y;
/// * cylinder O + r (cos u x + sin u y) + v z;
/// * cone O + (r + v tan α)(cos u x + sin u y) + v z;
/// * sphere O + r cos v (cos u x + sin u y) + r sin v z, v ∈ [−π/2, π/2];
/// * torus O + (R + r cos v)(cos u x + sin u y) + r sin v z.
#[derive(Debug, Clone, PartialEq)]
pub enum Surface {
    /// A plane.
    Plane {
        /// Its frame (z the normal).
        frame: Frame,
    },
    /// A circular cylinder.
    Cylinder {
        /// Its frame (z the axis).
        frame: Frame,
        /// The radius.
        radius: f64,
    },
    /// A circular cone.
    Cone {
        /// Its frame (z the axis).
        frame: Frame,
        /// The radius at v = 0.
        radius: f64,
        /// tan of the semi-angle.
        tan: f64,
    },
    /// A sphere.
    Sphere {
        /// Its frame (z the polar axis).
        frame: Frame,
        /// The radius.
        radius: f64,
    },
    /// A torus.
    Torus {
        /// Its frame (z the axis).
        frame: Frame,
        /// The major radius R.
        major: f64,
        /// The minor radius r.
        minor: f64,
    },
    /// A (rational) tensor B-spline.
    Nurbs(NurbsSurface),
    /// Bicubic patches (IGES 114): on patch (i, j), s = u − TU(i), t = v − TV(j),
    /// r = Σ c\[4q + p\] s^p t^q.
    Spline {
        /// TU.
        u_breaks: Vec<f64>,
        /// TV.
        v_breaks: Vec<f64>,
        /// Patch (i, j) at `i * n_v + j`; c\[0\] a point, the others position vectors.
        patches: Vec<[Vector3; 16]>,
    },
    /// The curve rotated by θ about the axis through `axis_point` along the unit
    /// `axis_dir` (right-handed).
    Revolution {
        /// A point of the axis.
        axis_point: Point3,
        /// The unit axis direction.
        axis_dir: Vector3,
        /// The rotated curve.
        curve: Box<Curve>,
        /// Which parameter is θ.
        angle: AngleParam,
        /// The range of θ (IGES 120's start and terminate angles; 0..2π for STEP).
        angles: (f64, f64),
        /// The range of the curve's parameter.
        range: (f64, f64),
    },
    /// C(u) + v d.
    Extrusion {
        /// The swept curve.
        curve: Box<Curve>,
        /// The extrusion vector.
        dir: Vector3,
        /// The range of u (the curve's).
        range: (f64, f64),
        /// The range of v: [0, 1] for IGES 122, unbounded for STEP.
        v_range: (f64, f64),
    },
    /// (1 − v) C₁(u) + v C₂(u), u, v ∈ [0, 1] (both curves parametrised on [0, 1]).
    Ruled {
        /// C₁.
        c1: Box<Curve>,
        /// C₂.
        c2: Box<Curve>,
    },
    /// S + d N with N = S_u × S_v / |S_u × S_v|.
    Offset {
        /// S.
        basis: Box<Surface>,
        /// d.
        distance: f64,
    },
    /// The image of a surface by an affine map.
    Mapped {
        /// The surface.
        surface: Box<Surface>,
        /// The map.
        map: Affine,
    },
}

/// The natural (untrimmed) parameter domain of a surface: intervals (infinite when the
/// surface is unbounded), periods of periodic directions, and whether the surface closes on
/// itself across a direction (a seam).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Domain {
    /// u range.
    pub u: (f64, f64),
    /// v range.
    pub v: (f64, f64),
    /// The period in u of a periodic parametrisation.
    pub u_period: Option<f64>,
    /// The period in v.
    pub v_period: Option<f64>,
    /// The surface meets itself across u = u.0 / u.1 (periodic, or a closed B-spline).
    pub u_closed: bool,
    /// The same for v.
    pub v_closed: bool,
}

impl Domain {
    fn rect(u: (f64, f64), v: (f64, f64)) -> Self {
        Domain {
            u,
            v,
            u_period: None,
            v_period: None,
            u_closed: false,
            v_closed: false,
        }
    }

    /// True when both intervals are finite.
    pub fn is_bounded(&self) -> bool {
        [self.u.0, self.u.1, self.v.0, self.v.1]
            .iter()
            .all(|x| x.is_finite())
    }
}

const INF: (f64, f64) = (f64::NEG_INFINITY, f64::INFINITY);

impl Surface {
    /// True for the analytic surfaces (plane, cylinder, cone, sphere, torus, possibly
    /// mapped), whose points invert in closed form.
    pub fn is_analytic(&self) -> bool {
        match self {
            Surface::Plane { .. }
            | Surface::Cylinder { .. }
            | Surface::Cone { .. }
            | Surface::Sphere { .. }
            | Surface::Torus { .. } => true,
            Surface::Mapped { surface, .. } => surface.is_analytic(),
            _ => false,
        }
    }

    /// The natural domain.
    pub fn domain(&self) -> Domain {
        let full = (0.0, 2.0 * PI);
        match self {
            Surface::Plane { .. } => Domain::rect(INF, INF),
            Surface::Cylinder { .. } | Surface::Cone { .. } => Domain {
                u_period: Some(2.0 * PI),
                u_closed: true,
                ..Domain::rect(full, INF)
            },
            Surface::Sphere { .. } => Domain {
                u_period: Some(2.0 * PI),
                u_closed: true,
                ..Domain::rect(full, (-FRAC_PI_2, FRAC_PI_2))
            },
            Surface::Torus { .. } => Domain {
                u_period: Some(2.0 * PI),
                v_period: Some(2.0 * PI),
                u_closed: true,
                v_closed: true,
                ..Domain::rect(full, full)
            },
            // A B-spline that closes on itself across a direction is periodic there as far
            // as the parameters of its points go (its seam is at the domain's ends).
            Surface::Nurbs(n) => {
                let (u, v) = n.domain();
                Domain {
                    u_closed: n.closed_u,
                    v_closed: n.closed_v,
                    u_period: n.closed_u.then_some(u.1 - u.0),
                    v_period: n.closed_v.then_some(v.1 - v.0),
                    ..Domain::rect(u, v)
                }
            }
            Surface::Spline {
                u_breaks, v_breaks, ..
            } => Domain::rect(
                (u_breaks[0], *u_breaks.last().unwrap_or(&u_breaks[0])),
                (v_breaks[0], *v_breaks.last().unwrap_or(&v_breaks[0])),
            ),
            Surface::Revolution {
                angle,
                angles,
                range,
                curve,
                ..
            } => {
                let whole = (angles.1 - angles.0 - 2.0 * PI).abs() <= 1e-8 * 2.0 * PI;
                let period = whole.then_some(2.0 * PI);
                // A closed generatrix over its whole period (a torus's circle) is periodic too.
                let c_period = curve
                    .period()
                    .filter(|p| (range.1 - range.0 - p).abs() <= 1e-8 * p);
                match angle {
                    AngleParam::U => Domain {
                        u_period: period,
                        u_closed: whole,
                        v_period: c_period,
                        v_closed: c_period.is_some(),
                        ..Domain::rect(*angles, *range)
                    },
                    AngleParam::V => Domain {
                        v_period: period,
                        v_closed: whole,
                        u_period: c_period,
                        u_closed: c_period.is_some(),
                        ..Domain::rect(*range, *angles)
                    },
                }
            }
            Surface::Extrusion {
                range,
                curve,
                v_range,
                ..
            } => Domain {
                u_period: curve
                    .period()
                    .filter(|p| (range.1 - range.0 - p).abs() <= 1e-12 * p),
                ..Domain::rect(*range, *v_range)
            },
            Surface::Ruled { .. } => Domain::rect((0.0, 1.0), (0.0, 1.0)),
            Surface::Offset { basis, .. } => basis.domain(),
            Surface::Mapped { surface, .. } => surface.domain(),
        }
    }

    /// S(u, v).
    pub fn point(&self, u: f64, v: f64) -> Point3 {
        match self {
            Surface::Plane { frame } => frame.at(u, v, 0.0),
            Surface::Cylinder { frame, radius } => frame.at(radius * u.cos(), radius * u.sin(), v),
            Surface::Cone { frame, radius, tan } => {
                let r = radius + v * tan;
                frame.at(r * u.cos(), r * u.sin(), v)
            }
            Surface::Sphere { frame, radius } => {
                let rc = radius * v.cos();
                frame.at(rc * u.cos(), rc * u.sin(), radius * v.sin())
            }
            Surface::Torus {
                frame,
                major,
                minor,
            } => {
                let r = major + minor * v.cos();
                frame.at(r * u.cos(), r * u.sin(), minor * v.sin())
            }
            Surface::Nurbs(n) => {
                let (u, v) = n.wrap(u, v);
                n.point(u, v)
            }
            Surface::Spline {
                u_breaks,
                v_breaks,
                patches,
            } => {
                let (m, n) = (u_breaks.len() - 1, v_breaks.len() - 1);
                let i = u_breaks[1..m].partition_point(|&b| b <= u);
                let j = v_breaks[1..n].partition_point(|&b| b <= v);
                let (s, t) = (u - u_breaks[i], v - v_breaks[j]);
                let c = &patches[i * n + j];
                let mut acc = Vector3::zeros();
                for q in (0..4).rev() {
                    let mut row = Vector3::zeros();
                    for p in (0..4).rev() {
                        row = row * s + c[4 * q + p];
                    }
                    acc = acc * t + row;
                }
                Point3::from(acc)
            }
            Surface::Revolution {
                axis_point,
                axis_dir,
                curve,
                angle,
                ..
            } => {
                let (theta, t) = match angle {
                    AngleParam::U => (u, v),
                    AngleParam::V => (v, u),
                };
                let p = curve.point(t) - axis_point;
                let d = axis_dir;
                let (s, c) = theta.sin_cos();
                axis_point + p * c + d.cross(&p) * s + d * d.dot(&p) * (1.0 - c)
            }
            Surface::Extrusion { curve, dir, .. } => curve.point(u) + dir * v,
            Surface::Ruled { c1, c2 } => {
                let a = c1.point(u);
                a + (c2.point(u) - a) * v
            }
            Surface::Offset { basis, distance } => {
                let (p, du, dv) = basis.derivs(u, v);
                let n = du.cross(&dv);
                let len = n.norm();
                if len > 0.0 {
                    p + n * (distance / len)
                } else {
                    p
                }
            }
            Surface::Mapped { surface, map } => map.point(&surface.point(u, v)),
        }
    }

    /// S, S_u, S_v (analytic for the elementary surfaces and B-splines, central differences
    /// otherwise).
    pub fn derivs(&self, u: f64, v: f64) -> (Point3, Vector3, Vector3) {
        match self {
            Surface::Plane { frame } => (frame.at(u, v, 0.0), frame.x, frame.y),
            Surface::Cylinder { frame, radius } => {
                let (s, c) = u.sin_cos();
                (
                    self.point(u, v),
                    (frame.y * c - frame.x * s) * *radius,
                    frame.z,
                )
            }
            Surface::Cone { frame, radius, tan } => {
                let (s, c) = u.sin_cos();
                let r = radius + v * tan;
                (
                    self.point(u, v),
                    (frame.y * c - frame.x * s) * r,
                    (frame.x * c + frame.y * s) * *tan + frame.z,
                )
            }
            Surface::Sphere { frame, radius } => {
                let (su, cu) = u.sin_cos();
                let (sv, cv) = v.sin_cos();
                (
                    self.point(u, v),
                    (frame.y * cu - frame.x * su) * (radius * cv),
                    ((frame.x * cu + frame.y * su) * (-sv) + frame.z * cv) * *radius,
                )
            }
            Surface::Torus {
                frame,
                major,
                minor,
            } => {
                let (su, cu) = u.sin_cos();
                let (sv, cv) = v.sin_cos();
                (
                    self.point(u, v),
                    (frame.y * cu - frame.x * su) * (major + minor * cv),
                    ((frame.x * cu + frame.y * su) * (-sv) + frame.z * cv) * *minor,
                )
            }
            Surface::Nurbs(n) => {
                let (u, v) = n.wrap(u, v);
                n.derivs(u, v)
            }
            Surface::Extrusion { curve, dir, .. } => {
                let (p, d) = curve.derivs(u);
                (p + dir * v, d, *dir)
            }
            Surface::Revolution {
                axis_point,
                axis_dir,
                curve,
                angle,
                ..
            } => {
                let (theta, t) = match angle {
                    AngleParam::U => (u, v),
                    AngleParam::V => (v, u),
                };
                let (c, dc) = curve.derivs(t);
                let d = axis_dir;
                let (sn, cs) = theta.sin_cos();
                let rot = |w: &Vector3| w * cs + d.cross(w) * sn + d * d.dot(w) * (1.0 - cs);
                let q = rot(&(c - axis_point));
                let p = axis_point + q;
                // d/dθ of the rotation is d × (the rotated vector).
                let (s_theta, s_t) = (d.cross(&q), rot(&dc));
                match angle {
                    AngleParam::U => (p, s_theta, s_t),
                    AngleParam::V => (p, s_t, s_theta),
                }
            }
            Surface::Ruled { c1, c2 } => {
                let (a, da) = c1.derivs(u);
                let (b, db) = c2.derivs(u);
                (a + (b - a) * v, da * (1.0 - v) + db * v, b - a)
            }
            Surface::Mapped { surface, map } => {
                let (p, du, dv) = surface.derivs(u, v);
                (map.point(&p), map.vector(&du), map.vector(&dv))
            }
            _ => {
                let d = self.domain();
                let scale = |r: (f64, f64), x: f64| {
                    let w = r.1 - r.0;
                    if w.is_finite() {
                        w.abs().max(x.abs())
                    } else {
                        1.0f64.max(x.abs())
                    }
                };
                let hu = 1e-6 * scale(d.u, u);
                let hv = 1e-6 * scale(d.v, v);
                (
                    self.point(u, v),
                    (self.point(u + hu, v) - self.point(u - hu, v)) / (2.0 * hu),
                    (self.point(u, v + hv) - self.point(u, v - hv)) / (2.0 * hv),
                )
            }
        }
    }

    /// The parameters of a point on an analytic surface, in closed form from its frame
    /// coordinates; angles in (−π, π] (the caller unwraps). `None` for other surfaces.
    pub fn invert(&self, p: &Point3) -> Option<(f64, f64)> {
        match self {
            Surface::Plane { frame } => {
                let q = frame.local(p)?;
                Some((q.x, q.y))
            }
            Surface::Cylinder { frame, .. } => {
                let q = frame.local(p)?;
                Some((q.y.atan2(q.x), q.z))
            }
            Surface::Cone { frame, .. } => {
                let q = frame.local(p)?;
                Some((q.y.atan2(q.x), q.z))
            }
            Surface::Sphere { frame, .. } => {
                let q = frame.local(p)?;
                let rho = q.x.hypot(q.y);
                Some((q.y.atan2(q.x), q.z.atan2(rho)))
            }
            Surface::Torus { frame, major, .. } => {
                let q = frame.local(p)?;
                let rho = q.x.hypot(q.y);
                Some((q.y.atan2(q.x), q.z.atan2(rho - major)))
            }
            Surface::Mapped { surface, map } => {
                let inv = map.linear.try_inverse()?;
                surface.invert(&Point3::from(inv * (p.coords - map.translation)))
            }
            _ => None,
        }
    }

    /// Parameter lines inside the domain where the surface may be only C0 (knots, patch
    /// borders, the curve's breaks).
    pub fn breaks(&self) -> (Vec<f64>, Vec<f64>) {
        match self {
            Surface::Nurbs(n) => (n.knots_u.breakpoints(), n.knots_v.breakpoints()),
            Surface::Spline {
                u_breaks, v_breaks, ..
            } => (u_breaks.clone(), v_breaks.clone()),
            Surface::Revolution {
                curve,
                angle,
                range,
                ..
            } => {
                let b = curve.breaks(range.0, range.1);
                match angle {
                    AngleParam::U => (Vec::new(), b),
                    AngleParam::V => (b, Vec::new()),
                }
            }
            Surface::Extrusion { curve, range, .. } => (curve.breaks(range.0, range.1), Vec::new()),
            Surface::Ruled { c1, c2 } => {
                let mut b = c1.breaks(0.0, 1.0);
                b.extend(c2.breaks(0.0, 1.0));
                b.sort_by(f64::total_cmp);
                b.dedup();
                (b, Vec::new())
            }
            Surface::Offset { basis, .. } => basis.breaks(),
            Surface::Mapped { surface, .. } => surface.breaks(),
            _ => (Vec::new(), Vec::new()),
        }
    }

    /// The exact patches of a polynomial surface with their parameter breaks: a plane over
    /// the box `(u, v)` (one bilinear patch), a 114 spline or a non-rational B-spline over its
    /// whole domain (one patch per span; the caller keeps the spans it needs).
    pub fn exact_patches(
        &self,
        u: (f64, f64),
        v: (f64, f64),
    ) -> Option<(SupportSurface, Vec<f64>, Vec<f64>)> {
        match self {
            Surface::Plane { frame } => {
                let o = frame.at(u.0, v.0, 0.0);
                let du = frame.x * (u.1 - u.0);
                let dv = frame.y * (v.1 - v.0);
                let patch = Patch {
                    deg_u: 1,
                    deg_v: 1,
                    coeffs: vec![o, Point3::from(dv), Point3::from(du), Point3::origin()],
                };
                Some((
                    SupportSurface::new("", 1, 1, vec![patch]),
                    vec![u.0, u.1],
                    vec![v.0, v.1],
                ))
            }
            Surface::Spline {
                u_breaks,
                v_breaks,
                patches,
            } => {
                let (m, n) = (u_breaks.len() - 1, v_breaks.len() - 1);
                let mut out = Vec::with_capacity(m * n);
                for j in 0..n {
                    for i in 0..m {
                        let c = &patches[i * n + j];
                        let (hu, hv) =
                            (u_breaks[i + 1] - u_breaks[i], v_breaks[j + 1] - v_breaks[j]);
                        let mut coeffs = vec![Point3::origin(); 16];
                        for p in 0..4 {
                            for q in 0..4 {
                                let f = hu.powi(p as i32) * hv.powi(q as i32);
                                coeffs[p * 4 + q] = Point3::from(c[4 * q + p] * f);
                            }
                        }
                        out.push(Patch {
                            deg_u: 3,
                            deg_v: 3,
                            coeffs,
                        });
                    }
                }
                Some((
                    SupportSurface::new("", m, n, out),
                    u_breaks.clone(),
                    v_breaks.clone(),
                ))
            }
            Surface::Nurbs(s) if !s.rational => {
                let (nu, nv) = (s.knots_u.n_basis(), s.knots_v.n_basis());
                // geom-db wants [i * n_v + j]; the model stores u fastest [i + n_u * j].
                let mut pts = vec![Point3::origin(); nu * nv];
                for j in 0..nv {
                    for i in 0..nu {
                        let h = s.ctrl[i + nu * j];
                        pts[i * nv + j] = Point3::new(h[0] / h[3], h[1] / h[3], h[2] / h[3]);
                    }
                }
                let ps = bspline_surface_to_power(&s.knots_u, &s.knots_v, &pts).ok()?;
                Some((ps.surface, ps.u_breaks, ps.v_breaks))
            }
            Surface::Mapped { surface, map } => {
                let (mut s, ub, vb) = surface.exact_patches(u, v)?;
                for p in &mut s.patches {
                    for (k, c) in p.coeffs.iter_mut().enumerate() {
                        *c = if k == 0 {
                            map.point(c)
                        } else {
                            Point3::from(map.vector(&c.coords))
                        };
                    }
                }
                Some((s, ub, vb))
            }
            _ => None,
        }
    }

    /// Applies an affine map: exactly on the surface's data where the map acts on it
    /// exactly, else as a [`Surface::Mapped`] wrapper.
    pub fn transform(&mut self, m: &Affine) {
        match self {
            Surface::Plane { frame }
            | Surface::Cylinder { frame, .. }
            | Surface::Cone { frame, .. }
            | Surface::Sphere { frame, .. }
            | Surface::Torus { frame, .. } => *frame = frame.transformed(m),
            Surface::Nurbs(n) => n.transform(m),
            Surface::Spline { patches, .. } => {
                for c in patches {
                    c[0] = m.point(&Point3::from(c[0])).coords;
                    for k in 1..16 {
                        c[k] = m.vector(&c[k]);
                    }
                }
            }
            Surface::Extrusion { curve, dir, .. } => {
                curve.transform(m);
                *dir = m.vector(dir);
            }
            Surface::Ruled { c1, c2 } => {
                c1.transform(m);
                c2.transform(m);
            }
            Surface::Mapped { map, .. } => *map = map.then(m),
            Surface::Revolution { .. } | Surface::Offset { .. } => {
                let inner = std::mem::replace(
                    self,
                    Surface::Ruled {
                        c1: Box::new(Curve::Polyline { points: Vec::new() }),
                        c2: Box::new(Curve::Polyline { points: Vec::new() }),
                    },
                );
                *self = Surface::Mapped {
                    surface: Box::new(inner),
                    map: *m,
                };
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame() -> Frame {
        Frame::orthonormal(
            Point3::new(1.0, -2.0, 0.5),
            Vector3::new(1.0, 1.0, 1.0),
            Some(Vector3::new(1.0, 0.0, 0.0)),
        )
        .unwrap()
    }

    fn analytic() -> Vec<Surface> {
        vec![
            Surface::Plane { frame: frame() },
            Surface::Cylinder {
                frame: frame(),
                radius: 2.0,
            },
            Surface::Cone {
                frame: frame(),
                radius: 1.5,
                tan: 0.3,
            },
            Surface::Sphere {
                frame: frame(),
                radius: 3.0,
            },
            Surface::Torus {
                frame: frame(),
                major: 4.0,
                minor: 1.0,
            },
        ]
    }

    /// Closed forms: distance to the axis / centre, and the inversion gives back (u, v).
    #[test]
    fn analytic_surfaces_follow_their_closed_forms() {
        let f = frame();
        for (k, s) in analytic().iter().enumerate() {
            for &(u, v) in &[(0.3, 0.2), (-2.0, 1.1), (3.0, -0.7)] {
                let p = s.point(u, v);
                let q = f.local(&p).unwrap();
                let rho = q.x.hypot(q.y);
                match k {
                    0 => assert!(q.z.abs() < 1e-14),
                    1 => assert!((rho - 2.0).abs() < 1e-14),
                    2 => assert!((rho - (1.5 + 0.3 * q.z)).abs() < 1e-14),
                    3 => assert!((q.norm() - 3.0).abs() < 1e-14),
                    _ => assert!(((rho - 4.0).hypot(q.z) - 1.0).abs() < 1e-14),
                }
                let (iu, iv) = s.invert(&p).unwrap();
                let back = s.point(iu, iv);
                assert!((back - p).norm() < 1e-13, "{k} {u} {v}");
                // Derivatives against central differences.
                let (_, du, dv) = s.derivs(u, v);
                let h = 1e-6;
                let fu = (s.point(u + h, v) - s.point(u - h, v)) / (2.0 * h);
                let fv = (s.point(u, v + h) - s.point(u, v - h)) / (2.0 * h);
                assert!((du - fu).norm() < 1e-8 && (dv - fv).norm() < 1e-8, "{k}");
            }
        }
    }

    #[test]
    fn mapped_analytic_surfaces_invert() {
        let m = Affine {
            linear: crate::prelude::Matrix3::new(2.0, 0.1, 0.0, 0.0, 0.5, 0.0, 0.3, 0.0, 1.0),
            translation: Vector3::new(5.0, 0.0, -1.0),
        };
        for mut s in analytic() {
            let orig = s.clone();
            s.transform(&m);
            let p = s.point(0.4, 0.6);
            assert!((p - m.point(&orig.point(0.4, 0.6))).norm() < 1e-13);
            let (u, v) = s.invert(&p).unwrap();
            assert!((s.point(u, v) - p).norm() < 1e-12);
        }
    }

    #[test]
    fn offset_of_a_sphere_is_a_sphere() {
        let s = Surface::Offset {
            basis: Box::new(Surface::Sphere {
                frame: frame(),
                radius: 3.0,
            }),
            distance: 0.5,
        };
        for &(u, v) in &[(0.3, 0.2), (2.0, -1.0)] {
            assert!(((s.point(u, v) - frame().origin).norm() - 3.5).abs() < 1e-13);
        }
    }
}
