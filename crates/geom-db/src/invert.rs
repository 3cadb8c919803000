//! Point inversion: the foot of the normal dropped from a point onto a surface or a curve
//! (Eq. 11), the one implementation of the workspace.
//!
//! For a surface r(u, v) and a point p the foot solves
//!
//! ```text
//! [p − r(u, v)] · [∂r/∂u, ∂r/∂v] = 0                                  (Eq. 11)
//! ```
//!
//! the stationarity of f(u, v) = ½ |r(u, v) − p|² (on a curve, (p − r(t)) · r′(t) = 0). It is
//! solved by the safeguarded Newton of [`crate::newton`] with the exact Hessian
//! H_ij = r_i · r_j + (r − p) · r_ij, in *global* parameters (so it crosses patch and arc
//! borders freely), damped by a projected backtracking line search, with bounded iterations
//! and the parameter box of the entity as bounds: a parameter held at its bound because the
//! distance still decreases outward is *active* and the foot is reported `on_boundary`.
//!
//! **Convergence** is on the tangential residual in length units,
//! max_i |(r − p) · r_i| / |r_i| over the free parameters, against
//! `rel_tol × length_scale` (default 1e-12 of the model's reference length, the bounding-box
//! diagonal, see [`InvertOptions::for_model`]); |r_i| is floored at 1e-3 of the other
//! tangent's length so that a pole (a degenerate patch edge, where one tangent vanishes)
//! does not amplify round-off.
//!
//! Local solves ([`foot_on_surface`], [`foot_on_curve`], [`SurfaceInverter::foot_from`])
//! start from given parameters. A global foot needs start points: [`SurfaceInverter::project`]
//! takes them from a sample grid of every patch (brute force, for checks and one-off
//! projections); `intersect` seeds the same Newton from a bounding-volume hierarchy for large
//! batches. A failed search is [`Error::InversionFailed`] naming the entity and the point.

use std::sync::OnceLock;

use nalgebra::{SMatrix, SVector};

use crate::db::GeomDb;
use crate::error::{Error, Result};
use crate::eval::{ParamCurve, ParamSurface};
use crate::newton::{self, Eval, NewtonReport, Outcome, Problem, Settings};
use crate::prelude::Point3;

/// Knobs of the point inversion: tolerance relative to a length scale, iterations.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InvertOptions {
    /// Convergence tolerance of the tangential residual relative to `length_scale`
    /// (default [`InvertOptions::REL_TOL`] = 1e-12, below the model's 1e-10 Newton accuracy).
    pub rel_tol: f64,
    /// The length scale (model units): the model's reference length (bounding-box diagonal).
    pub length_scale: f64,
    /// Newton iterations per start (default 50).
    pub max_iters: usize,
    /// Samples per patch (arc) and direction of the brute-force start search of
    /// [`SurfaceInverter::project`] / [`CurveInverter::project`] (default 8).
    pub samples_per_patch: usize,
    /// Newton starts of the brute-force search (default 4): the sample grid's local minima
    /// of the distance, nearest first, then the nearest samples, no two neighbours in the
    /// sample grid.
    pub max_starts: usize,
}

impl InvertOptions {
    /// Default relative tolerance of the tangential residual.
    pub const REL_TOL: f64 = 1e-12;

    /// Options with the tolerance relative to `length_scale` (non-positive or non-finite
    /// scales are replaced by 1).
    pub fn new(length_scale: f64) -> Self {
        Self {
            rel_tol: Self::REL_TOL,
            length_scale: if length_scale.is_finite() && length_scale > 0.0 {
                length_scale
            } else {
                1.0
            },
            max_iters: 50,
            samples_per_patch: 8,
            max_starts: 4,
        }
    }

    /// Options relative to the model's reference length ([`GeomDb::reference_length`]).
    pub fn for_model(db: &GeomDb) -> Self {
        Self::new(db.reference_length())
    }

