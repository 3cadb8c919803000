//! Parameters of points on the exact surfaces: closed form on the analytic surfaces (and
//! offsets of them), a seed from the sweep on surfaces of revolution and extrusion, then
//! the workspace's safeguarded Newton (Gauss–Newton form); unwrapping across periods; the exact parameters of a loop, and
//! their image in a support surface's global parameters.

use super::super::model::{AngleParam, Domain, Surface};
use super::faces::Rect;
use crate::invert::InvertOptions;
use crate::newton::{Eval, Problem, Settings, minimise};
use crate::prelude::Point3;
use nalgebra::{SMatrix, SVector};

/// Unwraps `x` by multiples of `period` to within half a period of `near`.
pub(crate) fn unwrap(x: f64, near: f64, period: f64) -> f64 {
    x + ((near - x) / period).round() * period
}

/// f = ½|S(u, v) − p|² in the Gauss–Newton form (H = JᵀJ: the exact surfaces give first
/// derivatives only) with the tangential residual of Eq. 11, |(S − p)·S_i| / |S_i|.
struct Foot<'a> {
    s: &'a Surface,
    p: Point3,
}

impl Problem<2> for Foot<'_> {
    fn eval(&self, x: &[f64; 2], active: &[bool; 2]) -> Eval<2> {
        let (q, su, sv) = self.s.derivs(x[0], x[1]);
        let r = q - self.p;
        let g = SVector::<f64, 2>::new(su.dot(&r), sv.dot(&r));
        let b = su.dot(&sv);
        let h = SMatrix::<f64, 2, 2>::new(su.dot(&su), b, b, sv.dot(&sv));
        let norms = [su.norm(), sv.norm()];
        let floor = 1e-3 * norms[0].max(norms[1]);
        let mut res: f64 = 0.0;
        for i in 0..2 {
            if !active[i] && norms[i] > 0.0 {
                res = res.max(g[i].abs() / norms[i].max(floor));
            }
        }
        let f = 0.5 * r.norm_squared();
        let ok = f.is_finite();
        Eval {
            f: if ok { f } else { f64::INFINITY },
            g,
            h,
            res: if ok { res } else { f64::INFINITY },
            fnoise: 16.0 * f64::EPSILON * r.norm() * (q.coords.norm() + self.p.coords.norm()),
        }
    }
}

/// The foot of the normal (Eq. 11) of `p` on `s` from `seed` by the workspace's one
/// safeguarded Newton ([`crate::newton::minimise`]), bounded to the finite parts of `d`
/// (periodic directions unbounded); the tolerance is
/// [`InvertOptions::REL_TOL`](crate::invert::InvertOptions::REL_TOL) of the point's scale.
pub(crate) fn newton(s: &Surface, d: &Domain, p: &Point3, seed: (f64, f64)) -> (f64, f64) {
    let bound = |r: (f64, f64), periodic: bool| {
        if periodic {
            (f64::NEG_INFINITY, f64::INFINITY)
        } else {
            r
        }
    };
    let (u, v) = (
        bound(d.u, d.u_period.is_some()),
        bound(d.v, d.v_period.is_some()),
    );
    let scale = p
        .coords
        .amax()
        .max(s.point(seed.0, seed.1).coords.amax())
        .max(1e-300);
    let settings = Settings {
        tol: InvertOptions::REL_TOL * scale,
        max_iters: 60,
    };
    let out = minimise(
        &Foot { s, p: *p },
        [seed.0, seed.1],
        &[u.0, v.0],
        &[u.1, v.1],
        settings,
    );
    (out.x[0], out.x[1])
}

/// True when (u, v) puts S within 1e-7 of its local parametric scale (|S_u| + |S_v|) of
/// `p`: Newton found the point, not a local minimum beside it.
fn found(s: &Surface, p: &Point3, (u, v): (f64, f64)) -> bool {
    let (q, su, sv) = s.derivs(u, v);
    (q - p).norm() <= 1e-7 * (su.norm() + sv.norm())
}

