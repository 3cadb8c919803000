//! Evaluators of IGES curves and surfaces in model space (transformation matrices applied),
//! and their exact conversions to the power basis where one exists.

use iges::{DeId, Entity, IgesFile, TransformationMatrix};

use super::Error;
use crate::bspline::KnotVector;
use crate::convert::{bspline_surface_to_power, bspline_to_power};
use crate::curve::Arc;
use crate::prelude::{Point3, Vector3};
use crate::surface::{Patch, SupportSurface};

/// Relative spread of weights under which a rational B-spline is treated as polynomial.
const EQUAL_WEIGHTS: f64 = 1e-12;

fn tr_point(t: &Option<TransformationMatrix>, p: [f64; 3]) -> Point3 {
    Point3::from(t.map_or(p, |m| m.apply_point(p)))
}

fn tr_vector(t: &Option<TransformationMatrix>, v: [f64; 3]) -> Vector3 {
    Vector3::from(t.map_or(v, |m| m.apply_vector(v)))
}

/// A B-spline (possibly rational) curve or surface basis restricted to a parameter range.
#[derive(Debug, Clone)]
pub(crate) struct Nurbs1 {
    kv: KnotVector,
    /// Homogeneous control points (w x, w y, w z, w).
    ctrl: Vec<[f64; 4]>,
    range: (f64, f64),
    rational: bool,
}

impl Nurbs1 {
    fn point(&self, t: f64) -> Point3 {
        let h = self.kv.curve_point(&self.ctrl, t);
        Point3::new(h[0] / h[3], h[1] / h[3], h[2] / h[3])
    }
}

/// A curve of the IGES file, evaluated in model space.
#[derive(Debug, Clone)]
pub(crate) enum CurveEval {
    /// Straight segment, t ∈ [0, 1].
    Line(Point3, Point3),
    /// Circle arc: centre + r (cos θ x̂ + sin θ ŷ), θ ∈ [θ0, θ1] (absolute angle).
    Circle {
        center: Point3,
        x: Vector3,
        y: Vector3,
        radius: f64,
        range: (f64, f64),
    },
    /// Conic x̂/ŷ parametrisation: center + x(t) x̂ + y(t) ŷ (ellipse: a cos t, b sin t;
    /// hyperbola: a cosh t, b sinh t; parabola: t²/(4f)... in the conic's principal frame).
    Conic {
        kind: ConicKind,
        origin: Point3,
        x: Vector3,
        y: Vector3,
        a: f64,
        b: f64,
        range: (f64, f64),
    },
    /// 112 parametric spline: cubic segments in s = t − T(i), transformed coefficients.
    Spline {
        breaks: Vec<f64>,
        segments: Vec<[Point3; 4]>,
    },
    /// 126 rational B-spline.
    Nurbs(Nurbs1),
    /// 102: the pieces one after the other; piece i covers [offsets[i], offsets[i+1]].
    Composite {
        pieces: Vec<CurveEval>,
        offsets: Vec<f64>,
    },
}

/// The kind of a 104 conic.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum ConicKind {
    Ellipse,
    Hyperbola,
    Parabola,
}

impl CurveEval {
    /// The parameter interval.
    pub(crate) fn domain(&self) -> (f64, f64) {
        match self {
            CurveEval::Line(..) => (0.0, 1.0),
            CurveEval::Circle { range, .. } | CurveEval::Conic { range, .. } => *range,
            CurveEval::Spline { breaks, .. } => (breaks[0], *breaks.last().unwrap_or(&breaks[0])),
            CurveEval::Nurbs(n) => n.range,
            CurveEval::Composite { offsets, .. } => (offsets[0], *offsets.last().unwrap_or(&0.0)),
        }
    }