    /// Sets the relative tolerance.
    pub fn with_rel_tol(mut self, rel_tol: f64) -> Self {
        self.rel_tol = rel_tol;
        self
    }

    /// Sets the iteration bound.
    pub fn with_max_iters(mut self, n: usize) -> Self {
        self.max_iters = n;
        self
    }

    /// The absolute tolerance `rel_tol × length_scale`.
    pub fn tolerance(&self) -> f64 {
        self.rel_tol * self.length_scale
    }

    /// The Newton settings.
    pub fn settings(&self) -> Settings {
        Settings {
            tol: self.tolerance(),
            max_iters: self.max_iters,
        }
    }
}

/// The foot of the normal on a surface.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SurfaceFoot {
    /// Global parameters (u, v).
    pub uv: [f64; 2],
    /// Patch (i, j) containing (u, v): index of the break interval in u and in v.
    pub patch: [usize; 2],
    /// r(u, v).
    pub point: [f64; 3],
    /// |r(u, v) − p|.
    pub distance: f64,
    /// The foot is on the boundary of the parameter domain with the distance still
    /// decreasing outward (a constrained minimum): Eq. 11 holds only along the boundary.
    pub on_boundary: bool,
    /// The Newton run that produced this foot.
    pub report: NewtonReport,
    /// Number of Newton starts made.
    pub starts: usize,
}

/// The foot of the normal on a curve.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CurveFoot {
    /// Global parameter t.
    pub t: f64,
    /// Arc containing t (index of the break interval).
    pub arc: usize,
    /// r(t).
    pub point: [f64; 3],
    /// |r(t) − p|.
    pub distance: f64,
    /// The foot is an end of the parameter interval with the distance still decreasing
    /// outward.
    pub on_boundary: bool,
    /// The Newton run that produced this foot.
    pub report: NewtonReport,
    /// Number of Newton starts made.
    pub starts: usize,
}

/// f = ½|r(u, v) − p|² with the exact Hessian and the tangential residual (Eq. 11).
struct SurfProblem<'s, S: ParamSurface + ?Sized> {
    s: &'s S,
    p: Point3,
}

impl<S: ParamSurface + ?Sized> Problem<2> for SurfProblem<'_, S> {
    fn eval(&self, x: &[f64; 2], active: &[bool; 2]) -> Eval<2> {
        let d = self.s.derivs(x[0], x[1]);
        let r = d.point - self.p;
        let g = SVector::<f64, 2>::new(d.du.dot(&r), d.dv.dot(&r));
        let h = SMatrix::<f64, 2, 2>::new(
            d.du.dot(&d.du) + d.duu.dot(&r),
            d.du.dot(&d.dv) + d.duv.dot(&r),
            d.du.dot(&d.dv) + d.duv.dot(&r),
            d.dv.dot(&d.dv) + d.dvv.dot(&r),
        );
        // |(r − p)·r_i| / |r_i|; near a pole (|r_i| → 0 on a degenerate patch edge) the
        // denominator is floored at 1e-3 of the other tangent so round-off is not amplified
        let norms = [d.du.norm(), d.dv.norm()];
        let floor = 1e-3 * norms[0].max(norms[1]);
        let mut res: f64 = 0.0;
        for i in 0..2 {
            if !active[i] && norms[i] > 0.0 {
                res = res.max(g[i].abs() / norms[i].max(floor));
            }
        }
        let f = 0.5 * r.norm_squared();
        if !f.is_finite() {
            return Eval {
                f: f64::INFINITY,
                g,
                h,
                res: f64::INFINITY,
                fnoise: 0.0,
            };
        }
        let fnoise =
            16.0 * f64::EPSILON * r.norm() * (d.point.coords.norm() + self.p.coords.norm());
        Eval {
            f,
            g,
            h,
            res,
            fnoise,
        }
    }
}

/// f = ½|r(t) − p|² with the exact second derivative and the residual |(r − p)·r′| / |r′|.
struct CurveProblem<'s, C: ParamCurve + ?Sized> {
    c: &'s C,
    p: Point3,
}

