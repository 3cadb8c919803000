//! Stage 1, faces with exact geometry: each face's trimming box in its exact surface's
//! parameters, the model size and tolerances, and the support surface (power-basis patch
//! grid, Eqs. 7–10) of each distinct (surface, box).
//!
//! The box comes from the file's parameter-space curves when it gives trustworthy ones
//! (B-splines), else from the 3D boundary: every edge is sampled and inverted on the exact
//! surface (closed form on the analytic surfaces, safeguarded Newton elsewhere), unwrapped
//! along each loop across the period of periodic directions, so that a face crossing the
//! seam of a cylinder gets one connected box. A face without loops is its surface's
//! natural domain. Non-periodic directions are clipped to the natural domain.
//!
//! Margins: a planar support covers its face's box grown by a quarter of its extent on
//! each side, so that curves on it (a wing tip, the symmetry plane's section of the
//! fuselage) can move outward and still be re-intersected with it (Eq. 12); a B-spline
//! support keeps every knot span the face overlaps (a lofted wing keeps its span from the
//! root section inside the fuselage); periodic directions keep their seam uncut.
//!
//! Conversion is exact for planes (one bilinear patch over the box), 114 splines and
//! non-rational B-splines (every knot span, keeping the spans that overlap the box), and an
//! interpolation at the control nodes within the tolerance otherwise (module `approx`).
//! Either way the error against the exact surface is sampled between the nodes and reported.

use std::collections::HashMap;

use super::super::approx::{EXACT_MAX_DEGREE, chord_length, fit_surface, merge_short_spans};
use super::super::model::{CadModel, Domain, Surface};
use super::params::{invert, unwrap};

use super::super::{EntityConversion, Error, ImportOptions};
use crate::prelude::Point3;
use crate::surface::SupportSurface;

/// A rectangle of parameters ((u0, u1), (v0, v1)).
pub(crate) type Rect = ((f64, f64), (f64, f64));

/// One face's geometry. `domain` and `trim` are what the stages of issue 19's items 4–6
/// (untrimmed margins, seams) start from.
#[derive(Debug, Clone)]
#[allow(dead_code)]
pub(crate) struct FaceGeom {
    /// The natural (untrimmed) domain of its exact surface, with periods and seams.
    pub domain: Domain,
    /// The trimming box, in the exact surface's parameters.
    pub trim: Rect,
    /// Index into [`Faces::supports`].
    pub support: usize,
}

/// A support surface and how its global parameters map to the exact surface's: patch
/// column i covers u ∈ [u_breaks\[i\], u_breaks\[i+1\]] linearly (likewise v).
#[derive(Debug, Clone)]
pub(crate) struct Support {
    /// Index into the model's surfaces.
    pub model_surface: usize,
    /// The patch grid.
    pub surface: SupportSurface,
    /// Exact u at the patch columns' borders.
    pub u_breaks: Vec<f64>,
    /// Exact v at the patch rows' borders.
    pub v_breaks: Vec<f64>,
}

impl Support {
    /// The exact surface's (u, v) at the support's global (s, t).
    #[allow(dead_code)]
    pub fn exact_param(&self, s: f64, t: f64) -> (f64, f64) {
        let map = |b: &[f64], x: f64| {
            let n = b.len() - 1;
            let i = (x.floor().max(0.0) as usize).min(n - 1);
            b[i] + (x - i as f64) * (b[i + 1] - b[i])
        };
        (map(&self.u_breaks, s), map(&self.v_breaks, t))
    }
}

/// What stage 1 produces.
pub(crate) struct Faces {
    /// Per model face.
    pub faces: Vec<FaceGeom>,
    /// The support surfaces.
    pub supports: Vec<Support>,
    /// Model size: the bounding-box diagonal of the faces' surfaces, sampled over their
    /// trimming boxes (not the whole surface: a periodic fuselage cut in half, a plane's
    /// margin are not the model).
    pub size: f64,
    /// Approximation tolerance.
    pub tol: f64,
    /// Sewing tolerance.
    pub sew: f64,
    /// One entry per converted surface.
    pub conversions: Vec<EntityConversion>,
}

