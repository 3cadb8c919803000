//! Point inversion: the foot of the normal dropped from a point onto a surface or a curve
//! (Eq. 11), with global seeding and a safeguarded Newton in global parameters.
//!
//! For a surface r(u, v) and a point p the foot solves
//!
//! ```text
//! [p − r(u, v)] · [∂r/∂u, ∂r/∂v] = 0                                  (Eq. 11)
//! ```
//!
//! i.e. the stationarity of f(u, v) = ½ |r(u, v) − p|². The search is global:
//!
//! 1. **Seeding.** The parameter domain is cut along the patch borders ([`ParamSurface::breaks`])
//!    and each patch into a few cells; each cell is sampled on a 3 × 3 grid and bounded by the
//!    box of its samples inflated by the bilinear-interpolation error bound
//!    1.5 (Δu²/8 max|r_uu| + Δv²/8 max|r_vv|) (second derivatives taken at the samples).
//!    A bounding-volume hierarchy over the cell boxes is searched branch-and-bound: cells are
//!    visited by increasing box distance, the nearest sample of each visited cell gives an upper
//!    bound, and every cell whose box is nearer than the best upper bound is a candidate.
//! 2. **Newton.** From the nearest sample of each candidate cell (nearest box first), a
//!    box-constrained Newton on f with the exact Hessian
//!    H = [r_i·r_j + (r − p)·r_ij] (Levenberg–Marquardt shift while H is not positive definite,
//!    projected backtracking line search on f) runs in *global* parameters, so it crosses patch
//!    borders freely. A candidate whose box is farther than the best foot found so far is
//!    skipped; at most `max_starts` Newton runs are made.
//! 3. **Convergence** is on the tangential residual max_i |(r − p)·r_i| / |r_i| over the free
//!    parameters, in length units, against `rel_tol` × the length scale. A parameter held at its
//!    bound because the gradient pushes outward is *active*: the foot is then on the domain
//!    boundary, reported by `on_boundary` (the normal condition holds only along the boundary).
//!
//! Batches run in parallel with rayon; each point is independent, so results are identical for
//! any number of threads.

use std::sync::OnceLock;

use crate::bvh::{Aabb, Bvh};
use crate::error::{Error, Result};
use geom_db::eval::{ParamCurve, ParamSurface};
pub use geom_db::invert::{CurveFoot, SurfaceFoot, interval_of};
use geom_db::invert::{CurveInverter, InvertOptions, SurfaceInverter, interval_edges};
use geom_db::prelude::{Point3, Vector3};
use rayon::prelude::*;

/// Knobs of the foot-of-the-normal search.
#[derive(Debug, Clone, PartialEq)]
pub struct ProjectOptions {
    /// Convergence tolerance on the tangential residual, relative to the length scale
    /// (default 1e-12, well below the 1e-10 model accuracy).
    pub rel_tol: f64,
    /// Length scale (model size: bounding-box diagonal). `None`: the entity's own sampled
    /// bounding-box diagonal.
    pub length_scale: Option<f64>,
    /// Newton iterations per start (default 50).
    pub max_iters: usize,
    /// Minimum number of seeding cells along each parameter direction (default 16).
    pub min_cells: usize,
    /// Minimum number of seeding cells per patch (arc) along each direction (default 2).
    pub cells_per_patch: usize,
    /// Maximum number of Newton starts per point (default 16).
    pub max_starts: usize,
}

impl Default for ProjectOptions {
    fn default() -> Self {
        Self {
            rel_tol: 1e-12,
            length_scale: None,
            max_iters: 50,
            min_cells: 16,
            cells_per_patch: 2,
            max_starts: 16,
        }
    }
}

impl ProjectOptions {
    /// Sets the length scale (model size).
    pub fn with_length_scale(mut self, l: f64) -> Self {
        self.length_scale = Some(l);
        self
    }
    /// Sets the relative tolerance.
    pub fn with_rel_tol(mut self, t: f64) -> Self {
        self.rel_tol = t;
        self
    }
    /// Sets the maximum number of Newton starts per point.
    pub fn with_max_starts(mut self, n: usize) -> Self {
        self.max_starts = n;
        self
    }
    /// Sets the minimum number of seeding cells per direction.
    pub fn with_min_cells(mut self, n: usize) -> Self {
        self.min_cells = n;
        self
    }
}