impl<C: ParamCurve + ?Sized> Problem<1> for CurveProblem<'_, C> {
    fn eval(&self, x: &[f64; 1], active: &[bool; 1]) -> Eval<1> {
        let d = self.c.derivs(x[0]);
        let r = d.point - self.p;
        let g = d.d1.dot(&r);
        let h = d.d1.dot(&d.d1) + d.d2.dot(&r);
        let n = d.d1.norm();
        let res = if active[0] || n == 0.0 {
            0.0
        } else {
            g.abs() / n
        };
        let f = 0.5 * r.norm_squared();
        Eval {
            f: if f.is_finite() { f } else { f64::INFINITY },
            g: SVector::<f64, 1>::new(g),
            h: SMatrix::<f64, 1, 1>::new(h),
            res: if f.is_finite() { res } else { f64::INFINITY },
            fnoise: 16.0 * f64::EPSILON * r.norm() * (d.point.coords.norm() + self.p.coords.norm()),
        }
    }
}

/// Local Newton on Eq. (11) on surface `s` from `uv0`, parameters bounded to
/// `[lo, hi]` (usually the surface's domain). The outcome carries the parameters, the held
/// bounds and the [`NewtonReport`]; the caller decides what a failure means.
pub fn foot_on_surface<S: ParamSurface + ?Sized>(
    s: &S,
    p: &Point3,
    uv0: [f64; 2],
    lo: [f64; 2],
    hi: [f64; 2],
    settings: Settings,
) -> Outcome<2> {
    newton::minimise(&SurfProblem { s, p: *p }, uv0, &lo, &hi, settings)
}

/// Local Newton for the foot of the normal on curve `c` from `t0`, t bounded to [lo, hi]
/// (which may reach past the curve's domain: the end arcs are then extrapolated).
pub fn foot_on_curve<C: ParamCurve + ?Sized>(
    c: &C,
    p: &Point3,
    t0: f64,
    lo: f64,
    hi: f64,
    settings: Settings,
) -> Outcome<1> {
    newton::minimise(&CurveProblem { c, p: *p }, [t0], &[lo], &[hi], settings)
}

/// Index of the interval of sorted `edges` (first..last) containing x (last one closed).
pub fn interval_of(edges: &[f64], x: f64) -> usize {
    let n = edges.len().saturating_sub(1).max(1);
    let i = edges.partition_point(|&e| e <= x);
    i.saturating_sub(1).min(n - 1)
}

/// Sorted, deduplicated interval edges: the domain ends plus the breaks strictly inside.
pub fn interval_edges(lo: f64, hi: f64, breaks: &[f64]) -> Vec<f64> {
    let mut e = vec![lo];
    let mut inner: Vec<f64> = breaks
        .iter()
        .copied()
        .filter(|b| b.is_finite() && *b > lo && *b < hi)
        .collect();
    inner.sort_by(f64::total_cmp);
    inner.dedup();
    e.extend(inner);
    e.push(hi);
    e
}

/// `per` equal subdivisions of every interval of `edges`.
fn subdivide(edges: &[f64], per: usize) -> Vec<f64> {
    let per = per.max(1);
    let mut out = Vec::with_capacity((edges.len() - 1) * per + 1);
    for w in edges.windows(2) {
        for j in 0..per {
            out.push(w[0] + (w[1] - w[0]) * j as f64 / per as f64);
        }
    }
    out.push(edges[edges.len() - 1]);
    out
}

fn check_domain(label: &str, lo: f64, hi: f64, what: &str) -> Result<()> {
    if !(lo.is_finite() && hi.is_finite() && hi > lo) {
        return Err(Error::InversionInput {
            entity: label.to_string(),
            point: None,
            reason: format!("empty or non-finite {what} domain [{lo}, {hi}]"),
        });
    }
    Ok(())
}