/// Samples per edge use when bounding a face from its 3D edges.
const EDGE_SAMPLES: usize = 24;
/// Samples per parameter-space curve piece.
const UV_SAMPLES: usize = 32;
/// Samples per direction of each face's trimming box for the model size.
const SIZE_SAMPLES: usize = 16;

fn face_err(model: &CadModel, face: usize, reason: impl Into<String>) -> Error {
    let s = &model.faces[face].source;
    Error::Entity {
        file: model.file.clone(),
        entity: super::entity_name(model, s),
        reason: reason.into(),
    }
}

/// Min/max of a set of parameter pairs.
fn bounds(pts: &[(f64, f64)]) -> Option<Rect> {
    let mut r = (
        (f64::INFINITY, f64::NEG_INFINITY),
        (f64::INFINITY, f64::NEG_INFINITY),
    );
    for &(u, v) in pts {
        if u.is_finite() {
            r.0 = (r.0.0.min(u), r.0.1.max(u));
        }
        if v.is_finite() {
            r.1 = (r.1.0.min(v), r.1.1.max(v));
        }
    }
    (r.0.1 >= r.0.0 && r.1.1 >= r.1.0).then_some(r)
}

/// The range of sampled values of one parameter: min to max; for a periodic parameter
/// (values in [0, P)), the circle minus its largest gap, or a whole period from the seam
/// when the loop retraces one.
fn range(xs: &mut [f64], period: Option<f64>, seam: Option<f64>) -> Option<(f64, f64)> {
    if xs.is_empty() {
        return None;
    }
    xs.sort_by(f64::total_cmp);
    let n = xs.len();
    Some(match (period, seam) {
        (Some(p), Some(x)) => (x, x + p),
        (Some(p), None) => {
            let (mut gap, mut k) = (xs[0] + p - xs[n - 1], n - 1);
            for i in 0..n - 1 {
                if xs[i + 1] - xs[i] > gap {
                    gap = xs[i + 1] - xs[i];
                    k = i;
                }
            }
            if k == n - 1 {
                (xs[0], xs[n - 1])
            } else {
                (xs[k + 1], xs[k] + p)
            }
        }
        _ => (xs[0], xs[n - 1]),
    })
}