    /// r(t).
    pub(crate) fn point(&self, t: f64) -> Point3 {
        match self {
            CurveEval::Line(a, b) => a + (b - a) * t,
            CurveEval::Circle {
                center,
                x,
                y,
                radius,
                ..
            } => center + (x * t.cos() + y * t.sin()) * *radius,
            CurveEval::Conic {
                kind,
                origin,
                x,
                y,
                a,
                b,
                ..
            } => {
                let (cx, cy) = match kind {
                    ConicKind::Ellipse => (a * t.cos(), b * t.sin()),
                    ConicKind::Hyperbola => (a * t.cosh(), b * t.sinh()),
                    ConicKind::Parabola => (a * t * t, t),
                };
                origin + x * cx + y * cy
            }
            CurveEval::Spline { breaks, segments } => {
                let n = segments.len();
                let i = breaks[1..n].partition_point(|&b| b <= t);
                let s = t - breaks[i];
                let c = &segments[i];
                Point3::from(c[0].coords + (c[1].coords + (c[2].coords + c[3].coords * s) * s) * s)
            }
            CurveEval::Nurbs(n) => n.point(t),
            CurveEval::Composite { pieces, offsets } => {
                let n = pieces.len();
                let i = offsets[1..n].partition_point(|&o| o <= t);
                let (a, _) = pieces[i].domain();
                pieces[i].point(a + (t - offsets[i]))
            }
        }
    }

    /// Parameter values where the curve may be only C0 (knots, segment breaks): the
    /// approximation starts from these break points.
    pub(crate) fn breaks(&self) -> Vec<f64> {
        let (a, b) = self.domain();
        let mut out = match self {
            CurveEval::Spline { breaks, .. } => breaks.clone(),
            CurveEval::Nurbs(n) => n.kv.breakpoints(),
            CurveEval::Composite { offsets, .. } => offsets.clone(),
            _ => vec![a, b],
        };
        out.retain(|&t| t >= a && t <= b);
        out.dedup();
        if out.first() != Some(&a) {
            out.insert(0, a);
        }
        if out.last() != Some(&b) {
            out.push(b);
        }
        out
    }

    /// The exact power-basis arcs of the curve with their parameter breaks, when the curve
    /// is polynomial (110, 112, non-rational 126).
    pub(crate) fn exact(&self) -> Option<(Vec<Arc>, Vec<f64>)> {
        match self {
            CurveEval::Line(a, b) => Some((vec![Arc::line(*a, *b)], vec![0.0, 1.0])),
            CurveEval::Spline { breaks, segments } => {
                let arcs = segments
                    .iter()
                    .zip(breaks.windows(2))
                    .map(|(c, w)| {
                        let h = w[1] - w[0];
                        let mut coeffs = vec![
                            c[0],
                            Point3::from(c[1].coords * h),
                            Point3::from(c[2].coords * h * h),
                            Point3::from(c[3].coords * h * h * h),
                        ];
                        // Lower the degree when the top coefficients vanish (degree ≥ 1).
                        while coeffs.len() > 2
                            && coeffs.last().is_some_and(|p| p.coords == Vector3::zeros())
                        {
                            coeffs.pop();
                        }
                        Arc::new(coeffs)
                    })
                    .collect();
                Some((arcs, breaks.clone()))
            }
            CurveEval::Nurbs(n) if !n.rational && n.range == n.kv.domain() => {
                let pts: Vec<Point3> = n
                    .ctrl
                    .iter()
                    .map(|h| Point3::new(h[0], h[1], h[2]))
                    .collect();
                let arcs = bspline_to_power(&n.kv, &pts).ok()?;
                let mut breaks: Vec<f64> = arcs.iter().map(|a| a.t0).collect();
                breaks.push(arcs.last()?.t1);
                Some((arcs.into_iter().map(|a| a.arc).collect(), breaks))
            }
            _ => None,
        }
    }
}

