//! Conversions between the Bernstein (Bézier), B-spline and power bases, exact to round-off.
//!
//! * Bézier ↔ power on [0, 1]: with control points b_i of degree n,
//!   a_k = C(n,k) Σ_{i≤k} (−1)^{k−i} C(k,i) b_i and, back, b_i = Σ_{k≤i} C(i,k)/C(n,k) a_k.
//!   Tensor products apply the 1D maps along u and along v (A = M_u B M_vᵀ).
//! * B-spline (non-rational, any degree, any knots) → piecewise power basis: each non-empty
//!   knot span [t_s, t_{s+1}] of the domain becomes one arc (patch) whose Bézier points are
//!   the blossom values f(t_s^{p−i}, t_{s+1}^i), i = 0..p — the control points that inserting
//!   t_s and t_{s+1} until multiplicity p would produce (Boehm knot insertion), computed by
//!   the de Boor triangle with a different parameter at each level. Local u ∈ [0, 1] on the
//!   arc maps to t = t_s + u (t_{s+1} − t_s).
//! * Back: one arc (patch) → a single-span Bézier B-spline on [0, 1].

use crate::bspline::{KnotVector, binomial};
use crate::curve::Arc;
use crate::error::{Error, Result};
use crate::prelude::{Point3, Vector3};
use crate::surface::{Patch, SupportSurface};

/// M with a = M b (Bézier → power), row-major (n+1)².
fn bezier_to_power_matrix(n: usize) -> Vec<f64> {
    let m = n + 1;
    let mut out = vec![0.0; m * m];
    for k in 0..=n {
        let cnk = binomial(n, k);
        for i in 0..=k {
            let sign = if (k - i) % 2 == 0 { 1.0 } else { -1.0 };
            out[k * m + i] = cnk * binomial(k, i) * sign;
        }
    }
    out
}

/// N with b = N a (power → Bézier), row-major (n+1)².
fn power_to_bezier_matrix(n: usize) -> Vec<f64> {
    let m = n + 1;
    let mut out = vec![0.0; m * m];
    for i in 0..=n {
        for k in 0..=i {
            out[i * m + k] = binomial(i, k) / binomial(n, k);
        }
    }
    out
}

fn apply(mat: &[f64], pts: &[Point3]) -> Vec<Point3> {
    let m = pts.len();
    (0..m)
        .map(|r| {
            let mut acc = Vector3::zeros();
            for c in 0..m {
                let w = mat[r * m + c];
                if w != 0.0 {
                    acc += pts[c].coords * w;
                }
            }
            Point3::from(acc)
        })
        .collect()
}

fn apply_2d(mu: &[f64], mv: &[f64], nu: usize, nv: usize, pts: &[Point3]) -> Vec<Point3> {
    // along v for each row, then along u for each column
    let mut rows = Vec::with_capacity(nu * nv);
    for i in 0..nu {
        rows.extend(apply(mv, &pts[i * nv..(i + 1) * nv]));
    }
    let mut out = vec![Point3::origin(); nu * nv];
    for j in 0..nv {
        let col: Vec<Point3> = (0..nu).map(|i| rows[i * nv + j]).collect();
        for (i, p) in apply(mu, &col).into_iter().enumerate() {
            out[i * nv + j] = p;
        }
    }
    out
}

/// Power-basis coefficients a_0..a_n of the Bézier curve with control points b_0..b_n.
///
/// ```
/// use geom_db::{convert::bezier_to_power, prelude::Point3};
/// let b = [Point3::new(0.0, 0.0, 0.0), Point3::new(1.0, 2.0, 0.0), Point3::new(2.0, 0.0, 0.0)];
/// let a = bezier_to_power(&b);
/// assert_eq!(a[1], Point3::new(2.0, 4.0, 0.0)); // r'(0) = n (b1 − b0)
/// ```
pub fn bezier_to_power(b: &[Point3]) -> Vec<Point3> {
    if b.is_empty() {
        return Vec::new();
    }
    apply(&bezier_to_power_matrix(b.len() - 1), b)
}

/// Bézier control points b_0..b_n of the power-basis polynomial a_0..a_n on [0, 1].
pub fn power_to_bezier(a: &[Point3]) -> Vec<Point3> {
    if a.is_empty() {
        return Vec::new();
    }
    apply(&power_to_bezier_matrix(a.len() - 1), a)
}