/// The trimming box of face `fi`: as found, and clipped to (snapped onto) the natural
/// domain. Exact conversions select their knot spans with the first (a span narrower than
/// the snap at the domain's edge is a sliver outside the face).
fn trim_box(model: &CadModel, fi: usize, d: &Domain) -> Result<(Rect, Rect), Error> {
    let face = &model.faces[fi];
    let s = &model.surfaces[face.surface].surface;
    let raw = if !face.uv_bounds.is_empty() {
        let mut pts = Vec::new();
        for (c, a, b) in &face.uv_bounds {
            for w in c.breaks(a.min(*b), a.max(*b)).windows(2) {
                for k in 0..=UV_SAMPLES {
                    let q = c.point(w[0] + (w[1] - w[0]) * k as f64 / UV_SAMPLES as f64);
                    pts.push((q.x, q.y));
                }
            }
        }
        bounds(&pts)
    } else if face.loops.iter().any(|l| !l.edges.is_empty()) {
        // Every edge sampled and placed on the surface. A periodic parameter is kept in
        // [0, P) here: its range is found below as the circle minus its largest gap.
        let mut us: Vec<f64> = Vec::new();
        let mut vs: Vec<f64> = Vec::new();
        let (mut seam_u, mut seam_v) = (None, None);
        for lp in &face.loops {
            let mut prev: Option<(f64, f64)> = None;
            for e in &lp.edges {
                let c = &model.curves[e.curve].curve;
                let (lo, hi) = (e.t0.min(e.t1), e.t0.max(e.t1));
                let br = c.breaks(lo, hi);
                let mut ts: Vec<f64> = Vec::new();
                for w in br.windows(2) {
                    let per = (EDGE_SAMPLES / (br.len() - 1)).max(4);
                    for k in 0..per {
                        ts.push(w[0] + (w[1] - w[0]) * k as f64 / per as f64);
                    }
                }
                ts.push(hi);
                for t in ts {
                    let (u, v) = invert(s, d, &c.point(t), prev);
                    prev = Some((u, v));
                    // Where S_u vanishes (a pole) u says nothing (likewise v).
                    let (_, su, sv) = s.derivs(u, v);
                    let (nu, nv) = (su.norm(), sv.norm());
                    if nu > 1e-6 * nv && u.is_finite() {
                        us.push(d.u_period.map_or(u, |p| u.rem_euclid(p)));
                    }
                    if nv > 1e-6 * nu && v.is_finite() {
                        vs.push(d.v_period.map_or(v, |p| v.rem_euclid(p)));
                    }
                }
            }
            // A seam: an edge retraced by the loop at one value of a periodic parameter (a
            // sphere's meridian between its poles) — the face spans the whole period there.
            let at = |e: &super::super::model::EdgeUse, f: f64| {
                model.curves[e.curve].curve.point(e.t0 + f * (e.t1 - e.t0))
            };
            let size = lp
                .edges
                .iter()
                .map(|e| (at(e, 0.0) - at(e, 0.5)).norm())
                .fold(0.0, f64::max);
            for (k, e) in lp.edges.iter().enumerate() {
                let twice = lp.edges[k + 1..].iter().any(|f| {
                    [0.25, 0.5, 0.75]
                        .iter()
                        .all(|&x| (at(e, x) - at(f, 1.0 - x)).norm() <= 1e-7 * size)
                });
                if !twice {
                    continue;
                }
                let uv: Vec<(f64, f64)> = (1..8)
                    .map(|j| invert(s, d, &at(e, j as f64 / 8.0), None))
                    .collect();
                let constant = |get: fn(&(f64, f64)) -> f64, period: Option<f64>| {
                    let p = period?;
                    let x0 = get(&uv[0]);
                    uv.iter()
                        .all(|q| {
                            unwrap(get(q), x0, p) - x0 == 0.0
                                || (unwrap(get(q), x0, p) - x0).abs() < 1e-6 * p
                        })
                        .then_some(x0.rem_euclid(p))
                };
                seam_u = seam_u.or(constant(|q| q.0, d.u_period));
                seam_v = seam_v.or(constant(|q| q.1, d.v_period));
            }
        }
        match (
            range(&mut us, d.u_period, seam_u),
            range(&mut vs, d.v_period, seam_v),
        ) {
            (Some(u), Some(v)) => Some((u, v)),
            _ => None,
        }
    } else {
        if !d.is_bounded() {
            return Err(face_err(
                model,
                fi,
                "an unbounded surface (plane, cylinder, cone, extrusion) without a boundary cannot be a face",
            ));
        }
        return Ok(((d.u, d.v), (d.u, d.v)));
    };
    let Some(found) = raw else {
        return Err(face_err(
            model,
            fi,
            "cannot place the face's boundary on its surface",
        ));
    };
    let ((mut u0, mut u1), (mut v0, mut v1)) = found;
    // Periodic directions: at most one period; others: clipped to the natural domain.
    if let Some(p) = d.u_period
        && u1 - u0 > p
    {
        u1 = u0 + p;
    }
    if let Some(p) = d.v_period
        && v1 - v0 > p
    {
        v1 = v0 + p;
    }
    let clip = |l: f64, h: f64, r: (f64, f64), period: Option<f64>| {
        if let Some(p) = period {
            // Shifted by whole periods to start in [r.0, r.0 + p).
            let k = ((l - r.0) / p + 1e-9).floor();
            return (l - k * p, h - k * p);
        }
        if !(r.0.is_finite() && r.1.is_finite()) {
            return (l.max(r.0), h.min(r.1));
        }
        let pad = 1e-4 * (r.1 - r.0);
        let l = if l - pad <= r.0 { r.0 } else { l };
        let h = if h + pad >= r.1 { r.1 } else { h };
        (l.max(r.0), h.min(r.1))
    };
    (u0, u1) = clip(u0, u1, d.u, d.u_period);
    (v0, v1) = clip(v0, v1, d.v, d.v_period);
    if !(u1 > u0 && v1 > v0 && [u0, u1, v0, v1].iter().all(|x| x.is_finite())) {
        return Err(face_err(
            model,
            fi,
            format!("the face's parameter box [{u0}, {u1}] × [{v0}, {v1}] is empty"),
        ));
    }
    Ok((found, ((u0, u1), (v0, v1))))
}