/// Starts for the brute-force search (`dims`: lattice sizes, `k`: how many).
///
/// First the lattice's local minima of the sampled distance (a sample no farther than any of
/// its lattice neighbours), nearest first: one start in every valley of the distance, so a
/// point near a thin part (a trailing edge, where the upper and lower sides are millimetres
/// apart but far apart in the parameters) starts on both sides, not only on the side whose
/// samples happen to be a little nearer. Then, while fewer than `k`, the nearest samples not
/// next to (in the lattice) a start already taken.
fn lattice_starts<const D: usize>(d2: &[f64], dims: [usize; D], k: usize) -> Vec<usize> {
    let coords = |mut i: usize| {
        let mut c = [0usize; D];
        for (a, n) in c.iter_mut().zip(dims) {
            *a = i % n;
            i /= n;
        }
        c
    };
    let index = |c: &[usize; D]| {
        let mut i = 0;
        for a in (0..D).rev() {
            i = i * dims[a] + c[a];
        }
        i
    };
    // the 3^D - 1 lattice neighbours of sample i
    let neighbours = |i: usize| {
        let c = coords(i);
        let mut out = Vec::with_capacity(3usize.pow(D as u32));
        for m in 0..3usize.pow(D as u32) {
            let mut q = c;
            let mut mm = m;
            let mut inside = true;
            let mut same = true;
            for a in 0..D {
                let o = mm % 3;
                mm /= 3;
                same &= o == 1;
                match (c[a] + o).checked_sub(1) {
                    Some(x) if x < dims[a] => q[a] = x,
                    _ => inside = false,
                }
            }
            if inside && !same {
                out.push(index(&q));
            }
        }
        out
    };
    let mut minima: Vec<usize> = (0..d2.len())
        .filter(|&i| {
            d2[i].is_finite()
                && neighbours(i)
                    .iter()
                    .all(|&j| d2[j] >= d2[i] || d2[j].is_nan())
        })
        .collect();
    minima.sort_by(|&a, &b| d2[a].total_cmp(&d2[b]).then(a.cmp(&b)));
    let mut out: Vec<usize> = Vec::with_capacity(k);
    let near = |out: &[usize], i: usize| {
        let ci = coords(i);
        out.iter().any(|&j| {
            let cj = coords(j);
            (0..D).all(|a| ci[a].abs_diff(cj[a]) <= 1)
        })
    };
    for m in minima {
        if out.len() == k {
            break;
        }
        if !near(&out, m) {
            out.push(m);
        }
    }
    while out.len() < k {
        let mut best: Option<usize> = None;
        for (i, &d) in d2.iter().enumerate() {
            if !d.is_finite() || best.is_some_and(|b| d2[b] <= d) {
                continue;
            }
            if !near(&out, i) {
                best = Some(i);
            }
        }
        match best {
            Some(b) => out.push(b),
            None => break,
        }
    }
    out
}

/// Point inversion on one surface: local Newton from given parameters, and a global search
/// seeded by a sample grid of every patch (built at its first use).
pub struct SurfaceInverter<'a, S: ParamSurface + ?Sized> {
    label: String,
    surf: &'a S,
    lo: [f64; 2],
    hi: [f64; 2],
    edges: [Vec<f64>; 2],
    opts: InvertOptions,
    samples: OnceLock<(Vec<Point3>, Vec<f64>, Vec<f64>)>,
}

impl<'a, S: ParamSurface + ?Sized> SurfaceInverter<'a, S> {
    /// The inverter of `surf`; `label` names it in errors. Fails on an empty or non-finite
    /// parameter domain.
    pub fn new(label: impl Into<String>, surf: &'a S, opts: &InvertOptions) -> Result<Self> {
        let label = label.into();
        let (du, dv) = surf.domain();
        check_domain(&label, du[0], du[1], "u")?;
        check_domain(&label, dv[0], dv[1], "v")?;
        let (bu, bv) = surf.breaks();
        Ok(Self {
            edges: [
                interval_edges(du[0], du[1], &bu),
                interval_edges(dv[0], dv[1], &bv),
            ],
            label,
            surf,
            lo: [du[0], dv[0]],
            hi: [du[1], dv[1]],
            opts: *opts,
            samples: OnceLock::new(),
        })
    }

