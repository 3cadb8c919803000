//! Surface grid generation (§2.2): curves first, then each surface component by advancing
//! front in its parametric plane under the metric M = Jᵀ T J (Eq. 33 with T = I/h²).
//!
//! Boundary nodes get their (u, v) on the component's surface by projection (Eq. 11,
//! `intersect::project`), walking each loop and seeding every node from the previous one, so
//! a curve traversed twice across a seam (the wing's trailing edge) gets the (u, v) of the
//! side the loop is on. Poles (a loop through a corner where r_u or r_v vanishes) are not
//! supported and reported as an error naming the component and node.

use rayon::prelude::*;

use geom_db::eval::{ParamCurve, ParamSurface};
use geom_db::prelude::Point3;
use geom_db::{CurveCompId, GeomDb, SurfCompId};
use intersect::project::{ProjectOptions, SurfaceProjector};

use crate::aft;
use crate::curves::discretise_curve;
use crate::error::{Error, Result};
use crate::grid::{ComponentGrid, NodeSupport, PoleCopy, SurfaceGrid};
use crate::pole::{Domain, Pole, Side, degenerate_sides, fan_ring, pole_copy_uv};
use crate::smooth::Improve;
use crate::spacing::SizeField;

/// A side of a support surface's parameter rectangle is degenerate (a pole) when its image
/// stays within this fraction of the model's reference length.
pub const POLE_REL_TOL: f64 = 1e-8;

/// Knobs of the generator.
#[derive(Debug, Clone, PartialEq)]
pub struct GenerateOptions {
    /// Surface components to mesh (`None`: all).
    pub components: Option<Vec<SurfCompId>>,
    /// Improvement passes (each: a swap pass and a smoothing pass). Default 4.
    pub passes: usize,
    /// Largest accepted distance of a boundary node from its surface, relative to the model's
    /// reference length (default 1e-7).
    pub boundary_rel_tol: f64,
}

impl Default for GenerateOptions {
    fn default() -> Self {
        Self {
            components: None,
            passes: 4,
            boundary_rel_tol: 1e-7,
        }
    }
}

impl GenerateOptions {
    /// Meshes only the given components.
    pub fn with_components(mut self, c: Vec<SurfCompId>) -> Self {
        self.components = Some(c);
        self
    }
    /// Sets the number of improvement passes.
    pub fn with_passes(mut self, n: usize) -> Self {
        self.passes = n;
        self
    }
}

/// One node of a boundary loop: a regular node with its (u, v), or a pole (global node and
/// the index of its degenerate side in the surface's pole list).
#[derive(Debug, Clone, Copy)]
pub(crate) enum LoopNode {
    /// Global node and (u, v).
    At(u32, [f64; 2]),
    /// Global node on a degenerate side: index into the component's poles.
    Pole(u32, usize),
}

/// One boundary loop, without the closing repeat.
pub(crate) type BoundaryLoop = Vec<LoopNode>;

