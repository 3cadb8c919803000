//! Support-curve update by surface–surface intersection (§3.1, Eqs. 11–12).
//!
//! A support curve is the intersection of its two defining surfaces r₁ and r₂. It is defined
//! by control points (Eq. 4 gives the arcs through them). When the surfaces change, the curve
//! is re-solved point by point:
//!
//! 1. **Seeding, on the initial model** ([`IntersectionSeeds::new`]): for each control point
//!    pᵢ, its parameters (u₁, v₁) on r₁ and (u₂, v₂) on r₂ are the feet of the normal (Eq. 11,
//!    [`crate::project`]). The gaps |pᵢ − r_j| are checked against the allowed gap. The curve
//!    tangent tᵢ (given, or n₁ × n₂) is stored too.
//! 2. **Update, on the modified surfaces** ([`update_curve_points`]): Newton on
//!
//!    ```text
//!    r₁(u₁, v₁) − r₂(u₂, v₂⁰) = 0                                     (Eq. 12)
//!    ```
//!
//!    three equations in three unknowns, one parameter being *frozen* at its initial value.
//!    **What is frozen and why.** Three equations fix a point of a curve only if one degree of
//!    freedom along the curve is removed: freezing v₂ = v₂⁰ restricts the point to the
//!    iso-parametric line v₂ = v₂⁰ of surface 2, which crosses the curve, so the control point
//!    keeps its place *along* the curve (same station in surface 2's parametrisation) while it
//!    moves *across* to the new intersection. The 3 × 3 Jacobian J = [∂r₁/∂u₁, ∂r₁/∂v₁,
//!    −∂r₂/∂u₂] has det J = (r₁,u × r₁,v)·r₂,u, so it is well conditioned when the free
//!    direction of surface 2 is transversal to surface 1, i.e. transversal to the curve. We
//!    therefore choose, per point, which parameter of surface 2 to freeze: the one whose
//!    complementary direction has the larger sine |n₁ · r₂,w| / |r₂,w| (v₂ on ties, as in the
//!    paper). Only when both sines of surface 2 are below 0.1 (the curve runs almost along both
//!    of its iso-lines, a degenerate parametrisation) are the parameters of surface 1 considered
//!    too, with the roles of the surfaces exchanged. The frozen problem (½|r₁ − r₂|² in the
//!    three free parameters, Gauss–Newton) and the sines are geom-db's
//!    ([`geom_db::newton::pair`]), shared with the import's junction rebuild.
//! 3. **Fallback.** If the frozen parameter gives no solution (the Jacobian is singular at the
//!    start — sine below 1e-6 — or Newton does not reach |r₁ − r₂| ≤ tol, e.g. because the
//!    iso-line no longer meets the other surface inside its domain), the point is re-solved as
//!    the point of the new intersection in the *normal plane* of the old point:
//!
//!    ```text
//!    r₁(u₁, v₁) − r₂(u₂, v₂) = 0,   (r₁(u₁, v₁) − pᵢ) · tᵢ = 0
//!    ```
//!
//!    four equations in the four parameters (Gauss–Newton with the same safeguards). To first
//!    order it is the point of the new intersection closest to the old control point. The
//!    report says which method was used ([`Method`]).
//!
//! The new point is the midpoint of r₁ and r₂ at the solution (they agree within the
//! tolerance). Control points are independent, so they are solved in parallel; the result is
//! identical for any number of threads.

use crate::error::{Error, Result};
use crate::project::{ProjectOptions, SurfaceProjector};
use geom_db::eval::ParamSurface;
use geom_db::newton::pair::{Frozen, free_sines};
use geom_db::newton::{self, Eval, Problem, Settings};
use geom_db::prelude::{Point3, Vector3};
use nalgebra::{SMatrix, SVector};
use rayon::prelude::*;

