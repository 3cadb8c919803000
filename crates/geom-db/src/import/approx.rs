//! Piecewise polynomial approximation of curves and surfaces to a tolerance.
//!
//! Each arc (patch) interpolates the source at the Chebyshev–Lobatto control nodes of its
//! degree (the nodes of [`control`](crate::control), so A = V⁻¹R, Eq. 4, and
//! A = V_u⁻¹ R V_v⁻ᵀ, Eq. 9). Neighbours share their end (border) nodes, so the result is
//! C0 to round-off. The error is sampled between the nodes against the source at the same
//! parameter (an upper bound of the geometric distance); spans whose error exceeds the
//! tolerance are split in two until it does not, or until a size limit is reached.

use crate::control;
use crate::curve::Arc;
use crate::prelude::Point3;
use crate::surface::{Patch, SupportSurface};

/// Degree of approximating arcs.
pub(crate) const CURVE_DEGREE: usize = 7;
/// Degree (in u and in v) of approximating patches.
pub(crate) const SURFACE_DEGREE: usize = 7;
/// Highest degree converted exactly to the power basis. Above it the Bézier → power map
/// (entries up to C(n, k) C(k, i), 3.3e8 at degree 22) loses digits to cancellation (a
/// degree-22 B-spline came out 9.6e-6 off) and the control nodes of the database (Eq. 9) grow
/// as (n + 1)²; such entities are re-approximated at [`CURVE_DEGREE`] / [`SURFACE_DEGREE`]
/// from their own evaluation (de Boor, stable at any degree).
pub(crate) const EXACT_MAX_DEGREE: usize = 11;
/// Largest number of arcs per curve.
const MAX_ARCS: usize = 4096;
/// Largest number of patches per surface.
const MAX_PATCHES: usize = 16384;

/// Arcs approximating a curve, each with the source parameter interval it covers.
pub(crate) struct CurveFit {
    /// (a, b, arc): local u ∈ [0, 1] of the arc ↦ a + u (b − a).
    pub pieces: Vec<(f64, f64, Arc)>,
    /// Largest sampled error (between the nodes).
    pub max_error: f64,
}

fn arc_on(f: &dyn Fn(f64) -> Point3, a: f64, b: f64, deg: usize) -> (Arc, f64) {
    let pts: Vec<Point3> = control::nodes(deg)
        .iter()
        .map(|&x| f(a + x * (b - a)))
        .collect();
    let arc = Arc::from_control_points(&pts);
    let n_check = 4 * deg;
    let mut err: f64 = 0.0;
    for k in 0..n_check {
        let u = (k as f64 + 0.5) / n_check as f64;
        let d = (arc.point(u) - f(a + u * (b - a))).norm();
        err = if d.is_nan() {
            f64::INFINITY
        } else {
            err.max(d)
        };
    }
    (arc, err)
}

/// Approximates r(t), t between the first and last of `initial` breaks (which the arcs keep),
/// to `tol`. Returns `Err(best error)` when the arc limit is reached first.
pub(crate) fn fit_curve(
    f: &dyn Fn(f64) -> Point3,
    initial: &[f64],
    tol: f64,
) -> Result<CurveFit, f64> {
    let deg = CURVE_DEGREE;
    let mut arcs: Vec<(f64, f64, Arc)> = Vec::new();
    let mut max_error: f64 = 0.0;
    for w in initial.windows(2) {
        // Depth-first bisection keeps the arcs in parameter order.
        let mut stack = vec![(w[0], w[1])];
        while let Some((a, b)) = stack.pop() {
            let (arc, err) = arc_on(f, a, b, deg);
            let tiny = (b - a).abs() <= 1e-12 * (w[1] - w[0]).abs().max(1e-300);
            if err > tol && !tiny && arcs.len() + stack.len() < MAX_ARCS {
                let m = 0.5 * (a + b);
                stack.push((m, b));
                stack.push((a, m));
                continue;
            }
            if err > tol {
                return Err(err);
            }
            max_error = max_error.max(err);
            arcs.push((a, b, arc));
        }
    }
    Ok(CurveFit {
        pieces: arcs,
        max_error,
    })
}

