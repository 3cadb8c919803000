//! Stage 2, edges: every edge use of every face loop converted to power-basis arcs (Eqs.
//! 2–6) — exactly where the curve is polynomial, else interpolated at the control nodes
//! within the tolerance — each curve range once. A face without loops gets its support
//! surface's domain boundary. Pieces shorter than the sewing tolerance (poles, the apex of a
//! cone) are dropped.

use std::collections::HashMap;

use super::super::approx::{EXACT_MAX_DEGREE, chord_length, fit_curve, merge_short_spans};
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
                                let (arcs, conv) = convert(model, u.curve, lo, hi, (tol, sew))?;
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
///
/// A polynomial curve is converted exactly unless that is ill-conditioned: a degree above
/// [`EXACT_MAX_DEGREE`], a knot span no longer than the sewing tolerance (it would be a
/// degenerate arc), or exact arcs off by more than the tolerance. Then, as a curve that is
/// not polynomial, it is interpolated at the control nodes of degree-7 arcs from its own
/// evaluation, over its knot spans with the short ones merged into their neighbours, and
/// its report says why (`note`). A curve that cannot be fitted within the tolerance fails
/// naming the entity and the `--tolerance` that would let it pass.
fn convert(
    model: &CadModel,
    ci: usize,
    lo: f64,
    hi: f64,
    (tol, sew): (f64, f64),
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
    let f = |t: f64| c.point(t);
    // The error of arcs against the curve at 9 points of each (between and at the nodes).
    let sampled = |pieces: &[(f64, f64, Arc)]| {
        let mut err: f64 = 0.0;
        for (a, b, arc) in pieces {
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
        err
    };
    let mut note = None;
    let exact = c
        .exact_arcs(lo, hi)
        .filter(|p| !p.is_empty())
        .and_then(|p| {
            let degree = p.iter().map(|x| x.2.degree).max().unwrap_or(0);
            let short = p
                .iter()
                .filter(|(a, b, _)| chord_length(&f, *a, *b) <= sew)
                .count();
            let err = sampled(&p);
            let why = if degree > EXACT_MAX_DEGREE {
                format!("degree {degree} above {EXACT_MAX_DEGREE}")
            } else if short > 0 {
                format!("{short} knot spans no longer than the sewing tolerance {sew:.3e}")
            } else if !(err <= tol) {
                format!("its exact arcs are {err:.3e} off (round-off), above the tolerance")
            } else {
                return Some((p, err));
            };
            note = Some(why);
            None
        });
    let (pieces, method, mut err) = match exact {
        Some((p, err)) => (p, "exact", err),
        None => {
            let (breaks, merged) =
                merge_short_spans(&c.breaks(lo, hi), &|a, b| chord_length(&f, a, b), sew);
            if merged > 0 {
                let m = format!("{merged} knot spans shorter than {sew:.3e} merged");
                note = Some(match note {
                    Some(n) => format!("{n}; {m}"),
                    None => m,
                });
            }
            let fit = fit_curve(&f, &breaks, tol).map_err(|e| {
                bad(format!(
                    "cannot approximate within {tol:.3e} (best error {e:.3e}); --tolerance {} would let it pass",
                    suggest_tolerance(e)
                ))
            })?;
            let method = if note.is_some() {
                "reapproximated"
            } else {
                "fitted"
            };
            (fit.pieces, method, fit.max_error)
        }
    };
    err = err.max(sampled(&pieces));
    if !err.is_finite() {
        // Fitted arcs cannot be infinitely off but for a corrupt entity (an overflowing
        // coordinate, a NaN weight).
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
            note,
        },
    ))
}

/// A tolerance that would accept a fit whose best error was `e`: 2 e rounded up to two
/// significant digits.
pub(crate) fn suggest_tolerance(e: f64) -> String {
    if !e.is_finite() {
        return "(none: the entity does not evaluate)".into();
    }
    let x = 2.0 * e.max(f64::MIN_POSITIVE);
    let exp = x.log10().floor() as i32;
    let d = (x / 10f64.powi(exp - 1)).ceil() as i64; // 10..=100
    let (d, exp) = if d >= 100 { (10, exp + 1) } else { (d, exp) };
    format!("{}.{}e{exp}", d / 10, d % 10)
}

#[cfg(test)]
mod tests {
    #[test]
    fn suggested_tolerances_are_above_twice_the_error() {
        assert_eq!(super::suggest_tolerance(1.234e-6), "2.5e-6");
        assert_eq!(super::suggest_tolerance(4.99e-3), "1.0e-2");
        assert_eq!(super::suggest_tolerance(5.01e-7), "1.1e-6");
    }
}