/// Knobs of the curve update.
#[derive(Debug, Clone, PartialEq)]
pub struct SsiOptions {
    /// Length scale (model size). `None`: the larger sampled diagonal of the two surfaces.
    pub length_scale: Option<f64>,
    /// Newton tolerance on |r₁ − r₂| relative to the length scale (default 1e-10, the
    /// model's Newton tolerance; a converged Newton takes one more polishing step, so the
    /// residual is usually at round-off). Where two surfaces only meet along their borders
    /// with a small gap (edges that coincide within the model tolerance) the residual cannot
    /// go below the gap; this is why the default is not tighter.
    pub rel_tol: f64,
    /// Largest allowed distance of an initial control point from a defining surface,
    /// relative to the length scale (default 1e-6).
    pub max_initial_gap_rel: f64,
    /// Newton iterations per method (default 50).
    pub max_iters: usize,
    /// Options of the seeding projections.
    pub project: ProjectOptions,
}

impl Default for SsiOptions {
    fn default() -> Self {
        Self {
            length_scale: None,
            rel_tol: 1e-10,
            max_initial_gap_rel: 1e-6,
            max_iters: 50,
            project: ProjectOptions::default(),
        }
    }
}

impl SsiOptions {
    /// Sets the length scale (also for the seeding projections).
    pub fn with_length_scale(mut self, l: f64) -> Self {
        self.length_scale = Some(l);
        self.project.length_scale = Some(l);
        self
    }
    /// Sets the allowed initial gap (relative to the length scale).
    pub fn with_max_initial_gap_rel(mut self, g: f64) -> Self {
        self.max_initial_gap_rel = g;
        self
    }
}

/// A surface parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Param {
    /// u.
    U,
    /// v.
    V,
}

/// How a control point was re-solved.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Method {
    /// Eq. (12) with one parameter frozen at its initial value.
    Frozen {
        /// 1 or 2: the surface whose parameter is frozen.
        surface: u8,
        /// The frozen parameter.
        param: Param,
    },
    /// The fallback: the new intersection point in the normal plane of the old point.
    NormalPlane,
}

/// One control point of the initial model with its parameters on the defining surfaces.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SeedPoint {
    /// The initial control point pᵢ.
    pub point: [f64; 3],
    /// Its foot on surface 1 (Eq. 11).
    pub uv1: [f64; 2],
    /// Its foot on surface 2 (Eq. 11).
    pub uv2: [f64; 2],
    /// Unit curve tangent at pᵢ (given or n₁ × n₂).
    pub tangent: [f64; 3],
    /// Distances of pᵢ from surfaces 1 and 2.
    pub gap: [f64; 2],
    /// The parameter frozen in Eq. (12) for this point (chosen on the initial model).
    pub frozen: Method,
}

/// What the update needs from the initial model: one [`SeedPoint`] per control point.
/// Depends only on the baseline, so it is computed once and reused for every design step.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct IntersectionSeeds {
    /// The support curve's label.
    pub curve: String,
    /// Per control point.
    pub points: Vec<SeedPoint>,
    /// Length scale of the tolerances.
    pub length_scale: f64,
}

fn v3(p: [f64; 3]) -> Vector3 {
    Vector3::new(p[0], p[1], p[2])
}