/// Sum of 8 chords of r on [a, b]: the length of a piece, to tell degenerate ones.
pub(crate) fn chord_length(f: &dyn Fn(f64) -> Point3, a: f64, b: f64) -> f64 {
    let pts: Vec<Point3> = (0..=8).map(|k| f(a + (b - a) * k as f64 / 8.0)).collect();
    pts.windows(2).map(|w| (w[1] - w[0]).norm()).sum()
}

/// `breaks` (increasing) with every span whose length (`len(a, b)`) is at most `min_len`
/// merged into a neighbour: its end break is dropped (its start break for the last span),
/// so the span and the next are fitted as one. The first and last breaks are kept. Returns
/// the breaks and the number of spans merged.
pub(crate) fn merge_short_spans(
    breaks: &[f64],
    len: &dyn Fn(f64, f64) -> f64,
    min_len: f64,
) -> (Vec<f64>, usize) {
    let n = breaks.len();
    if n <= 2 {
        return (breaks.to_vec(), 0);
    }
    let mut out = vec![breaks[0]];
    let mut merged = 0;
    for (k, &b) in breaks.iter().enumerate().skip(1) {
        let a = *out.last().expect("first break");
        let short = len(a, b) <= min_len;
        if k + 1 < n {
            if short {
                merged += 1;
            } else {
                out.push(b);
            }
        } else {
            if short && out.len() > 1 {
                out.pop();
                merged += 1;
            }
            out.push(b);
        }
    }
    (out, merged)
}

/// Patches approximating r(u, v) and the source parameters of the patch grid lines.
pub(crate) struct SurfaceFit {
    /// The patch grid.
    pub surface: SupportSurface,
    /// Largest sampled error (between the nodes).
    pub max_error: f64,
    /// Source u at the patch columns' borders.
    pub u_breaks: Vec<f64>,
    /// Source v at the patch rows' borders.
    pub v_breaks: Vec<f64>,
}

struct PatchResult {
    patch: Patch,
    err: f64,
    err_u: f64,
    err_v: f64,
}

fn patch_on(
    f: &(dyn Fn(f64, f64) -> Point3 + Sync),
    (u0, u1): (f64, f64),
    (v0, v1): (f64, f64),
    deg: usize,
) -> PatchResult {
    let x = control::nodes(deg);
    let mut pts = Vec::with_capacity(x.len() * x.len());
    for &a in x {
        for &b in x {
            pts.push(f(u0 + a * (u1 - u0), v0 + b * (v1 - v0)));
        }
    }
    let patch = Patch::from_control_points(deg, deg, &pts);
    let n = 2 * deg;
    let mut err: f64 = 0.0;
    let mut err_u: f64 = 0.0;
    let mut err_v: f64 = 0.0;
    let check = |s: f64, t: f64| {
        let d = (patch.point(s, t) - f(u0 + s * (u1 - u0), v0 + t * (v1 - v0))).norm();
        if d.is_nan() { f64::INFINITY } else { d }
    };
    for i in 0..n {
        let s = (i as f64 + 0.5) / n as f64;
        for j in 0..n {
            let t = (j as f64 + 0.5) / n as f64;
            err = err.max(check(s, t));
        }
        // Between nodes in u only (v on a node line) and in v only.
        for &t in x {
            err_u = err_u.max(check(s, t));
            err_v = err_v.max(check(t, s));
        }
    }
    PatchResult {
        patch,
        err: err.max(err_u).max(err_v),
        err_u,
        err_v,
    }
}