/// The (u, v) of the boundary nodes of a component, walking its loops (see the module doc).
/// A node at the image of a degenerate side (a pole) is not projected; the node after it is
/// projected from seeds spread along the side and the foot farthest along the side from the
/// arrival is kept (so a loop that reaches a pole along a seam leaves it on the other side
/// of the seam, as the cap of a cylinder does).
pub(crate) fn boundary_params(
    db: &GeomDb,
    comp: SurfCompId,
    curve_nodes: &[Vec<u32>],
    coords: &[Point3],
    proj: &SurfaceProjector<'_, geom_db::SupportSurface>,
    poles: &[Pole],
    tol: f64,
) -> Result<Vec<BoundaryLoop>> {
    let sc = db.surface_component(comp);
    let surf = db.surface(sc.surface);
    let dom = surf.domain();
    let fail = |node: u32, distance: f64| Error::BoundaryProjection {
        component: comp,
        name: sc.name.clone(),
        node: node as usize,
        distance,
        tol,
    };
    let pole_at = |p: &Point3| poles.iter().position(|q| (q.point - p).norm() <= tol);
    let mut out = Vec::new();
    for lp in &sc.loops {
        // the node sequence with curve junctions merged
        let mut seq: Vec<u32> = Vec::new();
        for oc in lp {
            let mut ns = curve_nodes[oc.comp.index()].clone();
            if oc.reversed {
                ns.reverse();
            }
            if seq.last() == ns.first() {
                seq.pop();
            }
            seq.extend(ns);
        }
        if seq.len() > 1 && seq.first() == seq.last() {
            seq.pop();
        }
        let n = seq.len();
        let pole: Vec<Option<usize>> = seq.iter().map(|&g| pole_at(&coords[g as usize])).collect();
        if pole.iter().all(Option::is_some) {
            return Err(Error::Pole {
                component: comp,
                name: sc.name.clone(),
                node: seq[0] as usize,
                what: "every node of a boundary loop is a pole".into(),
            });
        }
        for i in 0..n {
            if pole[i].is_some() && pole[(i + 1) % n].is_some() {
                return Err(Error::Pole {
                    component: comp,
                    name: sc.name.clone(),
                    node: seq[i] as usize,
                    what: "two consecutive boundary nodes are poles".into(),
                });
            }
        }
        // start at a regular node after a regular node, from a global projection
        let start = (1..=n)
            .map(|k| k % n)
            .find(|&k| pole[k].is_none() && pole[(k + n - 1) % n].is_none())
            .unwrap_or_else(|| (0..n).find(|&k| pole[k].is_none()).expect("checked"));
        let walk = |seed: [f64; 2]| -> Result<(Vec<LoopNode>, [f64; 2])> {
            let mut prev = seed;
            let mut after_pole: Option<(usize, f64)> = None;
            let mut nodes = vec![LoopNode::Pole(0, 0); n];
            for k in 0..n {
                let i = (start + k) % n;
                let g = seq[i];
                if let Some(pi) = pole[i] {
                    nodes[i] = LoopNode::Pole(g, pi);
                    after_pole = Some((pi, poles[pi].side.along(prev)));
                    continue;
                }
                let p = coords[g as usize];
                let f = match after_pole.take() {
                    None if k == 0 => proj.project_from(&p, seed),
                    None => {
                        let mut f = proj.project_from(&p, prev);
                        if !f.report.converged || f.distance > tol {
                            let h = proj.project(&p)?;
                            if h.distance < f.distance || !f.report.converged {
                                f = h;
                            }
                        }
                        f
                    }
                    Some((pi, t_arrival)) => {
                        // feet from seeds along the side; keep the farthest from the arrival
                        let side = poles[pi].side;
                        let [a, b] = side.along_range(dom);
                        let s_range = match side.along_axis() {
                            1 => dom.0[1] - dom.0[0],
                            _ => dom.1[1] - dom.1[0],
                        };
                        let mut feet: Vec<_> = (0..=8)
                            .map(|j| {
                                let t = a + (b - a) * j as f64 / 8.0;
                                proj.project_from(&p, side.uv(dom, t, 1e-3 * s_range))
                            })
                            .filter(|f| f.report.converged && f.distance <= tol)
                            .collect();
                        feet.push(proj.project(&p)?);
                        feet.into_iter()
                            .filter(|f| f.distance <= tol)
                            .max_by(|x, y| {
                                let dx = (side.along(x.uv) - t_arrival).abs();
                                let dy = (side.along(y.uv) - t_arrival).abs();
                                dx.total_cmp(&dy)
                            })
                            .ok_or_else(|| fail(g, f64::INFINITY))?
                    }
                };
                if f.distance > tol {
                    return Err(fail(g, f.distance));
                }
                // a pole inside a curve (not at a node) or an undetected degenerate side
                let d = surf.derivs(f.uv[0], f.uv[1]);
                let (nu, nv) = (d.du.norm(), d.dv.norm());
                if nu.min(nv) <= 1e-8 * nu.max(nv) {
                    return Err(Error::Pole {
                        component: comp,
                        name: sc.name.clone(),
                        node: g as usize,
                        what: format!(
                            "a tangent vanishes there (|r_u| = {nu:.3e}, |r_v| = {nv:.3e}) but no side of the parameter rectangle is degenerate"
                        ),
                    });
                }
                nodes[i] = LoopNode::At(g, f.uv);
                prev = f.uv;
            }
            Ok((nodes, prev))
        };
        // the start node from a global projection; if it lies on a seam the global foot may
        // be on the other side from the one the walk comes back with: then walk again from
        // the foot seeded at the last node (so the loop closes without a jump)
        let p0 = coords[seq[start] as usize];
        let f0 = proj.project(&p0)?;
        let (mut nodes, last) = walk(f0.uv)?;
        let f1 = proj.project_from(&p0, last);
        let jump = (f1.uv[0] - f0.uv[0]).abs().max((f1.uv[1] - f0.uv[1]).abs());
        let span = (dom.0[1] - dom.0[0]).max(dom.1[1] - dom.1[0]);
        if f1.report.converged && f1.distance <= tol && jump > 1e-6 * span {
            nodes = walk(f1.uv)?.0;
        }
        out.push(nodes);
    }
    Ok(out)
}

