//! Exact curves of the neutral model: what IGES and STEP files define, evaluated in model
//! space, with their exact power-basis form where they are polynomial.

use super::frame::{Affine, Frame};
use super::nurbs::NurbsCurve;
use super::surface::Surface;
use crate::convert::bspline_to_power;
use crate::curve::Arc;
use crate::prelude::{Point3, Vector3};

/// The kind of a [`Curve::Conic`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ConicKind {
    /// origin + a cos t x + b sin t y (a = b = r for a circle).
    Ellipse,
    /// origin + a cosh t x + b sinh t y.
    Hyperbola,
    /// origin + a t² x + b t y.
    Parabola,
}

/// One piece of a [`Curve::Composite`]: `curve` on `[t0, t1]`, traversed backwards when
/// `reversed`; it covers the composite's parameters `[start, start + (t1 − t0)]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Piece {
    /// The curve.
    pub curve: Curve,
    /// Its parameter range.
    pub t0: f64,
    /// Its parameter range.
    pub t1: f64,
    /// Traversed from t1 to t0.
    pub reversed: bool,
    /// The composite parameter where the piece starts.
    pub start: f64,
}

/// An exact curve. Parameters are the source's (see each variant); a curve is used on a
/// parameter range given beside it (an edge, a boundary piece).
#[derive(Debug, Clone, PartialEq)]
pub enum Curve {
    /// origin + t dir.
    Line {
        /// The point at t = 0.
        origin: Point3,
        /// The derivative.
        dir: Vector3,
    },
    /// A conic in `frame` (its x and y axes; see [`ConicKind`]).
    Conic {
        /// Which conic.
        kind: ConicKind,
        /// The frame (origin: centre or vertex).
        frame: Frame,
        /// First coefficient.
        a: f64,
        /// Second coefficient.
        b: f64,
    },
    /// Straight segments through the points; t ∈ [0, n − 1], segment k on [k, k + 1].
    Polyline {
        /// The points.
        points: Vec<Point3>,
    },
    /// A (rational) B-spline.
    Nurbs(NurbsCurve),
    /// Cubic segments (IGES 112): on [T(i), T(i+1)], with s = t − T(i),
    /// r = c₀ + c₁ s + c₂ s² + c₃ s³.
    Spline {
        /// T(1..N+1).
        breaks: Vec<f64>,
        /// c₀..c₃ per segment (c₀ a point, the others as position vectors).
        segments: Vec<[Vector3; 4]>,
    },
    /// The basis curve offset in the plane normal to `normal`: C + d (C′ × n) / |C′ × n|
    /// (IGES 130; STEP `OFFSET_CURVE_3D` with n = −ref_direction).
    Offset {
        /// The curve offset.
        basis: Box<Curve>,
        /// The distance.
        distance: f64,
        /// The plane normal.
        normal: Vector3,
    },
    /// Pieces end to end.
    Composite {
        /// The pieces in order.
        pieces: Vec<Piece>,
    },
    /// s ∈ [0, 1] ↦ curve(t0 + s (t1 − t0)) (IGES normalised parameters).
    Reparam {
        /// The curve.
        curve: Box<Curve>,
        /// Parameter at s = 0.
        t0: f64,
        /// Parameter at s = 1.
        t1: f64,
    },
    /// S(B(t)): a parameter-space curve B (x, y = u, v) on a surface.
    OnSurface {
        /// The surface.
        surface: Box<Surface>,
        /// The parameter-space curve (z ignored).
        pcurve: Box<Curve>,
    },
    /// The image of a curve by an affine map (kept when the map does not act on the
    /// curve's data exactly, e.g. an offset curve under a non-similarity).
    Mapped {
        /// The curve.
        curve: Box<Curve>,
        /// The map.
        map: Affine,
    },
}

/// Central-difference step relative to the parameter scale.
const FD_STEP: f64 = 1e-6;

