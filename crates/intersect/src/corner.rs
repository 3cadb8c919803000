//! Corners by curve–curve intersection (§3.2, Eq. 13).
//!
//! A corner is where two support curves meet. After the curves changed, its parameters
//! (t_a, t_b) minimise the distance between the curves:
//!
//! ```text
//! [r_a(t_a) − r_b(t_b)] · dr_j/dt = 0,   j = a, b                       (Eq. 13)
//! ```
//!
//! solved as the minimisation of f = ½ |r_a − r_b|² by the safeguarded box-constrained Newton
//! of this crate (exact Hessian [[r_a'·r_a' + d·r_a'', −r_a'·r_b'], [−r_a'·r_b',
//! r_b'·r_b' − d·r_b'']], d = r_a − r_b; Levenberg–Marquardt shift when it is not positive
//! definite, e.g. for curves meeting tangentially). It starts from the corner's parameters
//! in the previous model when given; if that run does not end with the curves meeting, a
//! global start is added from the closest pairs of a coarse sampling of both curves. The
//! residual distance |r_a − r_b| is reported; curves that no longer meet (distance above the
//! meeting tolerance) are an error naming the corner and both curves.
//!
//! Corners usually sit at curve ends. A moved curve may end just short of the new corner;
//! `extension` lets the parameters run past the ends by that much (in parameter units), which
//! evaluates the end arcs' polynomials beyond their interval.

use crate::error::{Error, Result};
use geom_db::eval::ParamCurve;
use geom_db::newton::{self, Eval, Problem, Settings};
use geom_db::prelude::Point3;
use nalgebra::{SMatrix, SVector};

/// Knobs of the corner solve.
#[derive(Debug, Clone, PartialEq)]
pub struct CornerOptions {
    /// Length scale (model size). `None`: the larger sampled diagonal of the two curves.
    pub length_scale: Option<f64>,
    /// Newton tolerance on the tangential residual, relative (default 1e-12).
    pub rel_tol: f64,
    /// The curves meet if their distance is at most this, relative (default 1e-7, the
    /// "same point" tolerance of the topology).
    pub meet_rel_tol: f64,
    /// Newton iterations per start (default 50).
    pub max_iters: usize,
    /// How far past each curve's ends the parameters may run (parameter units, default 0).
    pub extension: f64,
    /// Samples per arc for the global start (default 8, at least 32 per curve).
    pub samples_per_arc: usize,
}

impl Default for CornerOptions {
    fn default() -> Self {
        Self {
            length_scale: None,
            rel_tol: 1e-12,
            meet_rel_tol: 1e-7,
            max_iters: 50,
            extension: 0.0,
            samples_per_arc: 8,
        }
    }
}

impl CornerOptions {
    /// Sets the length scale.
    pub fn with_length_scale(mut self, l: f64) -> Self {
        self.length_scale = Some(l);
        self
    }
    /// Sets the extension past the curve ends (parameter units).
    pub fn with_extension(mut self, e: f64) -> Self {
        self.extension = e;
        self
    }
    /// Sets the meeting tolerance (relative).
    pub fn with_meet_rel_tol(mut self, t: f64) -> Self {
        self.meet_rel_tol = t;
        self
    }
}

/// A solved corner.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CornerReport {
    /// Parameters on curve a and curve b.
    pub t: [f64; 2],
    /// The corner: midpoint of r_a(t_a) and r_b(t_b).
    pub point: [f64; 3],
    /// Residual distance |r_a(t_a) − r_b(t_b)|.
    pub distance: f64,
    /// Newton iterations (all starts).
    pub iterations: usize,
    /// Tangential residual of Eq. (13) (length units).
    pub residual: f64,
    /// Whether t_a, t_b ended at a bound of their (extended) domains.
    pub on_boundary: [bool; 2],
}

struct CornerProblem<'c, A: ?Sized, B: ?Sized> {
    a: &'c A,
    b: &'c B,
}

impl<A: ParamCurve + ?Sized, B: ParamCurve + ?Sized> Problem<2> for CornerProblem<'_, A, B> {
    fn eval(&self, x: &[f64; 2], active: &[bool; 2]) -> Eval<2> {
        let da = self.a.derivs(x[0]);
        let db = self.b.derivs(x[1]);
        let d = da.point - db.point;
        let g = SVector::<f64, 2>::new(d.dot(&da.d1), -d.dot(&db.d1));
        let c = -da.d1.dot(&db.d1);
        let h = SMatrix::<f64, 2, 2>::new(
            da.d1.dot(&da.d1) + d.dot(&da.d2),
            c,
            c,
            db.d1.dot(&db.d1) - d.dot(&db.d2),
        );
        let n = [da.d1.norm(), db.d1.norm()];
        let mut res: f64 = 0.0;
        for i in 0..2 {
            if !active[i] && n[i] > 0.0 {
                res = res.max(g[i].abs() / n[i]);
            }
        }
        let f = 0.5 * d.norm_squared();
        Eval {
            f: if f.is_finite() { f } else { f64::INFINITY },
            g,
            h,
            res: if f.is_finite() { res } else { f64::INFINITY },
            fnoise: 16.0
                * f64::EPSILON
                * d.norm()
                * (da.point.coords.norm() + db.point.coords.norm()),
        }
    }
}