/// The parametric polygon of a loop: a pole contributes its arrival and departure points on
/// the degenerate side.
fn loop_polygon(lp: &[LoopNode], poles: &[Pole], dom: Domain) -> Vec<[f64; 2]> {
    let n = lp.len();
    let mut out = Vec::with_capacity(n + 4);
    for i in 0..n {
        match lp[i] {
            LoopNode::At(_, uv) => out.push(uv),
            LoopNode::Pole(_, pi) => {
                let side = poles[pi].side;
                for nb in [lp[(i + n - 1) % n], lp[(i + 1) % n]] {
                    if let LoopNode::At(_, uv) = nb {
                        out.push(side.uv(dom, side.along(uv), 0.0));
                    }
                }
            }
        }
    }
    out
}

fn signed_area(uv: &[[f64; 2]]) -> f64 {
    let n = uv.len();
    (0..n)
        .map(|i| {
            let (a, b) = (uv[i], uv[(i + 1) % n]);
            a[0] * b[1] - a[1] * b[0]
        })
        .sum::<f64>()
        * 0.5
}

/// Meshes one component given the boundary; returns the component grid with local interior
/// nodes after the boundary ones, and their parameters.
///
/// Local node order: loop nodes (poles excluded), pole copies, then free nodes (the ring
/// nodes of the pole fans, then the nodes the front created).
fn mesh_component(
    db: &GeomDb,
    comp: SurfCompId,
    loops: Vec<BoundaryLoop>,
    poles: &[Pole],
    field: &SizeField,
    passes: usize,
) -> Result<ComponentGrid> {
    let sc = db.surface_component(comp);
    let surf = db.surface(sc.surface);
    let dom = surf.domain();
    let area0 = signed_area(&loop_polygon(&loops[0], poles, dom));
    let reverse = area0 < 0.0;
    // loop nodes (local 0..n_loop), front edges, and the pole fans
    let mut nodes: Vec<u32> = Vec::new();
    let mut uv: Vec<[f64; 2]> = Vec::new();
    let mut edges: Vec<[u32; 2]> = Vec::new();
    // ring nodes (uv) get local index n_loop + j after the loop nodes are known
    let mut ring_uv: Vec<[f64; 2]> = Vec::new();
    /// A node of a front path or fan: a loop node (local index) or ring node j.
    #[derive(Clone, Copy)]
    enum Ref {
        Loop(u32),
        Ring(u32),
    }
    // fans: (pole global, side, [r_k … r_0])
    let mut fans: Vec<(u32, Side, Vec<Ref>)> = Vec::new();
    let mut loop_paths: Vec<Vec<Ref>> = Vec::new();
    for (li, lp) in loops.iter().enumerate() {
        let a = signed_area(&loop_polygon(lp, poles, dom));
        if li > 0 && (a < 0.0) == (area0 < 0.0) {
            return Err(Error::LoopOrientation {
                component: comp,
                name: sc.name.clone(),
                lp: li,
                area: a,
            });
        }
        let mut lp = lp.clone();
        if reverse {
            lp.reverse();
        }
        // local indices of the regular nodes
        let mut local = vec![u32::MAX; lp.len()];
        for (i, x) in lp.iter().enumerate() {
            if let LoopNode::At(g, p) = *x {
                local[i] = nodes.len() as u32;
                nodes.push(g);
                uv.push(p);
            }
        }
        let n = lp.len();
        let mut path = Vec::new();
        for i in 0..n {
            match lp[i] {
                LoopNode::At(..) => path.push(Ref::Loop(local[i])),
                LoopNode::Pole(g, pi) => {
                    let (ip, inx) = ((i + n - 1) % n, (i + 1) % n);
                    let (LoopNode::At(_, up), LoopNode::At(_, un)) = (lp[ip], lp[inx]) else {
                        unreachable!("poles are not consecutive (checked)");
                    };
                    let side = poles[pi].side;
                    let s_r = 0.5 * (side.inward(dom, up) + side.inward(dom, un));
                    // a fan through the whole loop would leave no front: at least 2 triangles
                    // when the loop has only the two neighbours besides the pole
                    let k_min = if n <= 3 { 2 } else { 1 };
                    let (_, ts) = fan_ring(
                        surf,
                        side,
                        &poles[pi].point,
                        s_r,
                        side.along(un),
                        side.along(up),
                        k_min,
                    );
                    // ring from the previous node's side: r_{k−1} … r_1
                    let mut fan = vec![Ref::Loop(local[ip])];
                    for &t in ts.iter().rev() {
                        let j = ring_uv.len() as u32;
                        ring_uv.push(side.uv(dom, t, s_r));
                        path.push(Ref::Ring(j));
                        fan.push(Ref::Ring(j));
                    }
                    fan.push(Ref::Loop(local[inx]));
                    fans.push((g, side, fan));
                }
            }
        }
        loop_paths.push(path);
    }
    let n_loop = nodes.len();
    let ring0 = n_loop as u32;
    let resolve = |r: &Ref| match *r {
        Ref::Loop(l) => l,
        Ref::Ring(j) => ring0 + j,
    };
    for path in &loop_paths {
        let m = path.len();
        for k in 0..m {
            edges.push([resolve(&path[k]), resolve(&path[(k + 1) % m])]);
        }
    }
    let n_ring = ring_uv.len();
    let mut pts = uv.clone();
    pts.extend_from_slice(&ring_uv);
    let metric = |p: [f64; 2]| {
        let d = surf.derivs(p[0], p[1]);
        field.surface_metric(&d.point, &d.du, &d.dv)
    };
    let m =
        aft::triangulate(pts, &edges, &metric).map_err(|aft::Stuck(remaining, triangles)| {
            Error::FrontStuck {
                component: comp,
                name: sc.name.clone(),
                remaining,
                triangles,
            }
        })?;
    // renumber: loop nodes, pole copies, ring nodes, front nodes
    let n_pole: usize = fans.iter().map(|f| f.2.len() - 1).sum();
    let n_front = m.pts.len() - n_loop - n_ring;
    let shift = |v: u32| -> u32 {
        if (v as usize) < n_loop {
            v
        } else {
            v + n_pole as u32
        }
    };
    let mut all_uv: Vec<[f64; 2]> = Vec::with_capacity(n_loop + n_pole + n_ring + n_front);
    all_uv.extend_from_slice(&m.pts[..n_loop]);
    let mut pole_copies = Vec::with_capacity(n_pole);
    let mut tris: Vec<[u32; 3]> = m.tris.iter().map(|t| t.map(shift)).collect();
    let fan_ref = |r: &Ref| match *r {
        Ref::Loop(l) => l,
        Ref::Ring(j) => (n_loop + n_pole) as u32 + j,
    };
    for (g, side, fan) in &fans {
        for w in fan.windows(2) {
            // (r_{j+1}, P_j, r_j): r_{j+1} comes first in the fan list (previous side)
            let (a, b) = (fan_ref(&w[0]), fan_ref(&w[1]));
            let pl = all_uv.len() as u32;
            let uva = if (a as usize) < n_loop {
                m.pts[a as usize]
            } else {
                m.pts[a as usize - n_pole]
            };
            let uvb = if (b as usize) < n_loop {
                m.pts[b as usize]
            } else {
                m.pts[b as usize - n_pole]
            };
            all_uv.push(pole_copy_uv(*side, dom, uva, uvb));
            nodes.push(*g);
            pole_copies.push(PoleCopy {
                local: pl,
                side: *side,
            });
            tris.push([a, pl, b]);
        }
    }
    all_uv.extend_from_slice(&m.pts[n_loop..]);
    let n_boundary = n_loop + n_pole;
    let eval = |p: [f64; 2]| surf.point(p[0], p[1]);
    let mut x: Vec<Point3> = all_uv.iter().map(|p| eval(*p)).collect();
    for pc in &pole_copies {
        x[pc.local as usize] = poles
            .iter()
            .find(|q| q.side == pc.side)
            .expect("a pole copy's side is degenerate")
            .point;
    }
    let mut no_swap = vec![false; all_uv.len()];
    for pc in &pole_copies {
        no_swap[pc.local as usize] = true;
    }
    let mut imp = Improve {
        uv: all_uv,
        x,
        tris,
        n_fixed: n_boundary,
        no_swap,
        eval: &eval,
    };
    for _ in 0..passes {
        imp.swap_pass();
        imp.smooth_pass();
    }
    imp.swap_pass();
    nodes.resize(imp.uv.len(), u32::MAX);
    let mut g = ComponentGrid {
        comp,
        nodes,
        uv: imp.uv,
        n_boundary,
        triangles: imp.tris,
        flip: sc.inward == geom_db::Orientation::Negative,
        pole_copies,
    };
    g.refresh_pole_copies(dom);
    Ok(g)
}

