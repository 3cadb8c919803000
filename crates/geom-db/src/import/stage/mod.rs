//! The import as named stages over typed intermediate results, from the neutral model to
//! the database (spade's `delaunay_core` habit: one file per stage):
//!
//! 1. `faces`: each face's exact surface, natural domain and trimming box; the model size
//!    and tolerances; the support surfaces.
//! 2. `edges`: every boundary piece converted to arcs.
//! 3. `loops`: pieces chained into closed loops.
//! 4. `corners`: end points merged.
//! 5. `junctions`: T-junctions split.
//! 6. `sewing`: coincident pieces merged into sewn edges, each with its uses.
//! 7. `orientation`: inward signs, consistent across shared edges.
//! 8. `shells`: connected shells, volumes, the global sign.
//! 9. `database`: the validated [`GeomDb`] and the report; within it, roles, seams on
//!    support borders, junctions and
//! 10. `intersections`: each junction rebuilt as the intersection of its two supports.
//!
//! Each stage's result is a plain struct the next one reads; a stage the next engineer
//! adds (roles by shape, untrimmed margins, seams, control nodes, junctions) goes between
//! two of them.

pub(crate) mod corners;
pub(crate) mod database;
pub(crate) mod edges;
pub(crate) mod faces;
pub(crate) mod intersections;
pub(crate) mod junctions;
pub(crate) mod loops;
pub(crate) mod orientation;
pub(crate) mod params;
pub(crate) mod sewing;
pub(crate) mod shells;

use super::model::{CadModel, Source};
use super::{Error, ImportOptions, ImportReport};
use crate::curve::Arc;
use crate::db::GeomDb;
use crate::prelude::Point3;
use crate::quadrature::gauss_legendre;

/// Runs the stages on a neutral model (already in its output unit).
pub(crate) fn run(
    model: &CadModel,
    opts: &ImportOptions,
    report: ImportReport,
) -> Result<(GeomDb, ImportReport), Error> {
    if model.faces.is_empty() {
        return Err(Error::Model {
            file: model.file.clone(),
            reason: format!(
                "no surface to import (no face in the {} file)",
                model.format
            ),
        });
    }
    let faces = faces::run(model, opts)?;
    let mut edges = edges::run(model, &faces)?;
    let mut loops = loops::run(model, &edges, faces.sew)?;
    let mut corners = corners::run(&edges, faces.sew);
    junctions::run(&mut edges, &mut loops, &mut corners, faces.sew);
    let sewn = sewing::run(&edges, &loops, &corners, faces.sew);
    let mut oriented = orientation::run(model, &faces, &edges, &sewn);
    let shells = shells::run(model, &faces, &edges, &corners, &sewn, &mut oriented);
    database::run(
        model, &faces, &edges, &corners, &sewn, &oriented, &shells, opts, report,
    )
}

/// How an entity is named in messages: `entity at D line 37 (type 144)` (IGES) or
/// `#37 (ADVANCED_FACE)` (STEP).
pub(crate) fn entity_name(model: &CadModel, s: &Source) -> String {
    match s.label.strip_prefix('D') {
        Some(line) if model.format == "IGES" => {
            format!(
                "entity at D line {} (type {})",
                line.split('[').next().unwrap_or(line),
                s.kind
            )
        }
        _ => s.describe(),
    }
}

pub(crate) fn arcs_point(arcs: &[Arc], t: f64) -> Point3 {
    let n = arcs.len();
    let i = (t.floor().max(0.0) as usize).min(n - 1);
    arcs[i].point(t - i as f64)
}

pub(crate) fn reverse_arcs(arcs: &[Arc]) -> Vec<Arc> {
    arcs.iter().rev().map(Arc::reversed).collect()
}

/// Distance from `p` to the curve made of `arcs` and the global parameter of the foot:
/// the nearest of `samples`, then Newton on the arc.
pub(crate) fn foot_on_arcs(arcs: &[Arc], samples: &[(f64, Point3)], p: &Point3) -> (f64, f64) {
    let (mut t, mut best) = (0.0, f64::INFINITY);
    for &(s, q) in samples {
        let d = (q - p).norm_squared();
        if d < best {
            best = d;
            t = s;
        }
    }
    let n = arcs.len() as f64;
    let mut dist = (arcs_point(arcs, t) - p).norm();
    for _ in 0..20 {
        let i = (t.floor().max(0.0) as usize).min(arcs.len() - 1);
        let d = arcs[i].derivs(t - i as f64);
        let r = d.point - p;
        let g = r.dot(&d.d1);
        let h = d.d1.norm_squared() + r.dot(&d.d2);
        if !(h > 0.0) {
            break;
        }
        let nt = (t - g / h).clamp(0.0, n);
        let nd = (arcs_point(arcs, nt) - p).norm();
        if nd >= dist {
            break;
        }
        t = nt;
        dist = nd;
    }
    (dist, t)
}