/// Approximates r(u, v) over the grid spanned by the initial breaks (kept as patch
/// borders) to `tol`, refining whole columns and rows. `Err(best error)` when the patch
/// limit is reached first.
pub(crate) fn fit_surface(
    f: &(dyn Fn(f64, f64) -> Point3 + Sync),
    u_initial: &[f64],
    v_initial: &[f64],
    tol: f64,
) -> Result<SurfaceFit, f64> {
    let deg = SURFACE_DEGREE;
    let mut ub = u_initial.to_vec();
    let mut vb = v_initial.to_vec();
    loop {
        let (nu, nv) = (ub.len() - 1, vb.len() - 1);
        let cells: Vec<(usize, usize)> =
            (0..nv).flat_map(|j| (0..nu).map(move |i| (i, j))).collect();
        let results: Vec<PatchResult> = crate::par_map(&cells, |&(i, j)| {
            patch_on(f, (ub[i], ub[i + 1]), (vb[j], vb[j + 1]), deg)
        });
        let max_error = results.iter().map(|r| r.err).fold(0.0, f64::max);
        if max_error <= tol {
            let patches = results.into_iter().map(|r| r.patch).collect();
            return Ok(SurfaceFit {
                surface: SupportSurface::new("", nu, nv, patches),
                max_error,
                u_breaks: ub,
                v_breaks: vb,
            });
        }
        let mut split_u = vec![false; nu];
        let mut split_v = vec![false; nv];
        for (r, &(i, j)) in results.iter().zip(&cells) {
            if r.err > tol {
                if r.err_u >= 0.5 * tol || r.err_u >= r.err_v {
                    split_u[i] = true;
                }
                if r.err_v >= 0.5 * tol || r.err_v > r.err_u {
                    split_v[j] = true;
                }
            }
        }
        let grow_u = split_u.iter().filter(|&&s| s).count();
        let grow_v = split_v.iter().filter(|&&s| s).count();
        if (nu + grow_u) * (nv + grow_v) > MAX_PATCHES {
            return Err(max_error);
        }
        let refine = |b: &[f64], split: &[bool]| {
            let mut out = vec![b[0]];
            for (k, w) in b.windows(2).enumerate() {
                if split[k] {
                    out.push(0.5 * (w[0] + w[1]));
                }
                out.push(w[1]);
            }
            out
        };
        ub = refine(&ub, &split_u);
        vb = refine(&vb, &split_v);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn circle_to_tolerance() {
        let f = |t: f64| Point3::new(t.cos(), t.sin(), 0.0);
        let fit = fit_curve(&f, &[0.0, std::f64::consts::PI], 1e-9).unwrap();
        assert!(fit.max_error <= 1e-9);
        assert!(fit.pieces.len() >= 2);
        // Independent check on a fine grid: distance to the unit circle.
        for k in 0..=1000 {
            let t = k as f64 / 1000.0 * fit.pieces.len() as f64;
            let a = (t.floor() as usize).min(fit.pieces.len() - 1);
            let u = t - a as f64;
            let p = fit.pieces[a].2.point(u);
            assert!((p.coords.norm() - 1.0).abs() < 2e-9);
        }
    }

    #[test]
    fn short_spans_merge_into_their_neighbours() {
        let len = |a: f64, b: f64| b - a;
        let (b, n) = merge_short_spans(&[0.0, 0.3, 0.3 + 5e-7, 0.7, 1.0], &len, 1e-6);
        assert_eq!((b, n), (vec![0.0, 0.3, 0.7, 1.0], 1));
        // a short last span drops the break before it
        let (b, n) = merge_short_spans(&[0.0, 0.5, 1.0 - 1e-9, 1.0], &len, 1e-6);
        assert_eq!((b, n), (vec![0.0, 0.5, 1.0], 1));
        // a short first span drops its end break
        let (b, n) = merge_short_spans(&[0.0, 1e-7, 0.5, 1.0], &len, 1e-6);
        assert_eq!((b, n), (vec![0.0, 0.5, 1.0], 1));
        // nothing short: unchanged; a single span is never merged
        assert_eq!(merge_short_spans(&[0.0, 0.5, 1.0], &len, 1e-6).1, 0);
        assert_eq!(
            merge_short_spans(&[0.0, 1e-9], &len, 1e-6).0,
            vec![0.0, 1e-9]
        );
    }

    #[test]
    fn polynomial_is_reproduced_by_one_patch() {
        let f = |u: f64, v: f64| Point3::new(u, v, u * u * v - 3.0 * v.powi(3));
        let fit = fit_surface(&f, &[0.0, 2.0], &[-1.0, 1.0], 1e-10).unwrap();
        assert_eq!(fit.surface.patches.len(), 1);
        assert!(fit.max_error < 1e-10);
    }

    #[test]
    fn sphere_to_tolerance() {
        let f = |u: f64, v: f64| Point3::new(u.cos() * v.cos(), u.sin() * v.cos(), v.sin());
        let fit = fit_surface(&f, &[0.0, 3.0], &[-1.5, 1.5], 1e-8).unwrap();
        assert!(fit.max_error <= 1e-8);
    }
}
