//! The import pipeline: faces and their loops from the IGES entities, conversion, sewing,
//! orientation and the database build.

use std::collections::{BTreeMap, BTreeSet, HashMap, VecDeque};

use iges::{DeId, Entity, IgesFile};

use super::approx::{fit_curve, fit_surface};
use super::geometry::{Builder, SurfEval};
use super::roles;
use super::{
    EdgeReport, EntityConversion, Error, FaceReport, ImportOptions, ImportReport, ShellReport,
};
use crate::curve::{Arc, SupportCurve};
use crate::db::GeomDb;
use crate::eval::ParamSurface;
use crate::ids::{CornerId, CurveCompId, CurveId, SurfaceId};
use crate::invert::{InvertOptions, SurfaceInverter};
use crate::merge::PointMerger;
use crate::prelude::Point3;
use crate::surface::{Side, SupportSurface};
use crate::topology::{Corner, CurveComponent, Orientation, OrientedCurve, SurfaceComponent};

/// One boundary curve of a face loop before conversion.
struct LoopCurve {
    /// The IGES curve (a leaf: not a 102 or 142).
    de: DeId,
    /// Traversed against its own direction (141 SENSE 2, 508 OF 0).
    reversed: bool,
    /// For a parameter-space curve (a 142 without model-space curve): the surface it lies
    /// on; the model curve is then S(B(t)).
    on_surface: Option<DeId>,
}

/// A face before conversion.
struct FaceSrc {
    de: DeId,
    surface: DeId,
    /// Loops (outer first); an empty list means the boundary of the surface's domain.
    loops: Vec<Vec<LoopCurve>>,
    /// Parameter-space curves of the loops (for restricting approximated surfaces).
    param_curves: Vec<DeId>,
}

/// A converted edge: one boundary curve of one face loop.
struct Edge {
    face: usize,
    src: Option<DeId>,
    arcs: Vec<Arc>,
    start: Point3,
    end: Point3,
}

fn arcs_point(arcs: &[Arc], t: f64) -> Point3 {
    let n = arcs.len();
    let i = (t.floor().max(0.0) as usize).min(n - 1);
    arcs[i].point(t - i as f64)
}

fn reverse_arcs(arcs: &[Arc]) -> Vec<Arc> {
    arcs.iter().rev().map(Arc::reversed).collect()
}

/// Distance from `p` to the curve made of `arcs`, by dense sampling then Newton on the arc.
fn distance_to_arcs(arcs: &[Arc], samples: &[(f64, Point3)], p: &Point3) -> f64 {
    foot_on_arcs(arcs, samples, p).0
}

/// Distance from `p` to the curve made of `arcs` and the global parameter of the foot.
fn foot_on_arcs(arcs: &[Arc], samples: &[(f64, Point3)], p: &Point3) -> (f64, f64) {
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
fn split_arcs(arcs: &[Arc], t0: f64, t1: f64) -> Vec<Arc> {
    let mut out = Vec::new();
    for (k, a) in arcs.iter().enumerate() {
        let (s, e) = ((t0 - k as f64).max(0.0), (t1 - k as f64).min(1.0));
        if e - s > 1e-12 {
            out.push(super::export::sub_arc(a, s, e));
        }
    }
    out
}

fn curve_samples(arcs: &[Arc], per_arc: usize) -> Vec<(f64, Point3)> {
    let n = arcs.len() * per_arc;
    (0..=n)
        .map(|k| {
            let t = k as f64 / per_arc as f64;
            (t, arcs_point(arcs, t))
        })
        .collect()
}

struct Ctx<'a> {
    file: &'a IgesFile,
    b: Builder<'a>,
    report: ImportReport,
    curve_cache: HashMap<(DeId, Option<DeId>), (Vec<Arc>, f64)>,
}