impl IntersectionSeeds {
    /// Seeds the control points `points` of `curve` on its initial defining surfaces
    /// (Eq. 11). `tangents`, if given, are the curve tangents at the points (they are needed
    /// where the surfaces are tangent); otherwise n₁ × n₂ is used and tangent surfaces are an
    /// error. `arcs`, if given, are the degrees of the curve's arcs, the points being chained
    /// arc by arc (shared ends once) at the database's control-point nodes
    /// ([`geom_db::control::nodes`]): the frozen parameter is then chosen per arc, else per
    /// point (see the module documentation).
    pub fn new<S1, S2>(
        curve: impl Into<String>,
        points: &[Point3],
        tangents: Option<&[Vector3]>,
        arcs: Option<&[usize]>,
        s1: &SurfaceProjector<'_, S1>,
        s2: &SurfaceProjector<'_, S2>,
        opts: &SsiOptions,
    ) -> Result<Self>
    where
        S1: ParamSurface + ?Sized,
        S2: ParamSurface + ?Sized,
    {
        let curve = curve.into();
        let scale = opts
            .length_scale
            .unwrap_or(s1.length_scale().max(s2.length_scale()));
        let max_gap = opts.max_initial_gap_rel * scale;
        if let Some(t) = tangents
            && t.len() != points.len()
        {
            return Err(Error::BadEntity {
                entity: curve,
                reason: format!("{} tangents for {} control points", t.len(), points.len()),
            });
        }
        let seeds: Vec<Result<SeedPoint>> = points
            .par_iter()
            .enumerate()
            .map(|(i, p)| {
                if !p.iter().all(|c| c.is_finite()) {
                    return Err(Error::NonFinitePoint {
                        entity: curve.clone(),
                        index: i,
                    });
                }
                let f1 = s1.project_indexed(p, i)?;
                let f2 = s2.project_indexed(p, i)?;
                for (k, (f, s)) in [(f1.distance, s1.label()), (f2.distance, s2.label())]
                    .into_iter()
                    .enumerate()
                {
                    if f > max_gap {
                        return Err(Error::InitialGap {
                            curve: curve.clone(),
                            point: i,
                            surface: k + 1,
                            surface_label: s.to_string(),
                            gap: f,
                            tol: max_gap,
                        });
                    }
                }
                let t = match tangents {
                    Some(t) => {
                        let n = t[i].norm();
                        if !(n > 0.0 && n.is_finite()) {
                            return Err(Error::BadEntity {
                                entity: curve.clone(),
                                reason: format!("tangent {i} is zero or not finite"),
                            });
                        }
                        t[i] / n
                    }
                    None => {
                        let d1 = s1.surface().derivs(f1.uv[0], f1.uv[1]);
                        let d2 = s2.surface().derivs(f2.uv[0], f2.uv[1]);
                        let n1 = d1.du.cross(&d1.dv);
                        let n2 = d2.du.cross(&d2.dv);
                        let c = n1.normalize().cross(&n2.normalize());
                        let sine = c.norm();
                        if sine.is_nan() || sine <= 1e-8 {
                            return Err(Error::TangentSurfaces {
                                curve: curve.clone(),
                                point: i,
                                sine,
                            });
                        }
                        c / sine
                    }
                };
                Ok(SeedPoint {
                    point: [p.x, p.y, p.z],
                    uv1: f1.uv,
                    uv2: f2.uv,
                    tangent: [t.x, t.y, t.z],
                    gap: [f1.distance, f2.distance],
                    frozen: Method::NormalPlane,
                })
            })
            .collect();
        let mut points = seeds.into_iter().collect::<Result<Vec<_>>>()?;
        // continuity along the curve: where a local Newton from the previous point's
        // parameters finds a foot within the allowed gap, take it (on a closed surface the
        // global search may return the other side of a seam, e.g. u = 0 for u = 4)
        for i in 1..points.len() {
            let p = Point3::from(points[i].point);
            let (prev1, prev2) = (points[i - 1].uv1, points[i - 1].uv2);
            let l1 = s1.project_from(&p, prev1);
            if l1.report.converged && l1.distance <= max_gap {
                points[i].uv1 = l1.uv;
            }
            let l2 = s2.project_from(&p, prev2);
            if l2.report.converged && l2.distance <= max_gap {
                points[i].uv2 = l2.uv;
            }
        }
        // the frozen parameter of each point, on the initial surfaces
        let ys: Vec<[f64; 4]> = points
            .iter()
            .map(|p| [p.uv1[0], p.uv1[1], p.uv2[0], p.uv2[1]])
            .collect();
        let sines: Vec<[f64; 4]> = ys
            .iter()
            .map(|y| free_sines(s1.surface(), s2.surface(), y))
            .collect();
        let mut frozen: Vec<usize> = sines.iter().map(choose_point).collect();
        if let Some(degrees) = arcs {
            let total: usize = degrees.iter().sum();
            if total + 1 != points.len() || degrees.contains(&0) {
                return Err(Error::BadEntity {
                    entity: curve,
                    reason: format!(
                        "arcs of degrees {degrees:?} need {} chained control points, {} given",
                        total + 1,
                        points.len()
                    ),
                });
            }
            let mut k0 = 0;
            for (a, &n) in degrees.iter().enumerate() {
                let x = geom_db::control::nodes(n);
                let k = choose_arc(&sines[k0..=k0 + n], &ys[k0..=k0 + n], x);
                let first = if a == 0 { k0 } else { k0 + 1 };
                for f in &mut frozen[first..=k0 + n] {
                    *f = k;
                }
                k0 += n;
            }
        }
        // a point on a domain border of a surface (a curve ending on a surface's edge, e.g.
        // a junction at a wing trailing edge) keeps that parameter: it stays on the edge
        let (d1u, d1v) = s1.surface().domain();
        let (d2u, d2v) = s2.surface().domain();
        let lo = [d1u[0], d1v[0], d2u[0], d2v[0]];
        let hi = [d1u[1], d1v[1], d2u[1], d2v[1]];
        for ((f, y), sn) in frozen.iter_mut().zip(&ys).zip(&sines) {
            for &k in &PREFERENCE {
                let w = hi[k] - lo[k];
                let on_border =
                    (y[k] - lo[k]).abs() <= 1e-12 * w || (hi[k] - y[k]).abs() <= 1e-12 * w;
                if on_border && sn[k] >= 1e-3 {
                    *f = k;
                    break;
                }
            }
        }
        for (p, f) in points.iter_mut().zip(frozen) {
            p.frozen = method_of(f);
        }
        Ok(Self {
            curve,
            points,
            length_scale: scale,
        })
    }
}

