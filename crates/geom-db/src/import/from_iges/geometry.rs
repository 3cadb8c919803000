//! IGES curves and surfaces as exact curves and surfaces of the neutral model, in the
//! definition space of the entity that points to them: an entity's own 124 chain maps its
//! definition space into its parent's (children are built first, then the parent's map is
//! applied to the whole).

use std::f64::consts::PI;

use iges::{DeId, Entity};

use super::Front;
use crate::import::Error;
use crate::import::model::{
    Affine, AngleParam, ConicKind, Curve, Frame, Piece, Surface, canonical_curve,
    canonical_surface, closure_tol,
};
use crate::prelude::{Matrix3, Point3, Vector3};

/// Curves and surfaces nest at most this deep (a cycle in a corrupt file stops here).
const MAX_DEPTH: usize = 16;

fn affine(m: &iges::TransformationMatrix) -> Affine {
    let r = &m.rotation;
    Affine {
        linear: Matrix3::new(
            r[0][0], r[0][1], r[0][2], r[1][0], r[1][1], r[1][2], r[2][0], r[2][1], r[2][2],
        ),
        translation: Vector3::from(m.translation),
    }
}

fn p3(v: [f64; 3]) -> Point3 {
    Point3::from(v)
}

impl Front<'_> {
    /// The entity's own transformation (its 124 chain), `None` for the identity.
    pub(super) fn own_map(&self, id: DeId) -> Result<Option<Affine>, Error> {
        Ok(self
            .file
            .transform(id)
            .map_err(Error::Iges)?
            .map(|m| affine(&m)))
    }

    /// A 116 point (its own map applied).
    fn point_entity(&self, from: DeId, id: DeId) -> Result<Point3, Error> {
        let r = self.file.expect(from, id, &[116]).map_err(Error::Iges)?;
        let Entity::Point(p) = &r.entity else {
            return Err(self.bad(from, format!("D{} is not a decoded 116 point", id.line())));
        };
        let q = p3(p.point);
        Ok(match self.own_map(id)? {
            Some(m) => m.point(&q),
            None => q,
        })
    }

    /// A 123 direction (its own map's linear part applied).
    fn direction_entity(&self, from: DeId, id: DeId) -> Result<Vector3, Error> {
        let r = self.file.expect(from, id, &[123]).map_err(Error::Iges)?;
        let Entity::Direction(d) = &r.entity else {
            return Err(self.bad(
                from,
                format!("D{} is not a decoded 123 direction", id.line()),
            ));
        };
        let v = Vector3::from(d.direction);
        Ok(match self.own_map(id)? {
            Some(m) => m.vector(&v),
            None => v,
        })
    }

    /// The curve of entity `id` and its parameter range: 100, 102, 104, 106, 110, 112, 126,
    /// 130, and 142's model-space curve.
    pub(super) fn build_curve(&self, id: DeId, depth: usize) -> Result<(Curve, (f64, f64)), Error> {
        if depth > MAX_DEPTH {
            return Err(self.bad(id, "curves nest more than 16 levels deep (a cycle?)"));
        }
        let rec = self
            .file
            .get(id)
            .ok_or_else(|| self.bad(id, "pointer names no entity"))?;
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        let (mut curve, range) = match &rec.entity {
            Entity::Line(l) => {
                if rec.de.form != 0 {
                    return Err(self.bad(
                        id,
                        format!(
                            "line form {} (ray or unbounded line) cannot bound a surface",
                            rec.de.form
                        ),
                    ));
                }
                let (a, b) = (p3(l.start), p3(l.end));
                (
                    Curve::Line {
                        origin: a,
                        dir: b - a,
                    },
                    (0.0, 1.0),
                )
            }
            Entity::CircularArc(a) => {
                let (cx, cy) = (a.center[0], a.center[1]);
                let r = (a.start[0] - cx).hypot(a.start[1] - cy);
                if !(r > 0.0) || !r.is_finite() {
                    return Err(self.bad(id, "circular arc of zero radius"));
                }
                let t0 = (a.start[1] - cy).atan2(a.start[0] - cx);
                let mut t1 = (a.end[1] - cy).atan2(a.end[0] - cx);
                while t1 <= t0 + 1e-14 {
                    t1 += 2.0 * PI;
                }
                let frame = Frame {
                    origin: Point3::new(cx, cy, a.z),
                    x: Vector3::x(),
                    y: Vector3::y(),
                    z: Vector3::z(),
                };
                (
                    Curve::Conic {
                        kind: ConicKind::Ellipse,
                        frame,
                        a: r,
                        b: r,
                    },
                    (t0, t1),
                )
            }
            Entity::ConicArc(c) => self.conic(id, c, rec.de.form)?,
            Entity::CopiousData(c) => {
                if c.points.len() < 2 {
                    return Err(
                        self.bad(id, "copious data with fewer than 2 points is not a curve")
                    );
                }
                if !c.points.iter().all(|p| finite(p)) {
                    return Err(self.bad(id, "copious data point is not finite"));
                }
                let n = c.points.len();
                (
                    Curve::Polyline {
                        points: c.points.iter().map(|&p| p3(p)).collect(),
                    },
                    (0.0, (n - 1) as f64),
                )
            }
            Entity::SplineCurve(s) => {
                if !finite(&s.breakpoints) || s.breakpoints.windows(2).any(|w| w[1] <= w[0]) {
                    return Err(self.bad(id, "break points are not increasing"));
                }
                let segments = s
                    .segments
                    .iter()
                    .map(|c| std::array::from_fn(|k| Vector3::new(c[0][k], c[1][k], c[2][k])))
                    .collect();
                let range = (s.breakpoints[0], *s.breakpoints.last().expect("N ≥ 1"));
                (
                    Curve::Spline {
                        breaks: s.breakpoints.clone(),
                        segments,
                    },
                    range,
                )
            }
            Entity::BSplineCurve(b) => {
                let pts: Vec<Point3> = b.control_points.iter().map(|&p| p3(p)).collect();
                let n = canonical_curve(b.degree, &b.knots, &pts, &b.weights)
                    .map_err(|e| self.bad(id, e))?;
                let (d0, d1) = n.domain();
                let range = (b.range[0].max(d0), b.range[1].min(d1));
                if !(range.1 > range.0) {
                    return Err(self.bad(
                        id,
                        format!(
                            "parameter range {:?} is empty or outside the knots",
                            b.range
                        ),
                    ));
                }
                // Snap a range equal to the domain up to round-off.
                let snap = |x: f64, d: f64| {
                    if (x - d).abs() <= 1e-12 * (d1 - d0) {
                        d
                    } else {
                        x
                    }
                };
                (Curve::Nurbs(n), (snap(range.0, d0), snap(range.1, d1)))
            }
            Entity::CompositeCurve(c) => {
                if c.curves.is_empty() {
                    return Err(self.bad(id, "composite curve without constituents"));
                }
                let mut pieces = Vec::with_capacity(c.curves.len());
                let mut start = 0.0;
                for &p in &c.curves {
                    let (curve, (t0, t1)) = self.build_curve(p, depth + 1)?;
                    pieces.push(Piece {
                        curve,
                        t0,
                        t1,
                        reversed: false,
                        start,
                    });
                    start += t1 - t0;
                }
                (Curve::Composite { pieces }, (0.0, start))
            }
            Entity::OffsetCurve(o) => {
                if o.flag != 1 {
                    return Err(self.bad(
                        id,
                        format!(
                            "offset curve with distance flag {} (varying distance) is not supported",
                            o.flag
                        ),
                    ));
                }
                let (basis, _) = self.build_curve(o.base, depth + 1)?;
                let normal = Vector3::from(o.normal);
                if !(normal.norm() > 0.0) || !finite(&[o.d1, o.range[0], o.range[1]]) {
                    return Err(self.bad(
                        id,
                        "offset curve with a null plane normal or a non-finite value",
                    ));
                }
                if !(o.range[1] > o.range[0]) {
                    return Err(self.bad(id, format!("parameter range {:?} is empty", o.range)));
                }
                (
                    Curve::Offset {
                        basis: Box::new(basis),
                        distance: o.d1,
                        normal,
                    },
                    (o.range[0], o.range[1]),
                )
            }
            Entity::CurveOnSurface(c) => match c.model_curve {
                Some(m) => return self.build_curve(m, depth + 1),
                None => return Err(self.bad(id, "curve on surface without a model-space curve")),
            },
            _ => {
                return Err(self.bad(
                    id,
                    format!(
                        "entity type {} is not a supported curve",
                        rec.de.entity_type
                    ),
                ));
            }
        };
        if let Some(m) = self.own_map(id)? {
            curve.transform(&m);
        }
        Ok((curve, range))
    }

    /// A 104 conic arc in its principal frame.
    fn conic(&self, id: DeId, c: &iges::ConicArc, form: i32) -> Result<(Curve, (f64, f64)), Error> {
        let [a, b, cc, d, e, f] = c.coefficients;
        // Rotate to principal axes: angle φ with tan 2φ = B / (A − C).
        let phi = 0.5 * b.atan2(a - cc);
        let (s, co) = phi.sin_cos();
        let a2 = a * co * co + b * co * s + cc * s * s;
        let c2 = a * s * s - b * co * s + cc * co * co;
        let d2 = d * co + e * s;
        let e2 = -d * s + e * co;
        let to_local = |x: f64, y: f64| (x * co + y * s, -x * s + y * co);
        let x_axis = Vector3::new(co, s, 0.0);
        let y_axis = Vector3::new(-s, co, 0.0);
        let (sx, sy) = to_local(c.start[0], c.start[1]);
        let (ex, ey) = to_local(c.end[0], c.end[1]);
        let scale = a2.abs().max(c2.abs()).max(1e-300);
        let tiny = 1e-12 * scale;
        let frame = |origin: [f64; 3], x: Vector3, y: Vector3| Frame {
            origin: p3(origin),
            x,
            y,
            z: x.cross(&y),
        };
        if a2.abs() > tiny && c2.abs() > tiny {
            // Central conic: centre (x0, y0), A'(x−x0)² + C'(y−y0)² = k.
            let (x0, y0) = (-d2 / (2.0 * a2), -e2 / (2.0 * c2));
            let k = a2 * x0 * x0 + c2 * y0 * y0 - f;
            let (p, q) = (k / a2, k / c2);
            let origin = [x0 * co - y0 * s, x0 * s + y0 * co, c.z];
            if p > 0.0 && q > 0.0 {
                let (ra, rb) = (p.sqrt(), q.sqrt());
                let t0 = ((sy - y0) / rb).atan2((sx - x0) / ra);
                let mut t1 = ((ey - y0) / rb).atan2((ex - x0) / ra);
                while t1 <= t0 + 1e-14 {
                    t1 += 2.0 * PI;
                }
                return Ok((
                    Curve::Conic {
                        kind: ConicKind::Ellipse,
                        frame: frame(origin, x_axis, y_axis),
                        a: ra,
                        b: rb,
                    },
                    (t0, t1),
                ));
            }
            if p * q < 0.0 {
                // Hyperbola opening along the axis with the positive term.
                let (swap, ra, rb) = if p > 0.0 {
                    (false, p.sqrt(), (-q).sqrt())
                } else {
                    (true, q.sqrt(), (-p).sqrt())
                };
                let (xa, ya) = if swap {
                    (y_axis, -x_axis)
                } else {
                    (x_axis, y_axis)
                };
                let loc = |x: f64, y: f64| {
                    if swap {
                        (y - y0, -(x - x0))
                    } else {
                        (x - x0, y - y0)
                    }
                };
                let (s0x, s0y) = loc(sx, sy);
                let (_, e0y) = loc(ex, ey);
                let sign = s0x.signum();
                let t0 = (s0y / rb).asinh();
                let t1 = (e0y / rb).asinh();
                return Ok((
                    Curve::Conic {
                        kind: ConicKind::Hyperbola,
                        frame: frame(origin, xa * sign, ya * sign),
                        a: ra,
                        b: rb,
                    },
                    if t0 < t1 { (t0, t1) } else { (t1, t0) },
                ));
            }
            return Err(self.bad(id, format!("conic (form {form}) is degenerate")));
        }
        // Parabola: A' x² + D' x + E' y + F = 0 (or with x and y exchanged).
        let (swap, aa, dd, ee) = if a2.abs() > tiny {
            (false, a2, d2, e2)
        } else {
            (true, c2, e2, d2)
        };
        if ee.abs() <= tiny {
            return Err(self.bad(id, format!("conic (form {form}) is degenerate")));
        }
        // y = −(A' x² + D' x + F) / E'; vertex at x_v = −D'/(2A').
        let xv = -dd / (2.0 * aa);
        let yv = -(aa * xv * xv + dd * xv + f) / ee;
        let k = -aa / ee; // y − yv = k (x − xv)²
        let (xa, ya) = if swap {
            (y_axis, x_axis)
        } else {
            (x_axis, y_axis)
        };
        let vertex = if swap { (yv, xv) } else { (xv, yv) };
        let origin = [
            vertex.0 * co - vertex.1 * s,
            vertex.0 * s + vertex.1 * co,
            c.z,
        ];
        let (s_par, e_par) = if swap {
            (sy - xv, ey - xv)
        } else {
            (sx - xv, ex - xv)
        };
        // point = vertex + ya (k t²) + xa t
        Ok((
            Curve::Conic {
                kind: ConicKind::Parabola,
                frame: frame(origin, ya, xa),
                a: k,
                b: 1.0,
            },
            if s_par < e_par {
                (s_par, e_par)
            } else {
                (e_par, s_par)
            },
        ))
    }

    /// The surface of entity `id`: 108, 114, 118, 120, 122, 128, 140, 190–198 (143, 144 and
    /// 510 are faces, resolved by the caller).
    pub(super) fn build_surface(&self, id: DeId, depth: usize) -> Result<Surface, Error> {
        if depth > MAX_DEPTH {
            return Err(self.bad(id, "surfaces nest more than 16 levels deep (a cycle?)"));
        }
        let rec = self
            .file
            .get(id)
            .ok_or_else(|| self.bad(id, "pointer names no entity"))?;
        let mut s = match &rec.entity {
            Entity::SplineSurface(s) => {
                let ok = |b: &[f64]| {
                    b.windows(2).all(|w| w[1] > w[0]) && b.iter().all(|x| x.is_finite())
                };
                if !ok(&s.u_breaks) || !ok(&s.v_breaks) {
                    return Err(self.bad(id, "break points are not increasing"));
                }
                Surface::Spline {
                    u_breaks: s.u_breaks.clone(),
                    v_breaks: s.v_breaks.clone(),
                    patches: s
                        .patches
                        .iter()
                        .map(|c| std::array::from_fn(|k| Vector3::new(c[0][k], c[1][k], c[2][k])))
                        .collect(),
                }
            }
            Entity::BSplineSurface(b) => {
                let pts: Vec<Point3> = b.control_points.iter().map(|&p| p3(p)).collect();
                let mut n = canonical_surface(
                    (b.degree_u, &b.knots_u),
                    (b.degree_v, &b.knots_v),
                    &pts,
                    &b.weights,
                )
                .map_err(|e| self.bad(id, e))?;
                n.closed_u =
                    (b.closed_u || b.periodic_u) && n.meets_itself(true, closure_tol(&pts));
                n.closed_v =
                    (b.closed_v || b.periodic_v) && n.meets_itself(false, closure_tol(&pts));
                Surface::Nurbs(n)
            }
            Entity::SurfaceOfRevolution(s) => {
                let (axis, _) = self.build_curve(s.axis, depth + 1)?;
                let Curve::Line { origin, dir } = axis else {
                    return Err(self.bad(id, "the axis of revolution is not a line (110)"));
                };
                if !(dir.norm() > 0.0) {
                    return Err(self.bad(id, "the axis of revolution has zero length"));
                }
                if !(s.end_angle > s.start_angle) {
                    return Err(self.bad(id, "the angle range is empty"));
                }
                let (curve, range) = self.build_curve(s.generatrix, depth + 1)?;
                Surface::Revolution {
                    axis_point: origin,
                    axis_dir: dir / dir.norm(),
                    curve: Box::new(curve),
                    angle: AngleParam::V,
                    angles: (s.start_angle, s.end_angle),
                    range,
                }
            }
            Entity::RuledSurface(r) => {
                let (c1, (a1, b1)) = self.build_curve(r.curve1, depth + 1)?;
                let (c2, (a2, b2)) = self.build_curve(r.curve2, depth + 1)?;
                let (a2, b2) = if r.reversed { (b2, a2) } else { (a2, b2) };
                Surface::Ruled {
                    c1: Box::new(Curve::Reparam {
                        curve: Box::new(c1),
                        t0: a1,
                        t1: b1,
                    }),
                    c2: Box::new(Curve::Reparam {
                        curve: Box::new(c2),
                        t0: a2,
                        t1: b2,
                    }),
                }
            }
            Entity::TabulatedCylinder(c) => {
                let (directrix, (a, b)) = self.build_curve(c.directrix, depth + 1)?;
                let start = directrix.point(a);
                // The terminate point is in the directrix's definition space.
                let end = match self.own_map(c.directrix)? {
                    Some(m) => m.point(&p3(c.end)),
                    None => p3(c.end),
                };
                Surface::Extrusion {
                    curve: Box::new(Curve::Reparam {
                        curve: Box::new(directrix),
                        t0: a,
                        t1: b,
                    }),
                    dir: end - start,
                    range: (0.0, 1.0),
                    v_range: (0.0, 1.0),
                }
            }
            Entity::OffsetSurface(o) => {
                if !o.distance.is_finite() {
                    return Err(self.bad(id, "offset distance is not finite"));
                }
                Surface::Offset {
                    basis: Box::new(self.build_surface(o.surface, depth + 1)?),
                    distance: o.distance,
                }
            }
            Entity::Plane(p) => {
                let [a, b, c, d] = p.coefficients;
                let n = Vector3::new(a, b, c);
                let n2 = n.norm_squared();
                if !(n2 > 0.0) || !n2.is_finite() || !d.is_finite() {
                    return Err(self.bad(id, "plane with a null or non-finite normal"));
                }
                let frame = Frame::from_normal(Point3::from(n * (d / n2)), n)
                    .ok_or_else(|| self.bad(id, "plane with a degenerate normal"))?;
                Surface::Plane { frame }
            }
            Entity::PlaneSurface(p) => Surface::Plane {
                frame: self.frame(id, p.location, p.normal, p.refdir)?,
            },
            Entity::CylindricalSurface(c) => Surface::Cylinder {
                frame: self.frame(id, c.location, c.axis, c.refdir)?,
                radius: self.positive(id, c.radius, "radius")?,
            },
            Entity::ConicalSurface(c) => {
                let angle = c.semi_angle.to_radians();
                if !(angle > 0.0 && angle < PI / 2.0 && c.radius >= 0.0) {
                    return Err(self.bad(
                        id,
                        format!(
                            "cone of semi-angle {}° and radius {}: the angle must be in (0°, 90°) and the radius ≥ 0",
                            c.semi_angle, c.radius
                        ),
                    ));
                }
                Surface::Cone {
                    frame: self.frame(id, c.location, c.axis, c.refdir)?,
                    radius: c.radius,
                    tan: angle.tan(),
                }
            }
            Entity::SphericalSurface(s) => {
                let center = self.point_entity(id, s.center)?;
                let axis = match s.axis {
                    Some(a) => self.direction_entity(id, a)?,
                    None => Vector3::z(),
                };
                let refdir = s.refdir.map(|r| self.direction_entity(id, r)).transpose()?;
                Surface::Sphere {
                    frame: Frame::orthonormal(center, axis, refdir).ok_or_else(|| {
                        self.bad(id, "null axis or reference direction along the axis")
                    })?,
                    radius: self.positive(id, s.radius, "radius")?,
                }
            }
            Entity::ToroidalSurface(t) => {
                if !(t.minor > 0.0 && t.major > t.minor) {
                    return Err(self.bad(
                        id,
                        format!(
                            "torus radii {} and {}: need major > minor > 0",
                            t.major, t.minor
                        ),
                    ));
                }
                Surface::Torus {
                    frame: self.frame(id, t.center, t.axis, t.refdir)?,
                    major: t.major,
                    minor: t.minor,
                }
            }
            _ => {
                return Err(self.bad(
                    id,
                    format!(
                        "entity type {} is not a supported surface",
                        rec.de.entity_type
                    ),
                ));
            }
        };
        if let Some(m) = self.own_map(id)? {
            s.transform(&m);
        }
        Ok(s)
    }

    fn positive(&self, id: DeId, x: f64, what: &str) -> Result<f64, Error> {
        if x > 0.0 && x.is_finite() {
            Ok(x)
        } else {
            Err(self.bad(id, format!("{what} {x} is not positive")))
        }
    }

    /// The frame of a 190–198 surface: location (116), axis (123), reference direction.
    fn frame(
        &self,
        id: DeId,
        location: DeId,
        axis: DeId,
        refdir: Option<DeId>,
    ) -> Result<Frame, Error> {
        let o = self.point_entity(id, location)?;
        let z = self.direction_entity(id, axis)?;
        let x = refdir.map(|r| self.direction_entity(id, r)).transpose()?;
        Frame::orthonormal(o, z, x)
            .ok_or_else(|| self.bad(id, "null axis or reference direction along the axis"))
    }
}
