//! Classification of an imported surface grid (e.g. SU2, no parameters) against a database:
//! every node gets its support entity and parameters by projection (Eq. 11).
//!
//! Markers are matched to surface components by name. A node used by two or more markers, or
//! lying on a free edge of its marker (an edge used by one triangle of it), or lying (within
//! the tolerance) on a seam curve of its component (a curve component its loops use twice,
//! e.g. the wing's trailing edge, a cylinder cap's radius) or one of its corners, is a
//! boundary node: it is a corner if within the tolerance of a corner of its components' loops,
//! otherwise it is projected on the curve components of those loops (the nearest foot inside
//! a component's range wins). Other nodes are projected on their component's surface.
//! A node farther than the tolerance from every candidate is an error naming it.
//! Boundary nodes get their (u, v) on each adjacent component by projection seeded at a
//! neighbouring interior node of each triangle, so a node on a seam gets one local copy per
//! side. A node at a pole (the image of a degenerate side of the surface's parameter
//! rectangle, see [`crate::pole`]) gets one local copy per triangle, by the pole-copy
//! convention. Nodes are snapped onto their entity (their positions become the evaluation at the
//! recovered parameters); the report gives the distances moved.

use std::collections::HashMap;

use geom_db::eval::ParamCurve;
use geom_db::prelude::Point3;
use geom_db::{CurveCompId, GeomDb, SurfCompId};
use intersect::project::{CurveProjector, ProjectOptions, SurfaceProjector};
use mesh::{ElementKind, Mesh};

use crate::error::{Error, Result};
use crate::generate::POLE_REL_TOL;
use crate::grid::{ComponentGrid, NodeSupport, PoleCopy, SurfaceGrid, marker_name};
use crate::pole::{Side, degenerate_sides, pole_copy_uv};

/// Knobs of the classification.
#[derive(Debug, Clone, PartialEq)]
pub struct ClassifyOptions {
    /// Largest accepted node distance from its entity, relative to the model's reference
    /// length (default 1e-6).
    pub rel_tol: f64,
}

impl Default for ClassifyOptions {
    fn default() -> Self {
        Self { rel_tol: 1e-6 }
    }
}

/// Distances found by the classification.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ClassifyReport {
    /// Nodes classified on corners.
    pub corners: usize,
    /// Nodes classified on curve components.
    pub curve_nodes: usize,
    /// Nodes classified inside surface components.
    pub surface_nodes: usize,
    /// Largest node–entity distance.
    pub max_distance: f64,
    /// The node with that distance.
    pub worst_node: usize,
    /// Mean node–entity distance.
    pub mean_distance: f64,
}

