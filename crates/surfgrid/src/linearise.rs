//! The surface-grid update linearised (issue 22): forward (Jacobian–vector) and reverse
//! (vector–Jacobian) products of what [`Updater::update`] computed, for a perturbation of
//! the updated model given as a [`ModelTangent`] (control nodes, the re-intersected curves'
//! own control points, corners and curve components' ranges; `intersect`'s
//! `ModelLinearisation::jvp` gives it).
//!
//! Outputs dX: one vector per grid node. In the order of the update (docs/crates/surfgrid.md,
//! "Linearisation"):
//!
//! 1. **Corner nodes**: dX = δc, the corner's perturbation.
//! 2. **Curve nodes** at t′ = t0′ + s (t1′ − t0′), s = (t − t0)/(t1 − t0) frozen:
//!    dX = δr(t′) + r′(t′) dt′ with dt′ = (1 − s) δt0′ + s δt1′.
//! 3. **Boundary (u, v)** of each surface component, the foot of the normal (Eq. 11)
//!    F = [(S − X)·S_u, (S − X)·S_v] = 0: H duv = −[(δS − dX)·S_u + g·δS_u,
//!    (δS − dX)·S_v + g·δS_v] with g = S − X and H = [S_i·S_j + g·S_ij] (a parameter held
//!    on its domain bound keeps du = 0; pole copies keep theirs).
//! 4. **Harmonic re-map** of the interior: duv_free = A_ff⁻¹ R duv_boundary
//!    ([`HarmonicMap::solve`]), differentiated whether or not the update re-mapped (the
//!    update re-maps whenever a boundary (u, v) moves, so any perturbation that moves one
//!    re-maps; where none moves the map gives zero).
//! 5. **Smoothing** as it ran: each accepted move (node v, fraction w) replayed on the
//!    tangents, duv_v ← (1 − w) duv_v + w mean(duv of v's neighbours), in the same order.
//! 6. **Interior nodes**: dX = δS(u, v) + S_u du + S_v dv.
//!
//! The reverse product runs the transposes in the opposite order: it is the exact transpose
//! (the dot-product test holds to round-off; a component large enough to be re-mapped by
//! conjugate gradients instead of its factorisation is transposed to that solve's 1e-8).

use geom_db::eval::{ParamCurve, ParamSurface, SurfaceDerivs};
use geom_db::linearise::{CurveTangent, ModelTangent, SurfaceTangent};
use geom_db::prelude::{Matrix2, Vector2, Vector3};
use geom_db::{CurveId, GeomDb, SurfaceId};

use crate::error::{Error, Result};
use crate::grid::{NodeSupport, SurfaceGrid};
use crate::harmonic::HarmonicMap;
use crate::update::{UpdateOptions, UpdateRecord, UpdateReport, Updater};

/// A curve node: its curve, final parameter t′, r′(t′), component and frozen fraction s.
#[derive(Debug, Clone)]
struct CurveNode {
    node: usize,
    curve: CurveId,
    t: f64,
    d1: Vector3,
    comp: usize,
    s: f64,
}

/// A boundary node of a component whose (u, v) is the foot of the normal.
#[derive(Debug, Clone)]
struct Foot {
    local: usize,
    node: usize,
    uv: [f64; 2],
    d: SurfaceDerivs,
    /// g = S(u, v) − X.
    gap: Vector3,
    /// The inverse of H with a held parameter's row and column replaced by the identity.
    hinv: Matrix2,
    held: [bool; 2],
}

/// One surface component.
#[derive(Debug)]
struct Component<'u> {
    surface: SurfaceId,
    nodes: Vec<u32>,
    nb: usize,
    map: &'u HarmonicMap,
    feet: Vec<Foot>,
    /// Smoothing moves in the order made, and each local node's neighbours (CSR).
    moves: Vec<(u32, f64)>,
    adj_ptr: Vec<usize>,
    adj: Vec<u32>,
    /// Final (u, v) and derivatives of the interior nodes (local index − nb).
    uv: Vec<[f64; 2]>,
    derivs: Vec<SurfaceDerivs>,
}