/// The re-solved control point.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PointUpdate {
    /// New control point (midpoint of r₁ and r₂ at the solution).
    pub point: [f64; 3],
    /// Its parameters on surface 1.
    pub uv1: [f64; 2],
    /// Its parameters on surface 2.
    pub uv2: [f64; 2],
    /// The method that produced it.
    pub method: Method,
    /// The frozen-parameter choice tried first (also when the fallback was used).
    pub frozen: Method,
    /// Newton iterations (both methods added when the fallback ran).
    pub iterations: usize,
    /// |r₁ − r₂| at the solution.
    pub residual: f64,
    /// |new point − old point|.
    pub moved: f64,
}

/// The re-solved control points of a curve with a summary.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CurveUpdate {
    /// The support curve's label.
    pub curve: String,
    /// Per control point.
    pub points: Vec<PointUpdate>,
    /// Largest |r₁ − r₂|.
    pub max_residual: f64,
    /// Largest control-point move.
    pub max_move: f64,
    /// Total Newton iterations.
    pub iterations: usize,
    /// Number of points that needed the normal-plane fallback.
    pub fallbacks: usize,
}

impl CurveUpdate {
    /// The new control points.
    pub fn new_points(&self) -> Vec<Point3> {
        self.points
            .iter()
            .map(|p| Point3::new(p.point[0], p.point[1], p.point[2]))
            .collect()
    }
}

/// The fallback: r₁ − r₂ = 0 and (r₁ − p_old)·t = 0 in the four parameters.
struct NormalPlaneProblem<'s, S1: ?Sized, S2: ?Sized> {
    s1: &'s S1,
    s2: &'s S2,
    p_old: Point3,
    t: Vector3,
}