/// Runs stage 1.
pub(crate) fn run(model: &CadModel, opts: &ImportOptions) -> Result<Faces, Error> {
    let n = model.faces.len();
    let mut geoms: Vec<(Domain, Rect, Rect)> = Vec::with_capacity(n);
    for fi in 0..n {
        let s = &model.surfaces[model.faces[fi].surface].surface;
        let d = s.domain();
        let (raw, b) = trim_box(model, fi, &d)?;
        geoms.push((d, b, raw));
    }
    // Planar supports keep a margin beyond their face, so that a curve on them can move
    // outward when the model changes (Eq. 12 re-intersects it on the support, not the face).
    let margins: Vec<Option<Rect>> = geoms
        .iter()
        .enumerate()
        .map(|(fi, (_, b, _))| {
            let s = &model.surfaces[model.faces[fi].surface].surface;
            matches!(s, Surface::Plane { .. }).then(|| with_margin(*b))
        })
        .collect();
    // The model size.
    let (mut lo, mut hi) = (
        Point3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY),
        Point3::new(f64::NEG_INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY),
    );
    for (fi, (_, b, _)) in geoms.iter().enumerate() {
        let s = &model.surfaces[model.faces[fi].surface].surface;
        let ((u0, u1), (v0, v1)) = *b;
        for i in 0..=SIZE_SAMPLES {
            for j in 0..=SIZE_SAMPLES {
                let (fu, fv) = (
                    i as f64 / SIZE_SAMPLES as f64,
                    j as f64 / SIZE_SAMPLES as f64,
                );
                let p = s.point(u0 + (u1 - u0) * fu, v0 + (v1 - v0) * fv);
                if p.coords.iter().all(|c| c.is_finite()) {
                    lo = lo.inf(&p);
                    hi = hi.sup(&p);
                }
            }
        }
    }
    let size = (hi - lo).norm();
    let size = if size.is_finite() && size > 0.0 {
        size
    } else {
        1.0
    };
    let tol = opts.tolerance.unwrap_or(opts.rel_tolerance * size);
    let sew = opts
        .sew_tolerance
        .unwrap_or((opts.rel_sew_tolerance * size).max(10.0 * tol));
    if !(tol > 0.0) || !(sew > 0.0) {
        return Err(Error::Model {
            file: model.file.clone(),
            reason: format!("tolerances must be positive (approximation {tol}, sewing {sew})"),
        });
    }
    // Support surfaces, one per distinct (surface, box).
    let mut supports: Vec<Support> = Vec::new();
    let mut conversions = Vec::new();
    let mut key_of: HashMap<(usize, [u64; 4]), usize> = HashMap::new();
    let mut faces = Vec::with_capacity(n);
    for (fi, (d, trim, raw)) in geoms.into_iter().enumerate() {
        let si = model.faces[fi].surface;
        let (b, raw) = margins[fi].map_or((trim, raw), |m| (m, m));
        let key = (
            si,
            [
                b.0.0.to_bits(),
                b.0.1.to_bits(),
                b.1.0.to_bits(),
                b.1.1.to_bits(),
            ],
        );
        let k = match key_of.get(&key) {
            Some(&k) => k,
            None => {
                let (sup, conv) = convert(model, fi, &d, b, raw, (tol, sew))?;
                supports.push(sup);
                conversions.push(conv);
                key_of.insert(key, supports.len() - 1);
                supports.len() - 1
            }
        };
        faces.push(FaceGeom {
            domain: d,
            trim,
            support: k,
        });
    }
    Ok(Faces {
        faces,
        supports,
        size,
        tol,
        sew,
        conversions,
    })
}