/// Cell subdivision of the intervals given by `edges`: at least `per` cells per interval and
/// at least `min_total` cells overall.
fn cell_edges(edges: &[f64], per: usize, min_total: usize) -> Vec<f64> {
    let n = edges.len() - 1;
    let k = per.max(1).max(min_total.div_ceil(n));
    let mut out = Vec::with_capacity(n * k + 1);
    for w in edges.windows(2) {
        for j in 0..k {
            out.push(w[0] + (w[1] - w[0]) * j as f64 / k as f64);
        }
    }
    out.push(edges[n]);
    out
}

struct SurfCell {
    rect: [f64; 4],
    first_sample: u32,
    /// Oriented box: centre, axes (r_u, n × r_u, n at the centre) and extents per axis.
    obb_c: Point3,
    obb_axes: [Vector3; 3],
    obb_lo: [f64; 3],
    obb_hi: [f64; 3],
}

impl SurfCell {
    /// Squared distance from p to the oriented box (a lower bound of the distance to the
    /// surface inside the cell, as the axis-aligned box is).
    fn obb_dist2(&self, p: &Point3) -> f64 {
        let d = p - self.obb_c;
        let mut s = 0.0;
        for k in 0..3 {
            let x = d.dot(&self.obb_axes[k]);
            let e = (self.obb_lo[k] - x).max(x - self.obb_hi[k]).max(0.0);
            s += e * e;
        }
        s
    }
}

/// Foot-of-the-normal search on one surface: the seeding hierarchy is built once (it depends
/// only on the surface) and reused for every point. With a length scale in the options it is
/// built at the first global search, so a projector used only for local Newton
/// ([`SurfaceProjector::project_from`]) never pays for it.
pub struct SurfaceProjector<'a, S: ParamSurface + ?Sized> {
    /// geom-db's point inversion: label, surface, patch edges and the local Newton.
    inv: SurfaceInverter<'a, S>,
    seeds: OnceLock<SurfSeeds>,
    scale: f64,
    tol: f64,
    opts: ProjectOptions,
}

/// The seeding hierarchy of a surface: cells of its parameter domain with their samples and
/// bounding boxes in a BVH.
struct SurfSeeds {
    cells: Vec<SurfCell>,
    samples: Vec<(Point3, [f64; 2])>,
    bvh: Bvh,
}

const SAMPLES_PER_CELL: usize = 9;

fn check_domain(label: &str, lo: f64, hi: f64, what: &str) -> Result<()> {
    if !(lo.is_finite() && hi.is_finite() && hi > lo) {
        return Err(Error::BadEntity {
            entity: label.to_string(),
            reason: format!("empty or non-finite {what} domain [{lo}, {hi}]"),
        });
    }
    Ok(())
}

/// geom-db's inversion options from the search's options and the length scale.
fn invert_options(opts: &ProjectOptions, scale: f64) -> InvertOptions {
    InvertOptions {
        rel_tol: opts.rel_tol,
        length_scale: scale,
        max_iters: opts.max_iters,
        ..InvertOptions::new(scale)
    }
}

fn non_finite(label: &str, what: &str) -> Error {
    Error::BadEntity {
        entity: label.to_string(),
        reason: format!("non-finite evaluation at {what}"),
    }
}

impl<'a, S: ParamSurface + ?Sized> SurfaceProjector<'a, S> {
    /// Builds the seeding hierarchy of `surf`; `label` names the surface in errors.
    pub fn new(label: impl Into<String>, surf: &'a S, opts: &ProjectOptions) -> Result<Self> {
        let label = label.into();
        let (du, dv) = surf.domain();
        check_domain(&label, du[0], du[1], "u")?;
        check_domain(&label, dv[0], dv[1], "v")?;
        let mut pr = Self {
            // the tolerance is set below, once the length scale is known
            inv: SurfaceInverter::new(label, surf, &invert_options(opts, 1.0))?,
            seeds: OnceLock::new(),
            scale: 0.0,
            tol: 0.0,
            opts: opts.clone(),
        };
        // Without a given length scale the hierarchy (whose size gives it) is built now.
        let scale = match opts.length_scale {
            Some(l) => l.max(f64::MIN_POSITIVE),
            None => {
                let (seeds, scale) = pr.build_seeds(None)?;
                let _ = pr.seeds.set(seeds);
                scale
            }
        };
        pr.scale = scale;
        pr.tol = opts.rel_tol * scale;
        pr.inv = SurfaceInverter::new(
            pr.inv.label().to_string(),
            surf,
            &invert_options(opts, scale),
        )?;
        Ok(pr)
    }