impl<S1, S2> Problem<4> for NormalPlaneProblem<'_, S1, S2>
where
    S1: ParamSurface + ?Sized,
    S2: ParamSurface + ?Sized,
{
    fn eval(&self, y: &[f64; 4], _active: &[bool; 4]) -> Eval<4> {
        let d1 = self.s1.derivs(y[0], y[1]);
        let d2 = self.s2.derivs(y[2], y[3]);
        let diff = d1.point - d2.point;
        let plane = (d1.point - self.p_old).dot(&self.t);
        let f4 = SVector::<f64, 4>::new(diff.x, diff.y, diff.z, plane);
        let cols = [d1.du, d1.dv, -d2.du, -d2.dv];
        let mut j = SMatrix::<f64, 4, 4>::zeros();
        for (c, col) in cols.iter().enumerate() {
            for r in 0..3 {
                j[(r, c)] = col[r];
            }
        }
        j[(3, 0)] = d1.du.dot(&self.t);
        j[(3, 1)] = d1.dv.dot(&self.t);
        let g = j.transpose() * f4;
        let h = j.transpose() * j;
        let r = f4.norm();
        Eval {
            f: if r.is_finite() {
                0.5 * r * r
            } else {
                f64::INFINITY
            },
            g,
            h,
            res: if r.is_finite() { r } else { f64::INFINITY },
            fnoise: 16.0
                * f64::EPSILON
                * r
                * (d1.point.coords.norm() + d2.point.coords.norm() + self.p_old.coords.norm()),
        }
    }
}

/// Candidates in order of preference: v₂, u₂ (the paper freezes a parameter of surface 2),
/// then v₁, u₁.
const PREFERENCE: [usize; 4] = [3, 2, 1, 0];

/// The per-point choice (see the module documentation).
fn choose_point(sines: &[f64; 4]) -> usize {
    let best2 = if sines[2] > sines[3] { 2 } else { 3 };
    if sines[best2] >= 0.1 {
        return best2;
    }
    let best1 = if sines[0] > sines[1] { 0 } else { 1 };
    if sines[best1] > sines[best2] {
        best1
    } else {
        best2
    }
}

/// The per-arc choice: among the parameters that keep Eq. (12) well conditioned at every
/// control point of the arc (sine ≥ 0.1), the one whose values along the arc are closest to
/// an affine function of the local parameter at the control-point nodes `x` (so the new
/// control points keep the arc's parametrisation smooth); otherwise the best conditioned.
fn choose_arc(sines: &[[f64; 4]], y: &[[f64; 4]], x: &[f64]) -> usize {
    let mut best: Option<(f64, usize)> = None;
    let mut fallback = (f64::NEG_INFINITY, PREFERENCE[0]);
    for &k in &PREFERENCE {
        let smin = sines.iter().map(|s| s[k]).fold(f64::INFINITY, f64::min);
        if smin > fallback.0 {
            fallback = (smin, k);
        }
        if smin < 0.1 {
            continue;
        }
        let (p0, p1) = (y[0][k], y[y.len() - 1][k]);
        let range = p1 - p0;
        if range == 0.0 || !range.is_finite() {
            continue;
        }
        let nonlin = y
            .iter()
            .zip(x)
            .map(|(yi, &xi)| (yi[k] - (p0 + range * xi)).abs())
            .fold(0.0, f64::max)
            / range.abs();
        if best.is_none_or(|b| nonlin < b.0 - 1e-9) {
            best = Some((nonlin, k));
        }
    }
    best.map_or(fallback.1, |b| b.1)
}

fn index_of(m: Method) -> usize {
    match m {
        Method::Frozen {
            surface: 1,
            param: Param::U,
        } => 0,
        Method::Frozen {
            surface: 1,
            param: Param::V,
        } => 1,
        Method::Frozen {
            surface: 2,
            param: Param::U,
        } => 2,
        _ => 3,
    }
}

fn method_of(frozen: usize) -> Method {
    match frozen {
        0 => Method::Frozen {
            surface: 1,
            param: Param::U,
        },
        1 => Method::Frozen {
            surface: 1,
            param: Param::V,
        },
        2 => Method::Frozen {
            surface: 2,
            param: Param::U,
        },
        _ => Method::Frozen {
            surface: 2,
            param: Param::V,
        },
    }
}

