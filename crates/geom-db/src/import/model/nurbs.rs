//! Rational B-spline curves and surfaces of the neutral model (homogeneous control points),
//! evaluated with the bases of [`bspline`](crate::bspline) (Piegl & Tiller A4.1–A4.4: the
//! point is A/w, the first derivative (A′ − w′ C)/w).

use super::frame::Affine;
use crate::bspline::KnotVector;
use crate::prelude::{Point3, Vector3};

/// Relative spread of weights under which a B-spline is polynomial.
pub(crate) const EQUAL_WEIGHTS: f64 = 1e-12;

/// A (possibly rational) B-spline curve.
#[derive(Debug, Clone, PartialEq)]
pub struct NurbsCurve {
    /// Knots and degree.
    pub knots: KnotVector,
    /// Homogeneous control points (w x, w y, w z, w).
    pub ctrl: Vec<[f64; 4]>,
    /// True when the weights differ (beyond `EQUAL_WEIGHTS`).
    pub rational: bool,
}

/// A (possibly rational) tensor B-spline surface; control point (i, j) (i along u) at
/// `ctrl[i + n_u j]`.
#[derive(Debug, Clone, PartialEq)]
pub struct NurbsSurface {
    /// Knots and degree in u.
    pub knots_u: KnotVector,
    /// Knots and degree in v.
    pub knots_v: KnotVector,
    /// Homogeneous control points, u fastest.
    pub ctrl: Vec<[f64; 4]>,
    /// True when the weights differ.
    pub rational: bool,
    /// The file says the surface is closed in u (a seam).
    pub closed_u: bool,
    /// The file says the surface is closed in v.
    pub closed_v: bool,
}

