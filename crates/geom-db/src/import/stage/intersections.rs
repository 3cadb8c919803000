//! Stage 10, intersections: every junction (a curve with two defining support surfaces,
//! recorded by the database stage) is rebuilt as the intersection of its two *supports*,
//! so that the imported model is what the model update (Eq. 12) keeps up to date.
//!
//! The curve read from the file is the CAD kernel's approximation of the intersection of
//! the exact surfaces (OpenCASCADE's junction of `fixtures/cad/wing_body_periodic_*` is up
//! to 5.7e-6 m off the wing next to the trailing edge, by OpenCASCADE's own measure), and
//! its arcs straddle the patch borders of both supports, where the intersection has a
//! jump in its third derivative (cubic B-splines are C²): a polynomial through points of
//! such a curve converges slowly, so re-intersecting it at its control points left it up to
//! 8e-5 m off the wing between them. Here:
//!
//! 1. The curve is sampled (16 per arc) and each sample projected on both supports
//!    (Eq. 11, continued from the previous sample, the global search where the local foot
//!    is not trusted): four parameter histories (u₁, v₁, u₂, v₂).
//! 2. The *driving parameter* is one of them that is strictly monotonic along the curve and
//!    whose surface's other direction crosses the other surface well (sine ≥ 0.1 at every
//!    sample; the largest smallest sine wins): for a wing–fuselage junction, the wing's
//!    chordwise parameter. The curve is then a function of it, and the model update, which
//!    freezes the parameter closest to affine per arc, keeps each control point at its
//!    chordwise station of the wing: a tip scaled by −10 % shortens the junction without
//!    losing the points next to the trailing edge.
//! 3. Arcs are cut at the driving surface's patch borders and where another parameter
//!    crosses a patch border (linear interpolation between samples), so that each arc lies
//!    in one patch of each support, where the intersection is smooth; slivers shorter than
//!    1e-5 of the model size are merged.
//! 4. Each arc interpolates the intersection at the Chebyshev–Lobatto nodes of the driving
//!    parameter (Eq. 12 with that parameter frozen: ½|r₁ − r₂|² in the other three by the
//!    safeguarded Newton, [`crate::newton::pair::Frozen`]), at degree 4, 6, 8 or 10, the
//!    first whose distance to both supports at 2n + 2 points between the nodes is within the
//!    target (1e-10 of the model size); an arc still above it at degree 10 is halved (at
//!    most 4 times).
//!
//! The ends of the curve are solved the same way, so a junction that ends on a support's
//! border (the trailing edge of a closed wing) ends exactly on it; the caller moves the
//! corners there. A junction without a suitable driving parameter, or whose fit fails, is
//! kept as read, with a warning.

use crate::curve::Arc;
use crate::eval::ParamSurface;
use crate::invert::{InvertOptions, SurfaceInverter};
use crate::newton::Settings;
use crate::newton::pair::{Frozen, free_sines};
use crate::prelude::Point3;
use crate::surface::SupportSurface;

/// Samples per arc of the curve read from the file.
const SAMPLES_PER_ARC: usize = 16;
/// Degrees tried for each arc, in order.
const DEGREES: [usize; 4] = [4, 6, 8, 10];
/// How often an arc above the target at the highest degree is halved.
const MAX_HALVINGS: usize = 4;
/// Smallest sine between the driving surface's free direction and the other surface's
/// tangent plane ([`free_sines`], as for Eq. 12 in `intersect`).
const MIN_SINE: f64 = 0.1;

/// A junction rebuilt as the intersection of its supports.
#[derive(Debug, Clone)]
pub(crate) struct Fitted {
    /// The new arcs.
    pub arcs: Vec<Arc>,
    /// The driving parameter: 0, 1 (u, v of the first support), 2, 3 (of the second).
    pub driver: usize,
    /// Largest distance to either support at the check points of the arcs.
    pub max_distance: f64,
}

/// The two supports of a junction.
struct Pair<'a> {
    s: [&'a SupportSurface; 2],
    lo: [f64; 4],
    hi: [f64; 4],
}

impl Pair<'_> {
    fn point(&self, k: usize, y: &[f64; 4]) -> Point3 {
        self.s[k].point(y[2 * k], y[2 * k + 1])
    }
}