    /// The seeding hierarchy, built at the first call.
    fn seeds(&self) -> Result<&SurfSeeds> {
        if let Some(s) = self.seeds.get() {
            return Ok(s);
        }
        let (s, _) = self.build_seeds(Some(self.scale))?;
        Ok(self.seeds.get_or_init(|| s))
    }

    /// Builds the seeding hierarchy; `scale`: the length scale (None: the diagonal of the
    /// surface's samples, returned with the hierarchy).
    fn build_seeds(&self, scale: Option<f64>) -> Result<(SurfSeeds, f64)> {
        let (surf, opts, label) = (self.inv.surface(), &self.opts, self.inv.label());
        let [eu, ev] = self.inv.edges();
        let cu = cell_edges(eu, opts.cells_per_patch, opts.min_cells);
        let cv = cell_edges(ev, opts.cells_per_patch, opts.min_cells);
        let nc = (cu.len() - 1) * (cv.len() - 1);
        let mut cells = Vec::with_capacity(nc);
        let mut samples = Vec::with_capacity(nc * SAMPLES_PER_CELL);
        let mut boxes = Vec::with_capacity(nc);
        let mut all = Aabb::EMPTY;
        for j in 0..cv.len() - 1 {
            for i in 0..cu.len() - 1 {
                let rect = [cu[i], cu[i + 1], cv[j], cv[j + 1]];
                let first = samples.len() as u32;
                let mut b = Aabb::EMPTY;
                let (mut muu, mut mvv) = (0.0f64, 0.0f64);
                for b2 in 0..3 {
                    for a in 0..3 {
                        let u = rect[0] + (rect[1] - rect[0]) * a as f64 * 0.5;
                        let v = rect[2] + (rect[3] - rect[2]) * b2 as f64 * 0.5;
                        let d = surf.derivs(u, v);
                        if !(d.point.iter().all(|c| c.is_finite())) {
                            return Err(non_finite(label, &format!("(u, v) = ({u}, {v})")));
                        }
                        b.add(&d.point);
                        muu = muu.max(d.duu.norm());
                        mvv = mvv.max(d.dvv.norm());
                        samples.push((d.point, [u, v]));
                    }
                }
                let (hu, hv) = (rect[1] - rect[0], rect[3] - rect[2]);
                let infl = 1.5 * (hu * hu / 8.0 * muu + hv * hv / 8.0 * mvv);
                all = all.union(&b);
                boxes.push(b.inflated(infl));
                // oriented box in the frame of the centre sample (world axes where singular)
                let dc = surf.derivs(0.5 * (rect[0] + rect[1]), 0.5 * (rect[2] + rect[3]));
                let axes = match (dc.unit_normal(), dc.du.try_normalize(0.0)) {
                    (Some(n), Some(e1)) => [e1, n.cross(&e1), n],
                    _ => [Vector3::x(), Vector3::y(), Vector3::z()],
                };
                let mut lo = [f64::INFINITY; 3];
                let mut hi = [f64::NEG_INFINITY; 3];
                for (q, _) in &samples[first as usize..] {
                    let d = q - dc.point;
                    for k in 0..3 {
                        let x = d.dot(&axes[k]);
                        lo[k] = lo[k].min(x - infl);
                        hi[k] = hi[k].max(x + infl);
                    }
                }
                cells.push(SurfCell {
                    rect,
                    first_sample: first,
                    obb_c: dc.point,
                    obb_axes: axes,
                    obb_lo: lo,
                    obb_hi: hi,
                });
            }
        }
        let scale = scale.unwrap_or(all.diagonal()).max(f64::MIN_POSITIVE);
        // boxes also grow by a small fraction of the scale so that flat cells have volume
        let boxes = boxes
            .into_iter()
            .map(|b| b.inflated(1e-9 * scale))
            .collect();
        for c in &mut cells {
            for k in 0..3 {
                c.obb_lo[k] -= 1e-9 * scale;
                c.obb_hi[k] += 1e-9 * scale;
            }
        }
        let seeds = SurfSeeds {
            cells,
            samples,
            bvh: Bvh::new(boxes),
        };
        Ok((seeds, scale))
    }