fn samples<C: ParamCurve + ?Sized>(c: &C, per_arc: usize) -> Vec<(f64, Point3)> {
    let (lo, hi) = c.domain();
    let mut e: Vec<f64> = vec![lo];
    let mut b: Vec<f64> = c
        .breaks()
        .into_iter()
        .filter(|x| *x > lo && *x < hi)
        .collect();
    b.sort_by(f64::total_cmp);
    b.dedup();
    e.extend(b);
    e.push(hi);
    let k = per_arc.max(1).max(32usize.div_ceil(e.len() - 1));
    let mut out = Vec::new();
    for w in e.windows(2) {
        for j in 0..k {
            let t = w[0] + (w[1] - w[0]) * j as f64 / k as f64;
            out.push((t, c.point(t)));
        }
    }
    out.push((hi, c.point(hi)));
    out
}

/// Solves the corner `corner` of curves `a` and `b` (Eq. 13), starting from `seed` (the
/// corner's parameters in the previous model) when given.
pub fn solve_corner<A, B>(
    corner: &str,
    (label_a, a): (&str, &A),
    (label_b, b): (&str, &B),
    seed: Option<[f64; 2]>,
    opts: &CornerOptions,
) -> Result<CornerReport>
where
    A: ParamCurve + ?Sized,
    B: ParamCurve + ?Sized,
{
    let (a0, a1) = a.domain();
    let (b0, b1) = b.domain();
    for (l, lo, hi) in [(label_a, a0, a1), (label_b, b0, b1)] {
        if !(lo.is_finite() && hi.is_finite() && hi > lo) {
            return Err(Error::BadEntity {
                entity: l.to_string(),
                reason: format!("empty or non-finite domain [{lo}, {hi}]"),
            });
        }
    }
    let ext = opts.extension.max(0.0);
    let lo = [a0 - ext, b0 - ext];
    let hi = [a1 + ext, b1 + ext];
    // The samples of both arcs (the global starts and, without a given length scale, the
    // scale), taken only when needed: a seeded run that meets skips the global search.
    let sampled = std::cell::OnceCell::new();
    let sampled = || {
        sampled.get_or_init(|| {
            (
                samples(a, opts.samples_per_arc),
                samples(b, opts.samples_per_arc),
            )
        })
    };
    let scale = opts.length_scale.unwrap_or_else(|| {
        let diag = |s: &[(f64, Point3)]| {
            let mut bb = crate::bvh::Aabb::EMPTY;
            for (_, p) in s {
                bb.add(p);
            }
            bb.diagonal()
        };
        let (sa, sb) = sampled();
        diag(sa).max(diag(sb))
    });
    let settings = Settings {
        tol: opts.rel_tol * scale,
        max_iters: opts.max_iters,
    };
    let meet = opts.meet_rel_tol * scale;
    let prob = CornerProblem { a, b };
    // global starts: the closest sample pairs, at most 4, distinct in both parameters
    let global_starts = || {
        let (sa, sb) = sampled();
        let mut pairs: Vec<(f64, usize, usize)> = Vec::with_capacity(sa.len() * sb.len());
        for (i, (_, p)) in sa.iter().enumerate() {
            for (j, (_, q)) in sb.iter().enumerate() {
                pairs.push(((p - q).norm_squared(), i, j));
            }
        }
        pairs.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)).then(x.2.cmp(&y.2)));
        let mut used: Vec<(usize, usize)> = Vec::new();
        let mut starts = Vec::new();
        for &(_, i, j) in &pairs {
            if used.len() >= 4 {
                break;
            }
            if used
                .iter()
                .any(|&(ui, uj)| ui.abs_diff(i) <= 1 && uj.abs_diff(j) <= 1)
            {
                continue;
            }
            used.push((i, j));
            starts.push([sa[i].0, sb[j].0]);
        }
        starts
    };
    let mut starts: Vec<[f64; 2]> = seed.into_iter().collect();
    if seed.is_none() {
        starts.extend(global_starts());
    }
    let mut best: Option<CornerReport> = None;
    let mut iterations = 0;
    let mut k = 0;
    while k < starts.len() {
        let s = &starts[k];
        let o = newton::minimise(&prob, *s, &lo, &hi, settings);
        iterations += o.report.iterations;
        let pa = a.point(o.x[0]);
        let pb = b.point(o.x[1]);
        let dist = (pa - pb).norm();
        let m = Point3::from((pa.coords + pb.coords) * 0.5);
        let rep = CornerReport {
            t: o.x,
            point: [m.x, m.y, m.z],
            distance: dist,
            iterations,
            residual: o.eval.res,
            on_boundary: [
                o.x[0] <= lo[0] || o.x[0] >= hi[0],
                o.x[1] <= lo[1] || o.x[1] >= hi[1],
            ],
        };
        if best.is_none_or(|b| dist < b.distance) {
            best = Some(rep);
        }
        if k == 0 && seed.is_some() {
            // a seeded run that meets is accepted without the global search
            if dist <= meet {
                break;
            }
            starts.extend(global_starts());
        }
        k += 1;
    }
    let mut best = best.ok_or_else(|| Error::BadEntity {
        entity: corner.to_string(),
        reason: "no start for the corner search".into(),
    })?;
    best.iterations = iterations;
    if best.distance.is_nan() || best.distance > meet {
        return Err(Error::CurvesDoNotMeet {
            corner: corner.to_string(),
            curve_a: label_a.to_string(),
            curve_b: label_b.to_string(),
            distance: best.distance,
            tol: meet,
            iters: iterations,
            t_a: best.t[0],
            t_b: best.t[1],
        });
    }
    Ok(best)
}