/// Rebuilds the junction `arcs` on supports `sa` and `sb` (module doc). `scale` is the
/// model size. Errors are one-line reasons (the caller names the curve).
pub(crate) fn fit(
    sa: &SupportSurface,
    sb: &SupportSurface,
    arcs: &[Arc],
    scale: f64,
) -> Result<Fitted, String> {
    let (ua, va) = sa.domain();
    let (ub, vb) = sb.domain();
    let pair = Pair {
        s: [sa, sb],
        lo: [ua[0], va[0], ub[0], vb[0]],
        hi: [ua[1], va[1], ub[1], vb[1]],
    };
    let ys = histories(&pair, arcs, scale)?;
    let driver = driver(&pair, &ys)
        .ok_or("no parameter of either surface runs monotonically along it while crossing the other surface")?;
    // the driving parameter's values, snapped to a domain end they are within 1e-7 of
    let w = pair.hi[driver] - pair.lo[driver];
    let snap = |p: f64| {
        if (p - pair.lo[driver]).abs() <= 1e-7 * w {
            pair.lo[driver]
        } else if (pair.hi[driver] - p).abs() <= 1e-7 * w {
            pair.hi[driver]
        } else {
            p
        }
    };
    let ps: Vec<f64> = ys.iter().map(|y| y[driver]).collect();
    let (p0, p1) = (snap(ps[0]), snap(ps[ps.len() - 1]));
    let mut cuts = breaks(&ys, driver, p0, p1);
    cuts.insert(0, p0);
    cuts.push(p1);
    let guess = Guess {
        ps: &ps,
        ys: &ys,
        increasing: p1 > p0,
    };
    let tol = 1e-11 * scale;
    let target = 1e-10 * scale;
    // merge slivers (shorter than 1e-5 of the model size in space)
    let mut kept: Vec<(f64, [f64; 4])> = Vec::with_capacity(cuts.len());
    for (i, &p) in cuts.iter().enumerate() {
        let y = solve(&pair, driver, p, guess.at(p), tol)?;
        let last = i + 1 == cuts.len();
        if let Some(&(_, yk)) = kept.last() {
            let near = (pair.point(0, &y) - pair.point(0, &yk)).norm() < 1e-5 * scale;
            if near {
                if last {
                    kept.pop();
                } else {
                    continue;
                }
            }
        }
        kept.push((p, y));
    }
    if kept.len() < 2 {
        return Err("its ends coincide".into());
    }
    let mut out = Vec::new();
    let mut worst: f64 = 0.0;
    for w in kept.windows(2) {
        let (a, b) = (w[0], w[1]);
        fit_span(
            &pair,
            driver,
            a,
            b,
            &guess,
            (tol, target),
            0,
            &mut out,
            &mut worst,
        )?;
    }
    Ok(Fitted {
        arcs: out,
        driver,
        max_distance: worst,
    })
}

/// Parameters of both supports at samples of the curve, by feet of the normal continued
/// from the middle sample (where a global search starts, away from seams at the ends).
fn histories(pair: &Pair<'_>, arcs: &[Arc], scale: f64) -> Result<Vec<[f64; 4]>, String> {
    let io = InvertOptions::new(scale);
    let inv = [
        SurfaceInverter::new("", pair.s[0], &io).map_err(|e| e.to_string())?,
        SurfaceInverter::new("", pair.s[1], &io).map_err(|e| e.to_string())?,
    ];
    let n = arcs.len() * SAMPLES_PER_ARC;
    let pts: Vec<Point3> = (0..=n)
        .map(|j| super::arcs_point(arcs, j as f64 / SAMPLES_PER_ARC as f64))
        .collect();
    let trust = 1e-4 * scale;
    let mut ys = vec![[f64::NAN; 4]; n + 1];
    let mid = n / 2;
    let foot = |k: usize, j: usize, prev: Option<[f64; 2]>| -> Result<[f64; 2], String> {
        let p = &pts[j];
        let local = prev.map(|uv| inv[k].foot_from(p, uv));
        if let Some(f) = local
            && f.report.converged
            && f.distance <= trust
        {
            return Ok(f.uv);
        }
        let g = inv[k].nearest_indexed(p, j).map_err(|e| e.to_string())?;
        Ok(match local {
            Some(l) if l.distance < g.distance => l.uv,
            _ => g.uv,
        })
    };
    for k in 0..2 {
        let first = foot(k, mid, None)?;
        ys[mid][2 * k] = first[0];
        ys[mid][2 * k + 1] = first[1];
        let mut prev = first;
        for j in mid + 1..=n {
            prev = foot(k, j, Some(prev))?;
            ys[j][2 * k..2 * k + 2].copy_from_slice(&prev);
        }
        prev = first;
        for j in (0..mid).rev() {
            prev = foot(k, j, Some(prev))?;
            ys[j][2 * k..2 * k + 2].copy_from_slice(&prev);
        }
    }
    Ok(ys)
}