impl Ctx<'_> {
    fn bad(&self, id: DeId, reason: impl Into<String>) -> Error {
        Error::Entity {
            file: self.file.name.clone(),
            de: id.line(),
            entity_type: self.file.get(id).map_or(0, |r| r.de.entity_type),
            reason: reason.into(),
        }
    }

    fn ty(&self, id: DeId) -> i32 {
        self.file.get(id).map_or(0, |r| r.de.entity_type)
    }

    /// Leaves of a curve: 102 composites and 142 model curves resolved.
    fn leaves(
        &self,
        id: DeId,
        reversed: bool,
        out: &mut Vec<LoopCurve>,
        depth: usize,
    ) -> Result<(), Error> {
        if depth > 16 {
            return Err(self.bad(id, "curves nest more than 16 levels deep"));
        }
        let rec = self
            .file
            .get(id)
            .ok_or_else(|| self.bad(id, "pointer names no entity"))?;
        match &rec.entity {
            Entity::CompositeCurve(c) if rec.de.transform.is_none() => {
                let mut v = Vec::new();
                for &p in &c.curves {
                    self.leaves(p, false, &mut v, depth + 1)?;
                }
                if reversed {
                    v.reverse();
                    v.iter_mut().for_each(|l| l.reversed = !l.reversed);
                }
                out.extend(v);
            }
            Entity::CurveOnSurface(c) => match (c.model_curve, c.param_curve) {
                (Some(m), _) => self.leaves(m, reversed, out, depth + 1)?,
                (None, Some(b)) => {
                    let mut v = Vec::new();
                    self.leaves(b, reversed, &mut v, depth + 1)?;
                    v.iter_mut().for_each(|l| l.on_surface = Some(c.surface));
                    out.extend(v);
                }
                (None, None) => {
                    return Err(self.bad(id, "curve on surface without any curve"));
                }
            },
            _ => out.push(LoopCurve {
                de: id,
                reversed,
                on_surface: None,
            }),
        }
        Ok(())
    }

    fn faces(&mut self) -> Result<Vec<FaceSrc>, Error> {
        let f = self.file;
        let mut faces = Vec::new();
        let mut used_surfaces = BTreeSet::new();
        for (id, r) in f.iter() {
            match &r.entity {
                Entity::TrimmedSurface(t) => {
                    used_surfaces.insert(t.surface);
                    let mut loops = Vec::new();
                    let mut param_curves = Vec::new();
                    let bounds: Vec<DeId> =
                        t.outer.into_iter().chain(t.inner.iter().copied()).collect();
                    if t.outer.is_none() && !t.inner.is_empty() {
                        // The outer loop is the domain boundary: represented by an empty loop.
                        loops.push(Vec::new());
                    }
                    for b in bounds {
                        f.expect(id, b, &[142]).map_err(Error::Iges)?;
                        if let Entity::CurveOnSurface(c) = &f.get(b).expect("checked").entity {
                            param_curves.extend(c.param_curve);
                        }
                        let mut lp = Vec::new();
                        self.leaves(b, false, &mut lp, 0)?;
                        loops.push(lp);
                    }
                    faces.push(FaceSrc {
                        de: id,
                        surface: t.surface,
                        loops,
                        param_curves,
                    });
                }
                Entity::BoundedSurface(s) => {
                    used_surfaces.insert(s.surface);
                    let mut loops = Vec::new();
                    let mut param_curves = Vec::new();
                    for &b in &s.boundaries {
                        let r = f.expect(id, b, &[141]).map_err(Error::Iges)?;
                        let Entity::Boundary(bd) = &r.entity else {
                            continue;
                        };
                        let mut lp = Vec::new();
                        for c in &bd.curves {
                            self.leaves(c.model_curve, c.reversed, &mut lp, 0)?;
                            param_curves.extend(c.param_curves.iter().copied());
                        }
                        loops.push(lp);
                    }
                    faces.push(FaceSrc {
                        de: id,
                        surface: s.surface,
                        loops,
                        param_curves,
                    });
                }
                Entity::Face(fc) => {
                    used_surfaces.insert(fc.surface);
                    let mut loops = Vec::new();
                    for &l in &fc.loops {
                        let r = f.expect(id, l, &[508]).map_err(Error::Iges)?;
                        let Entity::Loop(lp) = &r.entity else {
                            continue;
                        };
                        let mut out = Vec::new();
                        for e in &lp.edges {
                            if e.is_vertex {
                                continue;
                            }
                            let er = f.expect(l, e.list, &[504]).map_err(Error::Iges)?;
                            let Entity::EdgeList(el) = &er.entity else {
                                continue;
                            };
                            let edge = el.edges.get(e.index - 1).ok_or_else(|| {
                                self.bad(
                                    l,
                                    format!(
                                        "edge index {} is beyond the {} edges of D{}",
                                        e.index,
                                        el.edges.len(),
                                        e.list.line()
                                    ),
                                )
                            })?;
                            self.leaves(edge.curve, !e.agrees, &mut out, 0)?;
                        }
                        loops.push(out);
                    }
                    if !fc.outer_loop_first && !loops.is_empty() {
                        loops.insert(0, Vec::new());
                    }
                    faces.push(FaceSrc {
                        de: id,
                        surface: fc.surface,
                        loops,
                        param_curves: Vec::new(),
                    });
                }
                Entity::CurveOnSurface(c) => {
                    used_surfaces.insert(c.surface);
                }
                Entity::Boundary(b) => {
                    used_surfaces.insert(b.surface);
                }
                _ => {}
            }
        }
        // Independent surfaces used by nothing: untrimmed faces.
        for (id, r) in f.iter() {
            let is_surface = matches!(
                r.entity,
                Entity::SplineSurface(_)
                    | Entity::BSplineSurface(_)
                    | Entity::RuledSurface(_)
                    | Entity::SurfaceOfRevolution(_)
                    | Entity::TabulatedCylinder(_)
            );
            if is_surface && r.de.status.subordinate == 0 && !used_surfaces.contains(&id) {
                faces.push(FaceSrc {
                    de: id,
                    surface: id,
                    loops: Vec::new(),
                    param_curves: Vec::new(),
                });
            }
        }
        for (id, r) in f.iter() {
            if let Entity::Unknown(_) = r.entity {
                self.report.warnings.push(format!(
                    "entity at D line {} (type {}) is not supported and was skipped",
                    id.line(),
                    r.de.entity_type
                ));
            }
        }
        Ok(faces)
    }

    fn convert_curve(
        &mut self,
        id: DeId,
        on_surface: Option<DeId>,
        tol: f64,
    ) -> Result<(Vec<Arc>, f64), Error> {
        if let Some(c) = self.curve_cache.get(&(id, on_surface)) {
            return Ok(c.clone());
        }
        let ev = self.b.curve(id)?;
        let (arcs, err, method) = match (on_surface, ev.exact()) {
            (None, Some((arcs, _))) => (arcs, 0.0, "exact"),
            _ => {
                let surf = on_surface.map(|s| self.b.surface(s)).transpose()?;
                let f = |t: f64| {
                    let p = ev.point(t);
                    match &surf {
                        Some(s) => s.point(p.x, p.y),
                        None => p,
                    }
                };
                let fit = fit_curve(&f, &ev.breaks(), tol).map_err(|e| {
                    self.bad(
                        id,
                        format!("cannot approximate within {tol:.3e} (best error {e:.3e})"),
                    )
                })?;
                (fit.arcs, fit.max_error, "approximated")
            }
        };
        if arcs.is_empty() {
            return Err(self.bad(id, "the curve has an empty parameter range"));
        }
        self.report.entities.push(EntityConversion {
            de: id.line(),
            entity_type: self.ty(id),
            method,
            pieces: arcs.len(),
            max_error: err,
        });
        self.curve_cache
            .insert((id, on_surface), (arcs.clone(), err));
        Ok((arcs, err))
    }

    fn convert_surface(
        &mut self,
        face: &FaceSrc,
        ev: &SurfEval,
        tol: f64,
    ) -> Result<SupportSurface, Error> {
        let id = face.surface;
        let ((u0, u1), (v0, v1)) = ev.domain();
        // The parameter box of the trimming curves, when they are known.
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for &pc in &face.param_curves {
            let c = self.b.curve(pc)?;
            // Sample every piece between its break points, ends included.
            for w in c.breaks().windows(2) {
                for k in 0..=32 {
                    let p = c.point(w[0] + (w[1] - w[0]) * k as f64 / 32.0);
                    for d in 0..2 {
                        lo[d] = lo[d].min(p[d]);
                        hi[d] = hi[d].max(p[d]);
                    }
                }
            }
        }
        let clip = |l: f64, h: f64, a: f64, b: f64| {
            if !(l.is_finite() && h.is_finite() && h > l) {
                return (a, b);
            }
            let pad = 1e-4 * (b - a);
            let l = if l - pad <= a { a } else { l };
            let h = if h + pad >= b { b } else { h };
            (l.max(a), h.min(b))
        };
        let (ur, vr) = (clip(lo[0], hi[0], u0, u1), clip(lo[1], hi[1], v0, v1));
        if let Some((s, ub, vb)) = ev.exact() {
            // Keep the spans that overlap the trimmed box by more than round-off (drops
            // sliver spans outside the face).
            let keep = |b: &[f64], (l, h): (f64, f64)| {
                let pad = 1e-6 * (b[b.len() - 1] - b[0]);
                let ks: Vec<usize> = (0..b.len() - 1)
                    .filter(|&k| b[k + 1].min(h) - b[k].max(l) > pad)
                    .collect();
                if ks.is_empty() {
                    (0, b.len() - 1)
                } else {
                    (ks[0], ks[ks.len() - 1] + 1)
                }
            };
            let raw = |d: usize, a: f64, b: f64| {
                if lo[d].is_finite() && hi[d].is_finite() && hi[d] > lo[d] {
                    (lo[d], hi[d])
                } else {
                    (a, b)
                }
            };
            let (i0, i1) = keep(&ub, raw(0, u0, u1));
            let (j0, j1) = keep(&vb, raw(1, v0, v1));
            let mut patches = Vec::new();
            for j in j0..j1 {
                for i in i0..i1 {
                    patches.push(s.patch(i, j).clone());
                }
            }
            let s = SupportSurface::new("", i1 - i0, j1 - j0, patches);
            self.report.entities.push(EntityConversion {
                de: id.line(),
                entity_type: self.ty(id),
                method: "exact",
                pieces: s.patches.len(),
                max_error: 0.0,
            });
            return Ok(s);
        }
        let (bu, bv) = ev.breaks();
        let keep = |b: Vec<f64>, (a, c): (f64, f64)| {
            let mut out = vec![a];
            out.extend(b.into_iter().filter(|&x| x > a && x < c));
            out.push(c);
            out
        };
        let f = |u: f64, v: f64| ev.point(u, v);
        let fit = fit_surface(&f, &keep(bu, ur), &keep(bv, vr), tol).map_err(|e| {
            self.bad(
                id,
                format!("cannot approximate within {tol:.3e} (best error {e:.3e})"),
            )
        })?;
        self.report.entities.push(EntityConversion {
            de: id.line(),
            entity_type: self.ty(id),
            method: "approximated",
            pieces: fit.surface.patches.len(),
            max_error: fit.max_error,
        });
        Ok(fit.surface)
    }
}