/// A finite window of a possibly infinite interval, around the values `hint` when given.
fn finite(r: (f64, f64), hint: Option<(f64, f64)>) -> (f64, f64) {
    match (r.0.is_finite() && r.1.is_finite(), hint) {
        (true, _) => r,
        (false, Some(h)) => (r.0.max(h.0), r.1.min(h.1)),
        (false, None) => (r.0.max(-1.0), r.1.min(1.0)),
    }
}

/// The parameters of `p` on `s`: closed form for analytic surfaces (and offsets of them),
/// else Newton from `prev` (the previous sample of the walk) or from the best of a grid.
pub(crate) fn invert(s: &Surface, d: &Domain, p: &Point3, prev: Option<(f64, f64)>) -> (f64, f64) {
    if let Some(uv) = s.invert(p) {
        return uv;
    }
    if let Surface::Offset { basis, .. } = s
        && let Some(uv) = basis.invert(p)
    {
        return uv;
    }
    if let Some(seed) = swept_seed(s, p) {
        let uv = newton(s, d, p, seed);
        if found(s, p, uv) {
            return uv;
        }
    }
    if let Some(seed) = prev {
        let uv = newton(s, d, p, seed);
        if found(s, p, uv) {
            return uv;
        }
    }
    // A grid with at least two samples in every knot span (at most 128 a direction), and
    // Newton from its nearest points in turn until one finds p.
    let (bu, bv) = s.breaks();
    let (gu, gv) = (
        grid(finite(d.u, None), &bu, 16, 128),
        grid(finite(d.v, None), &bv, 16, 128),
    );
    let mut seeds: Vec<(f64, (f64, f64))> = Vec::with_capacity(gu.len() * gv.len());
    for &u in &gu {
        for &v in &gv {
            seeds.push(((s.point(u, v) - p).norm_squared(), (u, v)));
        }
    }
    seeds.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut best: Option<(f64, (f64, f64))> = None;
    let tries = prev.into_iter().chain(seeds.iter().take(6).map(|s| s.1));
    for seed in tries {
        let uv = newton(s, d, p, seed);
        if found(s, p, uv) {
            return uv;
        }
        let dd = (s.point(uv.0, uv.1) - p).norm();
        if best.is_none_or(|b| dd < b.0) {
            best = Some((dd, uv));
        }
    }
    best.map_or((d.u.0, d.v.0), |b| b.1)
}

/// Sample values of the finite interval `r`: `n` equal steps, refined so that each knot
/// span of `breaks` inside `r` holds two interior values, at most `cap` values.
fn grid(r: (f64, f64), breaks: &[f64], n: usize, cap: usize) -> Vec<f64> {
    let mut xs: Vec<f64> = (0..=n)
        .map(|i| r.0 + (r.1 - r.0) * i as f64 / n as f64)
        .collect();
    let inside: Vec<f64> = breaks
        .iter()
        .copied()
        .filter(|&b| b >= r.0 && b <= r.1)
        .collect();
    if inside.len() >= 2 && 3 * inside.len() <= cap {
        for w in inside.windows(2) {
            xs.extend([
                w[0],
                w[0] + (w[1] - w[0]) / 3.0,
                w[0] + 2.0 * (w[1] - w[0]) / 3.0,
            ]);
        }
    }
    xs
}

