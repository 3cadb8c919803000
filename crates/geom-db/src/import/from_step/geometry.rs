//! STEP curves and surfaces as exact curves and surfaces of the neutral model (ISO 10303-42
//! parametrisations; angles converted from the file's plane-angle unit).

use std::f64::consts::PI;

use step::{ConicKind as StepConic, ElementaryKind, Entity, Id, Trim};

use super::Front;
use crate::import::Error;
use crate::import::model::{
    AngleParam, ConicKind, Curve, Frame, Piece, Surface, canonical_curve, canonical_surface,
    closure_tol,
};
use crate::prelude::{Point3, Vector3};

/// Curves and surfaces nest at most this deep (a cycle in a corrupt file stops here).
const MAX_DEPTH: usize = 16;

/// A curve and the parameter range its entity bounds it to, when it does (a B-spline's
/// knots, a trimmed curve's trims, a polyline's points).
pub(super) type Bounded = (Curve, Option<(f64, f64)>);

/// Expands distinct knots and multiplicities into the full knot vector.
fn expand(knots: &[f64], mults: &[usize]) -> Vec<f64> {
    knots
        .iter()
        .zip(mults)
        .flat_map(|(&k, &m)| std::iter::repeat_n(k, m))
        .collect()
}

impl Front<'_> {
    fn p(&self, from: Id, id: Id) -> Result<Point3, Error> {
        Ok(Point3::from(self.file.point(from, id, "point")?))
    }

    fn dir(&self, from: Id, id: Id) -> Result<Vector3, Error> {
        Ok(Vector3::from(self.file.direction(from, id, "direction")?))
    }

    /// The frame of an `AXIS2_PLACEMENT_2D` / `_3D` (ISO 10303-42 defaults).
    pub(super) fn placement(&self, from: Id, id: Id) -> Result<Frame, Error> {
        let Entity::Axis2Placement(a) = self.file.get(from, id, "position")?.1 else {
            return Err(self
                .file
                .wrong_type(from, id, "position", "AXIS2_PLACEMENT_2D/3D")
                .into());
        };
        let o = self.p(id, a.location)?;
        let z = match a.axis {
            Some(z) => self.dir(id, z)?,
            None => Vector3::z(),
        };
        let x = a.ref_direction.map(|r| self.dir(id, r)).transpose()?;
        Frame::orthonormal(o, z, x)
            .ok_or_else(|| self.bad(id, "null axis or reference direction along the axis"))
    }

    fn vector(&self, from: Id, id: Id) -> Result<Vector3, Error> {
        let Entity::Vector(v) = self.file.get(from, id, "vector")?.1 else {
            return Err(self.file.wrong_type(from, id, "vector", "VECTOR").into());
        };
        let d = self.dir(id, v.orientation)?;
        let n = d.norm();
        if !(n > 0.0) {
            return Err(self.bad(id, "null direction"));
        }
        Ok(d * (v.magnitude / n))
    }

    /// The curve of instance `id` (3D, or 2D in a parameter space with z = 0).
    pub(super) fn build_curve(&self, id: Id, depth: usize) -> Result<Bounded, Error> {
        if depth > MAX_DEPTH {
            return Err(self.bad(id, "curves nest more than 16 levels deep (a cycle?)"));
        }
        let (_, e) = self.file.get(id, id, "curve")?;
        let angle = self.angle;
        Ok(match e {
            Entity::Line(l) => (
                Curve::Line {
                    origin: self.p(id, l.point)?,
                    dir: self.vector(id, l.direction)?,
                },
                None,
            ),
            Entity::Conic(c) => {
                let frame = self.placement(id, c.position)?;
                if !(c.a > 0.0) || !c.a.is_finite() || !c.b.is_finite() {
                    return Err(self.bad(id, format!("conic with invalid size {} / {}", c.a, c.b)));
                }
                // Parameters are angles for circles and ellipses; curves keep radians.
                let (kind, a, b) = match c.kind {
                    StepConic::Circle | StepConic::Ellipse => (ConicKind::Ellipse, c.a, c.b),
                    StepConic::Hyperbola => (ConicKind::Hyperbola, c.a, c.b),
                    // C + f (t² x + 2 t y).
                    StepConic::Parabola => (ConicKind::Parabola, c.a, 2.0 * c.a),
                };
                let curve = Curve::Conic { kind, frame, a, b };
                if angle != 1.0 && kind == ConicKind::Ellipse {
                    // t in the file's angle unit: s ↦ curve(s · angle).
                    (
                        Curve::Reparam {
                            curve: Box::new(curve),
                            t0: 0.0,
                            t1: angle,
                        },
                        None,
                    )
                } else {
                    (curve, None)
                }
            }
            Entity::Polyline(pl) => {
                if pl.points.len() < 2 {
                    return Err(self.bad(id, "polyline with fewer than 2 points"));
                }
                let points = pl
                    .points
                    .iter()
                    .map(|&q| self.p(id, q))
                    .collect::<Result<Vec<_>, _>>()?;
                let n = points.len();
                (Curve::Polyline { points }, Some((0.0, (n - 1) as f64)))
            }
            Entity::BSplineCurve(b) => {
                let pts = b
                    .control_points
                    .iter()
                    .map(|&q| self.p(id, q))
                    .collect::<Result<Vec<_>, _>>()?;
                let w = b.weights.clone().unwrap_or_else(|| vec![1.0; pts.len()]);
                let knots = expand(&b.knots, &b.multiplicities);
                let n = canonical_curve(b.degree, &knots, &pts, &w).map_err(|e| self.bad(id, e))?;
                let d = n.domain();
                (Curve::Nurbs(n), Some(d))
            }
            Entity::TrimmedCurve(t) => {
                let (basis, _) = self.build_curve(t.basis, depth + 1)?;
                let param = |trims: &[Trim]| -> Result<f64, Error> {
                    if let Some(x) = trims.iter().find_map(|x| match x {
                        Trim::Parameter(v) => Some(*v),
                        Trim::Point(_) => None,
                    }) {
                        return Ok(x);
                    }
                    match trims.first() {
                        Some(Trim::Point(q)) => {
                            let p = self.p(id, *q)?;
                            self.param_on(id, &basis, &p, None)
                        }
                        _ => Err(self.bad(id, "a trim without a parameter or a point")),
                    }
                };
                let (mut a, mut b) = (param(&t.trim1)?, param(&t.trim2)?);
                // Parameters of conics are angles in the file's unit: the basis was
                // re-parametrised by the unit already.
                if let Some(p) = curve_period(&basis) {
                    // A closed basis is traversed from trim 1 to trim 2 in its sense.
                    if t.sense {
                        while b <= a {
                            b += p;
                        }
                    } else {
                        while a <= b {
                            a += p;
                        }
                    }
                }
                let range = if t.sense { (a, b) } else { (b, a) };
                (basis, Some(range))
            }
            Entity::SurfaceCurve(s) => return self.build_curve(s.curve, depth + 1),
            Entity::Pcurve(p) => {
                let surface = self.build_surface(p.surface, depth + 1)?;
                let Entity::Representation(r) =
                    self.file.get(id, p.representation, "reference_to_curve")?.1
                else {
                    return Err(self
                        .file
                        .wrong_type(
                            id,
                            p.representation,
                            "reference_to_curve",
                            "DEFINITIONAL_REPRESENTATION",
                        )
                        .into());
                };
                let Some(&c) = r.items.first() else {
                    return Err(self.bad(
                        p.representation,
                        "definitional representation without a curve",
                    ));
                };
                let (pcurve, range) = self.build_curve(c, depth + 1)?;
                (
                    Curve::OnSurface {
                        surface: Box::new(surface),
                        pcurve: Box::new(pcurve),
                    },
                    range,
                )
            }
            Entity::CompositeCurve(c) => {
                let mut pieces = Vec::with_capacity(c.segments.len());
                let mut start = 0.0;
                for &s in &c.segments {
                    let Entity::CompositeCurveSegment(seg) = self.file.get(id, s, "segments")?.1
                    else {
                        return Err(self
                            .file
                            .wrong_type(id, s, "segments", "COMPOSITE_CURVE_SEGMENT")
                            .into());
                    };
                    let (curve, range) = self.build_curve(seg.parent, depth + 1)?;
                    let (t0, t1) = range.ok_or_else(|| {
                        self.bad(
                            seg.parent,
                            "an unbounded curve cannot be a composite curve segment",
                        )
                    })?;
                    let (t0, t1) = if t0 <= t1 { (t0, t1) } else { (t1, t0) };
                    pieces.push(Piece {
                        curve,
                        t0,
                        t1,
                        reversed: !seg.same_sense,
                        start,
                    });
                    start += t1 - t0;
                }
                if pieces.is_empty() {
                    return Err(self.bad(id, "composite curve without segments"));
                }
                (Curve::Composite { pieces }, Some((0.0, start)))
            }
            Entity::OffsetCurve3d(o) => {
                let (basis, range) = self.build_curve(o.basis, depth + 1)?;
                let r = self.dir(id, o.ref_direction)?;
                (
                    Curve::Offset {
                        basis: Box::new(basis),
                        distance: o.distance,
                        normal: -r,
                    },
                    range,
                )
            }
            _ => {
                let ty = self.file.instance(id).map_or("?".into(), |i| i.type_name());
                return Err(self.bad(id, format!("{ty} is not a supported curve")));
            }
        })
    }

    /// The surface of instance `id`.
    pub(super) fn build_surface(&self, id: Id, depth: usize) -> Result<Surface, Error> {
        if depth > MAX_DEPTH {
            return Err(self.bad(id, "surfaces nest more than 16 levels deep (a cycle?)"));
        }
        let (_, e) = self.file.get(id, id, "surface")?;
        let positive = |x: f64, what: &str| {
            if x > 0.0 && x.is_finite() {
                Ok(x)
            } else {
                Err(self.bad(id, format!("{what} {x} is not positive")))
            }
        };
        Ok(match e {
            Entity::Elementary(s) => {
                let frame = self.placement(id, s.position)?;
                match s.kind {
                    ElementaryKind::Plane => Surface::Plane { frame },
                    ElementaryKind::Cylinder => Surface::Cylinder {
                        frame,
                        radius: positive(s.radius, "radius")?,
                    },
                    ElementaryKind::Cone => {
                        let a = s.second * self.angle;
                        if !(a > 0.0 && a < PI / 2.0 && s.radius >= 0.0) {
                            return Err(self.bad(
                                id,
                                format!(
                                    "cone of semi-angle {a} rad and radius {}: need (0, π/2) and ≥ 0",
                                    s.radius
                                ),
                            ));
                        }
                        Surface::Cone {
                            frame,
                            radius: s.radius,
                            tan: a.tan(),
                        }
                    }
                    ElementaryKind::Sphere => Surface::Sphere {
                        frame,
                        radius: positive(s.radius, "radius")?,
                    },
                    ElementaryKind::Torus => Surface::Torus {
                        frame,
                        major: positive(s.radius, "major radius")?,
                        minor: positive(s.second, "minor radius")?,
                    },
                }
            }
            Entity::BSplineSurface(b) => {
                let ku = expand(&b.u_knots, &b.u_multiplicities);
                let kv = expand(&b.v_knots, &b.v_multiplicities);
                let nu = b.control_points.len();
                let nv = b.control_points.first().map_or(0, Vec::len);
                let mut pts = vec![Point3::origin(); nu * nv];
                let mut w = vec![1.0; nu * nv];
                for (i, row) in b.control_points.iter().enumerate() {
                    for (j, &q) in row.iter().enumerate() {
                        pts[i + nu * j] = self.p(id, q)?;
                        if let Some(ws) = &b.weights {
                            w[i + nu * j] = ws[i][j];
                        }
                    }
                }
                let mut n = canonical_surface((b.u_degree, &ku), (b.v_degree, &kv), &pts, &w)
                    .map_err(|e| self.bad(id, e))?;
                n.closed_u = b.u_closed != Some(false) && n.meets_itself(true, closure_tol(&pts));
                n.closed_v = b.v_closed != Some(false) && n.meets_itself(false, closure_tol(&pts));
                Surface::Nurbs(n)
            }
            Entity::SurfaceOfRevolution(r) => {
                let Entity::Axis1Placement(a) = self.file.get(id, r.axis, "axis_position")?.1
                else {
                    return Err(self
                        .file
                        .wrong_type(id, r.axis, "axis_position", "AXIS1_PLACEMENT")
                        .into());
                };
                let o = self.p(r.axis, a.location)?;
                let d = match a.axis {
                    Some(z) => self.dir(r.axis, z)?,
                    None => Vector3::z(),
                };
                if !(d.norm() > 0.0) {
                    return Err(self.bad(r.axis, "null axis"));
                }
                let (curve, range) = self.build_curve(r.curve, depth + 1)?;
                Surface::Revolution {
                    axis_point: o,
                    axis_dir: d / d.norm(),
                    curve: Box::new(curve),
                    angle: AngleParam::U,
                    angles: (0.0, 2.0 * PI),
                    range: range.unwrap_or((f64::NEG_INFINITY, f64::INFINITY)),
                }
            }
            Entity::SurfaceOfLinearExtrusion(x) => {
                let (curve, range) = self.build_curve(x.curve, depth + 1)?;
                Surface::Extrusion {
                    curve: Box::new(curve),
                    dir: self.vector(id, x.direction)?,
                    range: range.unwrap_or((f64::NEG_INFINITY, f64::INFINITY)),
                    v_range: (f64::NEG_INFINITY, f64::INFINITY),
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
            Entity::RectangularTrimmedSurface(r) => self.build_surface(r.surface, depth + 1)?,
            _ => {
                let ty = self.file.instance(id).map_or("?".into(), |i| i.type_name());
                return Err(self.bad(id, format!("{ty} is not a supported surface")));
            }
        })
    }
}

/// The period of a closed curve's parametrisation (in its own parameter).
pub(super) fn curve_period(c: &Curve) -> Option<f64> {
    match c {
        Curve::Reparam { curve, t0, t1 } => curve.period().map(|p| p / (t1 - t0)),
        c => c.period(),
    }
}