/// Re-solves every control point of a curve on the modified surfaces `s1`, `s2` (Eq. 12 with
/// the normal-plane fallback) from its `seeds` on the initial model. Returns the new control
/// points; building the new arcs through them (Eq. 4) is the database's job.
pub fn update_curve_points<S1, S2>(
    seeds: &IntersectionSeeds,
    s1: &S1,
    s2: &S2,
    opts: &SsiOptions,
) -> Result<CurveUpdate>
where
    S1: ParamSurface + ?Sized,
    S2: ParamSurface + ?Sized,
{
    let scale = opts.length_scale.unwrap_or(seeds.length_scale);
    let tol = opts.rel_tol * scale;
    let (d1u, d1v) = s1.domain();
    let (d2u, d2v) = s2.domain();
    let lo = [d1u[0], d1v[0], d2u[0], d2v[0]];
    let hi = [d1u[1], d1v[1], d2u[1], d2v[1]];
    let settings = Settings {
        tol,
        max_iters: opts.max_iters,
    };
    let results: Vec<Result<PointUpdate>> = seeds
        .points
        .par_iter()
        .enumerate()
        .map(|(i, sp)| {
            let y0 = [sp.uv1[0], sp.uv1[1], sp.uv2[0], sp.uv2[1]];
            let p_old = Point3::new(sp.point[0], sp.point[1], sp.point[2]);
            let frozen = index_of(sp.frozen);
            let sine = free_sines(s1, s2, &y0)[frozen];
            let mut frozen_iters = 0;
            let mut frozen_res = f64::INFINITY;
            if sine > 1e-6 {
                let prob = Frozen::new(s1, s2, frozen, y0[frozen]);
                let (y, o) = prob.solve(&y0, &lo, &hi, settings);
                frozen_iters = o.report.iterations;
                frozen_res = o.eval.res;
                if o.report.converged {
                    return Ok(finish(
                        s1,
                        s2,
                        &y,
                        p_old,
                        method_of(frozen),
                        frozen,
                        o.report.iterations,
                    ));
                }
            }
            let prob = NormalPlaneProblem {
                s1,
                s2,
                p_old,
                t: v3(sp.tangent),
            };
            let o = newton::minimise(&prob, y0, &lo, &hi, settings);
            if o.report.converged {
                return Ok(finish(
                    s1,
                    s2,
                    &o.x,
                    p_old,
                    Method::NormalPlane,
                    frozen,
                    frozen_iters + o.report.iterations,
                ));
            }
            Err(Error::CurveUpdateFailed {
                curve: seeds.curve.clone(),
                point: i,
                frozen_iters,
                frozen_residual: frozen_res,
                fallback_iters: o.report.iterations,
                fallback_residual: o.eval.res,
                tol,
            })
        })
        .collect();
    let points = results.into_iter().collect::<Result<Vec<_>>>()?;
    let max_residual = points.iter().map(|p| p.residual).fold(0.0, f64::max);
    let max_move = points.iter().map(|p| p.moved).fold(0.0, f64::max);
    let iterations = points.iter().map(|p| p.iterations).sum();
    let fallbacks = points
        .iter()
        .filter(|p| p.method == Method::NormalPlane)
        .count();
    Ok(CurveUpdate {
        curve: seeds.curve.clone(),
        points,
        max_residual,
        max_move,
        iterations,
        fallbacks,
    })
}

fn finish<S1, S2>(
    s1: &S1,
    s2: &S2,
    y: &[f64; 4],
    p_old: Point3,
    method: Method,
    frozen: usize,
    iterations: usize,
) -> PointUpdate
where
    S1: ParamSurface + ?Sized,
    S2: ParamSurface + ?Sized,
{
    let a = s1.point(y[0], y[1]);
    let b = s2.point(y[2], y[3]);
    let m = Point3::from((a.coords + b.coords) * 0.5);
    PointUpdate {
        point: [m.x, m.y, m.z],
        uv1: [y[0], y[1]],
        uv2: [y[2], y[3]],
        method,
        frozen: method_of(frozen),
        iterations,
        residual: (a - b).norm(),
        moved: (m - p_old).norm(),
    }
}