/// The surface-grid update linearised at one model ([`Updater::linearise`]): forward and
/// reverse products (module doc).
#[derive(Debug)]
pub struct SurfaceLinearisation<'u> {
    model: GeomDb,
    n_nodes: usize,
    corners: Vec<(usize, usize)>,
    curves: Vec<CurveNode>,
    comps: Vec<Component<'u>>,
}

/// Local neighbour lists (CSR) of a triangulation of `n` nodes, sorted, without the node.
fn neighbours(tris: &[[u32; 3]], n: usize) -> (Vec<usize>, Vec<u32>) {
    let mut nb: Vec<Vec<u32>> = vec![Vec::new(); n];
    for t in tris {
        for i in 0..3 {
            for j in 0..3 {
                if i != j {
                    nb[t[i] as usize].push(t[j]);
                }
            }
        }
    }
    let mut ptr = Vec::with_capacity(n + 1);
    let mut adj = Vec::new();
    ptr.push(0);
    for mut l in nb {
        l.sort_unstable();
        l.dedup();
        adj.extend(l);
        ptr.push(adj.len());
    }
    (ptr, adj)
}

fn foot(
    local: usize,
    node: usize,
    uv: [f64; 2],
    d: SurfaceDerivs,
    x: Vector3,
    dom: ([f64; 2], [f64; 2]),
) -> Option<Foot> {
    let gap = d.point.coords - x;
    let held = [
        uv[0] <= dom.0[0] || uv[0] >= dom.0[1],
        uv[1] <= dom.1[0] || uv[1] >= dom.1[1],
    ];
    let c = d.du.dot(&d.dv) + gap.dot(&d.duv);
    let mut h = Matrix2::new(
        d.du.dot(&d.du) + gap.dot(&d.duu),
        c,
        c,
        d.dv.dot(&d.dv) + gap.dot(&d.dvv),
    );
    for (i, &hd) in held.iter().enumerate() {
        if hd {
            for j in 0..2 {
                h[(i, j)] = 0.0;
                h[(j, i)] = 0.0;
            }
            h[(i, i)] = 1.0;
        }
    }
    let hinv = h.try_inverse()?;
    Some(Foot {
        local,
        node,
        uv,
        d,
        gap,
        hinv,
        held,
    })
}