/// A starting point for the parameters of `p` on a swept surface: for a revolution, the
/// angle from the curve's mid-point to p about the axis, then the curve's parameter of p
/// turned back by it; for an extrusion, the curve's parameter of p moved back along the
/// extrusion onto the curve's mid-point, then v along it.
pub(crate) fn swept_seed(s: &Surface, p: &Point3) -> Option<(f64, f64)> {
    match s {
        Surface::Revolution {
            axis_point,
            axis_dir,
            curve,
            angle,
            range,
            ..
        } => {
            let (t0, t1) = (range.0.max(-1e6), range.1.min(1e6));
            let c = curve.point(0.5 * (t0 + t1)) - axis_point;
            let q = p - axis_point;
            let d = axis_dir;
            let (rc, rq) = (c - d * d.dot(&c), q - d * d.dot(&q));
            let theta = rc.cross(&rq).dot(d).atan2(rc.dot(&rq));
            // Rotate p back by θ (Rodrigues with −θ).
            let (sn, cs) = (-theta).sin_cos();
            let back = axis_point + q * cs + d.cross(&q) * sn + d * d.dot(&q) * (1.0 - cs);
            let t = curve.closest_param(&back, Some((t0, t1)))?;
            Some(match angle {
                AngleParam::U => (theta, t),
                AngleParam::V => (t, theta),
            })
        }
        Surface::Extrusion {
            curve, dir, range, ..
        } => {
            let (t0, t1) = (range.0.max(-1e6), range.1.min(1e6));
            let d2 = dir.norm_squared();
            if !(d2 > 0.0) {
                return None;
            }
            let mid = curve.point(0.5 * (t0 + t1));
            let back = p - dir * ((p - mid).dot(dir) / d2);
            let t = curve.closest_param(&back, Some((t0, t1)))?;
            Some((t, (p - curve.point(t)).dot(dir) / d2))
        }
        _ => None,
    }
}