/// A surface of the IGES file, evaluated in model space.
#[derive(Debug, Clone)]
pub(crate) enum SurfEval {
    /// 114: patches of bicubic coefficients, `coef[i][j]` with [p][q] = a_{pq} (s^p t^q).
    Spline {
        u_breaks: Vec<f64>,
        v_breaks: Vec<f64>,
        /// Patch (i, j) at `i * n_v + j`: 16 coefficients, index 4q + p.
        patches: Vec<[Point3; 16]>,
    },
    /// 128 rational B-spline surface; `ctrl[i + n_u j]` homogeneous.
    Nurbs {
        ku: KnotVector,
        kv: KnotVector,
        ctrl: Vec<[f64; 4]>,
        u_range: (f64, f64),
        v_range: (f64, f64),
        rational: bool,
    },
    /// 120: generatrix rotated about the axis (point, unit direction) by θ.
    Revolution {
        axis_point: Point3,
        axis_dir: Vector3,
        generatrix: Box<CurveEval>,
        angles: (f64, f64),
        outer: Option<TransformationMatrix>,
    },
    /// 118 (form 1 parametrisation): (1 − v) C1(u) + v C2(u), u ∈ [0, 1].
    Ruled {
        c1: Box<CurveEval>,
        c2: Box<CurveEval>,
        reversed: bool,
    },
    /// 122: C(u) + v (L − C(start)), u normalised to [0, 1].
    Tabulated {
        directrix: Box<CurveEval>,
        direction: Vector3,
    },
}

fn lerp(range: (f64, f64), s: f64) -> f64 {
    range.0 + s * (range.1 - range.0)
}

impl SurfEval {
    /// The parameter rectangle.
    pub(crate) fn domain(&self) -> ((f64, f64), (f64, f64)) {
        match self {
            SurfEval::Spline {
                u_breaks, v_breaks, ..
            } => (
                (u_breaks[0], *u_breaks.last().unwrap_or(&0.0)),
                (v_breaks[0], *v_breaks.last().unwrap_or(&0.0)),
            ),
            SurfEval::Nurbs {
                u_range, v_range, ..
            } => (*u_range, *v_range),
            SurfEval::Revolution {
                generatrix, angles, ..
            } => (generatrix.domain(), *angles),
            SurfEval::Ruled { .. } | SurfEval::Tabulated { .. } => ((0.0, 1.0), (0.0, 1.0)),
        }
    }

