//! Classification stage 4: the parametric triangulation of each component, with one local
//! copy of a boundary node per side (a seam node gets one per side, found by projection
//! seeded at a neighbouring interior node of each triangle) and one copy of a pole per
//! triangle (the pole-copy convention of [`crate::pole`]).

use std::collections::HashMap;

use geom_db::prelude::Point3;

use super::Context;
use super::supports::Supports;
use super::topology::{ComponentTriangles, Topology};
use crate::error::{Error, Result};
use crate::generate::POLE_REL_TOL;
use crate::grid::{ComponentGrid, NodeSupport, PoleCopy, marker_name};
use crate::pole::{Side, degenerate_sides, pole_copy_uv};

/// The local nodes of a component grid as they are made: global node, (u, v), boundary
/// flag and, for a pole copy, its degenerate side.
#[derive(Default)]
struct LocalNodes {
    nodes: Vec<u32>,
    uv: Vec<[f64; 2]>,
    is_b: Vec<bool>,
    pole_of: Vec<Option<Side>>,
}

impl LocalNodes {
    fn push(&mut self, v: u32, uv: [f64; 2], boundary: bool, pole: Option<Side>) -> u32 {
        let l = self.nodes.len() as u32;
        self.nodes.push(v);
        self.uv.push(uv);
        self.is_b.push(boundary);
        self.pole_of.push(pole);
        l
    }
}

/// Stage 4: the parametric grid of one component (boundary local nodes first).
pub(super) fn component_grid(
    c: &ComponentTriangles,
    ctx: &Context<'_>,
    topo: &Topology,
    s: &Supports,
) -> Result<ComponentGrid> {
    let (db, tol, coords) = (ctx.db, ctx.tol, &ctx.coords);
    let sc = db.surface_component(c.comp);
    let flip = sc.inward == geom_db::Orientation::Negative;
    let pr = &ctx.surf_proj[c.comp.index()];
    let ([u0, u1], [v0, v1]) = geom_db::eval::ParamSurface::domain(pr.surface());
    let dom = (u1 - u0).max(v1 - v0);
    let dom_r = ([u0, u1], [v0, v1]);
    let poles = degenerate_sides(pr.surface(), POLE_REL_TOL * db.reference_length());
    let mut local: HashMap<u32, Vec<u32>> = HashMap::new();
    let mut ln = LocalNodes::default();
    let mut ltris = Vec::with_capacity(c.triangles.len());
    for t in &c.triangles {
        let t = if flip { [t[0], t[2], t[1]] } else { *t };
        let seed = t
            .iter()
            .find_map(|&v| match s.support[v as usize] {
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
            p_uvs[j] = match s.support[v as usize] {
                NodeSupport::Surface { uv, .. } => uv,
                _ => {
                    let f = pr.project_from(&coords[v as usize], seed);
                    if !f.report.converged || f.distance > tol {
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
                            marker_name(db, c.comp),
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
                lt[j] = ln.push(v, p_uv, true, Some(side));
                continue;
            }
            let copies = local.entry(v).or_default();
            let found = copies.iter().copied().find(|&l| {
                let q = ln.uv[l as usize];
                (q[0] - p_uv[0]).abs() <= 1e-6 * dom && (q[1] - p_uv[1]).abs() <= 1e-6 * dom
            });
            lt[j] = match found {
                Some(l) => l,
                None => {
                    let l = ln.push(v, p_uv, topo.boundary[v as usize], None);
                    copies.push(l);
                    l
                }
            };
        }
        ltris.push(lt);
    }
    // A mesher orients its boundary triangles as it pleases (Gmsh and SU2 follow the CAD
    // face, or the fluid), so a component may come out clockwise in (u, v). When most of its
    // triangles do, reverse the local triangles (the update needs them counter-clockwise) and
    // the flip, so that the global triangles keep the grid's own orientation and only a
    // triangle folded against its neighbours counts as inverted.
    let cw = ltris
        .iter()
        .filter(|t| {
            let [a, b, d] = t.map(|l| ln.uv[l as usize]);
            (b[0] - a[0]) * (d[1] - a[1]) - (b[1] - a[1]) * (d[0] - a[0]) < 0.0
        })
        .count();
    let flip = if 2 * cw > ltris.len() {
        for t in &mut ltris {
            t.swap(1, 2);
        }
        !flip
    } else {
        flip
    };
    Ok(boundary_first(c, flip, &ln, &ltris))
}

/// The component grid with the boundary local nodes first (stable otherwise).
fn boundary_first(
    c: &ComponentTriangles,
    flip: bool,
    ln: &LocalNodes,
    ltris: &[[u32; 3]],
) -> ComponentGrid {
    let mut order: Vec<u32> = (0..ln.nodes.len() as u32).collect();
    order.sort_by_key(|&l| (!ln.is_b[l as usize], l));
    let mut perm = vec![0u32; ln.nodes.len()];
    for (new, &old) in order.iter().enumerate() {
        perm[old as usize] = new as u32;
    }
    ComponentGrid {
        comp: c.comp,
        nodes: order.iter().map(|&l| ln.nodes[l as usize]).collect(),
        uv: order.iter().map(|&l| ln.uv[l as usize]).collect(),
        n_boundary: ln.is_b.iter().filter(|&&b| b).count(),
        triangles: ltris.iter().map(|t| t.map(|l| perm[l as usize])).collect(),
        flip,
        pole_copies: order
            .iter()
            .enumerate()
            .filter_map(|(new, &l)| {
                ln.pole_of[l as usize].map(|side| PoleCopy {
                    local: new as u32,
                    side,
                })
            })
            .collect(),
    }
}