impl Curve {
    /// The natural parameter range, when the curve has one (`None` for lines, hyperbolas,
    /// parabolas and offsets of those).
    pub fn natural_range(&self) -> Option<(f64, f64)> {
        match self {
            Curve::Line { .. } => None,
            Curve::Conic { kind, .. } => {
                (*kind == ConicKind::Ellipse).then_some((0.0, 2.0 * std::f64::consts::PI))
            }
            Curve::Polyline { points } => Some((0.0, points.len().saturating_sub(1) as f64)),
            Curve::Nurbs(n) => Some(n.domain()),
            Curve::Spline { breaks, .. } => Some((breaks[0], *breaks.last()?)),
            Curve::Offset { basis, .. } => basis.natural_range(),
            Curve::Composite { pieces } => {
                let last = pieces.last()?;
                Some((pieces[0].start, last.start + (last.t1 - last.t0)))
            }
            Curve::Reparam { curve, t0, t1 } => {
                let (a, b) = curve.natural_range()?;
                let (s, e) = ((a - t0) / (t1 - t0), (b - t0) / (t1 - t0));
                Some((s.min(e), s.max(e)))
            }
            Curve::OnSurface { pcurve, .. } => pcurve.natural_range(),
            Curve::Mapped { curve, .. } => curve.natural_range(),
        }
    }

    /// The period of a closed periodic parametrisation (2π for an ellipse).
    pub fn period(&self) -> Option<f64> {
        match self {
            Curve::Conic {
                kind: ConicKind::Ellipse,
                ..
            } => Some(2.0 * std::f64::consts::PI),
            Curve::Offset { basis, .. } => basis.period(),
            Curve::Mapped { curve, .. } => curve.period(),
            Curve::Reparam { curve, t0, t1 } => curve.period().map(|p| p / (t1 - t0).abs()),
            _ => None,
        }
    }

    /// The parameter of the point of the curve nearest `p`: in closed form for lines and
    /// conics (exact for points on them), by segment for polylines, otherwise by sampling
    /// `range` (or the natural range) then safeguarded Newton on |C(t) − p|². Angles of
    /// conics come in (−π, π]. `None` when there is no range to search.
    pub fn closest_param(&self, p: &Point3, range: Option<(f64, f64)>) -> Option<f64> {
        match self {
            Curve::Line { origin, dir } => {
                let d2 = dir.norm_squared();
                (d2 > 0.0).then(|| (p - origin).dot(dir) / d2)
            }
            Curve::Conic { kind, frame, a, b } => {
                let q = frame.local(p)?;
                Some(match kind {
                    ConicKind::Ellipse => (q.y / b).atan2(q.x / a),
                    ConicKind::Hyperbola => (q.y / b).asinh(),
                    ConicKind::Parabola => q.y / b,
                })
            }
            Curve::Polyline { points } => {
                let mut best = (f64::INFINITY, 0.0);
                for (k, w) in points.windows(2).enumerate() {
                    let d = w[1] - w[0];
                    let s = if d.norm_squared() > 0.0 {
                        ((p - w[0]).dot(&d) / d.norm_squared()).clamp(0.0, 1.0)
                    } else {
                        0.0
                    };
                    let dist = (w[0] + d * s - p).norm();
                    if dist < best.0 {
                        best = (dist, k as f64 + s);
                    }
                }
                best.0.is_finite().then_some(best.1)
            }
            Curve::Reparam { curve, t0, t1 } => {
                let inner = range.map(|(a, b)| (t0 + a * (t1 - t0), t0 + b * (t1 - t0)));
                let inner = inner.map(|(a, b)| (a.min(b), a.max(b)));
                let t = curve.closest_param(p, inner)?;
                Some((t - t0) / (t1 - t0))
            }
            _ => {
                let (a, b) = range.or_else(|| self.natural_range())?;
                if !(a.is_finite() && b.is_finite()) {
                    return None;
                }
                let n = 64;
                let mut t = a;
                let mut best = f64::INFINITY;
                for k in 0..=n {
                    let s = a + (b - a) * k as f64 / n as f64;
                    let d = (self.point(s) - p).norm_squared();
                    if d < best {
                        best = d;
                        t = s;
                    }
                }
                let (lo, hi) = (a.min(b), a.max(b));
                let mut dist = best.sqrt();
                for _ in 0..30 {
                    let (c, d1) = self.derivs(t);
                    let g = (c - p).dot(&d1);
                    let h = d1.norm_squared();
                    if !(h > 0.0) {
                        break;
                    }
                    let nt = (t - g / h).clamp(lo, hi);
                    let nd = (self.point(nt) - p).norm();
                    if !(nd < dist) {
                        break;
                    }
                    let done = (nt - t).abs() <= 1e-15 * (hi - lo).abs().max(1.0);
                    t = nt;
                    dist = nd;
                    if done {
                        break;
                    }
                }
                Some(t)
            }
        }
    }