    /// r(u, v).
    pub(crate) fn point(&self, u: f64, v: f64) -> Point3 {
        match self {
            SurfEval::Spline {
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
                        row = row * s + c[4 * q + p].coords;
                    }
                    acc = acc * t + row;
                }
                Point3::from(acc)
            }
            SurfEval::Nurbs { ku, kv, ctrl, .. } => {
                let (pu, pv) = (ku.degree(), kv.degree());
                let mut nu = vec![0.0; pu + 1];
                let mut nv = vec![0.0; pv + 1];
                let su = ku.basis_into(u, &mut nu);
                let sv = kv.basis_into(v, &mut nv);
                let n_u = ku.n_basis();
                let mut h = [0.0; 4];
                for (b, &wv) in nv.iter().enumerate() {
                    let j = sv - pv + b;
                    for (a, &wu) in nu.iter().enumerate() {
                        let i = su - pu + a;
                        let c = &ctrl[i + n_u * j];
                        for k in 0..4 {
                            h[k] += wu * wv * c[k];
                        }
                    }
                }
                Point3::new(h[0] / h[3], h[1] / h[3], h[2] / h[3])
            }
            SurfEval::Revolution {
                axis_point,
                axis_dir,
                generatrix,
                outer,
                ..
            } => {
                let p = generatrix.point(u) - axis_point;
                let d = axis_dir;
                let (s, c) = v.sin_cos();
                let r = p * c + d.cross(&p) * s + d * d.dot(&p) * (1.0 - c);
                tr_point(outer, (axis_point + r).coords.into())
            }
            SurfEval::Ruled { c1, c2, reversed } => {
                let a = c1.point(lerp(c1.domain(), u));
                let s2 = if *reversed { 1.0 - u } else { u };
                let b = c2.point(lerp(c2.domain(), s2));
                a + (b - a) * v
            }
            SurfEval::Tabulated {
                directrix,
                direction,
            } => directrix.point(lerp(directrix.domain(), u)) + direction * v,
        }
    }

    /// Parameter lines where the surface may be only C0 (used as initial patch breaks).
    pub(crate) fn breaks(&self) -> (Vec<f64>, Vec<f64>) {
        let ((u0, u1), (v0, v1)) = self.domain();
        let clip = |mut b: Vec<f64>, lo: f64, hi: f64| {
            b.retain(|&x| x > lo && x < hi);
            b.insert(0, lo);
            b.push(hi);
            b.dedup();
            b
        };
        match self {
            SurfEval::Spline {
                u_breaks, v_breaks, ..
            } => (u_breaks.clone(), v_breaks.clone()),
            SurfEval::Nurbs { ku, kv, .. } => (
                clip(ku.breakpoints(), u0, u1),
                clip(kv.breakpoints(), v0, v1),
            ),
            SurfEval::Revolution { generatrix, .. } => {
                (clip(generatrix.breaks(), u0, u1), vec![v0, v1])
            }
            SurfEval::Ruled { .. } | SurfEval::Tabulated { .. } => (vec![u0, u1], vec![v0, v1]),
        }
    }

    /// The exact patches with their parameter breaks, for polynomial surfaces (114,
    /// non-rational 128 over its whole knot domain).
    pub(crate) fn exact(&self) -> Option<(SupportSurface, Vec<f64>, Vec<f64>)> {
        match self {
            SurfEval::Spline {
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
                                coeffs[p * 4 + q] = Point3::from(c[4 * q + p].coords * f);
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
            SurfEval::Nurbs {
                ku,
                kv,
                ctrl,
                u_range,
                v_range,
                rational,
            } if !rational && *u_range == ku.domain() && *v_range == kv.domain() => {
                let (nu, nv) = (ku.n_basis(), kv.n_basis());
                // geom-db wants [i * n_v + j]; IGES stores u fastest [i + n_u * j].
                let mut pts = vec![Point3::origin(); nu * nv];
                for j in 0..nv {
                    for i in 0..nu {
                        let h = ctrl[i + nu * j];
                        pts[i * nv + j] = Point3::new(h[0], h[1], h[2]);
                    }
                }
                let ps = bspline_surface_to_power(ku, kv, &pts).ok()?;
                Some((ps.surface, ps.u_breaks, ps.v_breaks))
            }
            _ => None,
        }
    }
}

/// Builds evaluators from the IGES entities, naming the entity in errors.
pub(crate) struct Builder<'a> {
    pub(crate) file: &'a IgesFile,
}