/// The surface grid of a whole model (or of the components `opts` selects): the public
/// entry point of generation (stable).
///
/// Curves first: every curve component used by a selected surface component is discretised
/// once to the size `field` (equidistribution, so neighbouring components share their curve
/// nodes and conform); then every surface component is triangulated (in parallel, the result
/// independent of the thread count) by advancing front in its parametric plane under the
/// metric M = Jᵀ T J (Eq. 33), with fans at its poles (degenerate sides: a fuselage nose and
/// tail, a cap centre, a tip cap's ends; see [`crate::pole`]), then swaps and smoothing.
///
/// The result ties every node to the geometry: corners ([`NodeSupport::Corner`], poles
/// included), curve nodes with t, surface nodes with (u, v); every triangle is positively
/// oriented with respect to its component's inward normal. Write it with
/// [`SurfaceGrid::to_mesh`] (one marker per surface component, named after it; MSH 4.1
/// with parametric nodes, SU2 or VTU through `mesh`), move it with the model with
/// [`crate::update()`] (at frozen parameters, re-map where a junction moved), and tie a grid
/// made elsewhere from it (e.g. the wall of a volume grid built on it) with
/// [`crate::classify()`].
///
/// ```no_run
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let text = std::fs::read_to_string("fixtures/geom/wing_body.ron")?;
/// let db = geom_db::GeomDb::from_ron_str(&text, "wing_body.ron")?;
/// let field = surfgrid::SizeField::uniform(0.1)?;
/// let grid = surfgrid::generate(&db, &field, &surfgrid::GenerateOptions::default())?;
/// let mesh = grid.to_mesh(&db);
/// let mut out = std::fs::File::create("wing_body.msh")?;
/// mesh::msh::write(&mesh, mesh::msh::Encoding::Binary, &mut out)?;
/// # Ok(())
/// # }
/// ```
///
/// Errors name the component (and node): a curve that cannot be discretised, a boundary node
/// off its surface, inconsistent loops, an unsupported pole, a front that cannot be closed.
pub fn generate(db: &GeomDb, field: &SizeField, opts: &GenerateOptions) -> Result<SurfaceGrid> {
    let comps: Vec<SurfCompId> = match &opts.components {
        Some(c) => c.clone(),
        None => (0..db.surface_components.len())
            .map(SurfCompId::from_index)
            .collect(),
    };
    if let Some(c) = comps
        .iter()
        .find(|c| c.index() >= db.surface_components.len())
    {
        return Err(Error::Mismatch {
            what: format!(
                "{c} does not exist ({} components)",
                db.surface_components.len()
            ),
        });
    }
    let mut coords: Vec<Point3> = db.corners.iter().map(|c| c.point).collect();
    let mut support: Vec<NodeSupport> = (0..db.corners.len())
        .map(|i| NodeSupport::Corner(geom_db::CornerId::from_index(i)))
        .collect();
    // curves used by the selected components, each discretised once
    let mut used = vec![false; db.curve_components.len()];
    for c in &comps {
        for lp in &db.surface_component(*c).loops {
            for oc in lp {
                used[oc.comp.index()] = true;
            }
        }
    }
    let ids: Vec<CurveCompId> = (0..used.len())
        .filter(|&i| used[i])
        .map(CurveCompId::from_index)
        .collect();
    let params: Vec<Result<Vec<f64>>> = ids
        .par_iter()
        .map(|&id| discretise_curve(db, id, field))
        .collect();
    let mut curve_nodes = vec![Vec::new(); db.curve_components.len()];
    for (&id, ts) in ids.iter().zip(params) {
        let ts = ts?;
        let cc = db.curve_component(id);
        let curve = db.curve(cc.curve);
        let mut ns = vec![cc.start.0];
        for &t in &ts[1..ts.len() - 1] {
            ns.push(coords.len() as u32);
            coords.push(curve.point(t));
            support.push(NodeSupport::Curve { comp: id, t });
        }
        ns.push(cc.end.0);
        curve_nodes[id.index()] = ns;
    }
    let tol = opts.boundary_rel_tol * db.reference_length();
    let pole_tol = POLE_REL_TOL * db.reference_length();
    let popts = ProjectOptions::default().with_length_scale(db.reference_length());
    let grids: Vec<Result<ComponentGrid>> = comps
        .par_iter()
        .map(|&c| {
            let sc = db.surface_component(c);
            let surf = db.surface(sc.surface);
            let proj = SurfaceProjector::new(sc.name.clone(), surf, &popts)?;
            let poles = degenerate_sides(surf, pole_tol);
            let loops = boundary_params(db, c, &curve_nodes, &coords, &proj, &poles, tol)?;
            mesh_component(db, c, loops, &poles, field, opts.passes)
        })
        .collect();
    let mut components = Vec::with_capacity(grids.len());
    for g in grids {
        let mut g = g?;
        let surf = db.surface(db.surface_component(g.comp).surface);
        for k in g.n_boundary..g.nodes.len() {
            g.nodes[k] = coords.len() as u32;
            coords.push(surf.point(g.uv[k][0], g.uv[k][1]));
            support.push(NodeSupport::Surface {
                comp: g.comp,
                uv: g.uv[k],
            });
        }
        components.push(g);
    }
    Ok(SurfaceGrid {
        coords,
        support,
        curve_nodes,
        components,
    })
}