/// Fraction of a planar face's box added on each side of its support.
const PLANE_MARGIN: f64 = 0.25;

/// `b` grown by [`PLANE_MARGIN`] of its extent on each side.
fn with_margin(((u0, u1), (v0, v1)): Rect) -> Rect {
    let (du, dv) = (PLANE_MARGIN * (u1 - u0), PLANE_MARGIN * (v1 - v0));
    ((u0 - du, u1 + du), (v0 - dv, v1 + dv))
}

/// The largest distance between the support and the exact surface, sampled at 5 × 5
/// points of every patch (borders included).
fn sampled_error(s: &Surface, sup: &Support) -> f64 {
    let mut err: f64 = 0.0;
    let (nu, nv) = (sup.surface.n_u, sup.surface.n_v);
    for i in 0..nu {
        for j in 0..nv {
            for a in 0..=4 {
                for b in 0..=4 {
                    let (gs, gt) = (i as f64 + a as f64 / 4.0, j as f64 + b as f64 / 4.0);
                    let (u, v) = sup.exact_param(gs, gt);
                    let p = crate::eval::ParamSurface::point(&sup.surface, gs, gt);
                    let d = (p - s.point(u, v)).norm();
                    err = if d.is_nan() {
                        f64::INFINITY
                    } else {
                        err.max(d)
                    };
                }
            }
        }
    }
    err
}