    /// C(t).
    pub fn point(&self, t: f64) -> Point3 {
        match self {
            Curve::Line { origin, dir } => origin + dir * t,
            Curve::Conic { kind, frame, a, b } => {
                let (x, y) = match kind {
                    ConicKind::Ellipse => (a * t.cos(), b * t.sin()),
                    ConicKind::Hyperbola => (a * t.cosh(), b * t.sinh()),
                    ConicKind::Parabola => (a * t * t, b * t),
                };
                frame.origin + frame.x * x + frame.y * y
            }
            Curve::Polyline { points } => {
                let n = points.len();
                if n < 2 {
                    return points.first().copied().unwrap_or_else(Point3::origin);
                }
                let k = (t.floor().max(0.0) as usize).min(n - 2);
                let s = t - k as f64;
                points[k] + (points[k + 1] - points[k]) * s
            }
            Curve::Nurbs(n) => n.point(t),
            Curve::Spline { breaks, segments } => {
                let n = segments.len();
                let i = breaks[1..n].partition_point(|&b| b <= t);
                let s = t - breaks[i];
                let c = &segments[i];
                Point3::from(c[0] + (c[1] + (c[2] + c[3] * s) * s) * s)
            }
            Curve::Offset {
                basis,
                distance,
                normal,
            } => {
                let (p, d) = basis.derivs(t);
                let n = d.cross(normal);
                let len = n.norm();
                if len > 0.0 {
                    p + n * (distance / len)
                } else {
                    p
                }
            }
            Curve::Composite { pieces } => {
                let (k, s) = Self::locate_piece(pieces, t);
                let pc = &pieces[k];
                let tt = if pc.reversed { pc.t1 - s } else { pc.t0 + s };
                pc.curve.point(tt)
            }
            Curve::Reparam { curve, t0, t1 } => curve.point(t0 + t * (t1 - t0)),
            Curve::OnSurface { surface, pcurve } => {
                let q = pcurve.point(t);
                surface.point(q.x, q.y)
            }
            Curve::Mapped { curve, map } => map.point(&curve.point(t)),
        }
    }

    fn locate_piece(pieces: &[Piece], t: f64) -> (usize, f64) {
        let n = pieces.len();
        let k = pieces[1..n].partition_point(|p| p.start <= t);
        (k, t - pieces[k].start)
    }

    /// C(t) and C′(t) (analytic where simple, central differences otherwise).
    pub fn derivs(&self, t: f64) -> (Point3, Vector3) {
        match self {
            Curve::Line { origin, dir } => (origin + dir * t, *dir),
            Curve::Conic { kind, frame, a, b } => {
                let (dx, dy) = match kind {
                    ConicKind::Ellipse => (-a * t.sin(), b * t.cos()),
                    ConicKind::Hyperbola => (a * t.sinh(), b * t.cosh()),
                    ConicKind::Parabola => (2.0 * a * t, *b),
                };
                (self.point(t), frame.x * dx + frame.y * dy)
            }
            Curve::Nurbs(n) => n.derivs(t),
            Curve::Spline { breaks, segments } => {
                let n = segments.len();
                let i = breaks[1..n].partition_point(|&b| b <= t);
                let s = t - breaks[i];
                let c = &segments[i];
                (
                    Point3::from(c[0] + (c[1] + (c[2] + c[3] * s) * s) * s),
                    c[1] + (c[2] * 2.0 + c[3] * (3.0 * s)) * s,
                )
            }
            Curve::Reparam { curve, t0, t1 } => {
                let (p, d) = curve.derivs(t0 + t * (t1 - t0));
                (p, d * (t1 - t0))
            }
            _ => {
                let scale = self
                    .natural_range()
                    .map_or(1.0, |(a, b)| (b - a).abs().max(1e-300));
                let h = FD_STEP * scale.max(t.abs()).max(1e-12);
                let d = (self.point(t + h) - self.point(t - h)) / (2.0 * h);
                (self.point(t), d)
            }
        }
    }