/// The loop of a support surface's domain boundary, counter-clockwise in (u, v).
fn domain_loop(s: &SupportSurface) -> Vec<Vec<Arc>> {
    let (nu, nv) = (s.n_u, s.n_v);
    let side = |arcs: Vec<Arc>| arcs;
    vec![
        side((0..nu).map(|i| s.patch(i, 0).border(Side::VMin)).collect()),
        side(
            (0..nv)
                .map(|j| s.patch(nu - 1, j).border(Side::UMax))
                .collect(),
        ),
        reverse_arcs(
            &(0..nu)
                .map(|i| s.patch(i, nv - 1).border(Side::VMax))
                .collect::<Vec<_>>(),
        ),
        reverse_arcs(
            &(0..nv)
                .map(|j| s.patch(0, j).border(Side::UMin))
                .collect::<Vec<_>>(),
        ),
    ]
}

/// ∮ G dv over a closed polygon in a surface's global parameters, with
/// G(u, v) = ∫_0^u x·(r_u × r_v)(s, v) ds (Green's theorem: the integral of x·N over the
/// enclosed region, counted positively for a counter-clockwise polygon).
fn green_flux(s: &SupportSurface, poly: &[(f64, f64)]) -> f64 {
    const GAUSS: [(f64, f64); 4] = [
        (0.069_431_844_202_973_71, 0.173_927_422_568_726_93),
        (0.330_009_478_207_571_9, 0.326_072_577_431_273_07),
        (0.669_990_521_792_428_1, 0.326_072_577_431_273_07),
        (0.930_568_155_797_026_3, 0.173_927_422_568_726_93),
    ];
    let g = |u: f64, v: f64| {
        let d = s.derivs(u, v);
        d.point.coords.dot(&d.du.cross(&d.dv))
    };
    let big_g = |u: f64, v: f64| {
        let mut acc = 0.0;
        let mut a = 0.0;
        // Four Gauss intervals per patch width (the integrand has degree ~3n in u).
        while a < u {
            let b = ((a * 4.0).floor() / 4.0 + 0.25).min(u);
            for &(x, w) in &GAUSS {
                acc += w * (b - a) * g(a + x * (b - a), v);
            }
            a = b;
        }
        acc
    };
    let mut total = 0.0;
    for k in 0..poly.len() {
        let (p, q) = (poly[k], poly[(k + 1) % poly.len()]);
        let dv = q.1 - p.1;
        if dv != 0.0 {
            total += big_g(0.5 * (p.0 + q.0), 0.5 * (p.1 + q.1)) * dv;
        }
    }
    total
}