/// Classifies the triangles of `mesh`'s markers (one per surface component, named as
/// [`marker_name`]) on `db`; returns the grid tied to the geometry and a report.
pub fn classify(
    mesh: &Mesh,
    db: &GeomDb,
    opts: &ClassifyOptions,
) -> Result<(SurfaceGrid, ClassifyReport)> {
    let tol = opts.rel_tol * db.reference_length();
    let popts = ProjectOptions::default().with_length_scale(db.reference_length());
    let n = mesh.n_nodes();
    let coords: Vec<Point3> = mesh
        .coords
        .iter()
        .map(|p| Point3::new(p[0], p[1], p[2]))
        .collect();
    // markers → components
    let mut comp_tris: Vec<(SurfCompId, Vec<[u32; 3]>)> = Vec::new();
    for m in &mesh.markers {
        let c = (0..db.surface_components.len())
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
        let tris = m
            .elements
            .group(ElementKind::Triangle)
            .map(|g| g.iter().map(|t| [t[0], t[1], t[2]]).collect())
            .unwrap_or_default();
        comp_tris.push((c, tris));
    }
    let mut comps_of: Vec<Vec<SurfCompId>> = vec![Vec::new(); n];
    let mut boundary = vec![false; n];
    for (c, tris) in &comp_tris {
        let mut ecount: HashMap<(u32, u32), u32> = HashMap::new();
        for t in tris {
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
    // projectors
    let surf_proj: Vec<SurfaceProjector<'_, geom_db::SupportSurface>> = db
        .surface_components
        .iter()
        .map(|sc| SurfaceProjector::new(sc.name.clone(), db.surface(sc.surface), &popts))
        .collect::<std::result::Result<_, _>>()?;
    let mut curve_proj: HashMap<u32, CurveProjector<'_, geom_db::SupportCurve>> = HashMap::new();
    // nodes inside one marker that lie on a seam curve of its component (a curve component
    // used twice by its loops: the wing's trailing edge, a cylinder cap's radius) or on a
    // corner of one (the cap's centre, a pole) are boundary nodes too
    for (c, _) in &comp_tris {
        let sc = db.surface_component(*c);
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
            let pr = CurveProjector::new(curve.name.clone(), curve, &popts)?;
            let (tlo, thi) = (comp.t0.min(comp.t1), comp.t0.max(comp.t1));
            for i in 0..n {
                if boundary[i] || comps_of[i].len() != 1 || comps_of[i][0] != *c {
                    continue;
                }
                let p = coords[i];
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
                    boundary[i] = true;
                }
            }
        }
    }
    let mut support = vec![NodeSupport::Free; n];
    let mut dist = vec![0.0; n];
    let mut used = vec![false; n];
    for i in 0..n {
        let cs = &comps_of[i];
        if cs.is_empty() {
            continue;
        }
        used[i] = true;
        let p = coords[i];
        if !boundary[i] {
            let f = surf_proj[cs[0].index()].project_indexed(&p, i)?;
            if f.distance > tol {
                return Err(Error::NodeOffGeometry {
                    node: i,
                    entity: format!("{} ({})", cs[0], db.surface_component(cs[0]).name),
                    distance: f.distance,
                    tol,
                });
            }
            support[i] = NodeSupport::Surface {
                comp: cs[0],
                uv: f.uv,
            };
            dist[i] = f.distance;
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
                    e.insert(CurveProjector::new(curve.name.clone(), curve, &popts)?);
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
                let f = pr.project_from(&p, t0);
                let t = f.t.clamp(lo, hi);
                let d = (curve.point(t) - p).norm();
                if d < best.0 {
                    best = (d, Some(NodeSupport::Curve { comp: cc, t }), cc.to_string());
                }
            }
        }
        if best.0 > tol || best.1.is_none() {
            return Err(Error::NodeOffGeometry {
                node: i,
                entity: best.2,
                distance: best.0,
                tol,
            });
        }
        support[i] = best.1.expect("checked");
        dist[i] = best.0;
    }
    // component grids: local copies of boundary nodes per side
    let mut components = Vec::new();
    for (c, tris) in &comp_tris {
        let sc = db.surface_component(*c);
        let flip = sc.inward == geom_db::Orientation::Negative;
        let pr = &surf_proj[c.index()];
        let ([u0, u1], [v0, v1]) = geom_db::eval::ParamSurface::domain(pr.surface());
        let dom = (u1 - u0).max(v1 - v0);
        let dom_r = ([u0, u1], [v0, v1]);
        let poles = degenerate_sides(pr.surface(), POLE_REL_TOL * db.reference_length());
        let mut pole_of: Vec<Option<Side>> = Vec::new();
        let mut local: HashMap<u32, Vec<u32>> = HashMap::new();
        let mut nodes: Vec<u32> = Vec::new();
        let mut uv: Vec<[f64; 2]> = Vec::new();
        let mut is_b: Vec<bool> = Vec::new();
        let mut ltris = Vec::with_capacity(tris.len());
        for t in tris {
            let t = if flip { [t[0], t[2], t[1]] } else { *t };
            let seed = t
                .iter()
                .find_map(|&v| match support[v as usize] {
                    NodeSupport::Surface { uv, .. } => Some(uv),
                    _ => None,
                })
                .map_or_else(
                    || {
                        let g = (coords[t[0] as usize].coords
                            + coords[t[1] as usize].coords
                            + coords[t[2] as usize].coords)
                            / 3.0;
                        pr.project(&Point3::from(g)).map(|f| f.uv)
                    },
                    Ok,
                )?;
            let mut lt = [0u32; 3];
            let pole_side = |v: u32| {
                poles
                    .iter()
                    .find(|q| (q.point - coords[v as usize]).norm() <= tol)
                    .map(|q| q.side)
            };
            let mut p_uvs = [[0.0; 2]; 3];
            let sides = t.map(pole_side);
            for (j, &v) in t.iter().enumerate() {
                if sides[j].is_some() {
                    continue;
                }
                p_uvs[j] = match support[v as usize] {
                    NodeSupport::Surface { uv, .. } => uv,
                    _ => {
                        let f = pr.project_from(&coords[v as usize], seed);
                        if !f.converged || f.distance > tol {
                            pr.project_indexed(&coords[v as usize], v as usize)?.uv
                        } else {
                            f.uv
                        }
                    }
                };
            }
            for j in 0..3 {
                if let Some(side) = sides[j] {
                    if sides[(j + 1) % 3].is_some() || sides[(j + 2) % 3].is_some() {
                        return Err(Error::Mismatch {
                            what: format!(
                                "a triangle of marker {:?} has two nodes at a pole ({} and another)",
                                marker_name(db, *c),
                                t[j]
                            ),
                        });
                    }
                    p_uvs[j] = pole_copy_uv(side, dom_r, p_uvs[(j + 1) % 3], p_uvs[(j + 2) % 3]);
                }
            }
            for (j, &v) in t.iter().enumerate() {
                let p_uv = p_uvs[j];
                if let Some(side) = sides[j] {
                    // a pole: one local copy per triangle
                    let l = nodes.len() as u32;
                    nodes.push(v);
                    uv.push(p_uv);
                    is_b.push(true);
                    pole_of.push(Some(side));
                    lt[j] = l;
                    continue;
                }
                let copies = local.entry(v).or_default();
                let found = copies.iter().copied().find(|&l| {
                    let q = uv[l as usize];
                    (q[0] - p_uv[0]).abs() <= 1e-6 * dom && (q[1] - p_uv[1]).abs() <= 1e-6 * dom
                });
                lt[j] = match found {
                    Some(l) => l,
                    None => {
                        let l = nodes.len() as u32;
                        nodes.push(v);
                        uv.push(p_uv);
                        is_b.push(boundary[v as usize]);
                        pole_of.push(None);
                        copies.push(l);
                        l
                    }
                };
            }
            ltris.push(lt);
        }
        // boundary local nodes first
        let mut order: Vec<u32> = (0..nodes.len() as u32).collect();
        order.sort_by_key(|&l| (!is_b[l as usize], l));
        let mut perm = vec![0u32; nodes.len()];
        for (new, &old) in order.iter().enumerate() {
            perm[old as usize] = new as u32;
        }
        let n_boundary = is_b.iter().filter(|&&b| b).count();
        components.push(ComponentGrid {
            comp: *c,
            nodes: order.iter().map(|&l| nodes[l as usize]).collect(),
            uv: order.iter().map(|&l| uv[l as usize]).collect(),
            n_boundary,
            triangles: ltris.iter().map(|t| t.map(|l| perm[l as usize])).collect(),
            flip,
            pole_copies: order
                .iter()
                .enumerate()
                .filter_map(|(new, &l)| {
                    pole_of[l as usize].map(|side| PoleCopy {
                        local: new as u32,
                        side,
                    })
                })
                .collect(),
        });
    }
    // curve node lists
    let mut curve_nodes: Vec<Vec<u32>> = vec![Vec::new(); db.curve_components.len()];
    let mut on_curve: Vec<Vec<(f64, u32)>> = vec![Vec::new(); db.curve_components.len()];
    for (i, s) in support.iter().enumerate() {
        if let (true, NodeSupport::Curve { comp, t }) = (used[i], s) {
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
    let mut report = ClassifyReport {
        corners: 0,
        curve_nodes: 0,
        surface_nodes: 0,
        max_distance: 0.0,
        worst_node: 0,
        mean_distance: 0.0,
    };
    let mut count = 0usize;
    for i in 0..n {
        if !used[i] {
            continue;
        }
        count += 1;
        match support[i] {
            NodeSupport::Corner(_) => report.corners += 1,
            NodeSupport::Curve { .. } => report.curve_nodes += 1,
            NodeSupport::Surface { .. } => report.surface_nodes += 1,
            NodeSupport::Free => {}
        }
        report.mean_distance += dist[i];
        if dist[i] > report.max_distance {
            report.max_distance = dist[i];
            report.worst_node = i;
        }
    }
    report.mean_distance /= count.max(1) as f64;
    let mut grid = SurfaceGrid {
        coords,
        support,
        curve_nodes,
        components,
    };
    // nodes snapped onto their entity (the distances are in the report), so the grid is
    // exactly the evaluation of its parameters and a zero model change leaves it unchanged
    for i in 0..n {
        grid.coords[i] = grid.evaluate_node(db, i);
    }
    Ok((grid, report))
}