    /// The surface's label.
    pub fn label(&self) -> &str {
        &self.label
    }

    /// The surface.
    pub fn surface(&self) -> &'a S {
        self.surf
    }

    /// The options.
    pub fn options(&self) -> &InvertOptions {
        &self.opts
    }

    /// The absolute convergence tolerance (length units).
    pub fn tolerance(&self) -> f64 {
        self.opts.tolerance()
    }

    /// The patch edges in u and v (domain ends and patch borders).
    pub fn edges(&self) -> &[Vec<f64>; 2] {
        &self.edges
    }

    /// The patch (interval of the breaks) containing (u, v).
    pub fn patch_of(&self, uv: [f64; 2]) -> [usize; 2] {
        [
            interval_of(&self.edges[0], uv[0]),
            interval_of(&self.edges[1], uv[1]),
        ]
    }

    /// Local Newton on Eq. (11) from `uv0` only (no global search): a warm start for points
    /// known to be near `uv0`. The report says whether it converged.
    pub fn foot_from(&self, p: &Point3, uv0: [f64; 2]) -> SurfaceFoot {
        let o = foot_on_surface(self.surf, p, uv0, self.lo, self.hi, self.opts.settings());
        let pt = self.surf.point(o.x[0], o.x[1]);
        SurfaceFoot {
            uv: o.x,
            patch: self.patch_of(o.x),
            point: [pt.x, pt.y, pt.z],
            distance: (pt - p).norm(),
            on_boundary: o.active.iter().any(|&a| a),
            report: o.report,
            starts: 1,
        }
    }

    fn samples(&self) -> &(Vec<Point3>, Vec<f64>, Vec<f64>) {
        self.samples.get_or_init(|| {
            let us = subdivide(&self.edges[0], self.opts.samples_per_patch);
            let vs = subdivide(&self.edges[1], self.opts.samples_per_patch);
            let mut pts = Vec::with_capacity(us.len() * vs.len());
            for &v in &vs {
                for &u in &us {
                    pts.push(self.surf.point(u, v));
                }
            }
            (pts, us, vs)
        })
    }

    /// Newton from the brute-force starts; (best converged foot, best foot overall).
    fn search(&self, p: &Point3, index: usize) -> Result<(Option<SurfaceFoot>, SurfaceFoot)> {
        if !p.iter().all(|c| c.is_finite()) {
            return Err(Error::InversionInput {
                entity: self.label.clone(),
                point: Some(index),
                reason: "the point has a non-finite coordinate".into(),
            });
        }
        let (pts, us, vs) = self.samples();
        let d2: Vec<f64> = pts.iter().map(|q| (q - p).norm_squared()).collect();
        let starts = lattice_starts(&d2, [us.len(), vs.len()], self.opts.max_starts);
        let mut conv: Option<SurfaceFoot> = None;
        let mut any: Option<SurfaceFoot> = None;
        // A foot held on the domain's boundary is tried again from half a patch inward:
        // Newton can stop on a bound at a constrained minimum (the rounded trailing edge of a
        // periodic wing, seen from a point on its upper side 4 cm from the edge, stopped
        // 3.6e-2 away at the edge) that a start inside the domain avoids; a foot that truly
        // lies on the boundary is found again.
        let inward = |f: &SurfaceFoot| {
            let mut uv = f.uv;
            for (a, x) in uv.iter_mut().enumerate() {
                let e = &self.edges[a];
                let n = e.len();
                if *x <= self.lo[a] && n > 1 {
                    *x = 0.5 * (e[0] + e[1]);
                } else if *x >= self.hi[a] && n > 1 {
                    *x = 0.5 * (e[n - 2] + e[n - 1]);
                }
            }
            uv
        };
        let mut n = 0;
        for &s in &starts {
            let mut uv = Some([us[s % us.len()], vs[s / us.len()]]);
            let mut retried = false;
            while let Some(start) = uv.take() {
                n += 1;
                let f = self.foot_from(p, start);
                if f.report.converged && conv.is_none_or(|b| f.distance < b.distance) {
                    conv = Some(f);
                }
                if any.is_none_or(|b| f.distance < b.distance) {
                    any = Some(f);
                }
                if f.on_boundary && !retried && start != inward(&f) {
                    retried = true;
                    uv = Some(inward(&f));
                }
            }
        }
        let set = |f: SurfaceFoot| SurfaceFoot { starts: n, ..f };
        let any = any.ok_or_else(|| Error::InversionInput {
            entity: self.label.clone(),
            point: Some(index),
            reason: "the surface has no finite sample".into(),
        })?;
        Ok((conv.map(set), set(any)))
    }

    /// The global foot of the normal from `p` by brute force: Newton from the nearest
    /// samples of a grid of `samples_per_patch`² points per patch (at most `max_starts`, no
    /// two neighbours), the nearest converged foot kept. `index` names the point in errors;
    /// no converged start is [`Error::InversionFailed`].
    pub fn project_indexed(&self, p: &Point3, index: usize) -> Result<SurfaceFoot> {
        let (conv, any) = self.search(p, index)?;
        conv.ok_or_else(|| inversion_failed(&self.label, index, any.report))
    }

    /// The global foot of the normal from `p` (see [`project_indexed`](Self::project_indexed)).
    pub fn project(&self, p: &Point3) -> Result<SurfaceFoot> {
        self.project_indexed(p, 0)
    }

    /// The nearest surface point found by the same search, converged or not (its report
    /// says). Its distance is an *upper bound* of the distance from `p` to the surface,
    /// whatever Newton did, so a gap measured with it is never under-estimated: the measure
    /// of checks, where round-off (e.g. a badly conditioned patch) can keep the tangential
    /// residual above the tolerance.
    pub fn nearest_indexed(&self, p: &Point3, index: usize) -> Result<SurfaceFoot> {
        let (conv, any) = self.search(p, index)?;
        Ok(conv.filter(|c| c.distance <= any.distance).unwrap_or(any))
    }
}