    /// The surface's label.
    pub fn label(&self) -> &str {
        self.inv.label()
    }

    /// The surface.
    pub fn surface(&self) -> &'a S {
        self.inv.surface()
    }

    /// The length scale used for tolerances.
    pub fn length_scale(&self) -> f64 {
        self.scale
    }

    /// The absolute convergence tolerance (length units).
    pub fn tolerance(&self) -> f64 {
        self.tol
    }

    /// The patch (interval of the breaks) containing (u, v).
    pub fn patch_of(&self, uv: [f64; 2]) -> [usize; 2] {
        self.inv.patch_of(uv)
    }

    /// Local Newton on Eq. (11) from the parameters `uv0` only (no global search): a warm
    /// start for points known to be near `uv0` (geom-db's
    /// [`SurfaceInverter::foot_from`]). The report says whether it converged.
    pub fn project_from(&self, p: &Point3, uv0: [f64; 2]) -> SurfaceFoot {
        self.inv.foot_from(p, uv0)
    }

    fn nearest_sample(seeds: &SurfSeeds, cell: usize, p: &Point3) -> (f64, [f64; 2]) {
        let c = &seeds.cells[cell];
        let s0 = c.first_sample as usize;
        let mut best = (f64::INFINITY, [c.rect[0], c.rect[2]]);
        for (q, uv) in &seeds.samples[s0..s0 + SAMPLES_PER_CELL] {
            let d = (q - p).norm_squared();
            if d < best.0 {
                best = (d, *uv);
            }
        }
        best
    }

    /// The global foot of the normal from `p` (Eq. 11); `index` names the point in errors.
    pub fn project_indexed(&self, p: &Point3, index: usize) -> Result<SurfaceFoot> {
        self.search(p, index, f64::INFINITY)?
            .ok_or_else(|| Error::ProjectionFailed {
                entity: self.label().to_string(),
                index,
                iters: 0,
                residual: f64::INFINITY,
                tol: self.tol,
            })
    }

    /// The global search; cells whose lower bound exceeds `upper` (a distance already
    /// achieved elsewhere) are skipped, and `None` means every cell was.
    fn search(&self, p: &Point3, index: usize, upper: f64) -> Result<Option<SurfaceFoot>> {
        if !p.iter().all(|c| c.is_finite()) {
            return Err(Error::NonFinitePoint {
                entity: self.label().to_string(),
                index,
            });
        }
        let seeds = self.seeds()?;
        let nearest = |cell: usize| Self::nearest_sample(seeds, cell, p);
        let mut cands = Vec::new();
        let init = if upper.is_finite() {
            let u = upper + 2.0 * self.tol;
            u * u
        } else {
            f64::INFINITY
        };
        seeds.bvh.candidates(
            p,
            init,
            |i, d| d.max(seeds.cells[i].obb_dist2(p)),
            |i| nearest(i).0,
            &mut cands,
        );
        if cands.is_empty() && upper.is_finite() {
            return Ok(None);
        }
        // the cell with the nearest sample first (the likeliest basin of the global foot),
        // then by increasing lower bound
        if let Some(k) = (0..cands.len()).min_by(|&a, &b| {
            let da = nearest(cands[a].1 as usize).0;
            let db = nearest(cands[b].1 as usize).0;
            da.total_cmp(&db).then(a.cmp(&b))
        }) {
            let c = cands.remove(k);
            cands.insert(0, c);
        }
        let mut best: Option<SurfaceFoot> = None;
        let mut worst_fail: Option<SurfaceFoot> = None;
        let mut found: Vec<[f64; 2]> = Vec::new();
        let mut started: Vec<[f64; 2]> = Vec::new();
        let mut starts = 0;
        for &(lb, cell) in &cands {
            if starts >= self.opts.max_starts {
                break;
            }
            if let Some(b) = &best {
                let slack = 2.0 * self.tol + 1e-12 * b.distance;
                let bd = b.distance + slack;
                if lb > bd * bd {
                    break;
                }
            }
            // a cell within one cell of a foot already found would lead Newton back to it
            let r = &seeds.cells[cell as usize].rect;
            let (wu, wv) = (r[1] - r[0], r[3] - r[2]);
            if found.iter().any(|uv: &[f64; 2]| {
                uv[0] >= r[0] - wu && uv[0] <= r[1] + wu && uv[1] >= r[2] - wv && uv[1] <= r[3] + wv
            }) {
                continue;
            }
            let (_, uv0) = nearest(cell as usize);
            // neighbouring cells share their border samples: the same start, the same foot
            if started.contains(&uv0) {
                continue;
            }
            started.push(uv0);
            starts += 1;
            let f = self.project_from(p, uv0);
            if f.report.converged {
                found.push(f.uv);
            }
            if f.report.converged {
                if best.is_none_or(|b| f.distance < b.distance) {
                    best = Some(f);
                }
            } else if worst_fail.is_none_or(|w| f.distance < w.distance) {
                worst_fail = Some(f);
            }
        }
        match best {
            Some(mut b) => {
                b.starts = starts;
                Ok(Some(b))
            }
            None => {
                let w = worst_fail.unwrap_or(SurfaceFoot {
                    uv: [f64::NAN; 2],
                    patch: [0, 0],
                    point: [f64::NAN; 3],
                    distance: f64::NAN,
                    on_boundary: false,
                    report: geom_db::newton::NewtonReport {
                        converged: false,
                        iterations: 0,
                        residual: f64::INFINITY,
                        tolerance: self.tol,
                    },
                    starts,
                });
                Err(Error::ProjectionFailed {
                    entity: self.label().to_string(),
                    index,
                    iters: w.report.iterations,
                    residual: w.report.residual,
                    tol: self.tol,
                })
            }
        }
    }

    /// The global foot of the normal from `p` (Eq. 11).
    pub fn project(&self, p: &Point3) -> Result<SurfaceFoot> {
        self.project_indexed(p, 0)
    }

    /// Feet of many points, in parallel (rayon); the result is the same for any thread count.
    pub fn project_many(&self, points: &[Point3]) -> Vec<Result<SurfaceFoot>> {
        points
            .par_iter()
            .enumerate()
            .map(|(i, p)| self.project_indexed(p, i))
            .collect()
    }

    /// Feet of many points; the first failure (lowest index) is returned as the error.
    pub fn project_all(&self, points: &[Point3]) -> Result<Vec<SurfaceFoot>> {
        self.project_many(points).into_iter().collect()
    }
}