/// The arcs of the part [t0, t1] (global parameters, t0 < t1) of a curve made of `arcs`.
pub(crate) fn split_arcs(arcs: &[Arc], t0: f64, t1: f64) -> Vec<Arc> {
    let mut out = Vec::new();
    for (k, a) in arcs.iter().enumerate() {
        let (s, e) = ((t0 - k as f64).max(0.0), (t1 - k as f64).min(1.0));
        if e - s > 1e-12 {
            out.push(super::export::sub_arc(a, s, e));
        }
    }
    out
}

pub(crate) fn curve_samples(arcs: &[Arc], per_arc: usize) -> Vec<(f64, Point3)> {
    let n = arcs.len() * per_arc;
    (0..=n)
        .map(|k| {
            let t = k as f64 / per_arc as f64;
            (t, arcs_point(arcs, t))
        })
        .collect()
}

/// A loop of face `fi` in its exact surface's parameters: per sewn edge of the loop,
/// (16 × arcs, 32..512, even) + 1 samples equally spaced in its parameter, in the loop's
/// direction, placed on the surface by [`params::exact_loop`] (continuous across seams and
/// periods).
pub(crate) fn loop_polygon(
    model: &CadModel,
    faces: &faces::Faces,
    fi: usize,
    lp: &[(usize, bool)],
    sewn: &sewing::Sewn,
    edges: &edges::Edges,
) -> Vec<Vec<(f64, f64)>> {
    let g = &faces.faces[fi];
    let s = &model.surfaces[model.faces[fi].surface].surface;
    let runs: Vec<Vec<Point3>> = lp
        .iter()
        .map(|&(k, reversed)| {
            let arcs = &edges.edges[sewn.edges[k].master].arcs;
            let na = arcs.len() as f64;
            let n = (16 * arcs.len()).max(64);
            (0..=n)
                .map(|j| {
                    let f = j as f64 / n as f64;
                    arcs_point(arcs, if reversed { 1.0 - f } else { f } * na)
                })
                .collect()
        })
        .collect();
    let retraces: Vec<bool> = (0..lp.len())
        .map(|i| i > 0 && lp[i - 1] == (lp[i].0, !lp[i].1))
        .collect();
    params::exact_loop(s, &g.domain, g.trim, &runs, &retraces)
}

/// The support's global parameter of the exact parameter `x`, given the support's
/// breaks; a direction whose trimming box spans a whole period wraps around it (a loop may
/// cross the seam), the others are clamped.
fn to_global(b: &[f64], x: f64, period: Option<f64>) -> f64 {
    let n = b.len() - 1;
    let (lo, hi) = (b[0], b[n]);
    let mut shift = 0.0;
    let mut x = x;
    if let Some(p) = period
        && (hi - lo - p).abs() <= 1e-9 * p
    {
        let k = ((x - lo) / p).floor();
        x -= k * p;
        shift = k * n as f64;
    }
    let x = x.clamp(lo, hi);
    let i = b[1..n].partition_point(|&y| y <= x);
    shift + i as f64 + (x - b[i]) / (b[i + 1] - b[i])
}

/// ∮ G dv over a closed loop of face `fi` given in its exact surface's parameters (u, v) as
/// [`loop_polygon`] runs, with G(u, v) = ∫ x·(S_u × S_v) du (Green's theorem: the integral of
/// x·N over the enclosed region, counted positively for a counter-clockwise loop).
///
/// The integrand is the face's support surface (within the tolerance of the exact one) in
/// the support's global parameters (U, V), which map to (u, v) linearly on each patch:
/// G(u, v) = (dV/dv) ∫_0^U x·(r_U × r_V) dU'. ∫ dU' is Gauss–Legendre on each patch, with
/// ⌈3p/2⌉ + 1 points for a patch of degree p in U, exact for the flux (continued
/// periodically across a seam); ∮ dv is composite Simpson's rule over
/// each run's equally spaced samples, the path taken as the parabola through each three
/// (fourth order), and over the straight segment (a pole's edge of the parameter domain)
/// joining a run to the next where they do not meet.
///
/// Returns the pair (flux, area): the same rule with the integrand |r_U × r_V| gives the
/// area of the region the loop bounds (signed: positive counter-clockwise). Both come from
/// one pass, since the surface derivatives dominate the cost.
pub(crate) fn green_flux_area(
    faces: &faces::Faces,
    fi: usize,
    runs: &[Vec<(f64, f64)>],
) -> (f64, f64) {
    green(faces, fi, runs, |d| {
        let n = d.du.cross(&d.dv);
        (d.point.coords.dot(&n), n.norm())
    })
}