impl Updater {
    /// Runs [`update`](Self::update) of `grid` (the grid this updater was made for) from
    /// `old` to `new` and linearises it there (module doc). The returned grid and report
    /// are the update's, bit for bit.
    pub fn linearise<'u>(
        &'u self,
        grid: &SurfaceGrid,
        old: &GeomDb,
        new: &GeomDb,
        opts: &UpdateOptions,
    ) -> Result<(SurfaceGrid, UpdateReport, SurfaceLinearisation<'u>)> {
        let (out, report, record) = self.update_recorded(grid, old, new, opts)?;
        let lin = self.linearise_recorded(grid, old, new, &out, &record)?;
        Ok((out, report, lin))
    }

    /// The linearisation of an update already made: `out` and `record` are what
    /// [`Updater::update_recorded`] returned for `grid`, `old` and `new` (the update is not
    /// run again).
    pub fn linearise_recorded<'u>(
        &'u self,
        grid: &SurfaceGrid,
        old: &GeomDb,
        new: &GeomDb,
        out: &SurfaceGrid,
        record: &UpdateRecord,
    ) -> Result<SurfaceLinearisation<'u>> {
        let moves = &record.moves;
        if out.components.len() != grid.components.len()
            || out.coords.len() != grid.coords.len()
            || moves.len() != grid.components.len()
        {
            return Err(Error::Mismatch {
                what: "an update record of another grid".into(),
            });
        }
        let mut corners = Vec::new();
        let mut curves = Vec::new();
        for (i, (s0, s1)) in grid.support.iter().zip(&out.support).enumerate() {
            match (*s0, *s1) {
                (NodeSupport::Corner(c), _) => corners.push((i, c.index())),
                (NodeSupport::Curve { comp, t }, NodeSupport::Curve { t: t1, .. }) => {
                    let (a, b) = (old.curve_component(comp), new.curve_component(comp));
                    curves.push(CurveNode {
                        node: i,
                        curve: b.curve,
                        t: t1,
                        d1: new.curve(b.curve).derivs(t1).d1,
                        comp: comp.index(),
                        s: (t - a.t0) / (a.t1 - a.t0),
                    });
                }
                _ => {}
            }
        }
        let mut comps = Vec::with_capacity(grid.components.len());
        for (ci, (cg, oc)) in grid.components.iter().zip(&out.components).enumerate() {
            let sc = new.surface_component(cg.comp);
            let surf = new.surface(sc.surface);
            let dom = surf.domain();
            let nb = cg.n_boundary;
            let is_pole = cg.pole_mask();
            let mut feet = Vec::new();
            for k in (0..nb).filter(|&k| !is_pole[k]) {
                let g = cg.nodes[k] as usize;
                let uv = oc.uv[k];
                let d = surf.derivs(uv[0], uv[1]);
                let f = foot(k, g, uv, d, out.coords[g].coords, dom).ok_or_else(|| {
                    Error::Mismatch {
                        what: format!(
                            "{}: node {g}: the linearised foot of the normal is singular",
                            sc.name
                        ),
                    }
                })?;
                feet.push(f);
            }
            let uv: Vec<[f64; 2]> = oc.uv[nb..].to_vec();
            let derivs = uv.iter().map(|p| surf.derivs(p[0], p[1])).collect();
            let moves = moves[ci].clone();
            let (adj_ptr, adj) = if moves.is_empty() {
                (Vec::new(), Vec::new())
            } else {
                neighbours(&cg.triangles, cg.nodes.len())
            };
            comps.push(Component {
                surface: sc.surface,
                nodes: cg.nodes.clone(),
                nb,
                map: self.harmonic(ci, grid),
                feet,
                moves,
                adj_ptr,
                adj,
                uv,
                derivs,
            });
        }
        Ok(SurfaceLinearisation {
            model: new.clone(),
            n_nodes: grid.n_nodes(),
            corners,
            curves,
            comps,
        })
    }
}