/// The driving parameter (module doc, step 2), if any.
fn driver(pair: &Pair<'_>, ys: &[[f64; 4]]) -> Option<usize> {
    let sines: Vec<[f64; 4]> = ys
        .iter()
        .map(|y| free_sines(pair.s[0], pair.s[1], y))
        .collect();
    let mut best: Option<(f64, usize)> = None;
    for k in 0..4 {
        let d: Vec<f64> = ys.windows(2).map(|w| w[1][k] - w[0][k]).collect();
        let monotonic = d.iter().all(|&x| x > 0.0) || d.iter().all(|&x| x < 0.0);
        if !monotonic {
            continue;
        }
        let smin = sines.iter().map(|s| s[k]).fold(f64::INFINITY, f64::min);
        if smin >= MIN_SINE && best.is_none_or(|b| smin > b.0) {
            best = Some((smin, k));
        }
    }
    best.map(|b| b.1)
}

/// Values of the driving parameter strictly inside (p0, p1) where the curve crosses a patch
/// border of either support (module doc, step 3), sorted from p0 to p1.
fn breaks(ys: &[[f64; 4]], driver: usize, p0: f64, p1: f64) -> Vec<f64> {
    let (lo, hi) = (p0.min(p1), p0.max(p1));
    let mut out: Vec<f64> = Vec::new();
    // the driving surface's own borders (integers of the support's global parameter)
    let mut b = lo.floor() + 1.0;
    while b < hi {
        out.push(b);
        b += 1.0;
    }
    for w in ys.windows(2) {
        let (pa, pb) = (w[0][driver], w[1][driver]);
        for k in (0..4).filter(|&k| k != driver) {
            let (qa, qb) = (w[0][k], w[1][k]);
            let (ql, qh) = (qa.min(qb), qa.max(qb));
            if qh - ql > 1.0 {
                continue; // a jump across a seam (a periodic support), not a crossing
            }
            let mut b = ql.floor() + 1.0;
            while b < qh {
                let p = pa + (b - qa) / (qb - qa) * (pb - pa);
                if p > lo && p < hi {
                    out.push(p);
                }
                b += 1.0;
            }
        }
    }
    out.sort_by(f64::total_cmp);
    out.dedup();
    if p1 < p0 {
        out.reverse();
    }
    out
}

/// Starting parameters at a value of the driving parameter: linear interpolation of the
/// samples' histories.
struct Guess<'g> {
    ps: &'g [f64],
    ys: &'g [[f64; 4]],
    increasing: bool,
}

impl Guess<'_> {
    fn at(&self, p: f64) -> [f64; 4] {
        let n = self.ps.len();
        let i = if self.increasing {
            self.ps.partition_point(|&x| x <= p)
        } else {
            self.ps.partition_point(|&x| x >= p)
        };
        let i = i.clamp(1, n - 1);
        let (a, b) = (self.ps[i - 1], self.ps[i]);
        let f = if b != a {
            ((p - a) / (b - a)).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let mut y = [0.0; 4];
        for (k, yk) in y.iter_mut().enumerate() {
            *yk = self.ys[i - 1][k] + f * (self.ys[i][k] - self.ys[i - 1][k]);
        }
        y
    }
}

/// The intersection point with the driving parameter frozen at `p` (Eq. 12), from `y0`.
fn solve(
    pair: &Pair<'_>,
    driver: usize,
    p: f64,
    y0: [f64; 4],
    tol: f64,
) -> Result<[f64; 4], String> {
    let prob = Frozen::new(pair.s[0], pair.s[1], driver, p);
    let (y, o) = prob.solve(&y0, &pair.lo, &pair.hi, Settings { tol, max_iters: 50 });
    if !o.report.converged {
        return Err(format!(
            "the supports do not meet at driving parameter {p} (|r1 - r2| = {:.3e} after {} iterations)",
            o.report.residual, o.report.iterations
        ));
    }
    Ok(y)
}