fn inversion_failed(label: &str, index: usize, r: NewtonReport) -> Error {
    Error::InversionFailed {
        entity: label.to_string(),
        point: index,
        iterations: r.iterations,
        residual: r.residual,
        tolerance: r.tolerance,
    }
}

/// Point inversion on one curve (the 1-D analogue of [`SurfaceInverter`]).
pub struct CurveInverter<'a, C: ParamCurve + ?Sized> {
    label: String,
    curve: &'a C,
    lo: f64,
    hi: f64,
    edges: Vec<f64>,
    opts: InvertOptions,
    samples: OnceLock<(Vec<Point3>, Vec<f64>)>,
}

impl<'a, C: ParamCurve + ?Sized> CurveInverter<'a, C> {
    /// The inverter of `curve`; `label` names it in errors.
    pub fn new(label: impl Into<String>, curve: &'a C, opts: &InvertOptions) -> Result<Self> {
        let label = label.into();
        let (lo, hi) = curve.domain();
        check_domain(&label, lo, hi, "t")?;
        Ok(Self {
            edges: interval_edges(lo, hi, &curve.breaks()),
            label,
            curve,
            lo,
            hi,
            opts: *opts,
            samples: OnceLock::new(),
        })
    }

    /// The curve's label.
    pub fn label(&self) -> &str {
        &self.label
    }

