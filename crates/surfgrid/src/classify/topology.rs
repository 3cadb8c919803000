//! Classification stages 1–2: which surface component each marker's triangles belong to,
//! and which nodes are boundary nodes (used by two components, on a free edge of their
//! marker, or on a seam curve or corner of their component).

use std::collections::HashMap;

use geom_db::eval::ParamCurve;
use geom_db::prelude::Point3;
use geom_db::{CurveCompId, SurfCompId};
use intersect::project::CurveProjector;
use mesh::{ElementKind, Mesh};

use super::Context;
use crate::error::{Error, Result};
use crate::grid::marker_name;

/// The triangles of one marker, with the surface component the marker names.
pub(super) struct ComponentTriangles {
    /// The surface component.
    pub comp: SurfCompId,
    /// Its triangles (global nodes, as in the marker).
    pub triangles: Vec<[u32; 3]>,
}

/// Stage 1: every marker matched to its surface component by name (triangles only).
pub(super) fn components(mesh: &Mesh, ctx: &Context<'_>) -> Result<Vec<ComponentTriangles>> {
    let db = ctx.db;
    let mut out = Vec::new();
    for m in &mesh.markers {
        let comp = (0..db.surface_components.len())
            .map(SurfCompId::from_index)
            .find(|&c| marker_name(db, c) == m.name)
            .ok_or_else(|| Error::UnknownMarker {
                marker: m.name.clone(),
            })?;
        if m.elements.count(ElementKind::Quad) > 0 {
            return Err(Error::Mismatch {
                what: format!("marker {:?} has quadrilaterals (triangles only)", m.name),
            });
        }
        let triangles = m
            .elements
            .group(ElementKind::Triangle)
            .map(|g| g.iter().map(|t| [t[0], t[1], t[2]]).collect())
            .unwrap_or_default();
        out.push(ComponentTriangles { comp, triangles });
    }
    Ok(out)
}

/// Per node: the components whose triangles use it, and whether it is a boundary node.
pub(super) struct Topology {
    /// Components using each node (empty: a node of no marker).
    pub comps_of: Vec<Vec<SurfCompId>>,
    /// Boundary nodes: classified on corners and curves, one local copy per side.
    pub boundary: Vec<bool>,
}

/// Stage 2: nodes used by two or more components, or on a free edge of their marker (an
/// edge of one triangle), or (within the tolerance) on a seam curve of their component (a
/// curve component its loops use twice, e.g. the wing's trailing edge, a cylinder cap's
/// radius) or on one of its corners, are boundary nodes.
pub(super) fn topology(comps: &[ComponentTriangles], ctx: &Context<'_>) -> Result<Topology> {
    let n = ctx.coords.len();
    let mut comps_of: Vec<Vec<SurfCompId>> = vec![Vec::new(); n];
    let mut boundary = vec![false; n];
    for ComponentTriangles { comp: c, triangles } in comps {
        let mut ecount: HashMap<(u32, u32), u32> = HashMap::new();
        for t in triangles {
            for i in 0..3 {
                let (a, b) = (t[i], t[(i + 1) % 3]);
                *ecount.entry((a.min(b), a.max(b))).or_insert(0) += 1;
                if !comps_of[a as usize].contains(c) {
                    comps_of[a as usize].push(*c);
                }
            }
        }
        for (&(a, b), &k) in &ecount {
            if k == 1 {
                boundary[a as usize] = true;
                boundary[b as usize] = true;
            }
        }
    }
    for (i, cs) in comps_of.iter().enumerate() {
        if cs.len() > 1 {
            boundary[i] = true;
        }
    }
    let mut topo = Topology { comps_of, boundary };
    for c in comps {
        mark_seam_nodes(c.comp, ctx, &mut topo)?;
    }
    Ok(topo)
}

/// Marks as boundary the nodes inside the one marker of component `c` that lie on a seam
/// curve of it (a curve component used twice by its loops) or on a corner of one (the cap's
/// centre, a pole).
fn mark_seam_nodes(c: SurfCompId, ctx: &Context<'_>, topo: &mut Topology) -> Result<()> {
    let (db, tol) = (ctx.db, ctx.tol);
    let sc = db.surface_component(c);
    let mut count: HashMap<CurveCompId, usize> = HashMap::new();
    for oc in sc.loops.iter().flatten() {
        *count.entry(oc.comp).or_insert(0) += 1;
    }
    let mut seams: Vec<CurveCompId> = count
        .into_iter()
        .filter(|&(_, k)| k > 1)
        .map(|(cc, _)| cc)
        .collect();
    seams.sort_unstable();
    for cc in seams {
        let comp = db.curve_component(cc);
        let curve = db.curve(comp.curve);
        // samples of the component, for a box test and the Newton start
        let samples: Vec<(f64, Point3)> = (0..=256)
            .map(|k| {
                let t = comp.param_at(k as f64 / 256.0);
                (t, curve.point(t))
            })
            .collect();
        let (mut lo, mut hi) = (samples[0].1, samples[0].1);
        for (_, q) in &samples {
            lo = lo.inf(q);
            hi = hi.sup(q);
        }
        let pad = 0.01 * (hi - lo).norm() + tol;
        let pr = CurveProjector::new(curve.name.clone(), curve, &ctx.popts)?;
        let (tlo, thi) = (comp.t0.min(comp.t1), comp.t0.max(comp.t1));
        for i in 0..ctx.coords.len() {
            if topo.boundary[i] || topo.comps_of[i].len() != 1 || topo.comps_of[i][0] != c {
                continue;
            }
            let p = ctx.coords[i];
            if (0..3).any(|k| p[k] < lo[k] - pad || p[k] > hi[k] + pad) {
                continue;
            }
            let t0 = samples
                .iter()
                .min_by(|a, b| (a.1 - p).norm().total_cmp(&(b.1 - p).norm()))
                .map(|x| x.0)
                .expect("samples");
            let f = pr.project_from(&p, t0);
            let t = f.t.clamp(tlo, thi);
            if (curve.point(t) - p).norm() <= tol {
                topo.boundary[i] = true;
            }
        }
    }
    Ok(())
}