/// Fits the span between the solved ends `a` and `b` (driving value, parameters), raising
/// the degree, then halving (module doc, step 4); pushes the arcs to `out`.
#[allow(clippy::too_many_arguments)]
fn fit_span(
    pair: &Pair<'_>,
    driver: usize,
    a: (f64, [f64; 4]),
    b: (f64, [f64; 4]),
    guess: &Guess<'_>,
    (tol, target): (f64, f64),
    depth: usize,
    out: &mut Vec<Arc>,
    worst: &mut f64,
) -> Result<(), String> {
    let mut best: Option<(Arc, f64)> = None;
    for n in DEGREES {
        let xs = crate::control::nodes(n);
        let mut ys = Vec::with_capacity(n + 1);
        for (i, &x) in xs.iter().enumerate() {
            ys.push(if i == 0 {
                a.1
            } else if i == n {
                b.1
            } else {
                let p = a.0 + x * (b.0 - a.0);
                solve(
                    pair,
                    driver,
                    p,
                    guess_or(guess, p, lerp(&a.1, &b.1, x)),
                    tol,
                )?
            });
        }
        let pts: Vec<Point3> = ys
            .iter()
            .map(|y| Point3::from((pair.point(0, y).coords + pair.point(1, y).coords) * 0.5))
            .collect();
        let arc = Arc::from_control_points(&pts);
        let err = span_error(pair, &arc, &ys, 2 * n + 2, tol);
        if err <= target {
            out.push(arc);
            *worst = worst.max(err);
            return Ok(());
        }
        if best.as_ref().is_none_or(|(_, e)| err < *e) {
            best = Some((arc, err));
        }
    }
    if depth < MAX_HALVINGS {
        let pm = 0.5 * (a.0 + b.0);
        let ym = solve(
            pair,
            driver,
            pm,
            guess_or(guess, pm, lerp(&a.1, &b.1, 0.5)),
            tol,
        )?;
        fit_span(
            pair,
            driver,
            a,
            (pm, ym),
            guess,
            (tol, target),
            depth + 1,
            out,
            worst,
        )?;
        return fit_span(
            pair,
            driver,
            (pm, ym),
            b,
            guess,
            (tol, target),
            depth + 1,
            out,
            worst,
        );
    }
    let (arc, err) = best.expect("at least one degree was tried");
    out.push(arc);
    *worst = worst.max(err);
    Ok(())
}

/// The samples' guess at `p` when it is finite, else `fallback`.
fn guess_or(guess: &Guess<'_>, p: f64, fallback: [f64; 4]) -> [f64; 4] {
    let g = guess.at(p);
    if g.iter().all(|x| x.is_finite()) {
        g
    } else {
        fallback
    }
}

fn lerp(a: &[f64; 4], b: &[f64; 4], x: f64) -> [f64; 4] {
    let mut y = [0.0; 4];
    for k in 0..4 {
        y[k] = a[k] + x * (b[k] - a[k]);
    }
    y
}

/// Largest distance from `m` points of `arc` between its nodes to either support (feet of
/// the normal from the parameters interpolated between the nodes').
fn span_error(pair: &Pair<'_>, arc: &Arc, ys: &[[f64; 4]], m: usize, tol: f64) -> f64 {
    let n = arc.degree;
    let xs = crate::control::nodes(n);
    let settings = Settings { tol, max_iters: 30 };
    let mut worst: f64 = 0.0;
    for j in 0..m {
        let s = (j as f64 + 0.5) / m as f64;
        let q = arc.point(s);
        let i = xs.partition_point(|&x| x <= s).clamp(1, n);
        let f = (s - xs[i - 1]) / (xs[i] - xs[i - 1]);
        let y = lerp(&ys[i - 1], &ys[i], f);
        for k in 0..2 {
            let o = crate::invert::foot_on_surface(
                pair.s[k],
                &q,
                [y[2 * k], y[2 * k + 1]],
                [pair.lo[2 * k], pair.lo[2 * k + 1]],
                [pair.hi[2 * k], pair.hi[2 * k + 1]],
                settings,
            );
            let d = (pair.s[k].point(o.x[0], o.x[1]) - q).norm();
            worst = worst.max(if d.is_finite() { d } else { f64::INFINITY });
        }
    }
    worst
}