    /// Parameters inside (t0, t1) where the curve may be only C0 (knots, segment and piece
    /// joins), with t0 and t1 (t0 < t1) first and last.
    pub fn breaks(&self, t0: f64, t1: f64) -> Vec<f64> {
        let inner: Vec<f64> = match self {
            Curve::Polyline { points } => (1..points.len().saturating_sub(1))
                .map(|k| k as f64)
                .collect(),
            Curve::Nurbs(n) => n.knots.breakpoints(),
            Curve::Spline { breaks, .. } => breaks.clone(),
            Curve::Composite { pieces } => pieces.iter().map(|p| p.start).collect(),
            Curve::Offset { basis, .. } => basis.breaks(t0, t1),
            Curve::Mapped { curve, .. } => curve.breaks(t0, t1),
            Curve::Reparam {
                curve,
                t0: a,
                t1: b,
            } => {
                let (lo, hi) = if a < b { (*a, *b) } else { (*b, *a) };
                curve
                    .breaks(lo, hi)
                    .into_iter()
                    .map(|x| (x - a) / (b - a))
                    .collect()
            }
            Curve::OnSurface { pcurve, .. } => pcurve.breaks(t0, t1),
            Curve::Line { .. } | Curve::Conic { .. } => Vec::new(),
        };
        let pad = 1e-12 * (t1 - t0).abs();
        let mut out = vec![t0];
        let mut inner: Vec<f64> = inner
            .into_iter()
            .filter(|&x| x > t0 + pad && x < t1 - pad)
            .collect();
        inner.sort_by(f64::total_cmp);
        inner.dedup();
        out.extend(inner);
        out.push(t1);
        out
    }

    /// The exact power-basis arcs of the curve on [t0, t1] (t0 < t1) when it is polynomial
    /// (lines, polylines, 112 splines, non-rational B-splines, and composites,
    /// reparametrisations and affine images of those): one arc per polynomial piece, cut at
    /// t0 and t1, each with the parameter interval it covers (local u ∈ [0, 1] ↦ a + u (b − a)).
    pub fn exact_arcs(&self, t0: f64, t1: f64) -> Option<Vec<(f64, f64, Arc)>> {
        let pieces: Vec<(f64, f64, Arc)> = match self {
            Curve::Line { origin, dir } => {
                return Some(vec![(
                    t0,
                    t1,
                    Arc::line(origin + dir * t0, origin + dir * t1),
                )]);
            }
            Curve::Polyline { points } => points
                .windows(2)
                .enumerate()
                .map(|(k, w)| (k as f64, k as f64 + 1.0, Arc::line(w[0], w[1])))
                .collect(),
            Curve::Spline { breaks, segments } => segments
                .iter()
                .zip(breaks.windows(2))
                .map(|(c, w)| {
                    let h = w[1] - w[0];
                    let mut coeffs = vec![
                        Point3::from(c[0]),
                        Point3::from(c[1] * h),
                        Point3::from(c[2] * (h * h)),
                        Point3::from(c[3] * (h * h * h)),
                    ];
                    // Lower the degree when the top coefficients vanish (degree ≥ 1).
                    while coeffs.len() > 2
                        && coeffs.last().is_some_and(|p| p.coords == Vector3::zeros())
                    {
                        coeffs.pop();
                    }
                    (w[0], w[1], Arc::new(coeffs))
                })
                .collect(),
            Curve::Nurbs(n) if !n.rational => bspline_to_power(&n.knots, &n.points())
                .ok()?
                .into_iter()
                .map(|a| (a.t0, a.t1, a.arc))
                .collect(),
            Curve::Reparam {
                curve,
                t0: a,
                t1: b,
            } => {
                let (s0, s1) = (a + t0 * (b - a), a + t1 * (b - a));
                let inner = if s0 <= s1 {
                    curve.exact_arcs(s0, s1)?
                } else {
                    reversed_pieces(curve.exact_arcs(s1, s0)?)
                };
                return Some(
                    inner
                        .into_iter()
                        .map(|(x, y, arc)| ((x - a) / (b - a), (y - a) / (b - a), arc))
                        .collect(),
                );
            }
            Curve::Composite { pieces } => {
                let mut out = Vec::new();
                for p in pieces {
                    let (a, b) = (p.start, p.start + (p.t1 - p.t0));
                    let (lo, hi) = (a.max(t0), b.min(t1));
                    if hi - lo <= 1e-12 * (t1 - t0).abs() {
                        continue;
                    }
                    let to_piece = |x: f64| {
                        if p.reversed {
                            p.t1 - (x - a)
                        } else {
                            p.t0 + (x - a)
                        }
                    };
                    let from_piece = |y: f64| {
                        if p.reversed {
                            a + (p.t1 - y)
                        } else {
                            a + (y - p.t0)
                        }
                    };
                    let (s0, s1) = (to_piece(lo), to_piece(hi));
                    let inner = if s0 <= s1 {
                        p.curve.exact_arcs(s0, s1)?
                    } else {
                        reversed_pieces(p.curve.exact_arcs(s1, s0)?)
                    };
                    out.extend(
                        inner
                            .into_iter()
                            .map(|(x, y, arc)| (from_piece(x), from_piece(y), arc)),
                    );
                }
                return (!out.is_empty()).then_some(out);
            }
            Curve::Mapped { curve, map } => {
                return Some(
                    curve
                        .exact_arcs(t0, t1)?
                        .into_iter()
                        .map(|(a, b, arc)| (a, b, Arc::new(map_coeffs(map, &arc.coeffs))))
                        .collect(),
                );
            }
            _ => return None,
        };
        cut_pieces(&pieces, t0, t1)
    }