/// The support surface of face `fi` over its box.
///
/// A polynomial surface is converted exactly unless that is ill-conditioned (a degree above
/// [`EXACT_MAX_DEGREE`], a knot span no wider than the sewing tolerance inside the face, or
/// exact patches off by more than the tolerance); then, like a surface that is not
/// polynomial, it is interpolated at the control nodes of degree-7 patches from its own
/// evaluation, over its knot spans with the narrow ones merged, and its report says why.
fn convert(
    model: &CadModel,
    fi: usize,
    d: &Domain,
    b: Rect,
    raw: Rect,
    (tol, sew): (f64, f64),
) -> Result<(Support, EntityConversion), Error> {
    let ms = &model.surfaces[model.faces[fi].surface];
    let s = &ms.surface;
    let (ur, vr) = b;
    let conv = |method: &'static str, pieces: usize, max_error: f64, note: Option<String>| {
        EntityConversion {
            entity: ms.source.label.clone(),
            kind: ms.source.kind.clone(),
            method,
            pieces,
            max_error,
            note,
        }
    };
    // The widths of the spans between breaks along u (at 5 v across the box) and along v.
    let width_u = |a: f64, c: f64| {
        (0..=4)
            .map(|k| {
                let v = vr.0 + (vr.1 - vr.0) * k as f64 / 4.0;
                chord_length(&|u| s.point(u, v), a, c)
            })
            .fold(0.0, f64::max)
    };
    let width_v = |a: f64, c: f64| {
        (0..=4)
            .map(|k| {
                let u = ur.0 + (ur.1 - ur.0) * k as f64 / 4.0;
                chord_length(&|v| s.point(u, v), a, c)
            })
            .fold(0.0, f64::max)
    };
    let mut note = None;
    if let Some((full, ub, vb)) = s.exact_patches(ur, vr) {
        // Keep the spans that overlap the box by more than round-off (drops sliver spans
        // outside the face).
        let keep = |br: &[f64], (l, h): (f64, f64)| {
            let pad = 1e-6 * (br[br.len() - 1] - br[0]);
            let ks: Vec<usize> = (0..br.len() - 1)
                .filter(|&k| br[k + 1].min(h) - br[k].max(l) > pad)
                .collect();
            if ks.is_empty() {
                (0, br.len() - 1)
            } else {
                (ks[0], ks[ks.len() - 1] + 1)
            }
        };
        let (i0, i1) = keep(&ub, raw.0);
        let (j0, j1) = keep(&vb, raw.1);
        let mut patches = Vec::new();
        for j in j0..j1 {
            for i in i0..i1 {
                patches.push(full.patch(i, j).clone());
            }
        }
        let sup = Support {
            model_surface: model.faces[fi].surface,
            surface: SupportSurface::new("", i1 - i0, j1 - j0, patches),
            u_breaks: ub[i0..=i1].to_vec(),
            v_breaks: vb[j0..=j1].to_vec(),
        };
        let degree = sup
            .surface
            .patches
            .iter()
            .map(|p| p.deg_u.max(p.deg_v))
            .max()
            .unwrap_or(0);
        let short = sup
            .u_breaks
            .windows(2)
            .filter(|w| width_u(w[0], w[1]) <= sew)
            .count()
            + sup
                .v_breaks
                .windows(2)
                .filter(|w| width_v(w[0], w[1]) <= sew)
                .count();
        let err = sampled_error(s, &sup);
        if degree > EXACT_MAX_DEGREE {
            note = Some(format!("degree {degree} above {EXACT_MAX_DEGREE}"));
        } else if short > 0 {
            note = Some(format!(
                "{short} knot spans no wider than the sewing tolerance {sew:.3e}"
            ));
        } else if !(err <= tol) {
            note = Some(format!(
                "its exact patches are {err:.3e} off (round-off), above the tolerance"
            ));
        } else {
            let c = conv("exact", sup.surface.patches.len(), err, None);
            return Ok((sup, c));
        }
    }
    let (bu, bv) = s.breaks();
    let inside = |br: Vec<f64>, (a, c): (f64, f64), period: Option<f64>| {
        let mut out = vec![a];
        let mut extra: Vec<f64> = br;
        if let Some(p) = period {
            // Knots of a periodic direction repeat every period.
            extra = extra
                .iter()
                .flat_map(|&x| (-2..=2).map(move |k| x + k as f64 * p))
                .collect();
        }
        extra.sort_by(f64::total_cmp);
        let pad = 1e-9 * (c - a);
        out.extend(extra.into_iter().filter(|&x| x > a + pad && x < c - pad));
        out.dedup();
        out.push(c);
        out
    };
    let (ub, mu) = merge_short_spans(&inside(bu, ur, d.u_period), &width_u, sew);
    let (vb, mv) = merge_short_spans(&inside(bv, vr, d.v_period), &width_v, sew);
    if mu + mv > 0 {
        let m = format!("{} knot spans narrower than {sew:.3e} merged", mu + mv);
        note = Some(match note {
            Some(n) => format!("{n}; {m}"),
            None => m,
        });
    }
    let f = |u: f64, v: f64| s.point(u, v);
    let fit = fit_surface(&f, &ub, &vb, tol).map_err(|e| {
        face_err(
            model,
            fi,
            format!(
                "cannot approximate surface {} within {tol:.3e} (best error {e:.3e}); --tolerance {} would let it pass",
                ms.source.describe(),
                super::edges::suggest_tolerance(e)
            ),
        )
    })?;
    let sup = Support {
        model_surface: model.faces[fi].surface,
        u_breaks: fit.u_breaks,
        v_breaks: fit.v_breaks,
        surface: fit.surface,
    };
    let method = if note.is_some() {
        "reapproximated"
    } else {
        "fitted"
    };
    let c = conv(method, sup.surface.patches.len(), fit.max_error, note);
    Ok((sup, c))
}