/// The distance under which a B-spline surface counts as meeting itself across a
/// direction: 1e-9 of its control net's bounding-box diagonal.
pub(crate) fn closure_tol(points: &[Point3]) -> f64 {
    let (mut lo, mut hi) = (points[0], points[0]);
    for p in points {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    1e-9 * (hi - lo).norm()
}

/// Whether weights differ by more than [`EQUAL_WEIGHTS`]; `Err` when one is not positive
/// and finite.
pub(crate) fn weights_rational(w: impl Iterator<Item = f64>) -> Result<bool, String> {
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for x in w {
        if !(x > 0.0) || !x.is_finite() {
            return Err(format!("weight {x} is not positive"));
        }
        lo = lo.min(x);
        hi = hi.max(x);
    }
    Ok(hi - lo > EQUAL_WEIGHTS * hi)
}

/// Knot values closer than this fraction of the knot domain's width are one value (a
/// writer's round-off: `0.3333333333` and `0.33333333330001`).
pub(crate) const SAME_KNOT: f64 = 1e-13;

/// A knot vector as a file gives it, made canonical: knot values within [`SAME_KNOT`] of
/// the domain's width snapped to the first of them, and every basis function that is
/// identically zero (t_i = t_{i+p+1}: a knot repeated more than p + 1 times, at an end or
/// inside, as when a value is listed twice with its multiplicity split) removed with its
/// control point, which changes nothing on the domain. Returns the knots and the indices
/// of the control points kept; `Err` for what no reading can mend (too few knots, not
/// finite, decreasing). An empty domain is left to [`KnotVector::new`] to refuse.
pub(crate) fn canonical_knots(
    degree: usize,
    knots: &[f64],
) -> crate::error::Result<(Vec<f64>, Vec<usize>)> {
    let bad = |reason: String| crate::error::Error::InvalidKnots { degree, reason };
    if let Some(i) = knots.iter().position(|k| !k.is_finite()) {
        return Err(bad(format!("knot {i} is not finite")));
    }
    if let Some(i) = knots.windows(2).position(|w| w[1] < w[0]) {
        return Err(bad(format!("knots decrease at index {}", i + 1)));
    }
    let n = knots.len();
    if n < 2 * (degree + 1) {
        return Err(bad(format!(
            "{n} knots given, at least {} needed",
            2 * (degree + 1)
        )));
    }
    let width = (knots[n - degree - 1] - knots[degree]).abs();
    let snap = SAME_KNOT * width;
    let mut k = knots.to_vec();
    for i in 1..n {
        if k[i] - k[i - 1] <= snap {
            k[i] = k[i - 1];
        }
    }
    let mut keep: Vec<usize> = (0..n - degree - 1).collect();
    // drop zero basis functions: N_i vanishes when t_i = t_{i+p+1}
    let mut i = 0;
    while i + degree + 1 < k.len() {
        if k[i] == k[i + degree + 1] {
            k.remove(i);
            keep.remove(i);
        } else {
            i += 1;
        }
    }
    Ok((k, keep))
}

/// A curve from a file's knots (any, see [`canonical_knots`]), points and weights.
pub(crate) fn canonical_curve(
    degree: usize,
    knots: &[f64],
    points: &[Point3],
    weights: &[f64],
) -> Result<NurbsCurve, String> {
    let n = knots.len().saturating_sub(degree + 1);
    if points.len() != n || weights.len() != n {
        return Err(format!(
            "{} control points and {} weights for {n} basis functions",
            points.len(),
            weights.len()
        ));
    }
    let (k, keep) = canonical_knots(degree, knots).map_err(|e| format!("knots: {e}"))?;
    let kv = KnotVector::new(degree, k).map_err(|e| format!("knots: {e}"))?;
    let pts: Vec<Point3> = keep.iter().map(|&i| points[i]).collect();
    let w: Vec<f64> = keep.iter().map(|&i| weights[i]).collect();
    NurbsCurve::new(kv, &pts, &w)
}

/// A surface from a file's knots (any, see [`canonical_knots`]), points and weights
/// (`[i + n_u j]`, n_u the number of the file's u basis functions).
pub(crate) fn canonical_surface(
    (degree_u, knots_u): (usize, &[f64]),
    (degree_v, knots_v): (usize, &[f64]),
    points: &[Point3],
    weights: &[f64],
) -> Result<NurbsSurface, String> {
    let nu = knots_u.len().saturating_sub(degree_u + 1);
    let nv = knots_v.len().saturating_sub(degree_v + 1);
    if points.len() != nu * nv || weights.len() != nu * nv {
        return Err(format!(
            "{} control points and {} weights for {nu} × {nv} basis functions",
            points.len(),
            weights.len()
        ));
    }
    let (ku, keep_u) = canonical_knots(degree_u, knots_u).map_err(|e| format!("u knots: {e}"))?;
    let (kv, keep_v) = canonical_knots(degree_v, knots_v).map_err(|e| format!("v knots: {e}"))?;
    let ku = KnotVector::new(degree_u, ku).map_err(|e| format!("u knots: {e}"))?;
    let kv = KnotVector::new(degree_v, kv).map_err(|e| format!("v knots: {e}"))?;
    let mut pts = Vec::with_capacity(keep_u.len() * keep_v.len());
    let mut w = Vec::with_capacity(pts.capacity());
    for &j in &keep_v {
        for &i in &keep_u {
            pts.push(points[i + nu * j]);
            w.push(weights[i + nu * j]);
        }
    }
    NurbsSurface::new(ku, kv, &pts, &w)
}

fn homogeneous(p: Point3, w: f64) -> [f64; 4] {
    [p.x * w, p.y * w, p.z * w, w]
}

fn transform_h(m: &Affine, h: &[f64; 4]) -> [f64; 4] {
    let w = h[3];
    homogeneous(m.point(&Point3::new(h[0] / w, h[1] / w, h[2] / w)), w)
}

impl NurbsCurve {
    /// A curve from its knots, points and weights (one per point).
    pub fn new(knots: KnotVector, points: &[Point3], weights: &[f64]) -> Result<Self, String> {
        if points.len() != knots.n_basis() || weights.len() != points.len() {
            return Err(format!(
                "{} control points and {} weights for {} basis functions",
                points.len(),
                weights.len(),
                knots.n_basis()
            ));
        }
        let rational = weights_rational(weights.iter().copied())?;
        Ok(NurbsCurve {
            ctrl: points
                .iter()
                .zip(weights)
                .map(|(p, &w)| homogeneous(*p, w))
                .collect(),
            knots,
            rational,
        })
    }

    /// The knot domain.
    pub fn domain(&self) -> (f64, f64) {
        self.knots.domain()
    }

    /// C(t).
    pub fn point(&self, t: f64) -> Point3 {
        let h = self.knots.curve_point(&self.ctrl, t);
        Point3::new(h[0] / h[3], h[1] / h[3], h[2] / h[3])
    }

    /// C(t) and C′(t).
    pub fn derivs(&self, t: f64) -> (Point3, Vector3) {
        let d = self.knots.curve_ders(&self.ctrl, t, 1);
        let (a, w) = (Vector3::new(d[0][0], d[0][1], d[0][2]), d[0][3]);
        let (a1, w1) = (Vector3::new(d[1][0], d[1][1], d[1][2]), d[1][3]);
        let c = a / w;
        (Point3::from(c), (a1 - c * w1) / w)
    }

    /// The Euclidean control points (for the polynomial case).
    pub fn points(&self) -> Vec<Point3> {
        self.ctrl
            .iter()
            .map(|h| Point3::new(h[0] / h[3], h[1] / h[3], h[2] / h[3]))
            .collect()
    }

    /// Maps the control points (exact: affine maps commute with the rational basis).
    pub fn transform(&mut self, m: &Affine) {
        for h in &mut self.ctrl {
            *h = transform_h(m, h);
        }
    }
}

impl NurbsSurface {
    /// A surface from its knots, points and weights (`[i + n_u j]`).
    pub fn new(
        knots_u: KnotVector,
        knots_v: KnotVector,
        points: &[Point3],
        weights: &[f64],
    ) -> Result<Self, String> {
        let n = knots_u.n_basis() * knots_v.n_basis();
        if points.len() != n || weights.len() != n {
            return Err(format!(
                "{} control points and {} weights for {} × {} basis functions",
                points.len(),
                weights.len(),
                knots_u.n_basis(),
                knots_v.n_basis()
            ));
        }
        let rational = weights_rational(weights.iter().copied())?;
        Ok(NurbsSurface {
            ctrl: points
                .iter()
                .zip(weights)
                .map(|(p, &w)| homogeneous(*p, w))
                .collect(),
            knots_u,
            knots_v,
            rational,
            closed_u: false,
            closed_v: false,
        })
    }

    /// (u, v) brought into the domain across a closed direction (unchanged otherwise).
    pub fn wrap(&self, u: f64, v: f64) -> (f64, f64) {
        let w = |x: f64, (a, b): (f64, f64), closed: bool| {
            if closed && !(a..=b).contains(&x) {
                a + (x - a).rem_euclid(b - a)
            } else {
                x
            }
        };
        let (du, dv) = self.domain();
        (w(u, du, self.closed_u), w(v, dv, self.closed_v))
    }

    /// Whether the surface meets itself across u = u0 / u1 (`u = true`) or v, sampled at 9
    /// points within `tol`.
    pub fn meets_itself(&self, u: bool, tol: f64) -> bool {
        let ((u0, u1), (v0, v1)) = self.domain();
        (0..=8).all(|k| {
            let f = k as f64 / 8.0;
            let (a, b) = if u {
                let v = v0 + f * (v1 - v0);
                (self.point(u0, v), self.point(u1, v))
            } else {
                let u = u0 + f * (u1 - u0);
                (self.point(u, v0), self.point(u, v1))
            };
            (a - b).norm() <= tol
        })
    }

    /// The knot domain ((u0, u1), (v0, v1)).
    pub fn domain(&self) -> ((f64, f64), (f64, f64)) {
        (self.knots_u.domain(), self.knots_v.domain())
    }

    /// S(u, v), S_u, S_v.
    pub fn derivs(&self, u: f64, v: f64) -> (Point3, Vector3, Vector3) {
        let (pu, pv) = (self.knots_u.degree(), self.knots_v.degree());
        let n_u = self.knots_u.n_basis();
        with_scratch(pu + 1, |nu0, nu1| {
            with_scratch(pv + 1, |nv0, nv1| {
                let su = self.knots_u.basis_ders1_into(u, nu0, nu1);
                let sv = self.knots_v.basis_ders1_into(v, nv0, nv1);
                let (mut a, mut au, mut av) = ([0.0; 4], [0.0; 4], [0.0; 4]);
                for b in 0..=pv {
                    let j = sv - pv + b;
                    for c in 0..=pu {
                        let i = su - pu + c;
                        let h = &self.ctrl[i + n_u * j];
                        let (n00, n10, n01) = (nu0[c] * nv0[b], nu1[c] * nv0[b], nu0[c] * nv1[b]);
                        for k in 0..4 {
                            a[k] += n00 * h[k];
                            au[k] += n10 * h[k];
                            av[k] += n01 * h[k];
                        }
                    }
                }
                let w = a[3];
                let s = Vector3::new(a[0], a[1], a[2]) / w;
                let du = (Vector3::new(au[0], au[1], au[2]) - s * au[3]) / w;
                let dv = (Vector3::new(av[0], av[1], av[2]) - s * av[3]) / w;
                (Point3::from(s), du, dv)
            })
        })
    }

    /// S(u, v).
    pub fn point(&self, u: f64, v: f64) -> Point3 {
        let (pu, pv) = (self.knots_u.degree(), self.knots_v.degree());
        let n_u = self.knots_u.n_basis();
        with_scratch(pu + 1, |nu, _| {
            with_scratch(pv + 1, |nv, _| {
                let su = self.knots_u.basis_into(u, nu);
                let sv = self.knots_v.basis_into(v, nv);
                let mut h = [0.0; 4];
                for (b, &wv) in nv.iter().enumerate() {
                    let j = sv - pv + b;
                    for (c, &wu) in nu.iter().enumerate() {
                        let i = su - pu + c;
                        let p = &self.ctrl[i + n_u * j];
                        for k in 0..4 {
                            h[k] += wu * wv * p[k];
                        }
                    }
                }
                Point3::new(h[0] / h[3], h[1] / h[3], h[2] / h[3])
            })
        })
    }

    /// Maps the control points.
    pub fn transform(&mut self, m: &Affine) {
        for h in &mut self.ctrl {
            *h = transform_h(m, h);
        }
    }
}

/// Runs `f` with two zeroed scratch slices of length `len`: on the stack up to order 16
/// (every surface CAD kernels write), on the heap beyond. The surface evaluations of the
/// import run millions of times, and allocating their basis arrays was a third of its time.
fn with_scratch<R>(len: usize, f: impl FnOnce(&mut [f64], &mut [f64]) -> R) -> R {
    const N: usize = 16;
    if len <= N {
        let (mut a, mut b) = ([0.0; N], [0.0; N]);
        f(&mut a[..len], &mut b[..len])
    } else {
        let (mut a, mut b) = (vec![0.0; len], vec![0.0; len]);
        f(&mut a, &mut b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn knots_repeated_beyond_the_order_lose_their_zero_basis_functions() {
        // degree 1, the end knot 0 three times: N_0 is zero
        let (k, keep) = canonical_knots(1, &[0.0, 0.0, 0.0, 1.0, 1.0]).unwrap();
        assert_eq!((k, keep), (vec![0.0, 0.0, 1.0, 1.0], vec![1, 2]));
        // degree 2, an inner knot four times (listed twice, multiplicities 2 + 2)
        let raw = [0., 0., 0., 0.5, 0.5, 0.5, 0.5, 1., 1., 1.];
        let (k, keep) = canonical_knots(2, &raw).unwrap();
        assert_eq!(k, vec![0., 0., 0., 0.5, 0.5, 0.5, 1., 1., 1.]);
        assert_eq!(keep, vec![0, 1, 2, 4, 5, 6]);
        // round-off between equal knots is removed
        let (k, _) = canonical_knots(1, &[0.0, 0.0, 0.5, 0.5 + 1e-16, 1.0, 1.0]).unwrap();
        assert_eq!(k[2], k[3]);
        // the same curve: evaluate both ways
        let pts: Vec<Point3> = (0..7)
            .map(|i| Point3::new(i as f64, (i * i) as f64, 0.0))
            .collect();
        let c = canonical_curve(2, &raw, &pts, &[1.0; 7]).unwrap();
        let kept: Vec<Point3> = keep.iter().map(|&i| pts[i]).collect();
        let kv = KnotVector::new(2, vec![0., 0., 0., 0.5, 0.5, 0.5, 1., 1., 1.]).unwrap();
        let d = NurbsCurve::new(kv, &kept, &[1.0; 6]).unwrap();
        for t in [0.0, 0.2, 0.49, 0.51, 0.9, 1.0] {
            assert!((c.point(t) - d.point(t)).norm() < 1e-15);
        }
        assert!(canonical_knots(1, &[0.0, 1.0, 0.5, 1.0]).is_err());
    }

    /// The rational quadratic quarter circle: C(t) on the unit circle, C′ by differences.
    #[test]
    fn quarter_circle_and_its_derivative() {
        let kv = KnotVector::new(2, vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0]).unwrap();
        let pts = [
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(1.0, 1.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
        ];
        let c = NurbsCurve::new(kv, &pts, &[1.0, 0.5f64.sqrt(), 1.0]).unwrap();
        assert!(c.rational);
        for k in 0..=10 {
            let t = k as f64 / 10.0;
            let (p, d) = c.derivs(t);
            assert!((p.coords.norm() - 1.0).abs() < 1e-15);
            let h = 1e-6;
            let fd = (c.point((t + h).min(1.0)) - c.point((t - h).max(0.0)))
                / ((t + h).min(1.0) - (t - h).max(0.0));
            assert!((d - fd).norm() < 1e-6 * d.norm(), "{t}");
        }
        assert!(NurbsCurve::new(KnotVector::bezier(2), &pts, &[1.0, 0.0, 1.0]).is_err());
    }
}