    /// The curve.
    pub fn curve(&self) -> &'a C {
        self.curve
    }

    /// The absolute convergence tolerance (length units).
    pub fn tolerance(&self) -> f64 {
        self.opts.tolerance()
    }

    /// The arc edges (domain ends and arc borders).
    pub fn edges(&self) -> &[f64] {
        &self.edges
    }

    /// Local Newton from `t0` with t in the curve's domain.
    pub fn foot_from(&self, p: &Point3, t0: f64) -> CurveFoot {
        self.foot_in(p, t0, self.lo, self.hi)
    }

    /// Local Newton from `t0` with t in [lo, hi] (which may reach past the domain: the end
    /// arcs are then extrapolated).
    pub fn foot_in(&self, p: &Point3, t0: f64, lo: f64, hi: f64) -> CurveFoot {
        let o = foot_on_curve(self.curve, p, t0, lo, hi, self.opts.settings());
        let pt = self.curve.point(o.x[0]);
        CurveFoot {
            t: o.x[0],
            arc: interval_of(&self.edges, o.x[0]),
            point: [pt.x, pt.y, pt.z],
            distance: (pt - p).norm(),
            on_boundary: o.active[0],
            report: o.report,
            starts: 1,
        }
    }

    fn samples(&self) -> &(Vec<Point3>, Vec<f64>) {
        self.samples.get_or_init(|| {
            let per = self
                .opts
                .samples_per_patch
                .max(64usize.div_ceil(self.edges.len() - 1));
            let ts = subdivide(&self.edges, per);
            (ts.iter().map(|&t| self.curve.point(t)).collect(), ts)
        })
    }

    /// Newton from the brute-force starts; (best converged foot, best foot overall).
    fn search(&self, p: &Point3, index: usize) -> Result<(Option<CurveFoot>, CurveFoot)> {
        if !p.iter().all(|c| c.is_finite()) {
            return Err(Error::InversionInput {
                entity: self.label.clone(),
                point: Some(index),
                reason: "the point has a non-finite coordinate".into(),
            });
        }
        let (pts, ts) = self.samples();
        let d2: Vec<f64> = pts.iter().map(|q| (q - p).norm_squared()).collect();
        let starts = lattice_starts(&d2, [ts.len()], self.opts.max_starts);
        let mut conv: Option<CurveFoot> = None;
        let mut any: Option<CurveFoot> = None;
        for &s in &starts {
            let f = self.foot_from(p, ts[s]);
            if f.report.converged && conv.is_none_or(|b| f.distance < b.distance) {
                conv = Some(f);
            }
            if any.is_none_or(|b| f.distance < b.distance) {
                any = Some(f);
            }
        }
        let n = starts.len();
        let set = |f: CurveFoot| CurveFoot { starts: n, ..f };
        let any = any.ok_or_else(|| Error::InversionInput {
            entity: self.label.clone(),
            point: Some(index),
            reason: "the curve has no finite sample".into(),
        })?;
        Ok((conv.map(set), set(any)))
    }

    /// The global foot of the normal from `p` by brute force over samples of every arc (at
    /// least 64 in all); `index` names the point in errors.
    pub fn project_indexed(&self, p: &Point3, index: usize) -> Result<CurveFoot> {
        let (conv, any) = self.search(p, index)?;
        conv.ok_or_else(|| inversion_failed(&self.label, index, any.report))
    }

    /// The global foot of the normal from `p`.
    pub fn project(&self, p: &Point3) -> Result<CurveFoot> {
        self.project_indexed(p, 0)
    }

    /// The nearest curve point found, converged or not: an upper bound of the distance
    /// (see [`SurfaceInverter::nearest_indexed`]).
    pub fn nearest_indexed(&self, p: &Point3, index: usize) -> Result<CurveFoot> {
        let (conv, any) = self.search(p, index)?;
        Ok(conv.filter(|c| c.distance <= any.distance).unwrap_or(any))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::curve::{Arc, SupportCurve};
    use crate::prelude::Vector3;
    use crate::surface::{Patch, SupportSurface};
    use std::f64::consts::FRAC_PI_2;

    fn quarter_cylinder() -> SupportSurface {
        SupportSurface::new(
            "q",
            4,
            1,
            (0..4)
                .map(|i| {
                    Patch::interpolate(8, 1, move |u, v| {
                        let th = (i as f64 + u) * FRAC_PI_2;
                        Point3::new(th.cos(), th.sin(), 2.0 * v)
                    })
                })
                .collect(),
        )
    }

    #[test]
    fn surface_feet_cross_patches_and_stop_on_the_boundary() {
        let s = quarter_cylinder();
        let inv = SurfaceInverter::new("cylinder", &s, &InvertOptions::new(3.0)).unwrap();
        for k in 0..40 {
            let u = 4.0 * (k as f64 + 0.3) / 40.0;
            let q = s.point(u, 0.4);
            let n = Vector3::new(q.x, q.y, 0.0);
            // outside and inside, local Newton started one patch away
            for off in [0.3, -0.2] {
                let p = q + n * off;
                let f = inv.foot_from(&p, [(u + 1.0) % 4.0, 0.5]);
                let g = inv.project(&p).unwrap();
                assert!(g.report.converged && !g.on_boundary, "{g:?}");
                // p is at |off| from q along the radius, the normal of the exact cylinder
                // (the interpolated one is within 1e-6 of it)
                assert!((g.distance - off.abs()).abs() < 1e-6, "{g:?}");
                let d = s.derivs(g.uv[0], g.uv[1]);
                let r = d.point - p;
                assert!(r.dot(&d.du).abs() <= 1e-12 * d.du.norm(), "Eq. 11: {g:?}");
                assert!(r.dot(&d.dv).abs() <= 1e-12 * d.dv.norm(), "Eq. 11: {g:?}");
                if f.report.converged {
                    assert!(f.distance >= g.distance - 1e-12);
                }
            }
        }
        // below the bottom: the foot is on v = 0, held at the bound
        let f = inv.project(&Point3::new(1.0, 0.0, -1.0)).unwrap();
        assert!(f.on_boundary && f.uv[1] == 0.0 && (f.distance - 1.0).abs() < 1e-12);
    }

    #[test]
    fn curve_feet_and_errors() {
        let c = SupportCurve::new(
            "c",
            (0..3)
                .map(|i| {
                    Arc::interpolate(6, move |x| {
                        let th = (i as f64 + x) * 0.7;
                        Point3::new(th.cos(), th.sin(), 0.1 * th)
                    })
                })
                .collect(),
        );
        let inv = CurveInverter::new("curve 7", &c, &InvertOptions::new(2.0)).unwrap();
        for k in 0..=30 {
            let t = 3.0 * k as f64 / 30.0;
            let q = c.point(t);
            let f = inv.project(&q).unwrap();
            assert!(f.distance < 1e-12 && (f.t - t).abs() < 1e-9, "{t}: {f:?}");
            assert_eq!(f.arc, (t as usize).min(2));
        }
        let err = inv.project(&Point3::new(f64::NAN, 0.0, 0.0)).unwrap_err();
        assert!(err.to_string().starts_with("curve 7: point 0"), "{err}");
        // no convergence within one iteration: the error names the entity
        let strict = InvertOptions::new(2.0)
            .with_max_iters(1)
            .with_rel_tol(1e-300);
        let inv = CurveInverter::new("curve 7", &c, &strict).unwrap();
        let err = inv
            .project_indexed(&Point3::new(0.3, 2.0, 1.0), 5)
            .unwrap_err();
        assert!(
            matches!(
                err,
                Error::InversionFailed {
                    point: 5,
                    iterations: 1,
                    ..
                }
            ),
            "{err}"
        );
        assert!(err.to_string().contains("curve 7"));
    }

    #[test]
    fn tolerance_is_relative_to_the_length_scale() {
        let o = InvertOptions::new(250.0);
        assert_eq!(o.tolerance(), 1e-12 * 250.0);
        assert_eq!(InvertOptions::new(f64::NAN).length_scale, 1.0);
    }
}