    /// Applies an affine map: exactly on the curve's data where the map acts on it exactly,
    /// else as a [`Curve::Mapped`] wrapper.
    pub fn transform(&mut self, m: &Affine) {
        match self {
            Curve::Line { origin, dir } => {
                *origin = m.point(origin);
                *dir = m.vector(dir);
            }
            Curve::Conic { frame, .. } => *frame = frame.transformed(m),
            Curve::Polyline { points } => points.iter_mut().for_each(|p| *p = m.point(p)),
            Curve::Nurbs(n) => n.transform(m),
            Curve::Spline { segments, .. } => {
                for c in segments {
                    c[0] = m.point(&Point3::from(c[0])).coords;
                    for k in 1..4 {
                        c[k] = m.vector(&c[k]);
                    }
                }
            }
            Curve::Composite { pieces } => pieces.iter_mut().for_each(|p| p.curve.transform(m)),
            Curve::Reparam { curve, .. } => curve.transform(m),
            Curve::OnSurface { surface, .. } => surface.transform(m),
            Curve::Mapped { map, .. } => *map = map.then(m),
            Curve::Offset { .. } => {
                let inner = std::mem::replace(self, Curve::Polyline { points: Vec::new() });
                *self = Curve::Mapped {
                    curve: Box::new(inner),
                    map: *m,
                };
            }
        }
    }
}

/// a₀ ↦ L a₀ + t, a_k ↦ L a_k: the power coefficients of the image of an arc.
fn map_coeffs(m: &Affine, c: &[Point3]) -> Vec<Point3> {
    c.iter()
        .enumerate()
        .map(|(k, p)| {
            if k == 0 {
                m.point(p)
            } else {
                Point3::from(m.vector(&p.coords))
            }
        })
        .collect()
}

/// Pieces of the reversed curve: reversed order, each arc reversed, intervals swapped.
fn reversed_pieces(p: Vec<(f64, f64, Arc)>) -> Vec<(f64, f64, Arc)> {
    p.into_iter()
        .rev()
        .map(|(a, b, arc)| (b, a, arc.reversed()))
        .collect()
}