impl SurfaceLinearisation<'_> {
    /// The updated model (the layout of the tangents).
    pub fn model(&self) -> &GeomDb {
        &self.model
    }

    /// Number of grid nodes (outputs).
    pub fn n_nodes(&self) -> usize {
        self.n_nodes
    }

    fn check(&self, t: &ModelTangent) -> Result<()> {
        let m = &self.model;
        if t.nodes.len() < m.control_nodes.len()
            || t.curves.len() != m.curves.len()
            || t.corners.len() != m.corners.len()
            || t.ranges.len() != m.curve_components.len()
        {
            return Err(Error::Mismatch {
                what: "a model tangent of another model's layout".into(),
            });
        }
        Ok(())
    }

    /// The forward product: dX per grid node for the model perturbation `t`.
    pub fn jvp(&self, t: &ModelTangent) -> Result<Vec<Vector3>> {
        self.check(t)?;
        let db = &self.model;
        let mut dx = vec![Vector3::zeros(); self.n_nodes];
        for &(i, c) in &self.corners {
            dx[i] = t.corners[c];
        }
        for c in &self.curves {
            let dc = t.curve_at(db, c.curve, c.t);
            let r = t.ranges[c.comp];
            dx[c.node] = dc.point + c.d1 * ((1.0 - c.s) * r[0] + c.s * r[1]);
        }
        for cp in &self.comps {
            let n = cp.nodes.len();
            let mut duv = vec![[0.0; 2]; n];
            for f in &cp.feet {
                let ds = t.surface_at(db, cp.surface, f.uv[0], f.uv[1]);
                let e = ds.point - dx[f.node];
                let mut r = Vector2::new(
                    e.dot(&f.d.du) + f.gap.dot(&ds.du),
                    e.dot(&f.d.dv) + f.gap.dot(&ds.dv),
                );
                for i in 0..2 {
                    if f.held[i] {
                        r[i] = 0.0;
                    }
                }
                let z = -(f.hinv * r);
                duv[f.local] = [z[0], z[1]];
            }
            cp.map.solve(&mut duv);
            for &(v, w) in &cp.moves {
                let v = v as usize;
                let nb = &cp.adj[cp.adj_ptr[v]..cp.adj_ptr[v + 1]];
                let mut m = [0.0; 2];
                for &j in nb {
                    m[0] += duv[j as usize][0];
                    m[1] += duv[j as usize][1];
                }
                let k = nb.len() as f64;
                duv[v] = [
                    (1.0 - w) * duv[v][0] + w * m[0] / k,
                    (1.0 - w) * duv[v][1] + w * m[1] / k,
                ];
            }
            for k in cp.nb..n {
                let (p, d) = (cp.uv[k - cp.nb], &cp.derivs[k - cp.nb]);
                let ds = t.surface_at(db, cp.surface, p[0], p[1]);
                dx[cp.nodes[k] as usize] = ds.point + d.du * duv[k][0] + d.dv * duv[k][1];
            }
        }
        Ok(dx)
    }

    /// The reverse product: adds to `bar` (a cotangent of the updated model, e.g.
    /// `ModelLinearisation::zero_tangent`) the cotangent given by `x_bar`, one vector per
    /// grid node.
    pub fn vjp(&self, x_bar: &[Vector3], bar: &mut ModelTangent) -> Result<()> {
        self.check(bar)?;
        if x_bar.len() != self.n_nodes {
            return Err(Error::Mismatch {
                what: format!(
                    "{} node cotangents for a grid of {} nodes",
                    x_bar.len(),
                    self.n_nodes
                ),
            });
        }
        let db = &self.model;
        let mut xb = x_bar.to_vec();
        for cp in &self.comps {
            let n = cp.nodes.len();
            let mut uvb = vec![[0.0; 2]; n];
            for k in cp.nb..n {
                let (p, d) = (cp.uv[k - cp.nb], &cp.derivs[k - cp.nb]);
                let b = xb[cp.nodes[k] as usize];
                uvb[k] = [d.du.dot(&b), d.dv.dot(&b)];
                let sb = SurfaceTangent {
                    point: b,
                    ..SurfaceTangent::default()
                };
                bar.add_surface_at(db, cp.surface, p[0], p[1], &sb);
            }
            for &(v, w) in cp.moves.iter().rev() {
                let v = v as usize;
                let b = uvb[v];
                let nb = &cp.adj[cp.adj_ptr[v]..cp.adj_ptr[v + 1]];
                let k = nb.len() as f64;
                for &j in nb {
                    uvb[j as usize][0] += w * b[0] / k;
                    uvb[j as usize][1] += w * b[1] / k;
                }
                uvb[v] = [(1.0 - w) * uvb[v][0], (1.0 - w) * uvb[v][1]];
            }
            cp.map.solve_transpose(&mut uvb);
            for f in &cp.feet {
                let zb = Vector2::new(uvb[f.local][0], uvb[f.local][1]);
                let mut rb = -(f.hinv.transpose() * zb);
                for i in 0..2 {
                    if f.held[i] {
                        rb[i] = 0.0;
                    }
                }
                let eb = f.d.du * rb[0] + f.d.dv * rb[1];
                let sb = SurfaceTangent {
                    point: eb,
                    du: f.gap * rb[0],
                    dv: f.gap * rb[1],
                };
                bar.add_surface_at(db, cp.surface, f.uv[0], f.uv[1], &sb);
                xb[f.node] -= eb;
            }
        }
        for c in &self.curves {
            let b = xb[c.node];
            let cb = CurveTangent {
                point: b,
                ..CurveTangent::default()
            };
            bar.add_curve_at(db, c.curve, c.t, &cb);
            let tb = c.d1.dot(&b);
            let r = &mut bar.ranges[c.comp];
            r[0] += (1.0 - c.s) * tb;
            r[1] += c.s * tb;
        }
        for &(i, c) in &self.corners {
            bar.corners[c] += xb[i];
        }
        Ok(())
    }
}
