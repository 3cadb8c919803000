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
use crate::grid::{ComponentGrid, NodeSupport, SurfaceGrid};
use crate::smooth::Improve;
use crate::spacing::SizeField;

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

/// The (u, v) of the boundary nodes of a component, walking its loops (see the module doc).
/// Returns per loop the sequence of (global node, uv), without the closing repeat.
pub(crate) fn boundary_params(
    db: &GeomDb,
    comp: SurfCompId,
    curve_nodes: &[Vec<u32>],
    coords: &[Point3],
    proj: &SurfaceProjector<'_, geom_db::SupportSurface>,
    tol: f64,
) -> Result<Vec<BoundaryLoop>> {
    let sc = db.surface_component(comp);
    let surf = db.surface(sc.surface);
    let fail = |node: u32, distance: f64| Error::BoundaryProjection {
        component: comp,
        name: sc.name.clone(),
        node: node as usize,
        distance,
        tol,
    };
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
        // seed from a global projection of a node away from corners
        let start = seq.len().min(1);
        let p0 = coords[seq[start] as usize];
        let f0 = proj.project(&p0)?;
        let mut prev = f0.uv;
        let mut uvs = vec![[0.0; 2]; seq.len()];
        for k in 0..seq.len() {
            let i = (start + k) % seq.len();
            let p = coords[seq[i] as usize];
            let mut f = proj.project_from(&p, prev);
            if !f.converged || f.distance > tol {
                let g = proj.project(&p)?;
                if g.distance < f.distance || !f.converged {
                    f = g;
                }
            }
            if f.distance > tol {
                return Err(fail(seq[i], f.distance));
            }
            // a pole: one of the tangents vanishes
            let d = surf.derivs(f.uv[0], f.uv[1]);
            let (nu, nv) = (d.du.norm(), d.dv.norm());
            if nu.min(nv) <= 1e-8 * nu.max(nv) {
                return Err(Error::Pole {
                    component: comp,
                    name: sc.name.clone(),
                    node: seq[i] as usize,
                    du: nu,
                    dv: nv,
                });
            }
            uvs[i] = f.uv;
            prev = f.uv;
        }
        out.push(seq.into_iter().zip(uvs).collect());
    }
    Ok(out)
}

/// One boundary loop: (global node, (u, v)) per node, without the closing repeat.
pub(crate) type BoundaryLoop = Vec<(u32, [f64; 2])>;

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
fn mesh_component(
    db: &GeomDb,
    comp: SurfCompId,
    loops: Vec<BoundaryLoop>,
    field: &SizeField,
    passes: usize,
) -> Result<ComponentGrid> {
    let sc = db.surface_component(comp);
    let surf = db.surface(sc.surface);
    let mut nodes = Vec::new();
    let mut uv = Vec::new();
    let mut edges = Vec::new();
    let area0 = signed_area(&loops[0].iter().map(|x| x.1).collect::<Vec<_>>());
    let reverse = area0 < 0.0;
    for (li, lp) in loops.iter().enumerate() {
        let a = signed_area(&lp.iter().map(|x| x.1).collect::<Vec<_>>());
        if li > 0 && (a < 0.0) == (area0 < 0.0) {
            return Err(Error::LoopOrientation {
                component: comp,
                name: sc.name.clone(),
                lp: li,
                area: a,
            });
        }
        let base = nodes.len() as u32;
        for &(g, p) in lp {
            nodes.push(g);
            uv.push(p);
        }
        let m = lp.len() as u32;
        for k in 0..m {
            let (a, b) = (base + k, base + (k + 1) % m);
            edges.push(if reverse { [b, a] } else { [a, b] });
        }
    }
    let n_boundary = nodes.len();
    let metric = |p: [f64; 2]| {
        let d = surf.derivs(p[0], p[1]);
        field.surface_metric(&d.point, &d.du, &d.dv)
    };
    let m = aft::triangulate(uv, &edges, &metric).map_err(|aft::Stuck(remaining, triangles)| {
        Error::FrontStuck {
            component: comp,
            name: sc.name.clone(),
            remaining,
            triangles,
        }
    })?;
    let eval = |p: [f64; 2]| surf.point(p[0], p[1]);
    let x = m.pts.iter().map(|p| eval(*p)).collect();
    let mut imp = Improve {
        uv: m.pts,
        x,
        tris: m.tris,
        n_fixed: n_boundary,
        eval: &eval,
    };
    for _ in 0..passes {
        imp.swap_pass();
        imp.smooth_pass();
    }
    imp.swap_pass();
    nodes.resize(imp.uv.len(), u32::MAX);
    Ok(ComponentGrid {
        comp,
        nodes,
        uv: imp.uv,
        n_boundary,
        triangles: imp.tris,
        flip: sc.inward == geom_db::Orientation::Negative,
    })
}

/// Discretises the curves of the selected components and triangulates each component.
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
    let popts = ProjectOptions::default().with_length_scale(db.reference_length());
    let grids: Vec<Result<ComponentGrid>> = comps
        .par_iter()
        .map(|&c| {
            let sc = db.surface_component(c);
            let proj = SurfaceProjector::new(sc.name.clone(), db.surface(sc.surface), &popts)?;
            let loops = boundary_params(db, c, &curve_nodes, &coords, &proj, tol)?;
            mesh_component(db, c, loops, field, opts.passes)
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