struct CurveCell {
    span: [f64; 2],
    first_sample: u32,
}

const CURVE_SAMPLES_PER_CELL: usize = 3;

/// Foot-of-the-normal search on one curve (the 1-D analogue of [`SurfaceProjector`]).
pub struct CurveProjector<'a, C: ParamCurve + ?Sized> {
    /// geom-db's point inversion: label, curve, arc edges and the local Newton.
    inv: CurveInverter<'a, C>,
    cells: Vec<CurveCell>,
    samples: Vec<(Point3, f64)>,
    bvh: Bvh,
    scale: f64,
    tol: f64,
    opts: ProjectOptions,
}

impl<'a, C: ParamCurve + ?Sized> CurveProjector<'a, C> {
    /// Builds the seeding hierarchy of `curve`; `label` names the curve in errors.
    pub fn new(label: impl Into<String>, curve: &'a C, opts: &ProjectOptions) -> Result<Self> {
        let label = label.into();
        let (lo, hi) = curve.domain();
        check_domain(&label, lo, hi, "t")?;
        let edges = interval_edges(lo, hi, &curve.breaks());
        let ce = cell_edges(&edges, opts.cells_per_patch.max(4), opts.min_cells * 2);
        let mut cells = Vec::with_capacity(ce.len() - 1);
        let mut samples = Vec::with_capacity(3 * (ce.len() - 1));
        let mut boxes = Vec::with_capacity(ce.len() - 1);
        let mut all = Aabb::EMPTY;
        for w in ce.windows(2) {
            let first = samples.len() as u32;
            let mut b = Aabb::EMPTY;
            let mut m2 = 0.0f64;
            for a in 0..3 {
                let t = w[0] + (w[1] - w[0]) * a as f64 * 0.5;
                let d = curve.derivs(t);
                if !d.point.iter().all(|c| c.is_finite()) {
                    return Err(non_finite(&label, &format!("t = {t}")));
                }
                b.add(&d.point);
                m2 = m2.max(d.d2.norm());
                samples.push((d.point, t));
            }
            let h = w[1] - w[0];
            all = all.union(&b);
            boxes.push(b.inflated(1.5 * h * h / 8.0 * m2));
            cells.push(CurveCell {
                span: [w[0], w[1]],
                first_sample: first,
            });
        }
        let scale = opts
            .length_scale
            .unwrap_or(all.diagonal())
            .max(f64::MIN_POSITIVE);
        let boxes = boxes
            .into_iter()
            .map(|b| b.inflated(1e-9 * scale))
            .collect();
        Ok(Self {
            inv: CurveInverter::new(label, curve, &invert_options(opts, scale))?,
            cells,
            samples,
            bvh: Bvh::new(boxes),
            scale,
            tol: opts.rel_tol * scale,
            opts: opts.clone(),
        })
    }