/// Tensor Bézier → power: `b[i * (deg_v + 1) + j]` → `a[k * (deg_v + 1) + l]` (the layout of
/// [`Patch::coeffs`]).
///
/// # Panics
/// If `b.len() != (deg_u + 1)(deg_v + 1)`.
pub fn bezier_to_power_2d(deg_u: usize, deg_v: usize, b: &[Point3]) -> Vec<Point3> {
    assert_eq!(b.len(), (deg_u + 1) * (deg_v + 1));
    apply_2d(
        &bezier_to_power_matrix(deg_u),
        &bezier_to_power_matrix(deg_v),
        deg_u + 1,
        deg_v + 1,
        b,
    )
}

/// Tensor power → Bézier (inverse of [`bezier_to_power_2d`]).
///
/// # Panics
/// If `a.len() != (deg_u + 1)(deg_v + 1)`.
pub fn power_to_bezier_2d(deg_u: usize, deg_v: usize, a: &[Point3]) -> Vec<Point3> {
    assert_eq!(a.len(), (deg_u + 1) * (deg_v + 1));
    apply_2d(
        &power_to_bezier_matrix(deg_u),
        &power_to_bezier_matrix(deg_v),
        deg_u + 1,
        deg_v + 1,
        a,
    )
}

/// Bézier points of span s (t_s < t_{s+1}) of a B-spline: blossom values
/// f(t_s^{p−i}, t_{s+1}^i) by the de Boor triangle.
fn span_bezier(kv: &KnotVector, ctrl: &[Vector3], s: usize) -> Vec<Vector3> {
    let p = kv.degree();
    let u = kv.knots();
    let (a, b) = (u[s], u[s + 1]);
    (0..=p)
        .map(|i| {
            let mut d: Vec<Vector3> = ctrl[s - p..=s].to_vec();
            // levels r = 1..p with parameter t_r: first p−i copies of a, then i copies of b
            for r in 1..=p {
                let t = if r <= p - i { a } else { b };
                for j in (s - p + r..=s).rev() {
                    let lo = u[j];
                    let hi = u[j + p + 1 - r];
                    let alpha = (t - lo) / (hi - lo);
                    let idx = j - (s - p);
                    d[idx] = d[idx - 1] * (1.0 - alpha) + d[idx] * alpha;
                }
            }
            d[p]
        })
        .collect()
}

/// The non-empty spans s of the domain (t_s < t_{s+1}) with their intervals.
fn spans(kv: &KnotVector) -> Vec<(usize, f64, f64)> {
    let p = kv.degree();
    let u = kv.knots();
    (p..kv.n_basis())
        .filter(|&s| u[s] < u[s + 1])
        .map(|s| (s, u[s], u[s + 1]))
        .collect()
}

/// One power-basis arc of an extracted B-spline and the B-spline parameter interval it covers
/// (local u ∈ [0, 1] ↦ t = t0 + u (t1 − t0)).
#[derive(Debug, Clone, PartialEq)]
pub struct PowerArc {
    /// Start of the knot span.
    pub t0: f64,
    /// End of the knot span.
    pub t1: f64,
    /// The arc in the power basis.
    pub arc: Arc,
}

/// Converts a non-rational B-spline curve to power-basis arcs, one per non-empty knot span of
/// the domain (Bézier extraction, see the module doc).
///
/// ```
/// use geom_db::{bspline::KnotVector, convert::bspline_to_power, prelude::Point3};
/// let kv = KnotVector::clamped_uniform(2, 4).unwrap();
/// let ctrl = [[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [2.0, 0.0, 0.0], [3.0, 1.0, 0.0]];
/// let pts: Vec<Point3> = ctrl.iter().map(|c| Point3::from(*c)).collect();
/// let arcs = bspline_to_power(&kv, &pts).unwrap();
/// assert_eq!(arcs.len(), 2);
/// let want = kv.curve_point(&ctrl, 0.75);
/// let got = arcs[1].arc.point(0.5);
/// assert!((got - Point3::from(want)).norm() < 1e-15);
/// ```
pub fn bspline_to_power(kv: &KnotVector, ctrl: &[Point3]) -> Result<Vec<PowerArc>> {
    if ctrl.len() != kv.n_basis() {
        return Err(Error::Conversion {
            reason: format!(
                "{} control points for {} basis functions",
                ctrl.len(),
                kv.n_basis()
            ),
        });
    }
    if kv.degree() == 0 || kv.degree() > crate::control::MAX_DEGREE {
        return Err(Error::Conversion {
            reason: format!("degree {} is not supported", kv.degree()),
        });
    }
    let c: Vec<Vector3> = ctrl.iter().map(|p| p.coords).collect();
    Ok(spans(kv)
        .into_iter()
        .map(|(s, t0, t1)| {
            let bez: Vec<Point3> = span_bezier(kv, &c, s)
                .into_iter()
                .map(Point3::from)
                .collect();
            PowerArc {
                t0,
                t1,
                arc: Arc::new(bezier_to_power(&bez)),
            }
        })
        .collect())
}

