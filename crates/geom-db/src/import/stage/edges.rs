//! Stage 2, edges: every edge use of every face loop converted to power-basis arcs (Eqs.
//! 2–6) — exactly where the curve is polynomial, else interpolated at the control nodes
//! within the tolerance — each curve range once. A face without loops gets its support
//! surface's domain boundary. Pieces shorter than the sewing tolerance (poles, the apex of a
//! cone) are dropped.

use std::collections::HashMap;

use super::super::approx::fit_curve;
use super::super::model::{CadModel, Source};
use super::super::{EntityConversion, Error};
use super::faces::Faces;
use super::{curve_samples, entity_name, reverse_arcs};
use crate::curve::Arc;
use crate::prelude::Point3;
use crate::surface::{Side, SupportSurface};

/// One converted boundary piece of one face loop.
#[derive(Debug, Clone)]
pub(crate) struct Edge {
    /// The model face.
    pub face: usize,
    /// The curve's source entity (`None` for a support surface's domain boundary).
    pub src: Option<Source>,
    /// The file's topological edge, when it has one.
    pub file_edge: Option<Source>,
    /// The arcs, in the direction the loop runs.
    pub arcs: Vec<Arc>,
    /// First point.
    pub start: Point3,
    /// Last point.
    pub end: Point3,
}

/// What stage 2 produces.
pub(crate) struct Edges {
    /// All pieces.
    pub edges: Vec<Edge>,
    /// Per face, per loop: the edge indices in loop order (before chaining).
    pub loops: Vec<Vec<Vec<usize>>>,
    /// One entry per converted curve range.
    pub conversions: Vec<EntityConversion>,
}

/// The loop of a support surface's domain boundary, counter-clockwise in (u, v).
fn domain_loop(s: &SupportSurface) -> Vec<Vec<Arc>> {
    let (nu, nv) = (s.n_u, s.n_v);
    vec![
        (0..nu).map(|i| s.patch(i, 0).border(Side::VMin)).collect(),
        (0..nv)
            .map(|j| s.patch(nu - 1, j).border(Side::UMax))
            .collect(),
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

/// Runs stage 2.
pub(crate) fn run(model: &CadModel, faces: &Faces) -> Result<Edges, Error> {
    let (tol, sew) = (faces.tol, faces.sew);
    let mut cache: HashMap<(usize, u64, u64), Vec<Arc>> = HashMap::new();
    let mut conversions = Vec::new();
    let mut edges = Vec::new();
    let mut loops = Vec::with_capacity(model.faces.len());
    for (fi, face) in model.faces.iter().enumerate() {
        let mut face_loops = Vec::new();
        let n_loops = face.loops.len().max(1);
        for li in 0..n_loops {
            let mut pieces: Vec<(Option<Source>, Option<Source>, Vec<Arc>)> = Vec::new();
            match face.loops.get(li) {
                Some(lp) if !lp.edges.is_empty() => {
                    for u in &lp.edges {
                        let (lo, hi) = (u.t0.min(u.t1), u.t0.max(u.t1));
                        let mc = &model.curves[u.curve];
                        let key = (u.curve, lo.to_bits(), hi.to_bits());
                        let arcs = match cache.get(&key) {
                            Some(a) => a.clone(),
                            None => {
                                let (arcs, conv) = convert(model, u.curve, lo, hi, tol)?;
                                conversions.push(conv);
                                cache.insert(key, arcs.clone());
                                arcs
                            }
                        };
                        let arcs = if u.t0 > u.t1 {
                            reverse_arcs(&arcs)
                        } else {
                            arcs
                        };
                        pieces.push((Some(mc.source.clone()), u.edge.clone(), arcs));
                    }
                }
                _ => {
                    let sup = &faces.supports[faces.faces[fi].support].surface;
                    for arcs in domain_loop(sup) {
                        pieces.push((None, None, arcs));
                    }
                }
            }
            let mut ids = Vec::new();
            for (src, file_edge, arcs) in pieces {
                let samples = curve_samples(&arcs, 4);
                let len: f64 = samples.windows(2).map(|w| (w[1].1 - w[0].1).norm()).sum();
                if len <= sew {
                    continue;
                }
                let (start, end) = (samples[0].1, samples.last().expect("samples").1);
                edges.push(Edge {
                    face: fi,
                    src,
                    file_edge,
                    arcs,
                    start,
                    end,
                });
                ids.push(edges.len() - 1);
            }
            if !ids.is_empty() {
                face_loops.push(ids);
            }
        }
        if face_loops.is_empty() {
            return Err(Error::Entity {
                file: model.file.clone(),
                entity: entity_name(model, &face.source),
                reason: "the face has no boundary of positive length".into(),
            });
        }
        loops.push(face_loops);
    }
    Ok(Edges {
        edges,
        loops,
        conversions,
    })
}

/// The arcs of a curve on [lo, hi], with the conversion's report (the error sampled at 8
/// points per arc between and at the nodes, against the exact curve).
fn convert(
    model: &CadModel,
    ci: usize,
    lo: f64,
    hi: f64,
    tol: f64,
) -> Result<(Vec<Arc>, EntityConversion), Error> {
    let mc = &model.curves[ci];
    let c = &mc.curve;
    let bad = |reason: String| Error::Entity {
        file: model.file.clone(),
        entity: entity_name(model, &mc.source),
        reason,
    };
    if !(hi > lo) || !lo.is_finite() || !hi.is_finite() {
        return Err(bad(format!(
            "the curve's parameter range [{lo}, {hi}] is empty or infinite"
        )));
    }
    // Each arc with the source interval it covers; the error is sampled at 8 points of
    // every arc (between and at the nodes) against the source at the same parameter.
    let (pieces, method, mut err) = match c.exact_arcs(lo, hi) {
        Some(p) => (p, "exact", 0.0f64),
        None => {
            let f = |t: f64| c.point(t);
            let fit = fit_curve(&f, &c.breaks(lo, hi), tol).map_err(|e| {
                bad(format!(
                    "cannot approximate within {tol:.3e} (best error {e:.3e})"
                ))
            })?;
            (fit.pieces, "fitted", fit.max_error)
        }
    };
    if pieces.is_empty() {
        return Err(bad("the curve has an empty parameter range".into()));
    }
    for (a, b, arc) in &pieces {
        for k in 0..=8 {
            let s = k as f64 / 8.0;
            let d = (arc.point(s) - c.point(a + s * (b - a))).norm();
            err = if d.is_nan() {
                f64::INFINITY
            } else {
                err.max(d)
            };
        }
    }
    if !err.is_finite() || (method == "exact" && err > tol) {
        // Exact arcs cannot be off, nor fitted ones infinitely, but for a corrupt entity
        // (an overflowing coordinate, a NaN weight).
        return Err(bad(format!(
            "its {method} arcs are {err:.3e} from the curve (tolerance {tol:.3e})"
        )));
    }
    let arcs: Vec<Arc> = pieces.into_iter().map(|x| x.2).collect();
    Ok((
        arcs.clone(),
        EntityConversion {
            entity: mc.source.label.clone(),
            kind: mc.source.kind.clone(),
            method,
            pieces: arcs.len(),
            max_error: err,
        },
    ))
}