/// The exact parameters of a loop given as runs of points (one run per edge use, in loop
/// order, each run's ends shared with its neighbours').
///
/// Each run is placed from its middle sample outwards, each sample inverted on `s` from its
/// neighbour, so that an end at an ambiguous place (a corner on a seam, a sharp trailing
/// edge where both sides meet) is reached from inside the run. Where a parameter says
/// nothing (a pole) the neighbour's value is kept. A periodic parameter whose box `trim`
/// is narrower than the period is taken in the box (each value determined); one whose box
/// is the whole period (a face around a seam) is kept continuous along the run, the run
/// shifted by a whole period to start where the previous one ended (or, for the first, into
/// the box); a run that retraces the previous run backwards at one value of it (a sphere's
/// meridian, both sides of the seam) is put one period away, on the other side of the box.
pub(crate) fn exact_loop(
    s: &Surface,
    d: &Domain,
    trim: Rect,
    runs: &[Vec<Point3>],
    retraces: &[bool],
) -> Vec<Vec<(f64, f64)>> {
    let full =
        |period: Option<f64>, r: (f64, f64)| period.filter(|&p| r.1 - r.0 >= p * (1.0 - 1e-9));
    let (full_u, full_v) = (full(d.u_period, trim.0), full(d.v_period, trim.1));
    // A periodic value in a box narrower than the period: from half the free part of the
    // circle below the box.
    let in_box = |x: f64, period: Option<f64>, r: (f64, f64)| match period {
        Some(p) if r.1 - r.0 < p * (1.0 - 1e-9) => {
            let lo = r.0 - 0.5 * (p - (r.1 - r.0));
            lo + (x - lo).rem_euclid(p)
        }
        _ => x,
    };
    let mut out: Vec<Vec<(f64, f64)>> = Vec::with_capacity(runs.len());
    for (r, run) in runs.iter().enumerate() {
        let n = run.len();
        let mut pts = vec![(0.0, 0.0); n];
        let mut poles = vec![(false, false); n];
        let mut place = |j: usize, from: Option<(f64, f64)>, pts: &mut Vec<(f64, f64)>| {
            let (mut u, mut v) = invert(s, d, &run[j], from);
            let (_, su, sv) = s.derivs(u, v);
            let (nu, nv) = (su.norm(), sv.norm());
            // A pole: a vanishing derivative, or an iso-line through the sample of (nearly)
            // no length (the tip of a lens cap over a round leading edge, where S_u vanishes
            // too at mid-v: the tangents of both halves cancel).
            let iso = |along_u: bool| {
                let (a, b) = if along_u { trim.0 } else { trim.1 };
                let at = |k: usize| {
                    let t = a + (b - a) * k as f64 / 8.0;
                    if along_u {
                        s.point(t, v)
                    } else {
                        s.point(u, t)
                    }
                };
                (0..8).map(|k| (at(k + 1) - at(k)).norm()).sum::<f64>()
            };
            let (lu, lv) = (iso(true), iso(false));
            poles[j] = (
                nu <= 1e-6 * nv || lu <= 1e-6 * lv,
                nv <= 1e-6 * nu || lv <= 1e-6 * lu,
            );
            if let Some((fu, fv)) = from {
                if let Some(p) = full_u {
                    u = unwrap(u, fu, p);
                }
                if let Some(p) = full_v {
                    v = unwrap(v, fv, p);
                }
            }
            pts[j] = (in_box(u, d.u_period, trim.0), in_box(v, d.v_period, trim.1));
        };
        let m = n / 2;
        place(m, None, &mut pts);
        for j in m + 1..n {
            let from = pts[j - 1];
            place(j, Some(from), &mut pts);
        }
        for j in (0..m).rev() {
            let from = pts[j + 1];
            place(j, Some(from), &mut pts);
        }
        // A pole's free parameter is taken from its nearest regular neighbour in the run, so
        // that the run reaches the pole along itself; the step to the next run is the pole's
        // own edge of the parameter domain.
        for j in 0..n {
            if poles[j].0
                && let Some(k) = (0..n)
                    .filter(|&k| !poles[k].0)
                    .min_by_key(|&k| k.abs_diff(j))
            {
                pts[j].0 = pts[k].0;
            }
            if poles[j].1
                && let Some(k) = (0..n)
                    .filter(|&k| !poles[k].1)
                    .min_by_key(|&k| k.abs_diff(j))
            {
                pts[j].1 = pts[k].1;
            }
        }
        // Around a seam: continue from the previous run, or start in the box.
        for (k, period, r0) in [(0usize, full_u, trim.0), (1, full_v, trim.1)] {
            let Some(p) = period else { continue };
            let get = |q: &(f64, f64)| if k == 0 { q.0 } else { q.1 };
            let first = get(&pts[0]);
            let target = match out.last().and_then(|l| l.last()) {
                Some(q) => unwrap(first, get(q), p),
                None => {
                    let mid = get(&pts[m]);
                    first + (in_box_full(mid, r0, p) - mid)
                }
            };
            let shift = target - first;
            for q in &mut pts {
                if k == 0 {
                    q.0 += shift;
                } else {
                    q.1 += shift;
                }
            }
        }
        if retraces.get(r) == Some(&true)
            && let Some(last) = out.last()
        {
            let shift = |get: fn(&(f64, f64)) -> f64, period: Option<f64>, lo: f64, hi: f64| {
                let p = period?;
                let (a, b) = pts
                    .iter()
                    .map(get)
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                        (a.min(x), b.max(x))
                    });
                if b - a > 1e-6 * p {
                    return None;
                }
                let was = get(&last[last.len() / 2]);
                Some(if (was - lo).abs() <= (was - hi).abs() {
                    was + p - a
                } else {
                    was - p - a
                })
            };
            let su = shift(|q| q.0, full_u, trim.0.0, trim.0.1);
            let sv = shift(|q| q.1, full_v, trim.1.0, trim.1.1);
            for q in &mut pts {
                q.0 += su.unwrap_or(0.0);
                q.1 += sv.unwrap_or(0.0);
            }
        }
        out.push(pts);
    }
    // Shift the loop by whole periods to centre it on the box.
    let (mut lo, mut hi) = (
        (f64::INFINITY, f64::INFINITY),
        (f64::NEG_INFINITY, f64::NEG_INFINITY),
    );
    for &(u, v) in out.iter().flatten() {
        lo = (lo.0.min(u), lo.1.min(v));
        hi = (hi.0.max(u), hi.1.max(v));
    }
    let centre = |a: f64, b: f64, r: (f64, f64), period: Option<f64>| {
        period.map_or(0.0, |p| {
            ((0.5 * (r.0 + r.1) - 0.5 * (a + b)) / p).round() * p
        })
    };
    let ku = centre(lo.0, hi.0, trim.0, full_u);
    let kv = centre(lo.1, hi.1, trim.1, full_v);
    for run in &mut out {
        for q in run.iter_mut() {
            q.0 += ku;
            q.1 += kv;
        }
    }
    out
}

/// `x` shifted by whole periods into [r.0, r.0 + p).
fn in_box_full(x: f64, r: (f64, f64), p: f64) -> f64 {
    r.0 + (x - r.0).rem_euclid(p)
}