/// A B-spline surface converted to patches, with the knot-span breakpoints along u and v
/// (patch (i, j) covers `[u_breaks[i], u_breaks[i+1]] × [v_breaks[j], v_breaks[j+1]]`).
#[derive(Debug, Clone)]
pub struct PowerSurface {
    /// Span breakpoints along u.
    pub u_breaks: Vec<f64>,
    /// Span breakpoints along v.
    pub v_breaks: Vec<f64>,
    /// The surface (no control nodes).
    pub surface: SupportSurface,
}

/// Converts a non-rational tensor B-spline surface to a patch grid, one patch per pair of
/// non-empty knot spans; `ctrl[i * kv.n_basis() + j]` is control point (i, j) (i along u).
pub fn bspline_surface_to_power(
    ku: &KnotVector,
    kv: &KnotVector,
    ctrl: &[Point3],
) -> Result<PowerSurface> {
    let (nu, nv) = (ku.n_basis(), kv.n_basis());
    if ctrl.len() != nu * nv {
        return Err(Error::Conversion {
            reason: format!(
                "{} control points for {nu} × {nv} basis functions",
                ctrl.len()
            ),
        });
    }
    for k in [ku, kv] {
        if k.degree() == 0 || k.degree() > crate::control::MAX_DEGREE {
            return Err(Error::Conversion {
                reason: format!("degree {} is not supported", k.degree()),
            });
        }
    }
    let (pu, pv) = (ku.degree(), kv.degree());
    let su = spans(ku);
    let sv = spans(kv);
    let c: Vec<Vector3> = ctrl.iter().map(|p| p.coords).collect();
    let mut patches = Vec::with_capacity(su.len() * sv.len());
    for &(sj, _, _) in &sv {
        for &(si, _, _) in &su {
            // u-extraction for each relevant v column j
            let mut rows = vec![Vector3::zeros(); (pu + 1) * (pv + 1)]; // [iu * (pv+1) + jv]
            for (jj, j) in (sj - pv..=sj).enumerate() {
                let col: Vec<Vector3> = (0..nu).map(|i| c[i * nv + j]).collect();
                for (iu, q) in span_bezier(ku, &col, si).into_iter().enumerate() {
                    rows[iu * (pv + 1) + jj] = q;
                }
            }
            // v-extraction of each Bézier row: build a local B-spline of the pv+1 points
            let mut bez = vec![Point3::origin(); (pu + 1) * (pv + 1)];
            for iu in 0..=pu {
                let mut full = vec![Vector3::zeros(); nv];
                full[sj - pv..=sj].copy_from_slice(&rows[iu * (pv + 1)..(iu + 1) * (pv + 1)]);
                for (jv, q) in span_bezier(kv, &full, sj).into_iter().enumerate() {
                    bez[iu * (pv + 1) + jv] = Point3::from(q);
                }
            }
            patches.push(Patch {
                deg_u: pu,
                deg_v: pv,
                coeffs: bezier_to_power_2d(pu, pv, &bez),
            });
        }
    }
    let breaks = |s: &[(usize, f64, f64)]| {
        let mut b: Vec<f64> = s.iter().map(|x| x.1).collect();
        b.extend(s.last().map(|x| x.2));
        b
    };
    Ok(PowerSurface {
        u_breaks: breaks(&su),
        v_breaks: breaks(&sv),
        surface: SupportSurface::new("", su.len(), sv.len(), patches),
    })
}

/// One arc as a single-span B-spline on [0, 1]: the Bézier knot vector and control points.
pub fn power_to_bspline(arc: &Arc) -> (KnotVector, Vec<Point3>) {
    (KnotVector::bezier(arc.degree), power_to_bezier(&arc.coeffs))
}

/// One patch as a single-span tensor B-spline on [0, 1]²: knot vectors in u and v and the
/// control points `[i * (deg_v + 1) + j]`.
pub fn patch_to_bspline(p: &Patch) -> (KnotVector, KnotVector, Vec<Point3>) {
    (
        KnotVector::bezier(p.deg_u),
        KnotVector::bezier(p.deg_v),
        power_to_bezier_2d(p.deg_u, p.deg_v, &p.coeffs),
    )
}