fn shoelace(poly: &[(f64, f64)]) -> f64 {
    let n = poly.len();
    (0..n)
        .map(|k| {
            let (a, b) = (poly[k], poly[(k + 1) % n]);
            a.0 * b.1 - b.0 * a.1
        })
        .sum::<f64>()
        * 0.5
}

/// Converts an IGES file into a validated geometric database.
///
/// Every face (144, 143, 510, or an independent untrimmed surface) becomes a surface
/// component over a support surface; boundary curves become curve components, shared
/// between faces where they coincide within the sewing tolerance. See the module
/// documentation for the algorithms.
pub fn import(file: &IgesFile, opts: &ImportOptions) -> Result<(GeomDb, ImportReport), Error> {
    let mut ctx = Ctx {
        file,
        b: Builder { file },
        report: ImportReport {
            file: file.name.clone(),
            units: unit_name(&file.global),
            reference_length: 0.0,
            tolerance: 0.0,
            sew_tolerance: 0.0,
            entities: Vec::new(),
            max_error: 0.0,
            faces: Vec::new(),
            shells: Vec::new(),
            curve_components: 0,
            sewn_edges: 0,
            max_sew_gap: 0.0,
            free_edges: Vec::new(),
            non_manifold_edges: Vec::new(),
            orientation_conflicts: 0,
            warnings: Vec::new(),
        },
        curve_cache: HashMap::new(),
    };
    let model_err = |reason: String| Error::Model {
        file: file.name.clone(),
        reason,
    };
    let faces = ctx.faces()?;
    if faces.is_empty() {
        return Err(model_err(
            "no surface to import (no 144, 143, 510 or independent surface entity)".into(),
        ));
    }
    // Surface evaluators and the model size.
    let mut evals = Vec::with_capacity(faces.len());
    let (mut lo, mut hi) = (
        Point3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY),
        Point3::new(f64::NEG_INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY),
    );
    for fc in &faces {
        let ev = ctx.b.surface(fc.surface)?;
        let ((u0, u1), (v0, v1)) = ev.domain();
        for i in 0..=8 {
            for j in 0..=8 {
                let p = ev.point(
                    u0 + (u1 - u0) * i as f64 / 8.0,
                    v0 + (v1 - v0) * j as f64 / 8.0,
                );
                if p.coords.iter().all(|c| c.is_finite()) {
                    lo = lo.inf(&p);
                    hi = hi.sup(&p);
                }
            }
        }
        evals.push(ev);
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
        return Err(model_err(format!(
            "tolerances must be positive (approximation {tol}, sewing {sew})"
        )));
    }
    ctx.report.reference_length = size;
    ctx.report.tolerance = tol;
    ctx.report.sew_tolerance = sew;

    // Surfaces and edges.
    let mut surfaces = Vec::with_capacity(faces.len());
    let mut surface_of: BTreeMap<(DeId, Vec<DeId>), usize> = BTreeMap::new();
    let mut face_surface = Vec::with_capacity(faces.len());
    let mut edges: Vec<Edge> = Vec::new();
    // Per face: loops as lists of (edge index, traversed reversed).
    let mut face_loops: Vec<Vec<Vec<(usize, bool)>>> = Vec::new();
    for (fi, (fc, ev)) in faces.iter().zip(&evals).enumerate() {
        let key = (fc.surface, fc.param_curves.clone());
        let si = match surface_of.get(&key) {
            Some(&si) => si,
            None => {
                let mut s = ctx.convert_surface(fc, ev, tol)?;
                s.name = format!("D{} ({})", fc.surface.line(), ctx.ty(fc.surface));
                surfaces.push(s);
                surface_of.insert(key, surfaces.len() - 1);
                surfaces.len() - 1
            }
        };
        face_surface.push(si);
        let mut loops_out = Vec::new();
        let n_loops = fc.loops.len().max(1);
        for li in 0..n_loops {
            let lp = fc.loops.get(li);
            let mut pieces: Vec<(Option<DeId>, Vec<Arc>)> = Vec::new();
            match lp {
                Some(lp) if !lp.is_empty() => {
                    for lc in lp {
                        let (arcs, _) = ctx.convert_curve(lc.de, lc.on_surface, tol)?;
                        let arcs = if lc.reversed {
                            reverse_arcs(&arcs)
                        } else {
                            arcs
                        };
                        pieces.push((Some(lc.de), arcs));
                    }
                }
                _ => {
                    for arcs in domain_loop(&surfaces[si]) {
                        pieces.push((None, arcs));
                    }
                }
            }
            // Drop degenerate pieces (poles).
            let mut ids = Vec::new();
            for (src, arcs) in pieces {
                let samples = curve_samples(&arcs, 4);
                let len: f64 = samples.windows(2).map(|w| (w[1].1 - w[0].1).norm()).sum();
                if len <= sew {
                    continue;
                }
                let (start, end) = (samples[0].1, samples.last().expect("samples").1);
                edges.push(Edge {
                    face: fi,
                    src,
                    arcs,
                    start,
                    end,
                });
                ids.push(edges.len() - 1);
            }
            if ids.is_empty() {
                continue;
            }
            // Chain: choose each piece's direction so that it starts where the previous ends.
            let chain = |first_rev: bool| -> Option<Vec<(usize, bool)>> {
                let mut out = Vec::with_capacity(ids.len());
                let e0 = &edges[ids[0]];
                let (s0, mut cur) = if first_rev {
                    (e0.end, e0.start)
                } else {
                    (e0.start, e0.end)
                };
                out.push((ids[0], first_rev));
                for &k in &ids[1..] {
                    let e = &edges[k];
                    if (e.start - cur).norm() <= sew {
                        out.push((k, false));
                        cur = e.end;
                    } else if (e.end - cur).norm() <= sew {
                        out.push((k, true));
                        cur = e.start;
                    } else {
                        return None;
                    }
                }
                ((cur - s0).norm() <= sew).then_some(out)
            };
            let chained = chain(false).or_else(|| chain(true)).ok_or_else(|| {
                ctx.bad(
                    fc.de,
                    format!(
                        "boundary loop {} is not closed within the sewing tolerance {sew:.3e}",
                        li + 1
                    ),
                )
            })?;
            loops_out.push(chained);
        }
        if loops_out.is_empty() {
            return Err(ctx.bad(fc.de, "the face has no boundary of positive length"));
        }
        face_loops.push(loops_out);
    }

    // Corners.
    let mut corners = PointMerger::new(sew);
    let mut max_gap: f64 = 0.0;
    let mut edge_corners = Vec::with_capacity(edges.len());
    for e in &edges {
        let (a, b) = (corners.insert(e.start), corners.insert(e.end));
        max_gap = max_gap.max(a.distance).max(b.distance);
        edge_corners.push((CornerId::from_index(a.index), CornerId::from_index(b.index)));
    }

    // T-junctions: a corner inside another edge splits that edge there.
    let mut new_edges: Vec<Edge> = Vec::with_capacity(edges.len());
    let mut new_corners = Vec::with_capacity(edges.len());
    let mut replaced: Vec<Vec<usize>> = Vec::with_capacity(edges.len());
    for (e, ed) in edges.into_iter().enumerate() {
        let samples = curve_samples(&ed.arcs, 8);
        let (mut lo, mut hi) = (samples[0].1, samples[0].1);
        for (_, q) in &samples {
            lo = lo.inf(q);
            hi = hi.sup(q);
        }
        let n = ed.arcs.len() as f64;
        let mut cuts: Vec<(f64, CornerId)> = Vec::new();
        for (ci, c) in corners.points().iter().enumerate() {
            let cid = CornerId::from_index(ci);
            if cid == edge_corners[e].0 || cid == edge_corners[e].1 {
                continue;
            }
            let inside = (0..3).all(|k| c[k] >= lo[k] - sew && c[k] <= hi[k] + sew);
            if !inside {
                continue;
            }
            let (d, t) = foot_on_arcs(&ed.arcs, &samples, c);
            let (ps, pe) = (arcs_point(&ed.arcs, t), (ed.start, ed.end));
            if d <= sew && (ps - pe.0).norm() > sew && (ps - pe.1).norm() > sew && t > 0.0 && t < n
            {
                max_gap = max_gap.max(d);
                cuts.push((t, cid));
            }
        }
        cuts.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut ids = Vec::new();
        let mut t_prev = 0.0;
        let mut c_prev = edge_corners[e].0;
        let mut p_prev = ed.start;
        for (t, cid) in cuts
            .into_iter()
            .chain(std::iter::once((n, edge_corners[e].1)))
        {
            if t - t_prev <= 1e-9 * n {
                continue;
            }
            let arcs = split_arcs(&ed.arcs, t_prev, t);
            let end = if t == n {
                ed.end
            } else {
                arcs_point(&ed.arcs, t)
            };
            new_edges.push(Edge {
                face: ed.face,
                src: ed.src,
                arcs,
                start: p_prev,
                end,
            });
            new_corners.push((c_prev, cid));
            ids.push(new_edges.len() - 1);
            t_prev = t;
            c_prev = cid;
            p_prev = end;
        }
        replaced.push(ids);
    }
    let edges = new_edges;
    let edge_corners = new_corners;
    for loops in &mut face_loops {
        for lp in loops.iter_mut() {
            let mut out = Vec::with_capacity(lp.len());
            for &(e, rev) in lp.iter() {
                let ids = &replaced[e];
                if rev {
                    out.extend(ids.iter().rev().map(|&k| (k, true)));
                } else {
                    out.extend(ids.iter().map(|&k| (k, false)));
                }
            }
            *lp = out;
        }
    }

    // Sewing: group coincident edges.
    let samples: Vec<Vec<(f64, Point3)>> =
        edges.iter().map(|e| curve_samples(&e.arcs, 16)).collect();
    // master[e] = (master edge, e runs against the master)
    let mut master: Vec<(usize, bool)> = (0..edges.len()).map(|e| (e, false)).collect();
    let mut by_pair: BTreeMap<(CornerId, CornerId), Vec<usize>> = BTreeMap::new();
    for (e, &(a, b)) in edge_corners.iter().enumerate() {
        by_pair.entry((a.min(b), a.max(b))).or_default().push(e);
    }
    for group in by_pair.values() {
        let mut masters: Vec<usize> = Vec::new();
        for &e in group {
            let mut found = None;
            for &m in &masters {
                // Coincident: e's samples lie on m.
                let probe: Vec<Point3> = (1..8)
                    .map(|k| {
                        arcs_point(&edges[e].arcs, edges[e].arcs.len() as f64 * k as f64 / 8.0)
                    })
                    .collect();
                let d = probe
                    .iter()
                    .map(|p| distance_to_arcs(&edges[m].arcs, &samples[m], p))
                    .fold(0.0, f64::max);
                if d <= sew {
                    let against = if edge_corners[e].0 != edge_corners[e].1 {
                        edge_corners[e].0 != edge_corners[m].0
                    } else {
                        // Closed edges: compare the quarter points.
                        let q = arcs_point(&edges[e].arcs, edges[e].arcs.len() as f64 * 0.25);
                        let nm = edges[m].arcs.len() as f64;
                        (arcs_point(&edges[m].arcs, 0.75 * nm) - q).norm()
                            < (arcs_point(&edges[m].arcs, 0.25 * nm) - q).norm()
                    };
                    max_gap = max_gap.max(d);
                    found = Some((m, against));
                    break;
                }
            }
            match found {
                Some(x) => master[e] = x,
                None => masters.push(e),
            }
        }
    }

    // Database: corners, curves, curve components.
    let model_name = if file.global.sender_product_id.trim().is_empty() {
        file.start.lines().next().unwrap_or("").trim().to_string()
    } else {
        file.global.sender_product_id.trim().to_string()
    };
    let mut db = GeomDb::empty(model_name);
    db.units = ctx.report.units.clone();
    db.corners = corners
        .points()
        .iter()
        .map(|&p| Corner {
            point: p,
            name: String::new(),
        })
        .collect();
    let mut comp_of_master: BTreeMap<usize, CurveCompId> = BTreeMap::new();
    let mut comp_sources: Vec<Vec<u32>> = Vec::new();
    for e in 0..edges.len() {
        if master[e].0 != e {
            continue;
        }
        let ed = &edges[e];
        let name = match ed.src {
            Some(d) => format!("D{} ({})", d.line(), ctx.ty(d)),
            None => format!("domain boundary of surface {}", face_surface[ed.face]),
        };
        let cid = CurveId::from_index(db.curves.len());
        let n = ed.arcs.len() as f64;
        db.curves
            .push(SupportCurve::new(name.clone(), ed.arcs.clone()));
        let (a, b) = edge_corners[e];
        comp_of_master.insert(e, CurveCompId::from_index(db.curve_components.len()));
        db.curve_components.push(CurveComponent {
            name,
            curve: cid,
            t0: 0.0,
            t1: n,
            start: a,
            end: b,
        });
        comp_sources.push(Vec::new());
    }
    for (e, ed) in edges.iter().enumerate() {
        let c = comp_of_master[&master[e].0];
        if let Some(d) = ed.src {
            let v = &mut comp_sources[c.index()];
            if !v.contains(&d.line()) {
                v.push(d.line());
            }
        }
    }

    // Surface components with loops; initial orientation from the outer loop's winding.
    let inv_opts = InvertOptions::new(size);
    let projectors: Vec<Option<SurfaceInverter<'_, SupportSurface>>> = surfaces
        .iter()
        .map(|s| SurfaceInverter::new("", s, &inv_opts).ok())
        .collect();
    let loop_poly = |fi: usize,
                     lp: &[(usize, bool)],
                     loops: &[OrientedCurve],
                     db: &GeomDb|
     -> Vec<(f64, f64)> {
        let pr = &projectors[face_surface[fi]];
        let mut poly = Vec::new();
        for oc in loops {
            let cc = &db.curve_components[oc.comp.index()];
            let arcs = &db.curves[cc.curve.index()].arcs;
            let n = (4 * arcs.len()).clamp(16, 256);
            for k in 0..n {
                let s_ = k as f64 / n as f64;
                let f = if oc.reversed { 1.0 - s_ } else { s_ };
                let p = arcs_point(arcs, cc.param_at(f));
                let uv = pr.as_ref().and_then(|pr| pr.nearest_indexed(&p, k).ok());
                poly.push(uv.map_or((f64::NAN, f64::NAN), |f| (f.uv[0], f.uv[1])));
            }
        }
        let _ = lp;
        poly
    };
    let mut comps: Vec<SurfaceComponent> = Vec::new();
    for (fi, loops) in face_loops.iter().enumerate() {
        let mut out_loops = Vec::new();
        for lp in loops {
            let ocs: Vec<OrientedCurve> = lp
                .iter()
                .map(|&(e, rev)| OrientedCurve {
                    comp: comp_of_master[&master[e].0],
                    reversed: rev ^ master[e].1,
                })
                .collect();
            out_loops.push(ocs);
        }
        let area = shoelace(&loop_poly(fi, &loops[0], &out_loops[0], &db));
        let inward = if area >= 0.0 {
            Orientation::Positive
        } else {
            Orientation::Negative
        };
        comps.push(SurfaceComponent {
            name: format!("D{} ({})", faces[fi].de.line(), ctx.ty(faces[fi].de)),
            surface: SurfaceId::from_index(face_surface[fi]),
            loops: out_loops,
            inward,
        });
    }

    // Uses of each curve component.
    let mut uses: BTreeMap<CurveCompId, Vec<(usize, bool)>> = BTreeMap::new();
    for (fi, c) in comps.iter().enumerate() {
        for lp in &c.loops {
            for oc in lp {
                uses.entry(oc.comp).or_default().push((fi, oc.reversed));
            }
        }
    }
    // Consistent orientation by a breadth-first walk.
    let nf = comps.len();
    let mut flip: Vec<Option<bool>> = vec![None; nf];
    let mut shell_of = vec![usize::MAX; nf];
    let mut n_shells = 0;
    let mut conflicts = 0;
    let mut adj: Vec<Vec<(usize, bool)>> = vec![Vec::new(); nf];
    for u in uses.values() {
        if let [(f1, r1), (f2, r2)] = u.as_slice()
            && f1 != f2
        {
            // flips must differ iff the uses run the same way
            adj[*f1].push((*f2, r1 == r2));
            adj[*f2].push((*f1, r1 == r2));
        }
    }
    for start in 0..nf {
        if flip[start].is_some() {
            continue;
        }
        flip[start] = Some(false);
        shell_of[start] = n_shells;
        let mut q = VecDeque::from([start]);
        while let Some(f) = q.pop_front() {
            for &(g, differ) in &adj[f] {
                let want = flip[f].expect("visited") ^ differ;
                match flip[g] {
                    None => {
                        flip[g] = Some(want);
                        shell_of[g] = n_shells;
                        q.push_back(g);
                    }
                    Some(x) if x != want => conflicts += 1,
                    _ => {}
                }
            }
        }
        n_shells += 1;
    }
    let apply_flip = |c: &mut SurfaceComponent| {
        for lp in &mut c.loops {
            lp.reverse();
            lp.iter_mut().for_each(|oc| oc.reversed = !oc.reversed);
        }
        c.inward = match c.inward {
            Orientation::Positive => Orientation::Negative,
            Orientation::Negative => Orientation::Positive,
        };
    };
    for (c, f) in comps.iter_mut().zip(&flip) {
        if f == &Some(true) {
            apply_flip(c);
        }
    }
    // Shell volumes and the global choice.
    let mut volumes = vec![0.0; n_shells];
    let mut sizes = vec![
        (
            Point3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY),
            Point3::new(f64::NEG_INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY)
        );
        n_shells
    ];
    for (fi, c) in comps.iter().enumerate() {
        let sh = shell_of[fi];
        for lp in &c.loops {
            let poly = loop_poly(fi, &[], lp, &db);
            volumes[sh] += green_flux(&surfaces[face_surface[fi]], &poly) / 3.0;
            for oc in lp {
                let cc = &db.curve_components[oc.comp.index()];
                for p in [
                    db.corners[cc.start.index()].point,
                    db.corners[cc.end.index()].point,
                ] {
                    sizes[sh].0 = sizes[sh].0.inf(&p);
                    sizes[sh].1 = sizes[sh].1.sup(&p);
                }
            }
        }
    }
    let diag: Vec<f64> = sizes
        .iter()
        .map(|(a, b)| {
            let d = (b - a).norm();
            if d.is_finite() { d } else { 0.0 }
        })
        .collect();
    let largest = (0..n_shells)
        .max_by(|&a, &b| diag[a].total_cmp(&diag[b]).then(b.cmp(&a)))
        .unwrap_or(0);
    let mut shell_flip = vec![false; n_shells];
    for sh in 0..n_shells {
        let want_negative = sh == largest;
        shell_flip[sh] = (volumes[sh] > 0.0) == want_negative;
        if opts.flip {
            shell_flip[sh] = !shell_flip[sh];
        }
        if shell_flip[sh] {
            volumes[sh] = -volumes[sh];
        }
    }
    for (fi, c) in comps.iter_mut().enumerate() {
        if shell_flip[shell_of[fi]] {
            apply_flip(c);
        }
    }
    db.surfaces = surfaces;
    db.surface_components = comps;

    // Report.
    let rep = &mut ctx.report;
    rep.orientation_conflicts = conflicts;
    rep.max_sew_gap = max_gap;
    rep.curve_components = db.curve_components.len();
    let mut uses: BTreeMap<CurveCompId, Vec<usize>> = BTreeMap::new();
    for (fi, c) in db.surface_components.iter().enumerate() {
        for lp in &c.loops {
            for oc in lp {
                uses.entry(oc.comp).or_default().push(fi);
            }
        }
    }
    let mut shell_closed = vec![true; n_shells];
    for (c, fs) in &uses {
        let er = EdgeReport {
            component: c.index(),
            curves: comp_sources[c.index()].clone(),
            faces: fs.iter().map(|&f| faces[f].de.line()).collect(),
        };
        match fs.len() {
            2 => rep.sewn_edges += 1,
            1 => {
                shell_closed[shell_of[fs[0]]] = false;
                rep.free_edges.push(er);
            }
            _ => {
                fs.iter().for_each(|&f| shell_closed[shell_of[f]] = false);
                rep.non_manifold_edges.push(er);
            }
        }
    }
    let roles = roles::recognise(&db, rep.sew_tolerance);
    for (fi, (c, r)) in db.surface_components.iter_mut().zip(&roles).enumerate() {
        c.name = format!("{}.D{}", r.name().replace(' ', ""), faces[fi].de.line());
    }
    for (fi, c) in db.surface_components.iter().enumerate() {
        rep.faces.push(FaceReport {
            role: roles[fi].name(),
            de: faces[fi].de.line(),
            entity_type: file.get(faces[fi].de).map_or(0, |r| r.de.entity_type),
            surface_de: faces[fi].surface.line(),
            component: fi,
            loops: c.loops.len(),
            inward: match c.inward {
                Orientation::Positive => "positive",
                Orientation::Negative => "negative",
            },
            shell: shell_of[fi],
        });
    }
    for sh in 0..n_shells {
        rep.shells.push(ShellReport {
            faces: shell_of.iter().filter(|&&s| s == sh).count(),
            closed: shell_closed[sh],
            volume: volumes[sh],
            size: diag[sh],
        });
    }
    rep.max_error = rep.entities.iter().map(|e| e.max_error).fold(0.0, f64::max);
    if conflicts > 0 {
        rep.warnings.push(format!("{conflicts} shared edges could not be oriented consistently (non-orientable or inconsistent model)"));
    }
    db.validate().map_err(|e| Error::Invalid {
        file: file.name.clone(),
        source: Box::new(e),
    })?;
    db.refresh_baseline();
    Ok((db, ctx.report))
}

fn unit_name(g: &iges::Global) -> Option<String> {
    let mm = g.unit_in_mm()?;
    let name = [
        (1.0, "mm"),
        (25.4, "in"),
        (304.8, "ft"),
        (1000.0, "m"),
        (10.0, "cm"),
        (1e6, "km"),
        (0.001, "um"),
    ]
    .iter()
    .find(|(v, _)| (*v - mm).abs() <= 1e-9 * v)
    .map(|(_, n)| n.to_string());
    Some(name.unwrap_or_else(|| format!("{mm} mm")))
}