    /// The curve's label.
    pub fn label(&self) -> &str {
        self.inv.label()
    }

    /// The curve.
    pub fn curve(&self) -> &'a C {
        self.inv.curve()
    }

    /// The length scale used for tolerances.
    pub fn length_scale(&self) -> f64 {
        self.scale
    }

    /// Local Newton on the curve analogue of Eq. (11), (p − r(t))·r'(t) = 0, from `t0`
    /// (geom-db's [`CurveInverter::foot_from`]).
    pub fn project_from(&self, p: &Point3, t0: f64) -> CurveFoot {
        self.inv.foot_from(p, t0)
    }

    fn nearest_sample(&self, cell: usize, p: &Point3) -> (f64, f64) {
        let c = &self.cells[cell];
        let s0 = c.first_sample as usize;
        let mut best = (f64::INFINITY, c.span[0]);
        for (q, t) in &self.samples[s0..s0 + CURVE_SAMPLES_PER_CELL] {
            let d = (q - p).norm_squared();
            if d < best.0 {
                best = (d, *t);
            }
        }
        best
    }

    /// The global foot of the normal from `p` on the curve; `index` names the point in errors.
    pub fn project_indexed(&self, p: &Point3, index: usize) -> Result<CurveFoot> {
        if !p.iter().all(|c| c.is_finite()) {
            return Err(Error::NonFinitePoint {
                entity: self.label().to_string(),
                index,
            });
        }
        let mut cands = Vec::new();
        self.bvh.candidates(
            p,
            f64::INFINITY,
            |_, d| d,
            |i| self.nearest_sample(i, p).0,
            &mut cands,
        );
        let mut best: Option<CurveFoot> = None;
        let mut fail: Option<CurveFoot> = None;
        let mut starts = 0;
        for &(lb, cell) in &cands {
            if starts >= self.opts.max_starts {
                break;
            }
            if let Some(b) = &best {
                let bd = b.distance + 2.0 * self.tol + 1e-12 * b.distance;
                if lb > bd * bd {
                    break;
                }
            }
            let (_, t0) = self.nearest_sample(cell as usize, p);
            starts += 1;
            let f = self.project_from(p, t0);
            if f.report.converged {
                if best.is_none_or(|b| f.distance < b.distance) {
                    best = Some(f);
                }
            } else if fail.is_none_or(|w| f.distance < w.distance) {
                fail = Some(f);
            }
        }
        match best {
            Some(mut b) => {
                b.starts = starts;
                Ok(b)
            }
            None => Err(Error::ProjectionFailed {
                entity: self.label().to_string(),
                index,
                iters: fail.map_or(0, |f| f.report.iterations),
                residual: fail.map_or(f64::INFINITY, |f| f.report.residual),
                tol: self.tol,
            }),
        }
    }

    /// The global foot of the normal from `p` on the curve.
    pub fn project(&self, p: &Point3) -> Result<CurveFoot> {
        self.project_indexed(p, 0)
    }

    /// Feet of many points, in parallel; identical for any thread count.
    pub fn project_many(&self, points: &[Point3]) -> Vec<Result<CurveFoot>> {
        points
            .par_iter()
            .enumerate()
            .map(|(i, p)| self.project_indexed(p, i))
            .collect()
    }
}

