//! Classification stage 3: every node used by a marker gets its support entity and
//! parameters by projection (Eq. 11): an interior node on its component's surface, a
//! boundary node on a corner (within the tolerance) or else on the nearest curve component
//! of its components' loops.

use std::collections::HashMap;

use geom_db::eval::ParamCurve;
use geom_db::{CurveCompId, SupportCurve};
use intersect::project::CurveProjector;

use super::Context;
use super::topology::Topology;
use crate::error::{Error, Result};
use crate::grid::NodeSupport;

/// Per node: its support and its distance from it.
pub(super) struct Supports {
    /// Support entity and parameters (`Free` for a node of no marker).
    pub support: Vec<NodeSupport>,
    /// Distance of the node from its support before snapping.
    pub dist: Vec<f64>,
    /// True for the nodes used by a marker.
    pub used: Vec<bool>,
}

/// Stage 3: the support of every node used by a marker; a node farther than the tolerance
/// from every candidate is an error naming it.
pub(super) fn supports(ctx: &Context<'_>, topo: &Topology) -> Result<Supports> {
    let (db, tol) = (ctx.db, ctx.tol);
    let n = ctx.coords.len();
    let mut curve_proj: HashMap<u32, CurveProjector<'_, SupportCurve>> = HashMap::new();
    let mut out = Supports {
        support: vec![NodeSupport::Free; n],
        dist: vec![0.0; n],
        used: vec![false; n],
    };
    for i in 0..n {
        let cs = &topo.comps_of[i];
        if cs.is_empty() {
            continue;
        }
        out.used[i] = true;
        let p = ctx.coords[i];
        if !topo.boundary[i] {
            let f = ctx.surf_proj[cs[0].index()].project_indexed(&p, i)?;
            if f.distance > tol {
                return Err(Error::NodeOffGeometry {
                    node: i,
                    entity: format!("{} ({})", cs[0], db.surface_component(cs[0]).name),
                    distance: f.distance,
                    tol,
                });
            }
            out.support[i] = NodeSupport::Surface {
                comp: cs[0],
                uv: f.uv,
            };
            out.dist[i] = f.distance;
            continue;
        }
        let mut curves: Vec<CurveCompId> = cs
            .iter()
            .flat_map(|c| {
                db.surface_component(*c)
                    .loops
                    .iter()
                    .flatten()
                    .map(|oc| oc.comp)
            })
            .collect();
        curves.sort_unstable();
        curves.dedup();
        let mut best: (f64, Option<NodeSupport>, String) = (f64::INFINITY, None, String::new());
        for &cc in &curves {
            let comp = db.curve_component(cc);
            for k in [comp.start, comp.end] {
                let d = (db.corner(k).point - p).norm();
                if d <= tol && d < best.0 {
                    best = (d, Some(NodeSupport::Corner(k)), k.to_string());
                }
            }
        }
        if best.1.is_none() {
            for &cc in &curves {
                let comp = db.curve_component(cc);
                let curve = db.curve(comp.curve);
                if let std::collections::hash_map::Entry::Vacant(e) = curve_proj.entry(comp.curve.0)
                {
                    e.insert(CurveProjector::new(curve.name.clone(), curve, &ctx.popts)?);
                }
                let pr = &curve_proj[&comp.curve.0];
                let (lo, hi) = (comp.t0.min(comp.t1), comp.t0.max(comp.t1));
                // local search from the parameter of the nearest of a few samples in range
                let mut t0 = lo;
                let mut dmin = f64::INFINITY;
                for s in 0..=32 {
                    let t = lo + (hi - lo) * s as f64 / 32.0;
                    let d = (curve.point(t) - p).norm();
                    if d < dmin {
                        dmin = d;
                        t0 = t;
                    }
                }
                // and the global foot on the whole support curve (a closed junction loop
                // passes near itself at a sharp trailing edge, where the nearest of the
                // samples can seed the wrong side), when it falls in the component's range
                let local = pr.project_from(&p, t0).t;
                let global = pr.project(&p).ok().map(|f| f.t);
                for t in std::iter::once(local).chain(global) {
                    let t = t.clamp(lo, hi);
                    let d = (curve.point(t) - p).norm();
                    if d < best.0 {
                        best = (d, Some(NodeSupport::Curve { comp: cc, t }), cc.to_string());
                    }
                }
            }
        }
        match best {
            (d, Some(s), _) if d <= tol => {
                out.support[i] = s;
                out.dist[i] = d;
            }
            (distance, _, entity) => {
                return Err(Error::NodeOffGeometry {
                    node: i,
                    entity,
                    distance,
                    tol,
                });
            }
        }
    }
    Ok(out)
}

/// Per curve component, its classified nodes ordered by parameter between its start and
/// end corners (empty for a component without nodes).
pub(super) fn curve_nodes(ctx: &Context<'_>, s: &Supports) -> Vec<Vec<u32>> {
    let db = ctx.db;
    let mut curve_nodes: Vec<Vec<u32>> = vec![Vec::new(); db.curve_components.len()];
    let mut on_curve: Vec<Vec<(f64, u32)>> = vec![Vec::new(); db.curve_components.len()];
    for (i, sup) in s.support.iter().enumerate() {
        if let (true, NodeSupport::Curve { comp, t }) = (s.used[i], sup) {
            let cc = db.curve_component(*comp);
            on_curve[comp.index()].push(((t - cc.t0) / (cc.t1 - cc.t0), i as u32));
        }
    }
    for (k, mut l) in on_curve.into_iter().enumerate() {
        if l.is_empty() {
            continue;
        }
        l.sort_by(|a, b| a.0.total_cmp(&b.0));
        let cc = &db.curve_components[k];
        let mut ns = vec![cc.start.0];
        ns.extend(l.iter().map(|x| x.1));
        ns.push(cc.end.0);
        curve_nodes[k] = ns;
    }
    curve_nodes
}