/// ∮ G dv with G = ∫ integrand dU, for a pair of integrands (see [`green_flux_area`]).
fn green(
    faces: &faces::Faces,
    fi: usize,
    runs: &[Vec<(f64, f64)>],
    integrand: impl Fn(&crate::eval::SurfaceDerivs) -> (f64, f64),
) -> (f64, f64) {
    type Pair = nalgebra::Vector2<f64>;
    let g_face = &faces.faces[fi];
    let sup = &faces.supports[g_face.support];
    let s = &sup.surface;
    let (nu, nv) = (s.n_u as f64, s.n_v as f64);
    let wrap = |x: f64, n: f64| {
        if (0.0..=n).contains(&x) {
            x
        } else {
            x.rem_euclid(n)
        }
    };
    let f = |u: f64, v: f64| {
        let (a, b) = integrand(&crate::eval::ParamSurface::derivs(
            s,
            wrap(u, nu),
            wrap(v, nv),
        ));
        Pair::new(a, b)
    };
    // The Gauss–Legendre rule of each patch degree in U: x·(r_U × r_V) has degree 3p − 1 in
    // U on a patch of degree p, which ⌈3p/2⌉ points integrate exactly; one more for the
    // area's |r_U × r_V|, which is not a polynomial.
    let mut rules: Vec<Vec<(f64, f64)>> = Vec::new();
    for patch in &s.patches {
        if rules.len() <= patch.deg_u {
            rules.resize(patch.deg_u + 1, Vec::new());
        }
        if rules[patch.deg_u].is_empty() {
            rules[patch.deg_u] = gauss_legendre((3 * patch.deg_u).div_ceil(2).max(1) + 1);
        }
    }
    let cell = |x: f64, n: usize| (x.floor().max(0.0) as usize).min(n - 1);
    // ∫_0^U at fixed V, patch by patch (continued periodically across a seam beyond the
    // support's U range).
    let big_g = |u: f64, v: f64| {
        let (from, to, sign) = if u >= 0.0 {
            (0.0, u, 1.0)
        } else {
            (u, 0.0, -1.0)
        };
        let j = cell(wrap(v, nv), s.n_v);
        let mut acc = Pair::zeros();
        let mut a = from;
        while a < to {
            let b = (a.floor() + 1.0).min(to);
            let i = cell(wrap(0.5 * (a + b), nu), s.n_u);
            for &(x, w) in &rules[s.patch(i, j).deg_u] {
                acc += f(a + x * (b - a), v) * (w * (b - a));
            }
            a = b;
        }
        acc * sign
    };
    let (pu, pv) = (g_face.domain.u_period, g_face.domain.v_period);
    let vb = &sup.v_breaks;
    // G in the exact parameters at an exact (u, v).
    let g_exact = |(u, v): (f64, f64)| {
        let (gu, gv) = (to_global(&sup.u_breaks, u, pu), to_global(vb, v, pv));
        let j = (wrap(gv, nv).floor().max(0.0) as usize).min(vb.len() - 2);
        big_g(gu, gv) / (vb[j + 1] - vb[j])
    };
    let simpson_run = |pts: &[(f64, f64)]| -> Pair {
        let gs: Vec<Pair> = pts.iter().map(|&q| g_exact(q)).collect();
        let mut acc = Pair::zeros();
        let mut j = 0;
        while j + 2 < pts.len() {
            let (v0, v1, v2) = (pts[j].1, pts[j + 1].1, pts[j + 2].1);
            acc += (gs[j] * (-3.0 * v0 + 4.0 * v1 - v2)
                + gs[j + 1] * (4.0 * (v2 - v0))
                + gs[j + 2] * (v0 - 4.0 * v1 + 3.0 * v2))
                / 6.0;
            j += 2;
        }
        if j + 1 < pts.len() {
            // An odd run ends with one trapezoid.
            acc += (gs[j] + gs[j + 1]) * (0.5 * (pts[j + 1].1 - pts[j].1));
        }
        acc
    };
    let mut total = Pair::zeros();
    for (i, run) in runs.iter().enumerate() {
        total += simpson_run(run);
        let next = &runs[(i + 1) % runs.len()];
        if let (Some(&a), Some(&b)) = (run.last(), next.first())
            && (a.0 - b.0).abs() + (a.1 - b.1).abs() > 1e-12
        {
            const PIECES: usize = 64;
            let seg: Vec<(f64, f64)> = (0..=PIECES)
                .map(|k| {
                    let t = k as f64 / PIECES as f64;
                    (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1))
                })
                .collect();
            total += simpson_run(&seg);
        }
    }
    (total.x, total.y)
}

/// Twice the signed area of a polygon, halved.
pub(crate) fn shoelace(poly: &[(f64, f64)]) -> f64 {
    let n = poly.len();
    (0..n)
        .map(|k| {
            let (a, b) = (poly[k], poly[(k + 1) % n]);
            a.0 * b.1 - b.0 * a.1
        })
        .sum::<f64>()
        * 0.5
}