/// The foot of the normal on the nearest surface of a set.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SetFoot {
    /// Index of the surface in the set.
    pub surface: usize,
    /// The foot on that surface.
    pub foot: SurfaceFoot,
}

/// Foot of the normal on the nearest of several surfaces (e.g. classifying the boundary nodes
/// of an imported grid on a model's support surfaces). Surfaces are visited by increasing
/// distance of their bounding box; one whose box is farther than the best foot found is
/// skipped. Ties go to the lower surface index.
pub struct SurfaceSetProjector<'a, S: ParamSurface + ?Sized> {
    projs: Vec<SurfaceProjector<'a, S>>,
}

impl<'a, S: ParamSurface + ?Sized> SurfaceSetProjector<'a, S> {
    /// Builds one [`SurfaceProjector`] per `(label, surface)`.
    pub fn new(surfaces: &[(String, &'a S)], opts: &ProjectOptions) -> Result<Self> {
        let projs = surfaces
            .iter()
            .map(|(l, s)| SurfaceProjector::new(l.clone(), *s, opts))
            .collect::<Result<Vec<_>>>()?;
        Ok(Self { projs })
    }

    /// The per-surface projectors.
    pub fn projectors(&self) -> &[SurfaceProjector<'a, S>] {
        &self.projs
    }

    /// The foot on the nearest surface; `index` names the point in errors. A surface whose
    /// search fails (no Newton start converged) is an error: its true foot could be nearer.
    pub fn project_indexed(&self, p: &Point3, index: usize) -> Result<SetFoot> {
        let mut order = Vec::with_capacity(self.projs.len());
        for (i, pr) in self.projs.iter().enumerate() {
            order.push((pr.seeds()?.bvh.root_box().dist2(p), i));
        }
        order.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let mut best: Option<SetFoot> = None;
        for (lb, i) in order {
            if let Some(b) = &best {
                let bd = b.foot.distance * (1.0 + 1e-12) + self.projs[i].tol;
                if lb > bd * bd {
                    break;
                }
            }
            let upper = best.map_or(f64::INFINITY, |b| b.foot.distance);
            let Some(f) = self.projs[i].search(p, index, upper)? else {
                continue;
            };
            if best.is_none_or(|b| f.distance < b.foot.distance) {
                best = Some(SetFoot {
                    surface: i,
                    foot: f,
                });
            }
        }
        best.ok_or_else(|| Error::BadEntity {
            entity: "surface set".into(),
            reason: "no surfaces".into(),
        })
    }

    /// Feet of many points in parallel (rayon); identical for any thread count.
    pub fn project_many(&self, points: &[Point3]) -> Vec<Result<SetFoot>> {
        points
            .par_iter()
            .enumerate()
            .map(|(i, p)| self.project_indexed(p, i))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn intervals_and_edges() {
        let e = interval_edges(0.0, 3.0, &[2.0, 1.0, 1.0, 5.0]);
        assert_eq!(e, vec![0.0, 1.0, 2.0, 3.0]);
        assert_eq!(interval_of(&e, 0.0), 0);
        assert_eq!(interval_of(&e, 1.0), 1);
        assert_eq!(interval_of(&e, 2.999), 2);
        assert_eq!(interval_of(&e, 3.0), 2);
        let c = cell_edges(&e, 2, 16);
        assert_eq!(c.len(), 3 * 6 + 1);
        assert_eq!(*c.last().unwrap(), 3.0);
    }
}