/// The arcs of consecutive polynomial pieces `(a, b, arc)` (local u ∈ [0, 1] on [a, b]) cut
/// to [t0, t1].
fn cut_pieces(pieces: &[(f64, f64, Arc)], t0: f64, t1: f64) -> Option<Vec<(f64, f64, Arc)>> {
    let mut out = Vec::new();
    let tiny = 1e-12 * (t1 - t0).abs();
    for (a, b, arc) in pieces {
        let (lo, hi) = (a.max(t0), b.min(t1));
        if hi - lo <= tiny {
            continue;
        }
        let (s, e) = ((lo - a) / (b - a), (hi - a) / (b - a));
        if s <= 1e-15 && e >= 1.0 - 1e-15 {
            out.push((*a, *b, arc.clone()));
        } else {
            out.push((lo, hi, super::super::export::sub_arc(arc, s, e)));
        }
    }
    (!out.is_empty()).then_some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bspline::KnotVector;

    fn frame() -> Frame {
        Frame::orthonormal(
            Point3::new(1.0, 2.0, 3.0),
            Vector3::new(0.0, 0.0, 1.0),
            Some(Vector3::new(1.0, 1.0, 0.0)),
        )
        .unwrap()
    }

    /// Closed forms: a circle of radius 2 about (1, 2, 3) in the plane z = 3, rotated 45°.
    #[test]
    fn conics_follow_their_closed_forms() {
        let c = Curve::Conic {
            kind: ConicKind::Ellipse,
            frame: frame(),
            a: 2.0,
            b: 2.0,
        };
        let s = 0.5f64.sqrt();
        for k in 0..8 {
            let t = k as f64 * 0.7;
            let p = c.point(t);
            let want = Point3::new(
                1.0 + 2.0 * (s * t.cos() - s * t.sin()),
                2.0 + 2.0 * (s * t.cos() + s * t.sin()),
                3.0,
            );
            assert!((p - want).norm() < 1e-14);
            let (_, d) = c.derivs(t);
            assert!((d.norm() - 2.0).abs() < 1e-14);
            assert!(d.dot(&(p - frame().origin)).abs() < 1e-13);
        }
        let h = Curve::Conic {
            kind: ConicKind::Hyperbola,
            frame: frame(),
            a: 3.0,
            b: 1.5,
        };
        // (x/a)² − (y/b)² = 1 in the frame.
        for t in [-1.0, 0.0, 0.4, 2.0] {
            let q = frame().local(&h.point(t)).unwrap();
            assert!(((q.x / 3.0).powi(2) - (q.y / 1.5).powi(2) - 1.0).abs() < 1e-12);
        }
        let p = Curve::Conic {
            kind: ConicKind::Parabola,
            frame: frame(),
            a: 0.25,
            b: 1.0,
        };
        // x = y² / 4 in the frame (focal distance 1).
        for t in [-2.0, 0.5, 3.0] {
            let q = frame().local(&p.point(t)).unwrap();
            assert!((q.x - q.y * q.y / 4.0).abs() < 1e-13);
        }
    }

    #[test]
    fn polynomial_curves_convert_exactly_on_a_sub_range() {
        let kv = KnotVector::new(3, vec![0.0, 0.0, 0.0, 0.0, 0.4, 1.0, 1.0, 1.0, 1.0]).unwrap();
        let pts: Vec<Point3> = (0..5)
            .map(|i| Point3::new(i as f64, (i * i) as f64 * 0.3, (i as f64).sin()))
            .collect();
        let c = Curve::Nurbs(NurbsCurve::new(kv, &pts, &[2.0; 5]).unwrap());
        let arcs: Vec<Arc> = c
            .exact_arcs(0.1, 0.9)
            .unwrap()
            .into_iter()
            .map(|x| x.2)
            .collect();
        assert_eq!(arcs.len(), 2);
        // Arc 0 covers [0.1, 0.4], arc 1 [0.4, 0.9].
        for (k, (a, b)) in [(0.1, 0.4), (0.4, 0.9)].into_iter().enumerate() {
            for s in [0.0, 0.3, 1.0] {
                let got = arcs[k].point(s);
                let want = c.point(a + s * (b - a));
                assert!((got - want).norm() < 1e-13, "{k} {s}");
            }
        }
        let p = Curve::Polyline {
            points: vec![
                Point3::origin(),
                Point3::new(1.0, 0.0, 0.0),
                Point3::new(1.0, 2.0, 0.0),
            ],
        };
        let arcs: Vec<Arc> = p
            .exact_arcs(0.5, 2.0)
            .unwrap()
            .into_iter()
            .map(|x| x.2)
            .collect();
        assert_eq!(arcs.len(), 2);
        assert!((arcs[0].point(0.0) - Point3::new(0.5, 0.0, 0.0)).norm() < 1e-15);
        assert!((arcs[1].point(1.0) - Point3::new(1.0, 2.0, 0.0)).norm() < 1e-15);
        assert!(
            Curve::Conic {
                kind: ConicKind::Ellipse,
                frame: frame(),
                a: 1.0,
                b: 1.0
            }
            .exact_arcs(0.0, 1.0)
            .is_none()
        );
    }

    #[test]
    fn offset_curve_is_at_its_distance() {
        let circle = Curve::Conic {
            kind: ConicKind::Ellipse,
            frame: frame(),
            a: 2.0,
            b: 2.0,
        };
        // C′ × z points outwards for a counter-clockwise circle: radius 2 + 0.5.
        let o = Curve::Offset {
            basis: Box::new(circle),
            distance: 0.5,
            normal: Vector3::z(),
        };
        for t in [0.0, 1.0, 4.0] {
            assert!(((o.point(t) - frame().origin).norm() - 2.5).abs() < 1e-14);
        }
    }
}