impl Builder<'_> {
    fn bad(&self, id: DeId, reason: impl Into<String>) -> Error {
        Error::Entity {
            file: self.file.name.clone(),
            de: id.line(),
            entity_type: self.file.get(id).map_or(0, |r| r.de.entity_type),
            reason: reason.into(),
        }
    }

    fn transform(&self, id: DeId) -> Result<Option<TransformationMatrix>, Error> {
        self.file.transform(id).map_err(Error::Iges)
    }

    fn knots(
        &self,
        id: DeId,
        degree: usize,
        knots: &[f64],
        what: &str,
    ) -> Result<KnotVector, Error> {
        KnotVector::new(degree, knots.to_vec()).map_err(|e| self.bad(id, format!("{what}: {e}")))
    }

    /// The model-space curve of entity `id` (100, 102, 104, 110, 112, 126, 142's model
    /// curve).
    pub(crate) fn curve(&self, id: DeId) -> Result<CurveEval, Error> {
        self.curve_depth(id, 0)
    }

    fn curve_depth(&self, id: DeId, depth: usize) -> Result<CurveEval, Error> {
        if depth > 16 {
            return Err(self.bad(id, "curves nest more than 16 levels deep (a cycle?)"));
        }
        let rec = self
            .file
            .get(id)
            .ok_or_else(|| self.bad(id, "pointer names no entity"))?;
        let t = self.transform(id)?;
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        Ok(match &rec.entity {
            Entity::Line(l) => {
                let (a, b) = (tr_point(&t, l.start), tr_point(&t, l.end));
                if rec.de.form != 0 {
                    return Err(self.bad(
                        id,
                        format!(
                            "line form {} (ray or unbounded line) cannot bound a surface",
                            rec.de.form
                        ),
                    ));
                }
                CurveEval::Line(a, b)
            }
            Entity::CircularArc(a) => {
                let (cx, cy) = (a.center[0], a.center[1]);
                let r = ((a.start[0] - cx).powi(2) + (a.start[1] - cy).powi(2)).sqrt();
                if !(r > 0.0) || !r.is_finite() {
                    return Err(self.bad(id, "circular arc of zero radius"));
                }
                let t0 = (a.start[1] - cy).atan2(a.start[0] - cx);
                let mut t1 = (a.end[1] - cy).atan2(a.end[0] - cx);
                while t1 <= t0 + 1e-14 {
                    t1 += 2.0 * std::f64::consts::PI;
                }
                CurveEval::Circle {
                    center: tr_point(&t, [cx, cy, a.z]),
                    x: tr_vector(&t, [1.0, 0.0, 0.0]),
                    y: tr_vector(&t, [0.0, 1.0, 0.0]),
                    radius: r,
                    range: (t0, t1),
                }
            }
            Entity::ConicArc(c) => self.conic(id, c, rec.de.form, &t)?,
            Entity::SplineCurve(s) => {
                if !finite(&s.breakpoints) || s.breakpoints.windows(2).any(|w| w[1] <= w[0]) {
                    return Err(self.bad(id, "break points are not increasing"));
                }
                let segments = s
                    .segments
                    .iter()
                    .map(|c| {
                        let col = |k: usize| [c[0][k], c[1][k], c[2][k]];
                        [
                            tr_point(&t, col(0)),
                            Point3::from(tr_vector(&t, col(1))),
                            Point3::from(tr_vector(&t, col(2))),
                            Point3::from(tr_vector(&t, col(3))),
                        ]
                    })
                    .collect();
                CurveEval::Spline {
                    breaks: s.breakpoints.clone(),
                    segments,
                }
            }
            Entity::BSplineCurve(b) => {
                let kv = self.knots(id, b.degree, &b.knots, "knots")?;
                let (w0, w1) = b
                    .weights
                    .iter()
                    .fold((f64::INFINITY, 0.0f64), |(a, c), &w| (a.min(w), c.max(w)));
                if !(w0 > 0.0) || !w1.is_finite() {
                    return Err(self.bad(id, "weights must be positive"));
                }
                let ctrl = b
                    .control_points
                    .iter()
                    .zip(&b.weights)
                    .map(|(p, &w)| {
                        let q = tr_point(&t, *p);
                        [q.x * w, q.y * w, q.z * w, w]
                    })
                    .collect();
                let (d0, d1) = kv.domain();
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
                CurveEval::Nurbs(Nurbs1 {
                    kv,
                    ctrl,
                    range: (snap(range.0, d0), snap(range.1, d1)),
                    rational: w1 - w0 > EQUAL_WEIGHTS * w1,
                })
            }
            Entity::CompositeCurve(c) => {
                if c.curves.is_empty() {
                    return Err(self.bad(id, "composite curve without constituents"));
                }
                let mut pieces = Vec::new();
                let mut offsets = Vec::new();
                for &p in &c.curves {
                    let e = self.curve_depth(p, depth + 1)?;
                    let e = match (&t, e) {
                        (None, e) => e,
                        (Some(_), _) => {
                            return Err(
                                self.bad(id, "transformed composite curves are not supported")
                            );
                        }
                    };
                    let (a, b) = e.domain();
                    let start = offsets.last().copied().unwrap_or(a);
                    if offsets.is_empty() {
                        offsets.push(start);
                    }
                    offsets.push(start + (b - a));
                    pieces.push(e);
                }
                CurveEval::Composite { pieces, offsets }
            }
            Entity::CurveOnSurface(c) => match c.model_curve {
                Some(m) => self.curve_depth(m, depth + 1)?,
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
        })
    }

    fn conic(
        &self,
        id: DeId,
        c: &iges::ConicArc,
        form: i32,
        t: &Option<TransformationMatrix>,
    ) -> Result<CurveEval, Error> {
        let [a, b, cc, d, e, f] = c.coefficients;
        // Rotate to principal axes: angle φ with tan 2φ = B / (A − C).
        let phi = 0.5 * b.atan2(a - cc);
        let (s, co) = phi.sin_cos();
        let a2 = a * co * co + b * co * s + cc * s * s;
        let c2 = a * s * s - b * co * s + cc * co * co;
        let d2 = d * co + e * s;
        let e2 = -d * s + e * co;
        let to_local = |x: f64, y: f64| (x * co + y * s, -x * s + y * co);
        let x_axis = tr_vector(t, [co, s, 0.0]);
        let y_axis = tr_vector(t, [-s, co, 0.0]);
        let (sx, sy) = to_local(c.start[0], c.start[1]);
        let (ex, ey) = to_local(c.end[0], c.end[1]);
        let scale = a2.abs().max(c2.abs()).max(1e-300);
        let tiny = 1e-12 * scale;
        if a2.abs() > tiny && c2.abs() > tiny {
            // Central conic: centre (x0, y0), A'(x−x0)² + C'(y−y0)² = k.
            let (x0, y0) = (-d2 / (2.0 * a2), -e2 / (2.0 * c2));
            let k = a2 * x0 * x0 + c2 * y0 * y0 - f;
            let (p, q) = (k / a2, k / c2);
            let origin_l = [x0 * co - y0 * s, x0 * s + y0 * co, c.z];
            if p > 0.0 && q > 0.0 {
                let (ra, rb) = (p.sqrt(), q.sqrt());
                let t0 = ((sy - y0) / rb).atan2((sx - x0) / ra);
                let mut t1 = ((ey - y0) / rb).atan2((ex - x0) / ra);
                while t1 <= t0 + 1e-14 {
                    t1 += 2.0 * std::f64::consts::PI;
                }
                return Ok(CurveEval::Conic {
                    kind: ConicKind::Ellipse,
                    origin: tr_point(t, origin_l),
                    x: x_axis,
                    y: y_axis,
                    a: ra,
                    b: rb,
                    range: (t0, t1),
                });
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
                let (e0x, e0y) = loc(ex, ey);
                let sign = s0x.signum();
                let t0 = (s0y / rb).asinh();
                let t1 = (e0y / rb).asinh();
                let _ = e0x;
                return Ok(CurveEval::Conic {
                    kind: ConicKind::Hyperbola,
                    origin: tr_point(t, origin_l),
                    x: xa * sign,
                    y: ya * sign,
                    a: ra,
                    b: rb,
                    range: if t0 < t1 { (t0, t1) } else { (t1, t0) },
                });
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
        let vertex_l = if swap { (yv, xv) } else { (xv, yv) };
        let origin_l = [
            vertex_l.0 * co - vertex_l.1 * s,
            vertex_l.0 * s + vertex_l.1 * co,
            c.z,
        ];
        let (s_par, e_par) = if swap {
            (sy - xv, ey - xv)
        } else {
            (sx - xv, ex - xv)
        };
        // point = vertex + ya (k t²) + xa t
        Ok(CurveEval::Conic {
            kind: ConicKind::Parabola,
            origin: tr_point(t, origin_l),
            x: ya,
            y: xa,
            a: k,
            b: 1.0,
            range: if s_par < e_par {
                (s_par, e_par)
            } else {
                (e_par, s_par)
            },
        })
    }

    /// The surface of entity `id` (114, 118, 120, 122, 128; 143/144/510 are resolved by the
    /// caller).
    pub(crate) fn surface(&self, id: DeId) -> Result<SurfEval, Error> {
        let rec = self
            .file
            .get(id)
            .ok_or_else(|| self.bad(id, "pointer names no entity"))?;
        let t = self.transform(id)?;
        Ok(match &rec.entity {
            Entity::SplineSurface(s) => {
                let ok = |b: &[f64]| {
                    b.windows(2).all(|w| w[1] > w[0]) && b.iter().all(|x| x.is_finite())
                };
                if !ok(&s.u_breaks) || !ok(&s.v_breaks) {
                    return Err(self.bad(id, "break points are not increasing"));
                }
                let patches = s
                    .patches
                    .iter()
                    .map(|c| {
                        std::array::from_fn(|k| {
                            let v = [c[0][k], c[1][k], c[2][k]];
                            if k == 0 {
                                tr_point(&t, v)
                            } else {
                                Point3::from(tr_vector(&t, v))
                            }
                        })
                    })
                    .collect();
                SurfEval::Spline {
                    u_breaks: s.u_breaks.clone(),
                    v_breaks: s.v_breaks.clone(),
                    patches,
                }
            }
            Entity::BSplineSurface(b) => {
                let ku = self.knots(id, b.degree_u, &b.knots_u, "u knots")?;
                let kv = self.knots(id, b.degree_v, &b.knots_v, "v knots")?;
                let (w0, w1) = b
                    .weights
                    .iter()
                    .fold((f64::INFINITY, 0.0f64), |(a, c), &w| (a.min(w), c.max(w)));
                if !(w0 > 0.0) || !w1.is_finite() {
                    return Err(self.bad(id, "weights must be positive"));
                }
                let ctrl = b
                    .control_points
                    .iter()
                    .zip(&b.weights)
                    .map(|(p, &w)| {
                        let q = tr_point(&t, *p);
                        [q.x * w, q.y * w, q.z * w, w]
                    })
                    .collect();
                let clip = |r: [f64; 2], d: (f64, f64), what: &str| -> Result<(f64, f64), Error> {
                    let lo = if (r[0] - d.0).abs() <= 1e-12 * (d.1 - d.0) {
                        d.0
                    } else {
                        r[0].max(d.0)
                    };
                    let hi = if (r[1] - d.1).abs() <= 1e-12 * (d.1 - d.0) {
                        d.1
                    } else {
                        r[1].min(d.1)
                    };
                    if hi > lo {
                        Ok((lo, hi))
                    } else {
                        Err(self.bad(
                            id,
                            format!("{what} range {r:?} is empty or outside the knots"),
                        ))
                    }
                };
                SurfEval::Nurbs {
                    u_range: clip(b.u_range, ku.domain(), "u")?,
                    v_range: clip(b.v_range, kv.domain(), "v")?,
                    ku,
                    kv,
                    ctrl,
                    rational: w1 - w0 > EQUAL_WEIGHTS * w1,
                }
            }
            Entity::SurfaceOfRevolution(s) => {
                let axis = self.curve(s.axis)?;
                let CurveEval::Line(a, b) = axis else {
                    return Err(self.bad(id, "the axis of revolution is not a line (110)"));
                };
                let d = b - a;
                if !(d.norm() > 0.0) {
                    return Err(self.bad(id, "the axis of revolution has zero length"));
                }
                if !(s.end_angle > s.start_angle) {
                    return Err(self.bad(id, "the angle range is empty"));
                }
                SurfEval::Revolution {
                    axis_point: a,
                    axis_dir: d / d.norm(),
                    generatrix: Box::new(self.curve(s.generatrix)?),
                    angles: (s.start_angle, s.end_angle),
                    outer: t,
                }
            }
            Entity::RuledSurface(r) => {
                if t.is_some() {
                    return Err(self.bad(id, "transformed ruled surfaces are not supported"));
                }
                SurfEval::Ruled {
                    c1: Box::new(self.curve(r.curve1)?),
                    c2: Box::new(self.curve(r.curve2)?),
                    reversed: r.reversed,
                }
            }
            Entity::TabulatedCylinder(c) => {
                if t.is_some() {
                    return Err(self.bad(id, "transformed tabulated cylinders are not supported"));
                }
                let directrix = self.curve(c.directrix)?;
                let start = directrix.point(directrix.domain().0);
                // The terminate point is in the directrix's definition space.
                let tt = self.transform(c.directrix)?;
                let end = tr_point(&tt, c.end);
                SurfEval::Tabulated {
                    directrix: Box::new(directrix),
                    direction: end - start,
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
        })
    }
}
