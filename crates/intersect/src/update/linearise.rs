//! The model update linearised (issue 22): forward (Jacobian–vector) and reverse
//! (vector–Jacobian) products of [`ModelBaseline::update`] at one set of control nodes, by
//! the implicit function theorem on the equations the update solved. No finite differences.
//!
//! Inputs: a perturbation dP of the control nodes (the update's input). Outputs: a
//! [`ModelTangent`] of the updated model: the control nodes (the junctions' nodes follow
//! their curves' new control points, the others are dP), each re-intersected curve's control
//! points arc by arc, the corners and the curve components' parameter ranges. In order
//! (docs/crates/intersect.md, "Linearisation"):
//!
//! 1. **Surfaces** (Eq. 9) are linear in their nodes: δS(u, v) = Σ ℓ_i(u) ℓ_j(v) dP_ij
//!    ([`geom_db::linearise`]).
//! 2. **Curve control points** (Eq. 12): F(y) = S₁(u₁, v₁) − S₂(u₂, v₂) = 0 with one
//!    parameter frozen: J_F dy_free = −(δS₁ − δS₂); the normal-plane fallback adds
//!    (S₁ − p_old)·t = 0, a 4 × 4 system. The point is the midpoint:
//!    dq = ½ (S₁,y dy₁ + δS₁ + S₂,y dy₂ + δS₂).
//! 3. **Corners** (Eq. 13): G = [d·a′, −d·b′] = 0 (d = a(t_a) − b(t_b)):
//!    H dt = −[(δa − δb)·a′ + d·δa′, −(δa − δb)·b′ − d·δb′] with the Hessian H of the
//!    solve; the corner is the midpoint ½ (a + b). A corner on one curve is δc(t).
//! 4. **Snap**: a re-intersected curve's end control point at a corner is that corner.
//!    A junction the update re-fitted (degrees raised) is differentiated through its re-fit
//!    rounds ([`super::refit`]: foot seeds and Eq. 12 again at the new nodes).
//! 5. **Component ends** inside a curve: the foot of the normal of the corner on the final
//!    curve, (c(t) − p)·c′(t) = 0: dt = −[(δc − dp)·c′ + (c − p)·δc′] / (c′·c′ + (c − p)·c″).
//! 6. **Junction nodes**: the mean of the new control points of the curves that use them.
//!
//! What the update computed is differentiated *generically*: a curve or corner the update
//! left alone because nothing it depends on changed (its surfaces kept their coefficients)
//! is differentiated as re-solved, since any perturbation of what it depends on re-solves it
//! (at that x its derivative is then the would-be solve's; where nothing it depends on moves
//! it is zero). The equations' solutions are re-computed here by the same code the update
//! ran (bit for bit the same where the update ran it).

use geom_db::eval::{CurveDerivs, ParamCurve, ParamSurface, SurfaceDerivs};
use geom_db::linearise::{CurveTangent, ModelTangent, SurfaceTangent};
use geom_db::prelude::{Matrix2, Point3, Vector3};
use geom_db::{CornerId, CurveId, GeomDb, SurfaceId};
use nalgebra::{Matrix3, Matrix4, Vector4};

use super::refit::RefitLin;
use super::{ModelBaseline, arcs_from_chain, corner_label, curve_label};
use crate::corner::{CornerOptions, solve_corner};
use crate::error::{Error, Result};
use crate::ssi::{Method, Param, SsiOptions, update_curve_points};

/// One control point of a re-intersected curve: the solved Eq. 12 and its factorised
/// Jacobian.
#[derive(Debug, Clone)]
pub(super) struct PointLin {
    /// Parameters y = [u₁, v₁, u₂, v₂] at the solution.
    y: [f64; 4],
    /// Surface 1 and 2 at the solution.
    s1: SurfaceDerivs,
    s2: SurfaceDerivs,
    kind: PointKind,
}

#[derive(Debug, Clone)]
enum PointKind {
    /// Eq. 12 with parameter `frozen` held: inverse of the 3 × 3 Jacobian of the free ones.
    Frozen { frozen: usize, jinv: Matrix3<f64> },
    /// The normal-plane fallback: inverse of its 4 × 4 Jacobian.
    Plane { jinv: Matrix4<f64> },
}

/// The pseudo-inverse of a rank-deficient 3 × 3 Jacobian of Eq. 12, singular values below
/// 1e-12 of the largest cut; `None` when every singular value is cut (no direction solved).
fn pseudo_inverse3(j: &Matrix3<f64>) -> Option<Matrix3<f64>> {
    let svd = j.svd(true, true);
    let largest = svd.singular_values.max();
    if largest <= 0.0 {
        return None;
    }
    svd.pseudo_inverse(1e-12 * largest).ok()
}

impl PointLin {
    pub(super) fn new(
        label: &str,
        i: usize,
        y: [f64; 4],
        s1: SurfaceDerivs,
        s2: SurfaceDerivs,
        method: Method,
        t: Vector3,
    ) -> Result<Self> {
        let cols = [s1.du, s1.dv, -s2.du, -s2.dv];
        let singular = |what: &str| Error::BadEntity {
            entity: label.to_string(),
            reason: format!("control point {i}: the linearised {what} is singular"),
        };
        let kind = match method {
            Method::Frozen { surface, param } => {
                let frozen = match (surface, param) {
                    (1, Param::U) => 0,
                    (1, Param::V) => 1,
                    (2, Param::U) => 2,
                    _ => 3,
                };
                let mut j = Matrix3::zeros();
                let mut k = 0;
                for (c, col) in cols.iter().enumerate() {
                    if c != frozen {
                        j.set_column(k, col);
                        k += 1;
                    }
                }
                // Singular where a surface degenerates (a column vanishes at a collapsed
                // edge, e.g. a tip cap's leading-edge point): the parameter along the
                // null space does not move the point, so the least-squares solution gives
                // the one dq (pseudo-inverse; its transpose serves the reverse product).
                let jinv = match j.try_inverse() {
                    Some(inv) => inv,
                    None => pseudo_inverse3(&j).ok_or_else(|| singular("Eq. 12"))?,
                };
                PointKind::Frozen { frozen, jinv }
            }
            Method::NormalPlane => {
                let mut j = Matrix4::zeros();
                for (c, col) in cols.iter().enumerate() {
                    for r in 0..3 {
                        j[(r, c)] = col[r];
                    }
                }
                j[(3, 0)] = s1.du.dot(&t);
                j[(3, 1)] = s1.dv.dot(&t);
                let jinv = j
                    .try_inverse()
                    .ok_or_else(|| singular("normal-plane system"))?;
                PointKind::Plane { jinv }
            }
        };
        Ok(Self { y, s1, s2, kind })
    }

    /// The solution's parameters [u₁, v₁, u₂, v₂].
    pub(super) fn y(&self) -> [f64; 4] {
        self.y
    }

    /// Surface 1 at the solution.
    pub(super) fn s1(&self) -> &SurfaceDerivs {
        &self.s1
    }

    /// The frozen parameter (index into y), None for the normal-plane fallback.
    pub(super) fn frozen(&self) -> Option<usize> {
        match &self.kind {
            PointKind::Frozen { frozen, .. } => Some(*frozen),
            PointKind::Plane { .. } => None,
        }
    }

    /// The Jacobian column of y_k in Eq. 12: [r₁,u, r₁,v, −r₂,u, −r₂,v]_k.
    fn column(&self, k: usize) -> Vector3 {
        match k {
            0 => self.s1.du,
            1 => self.s1.dv,
            2 => -self.s2.du,
            _ => -self.s2.dv,
        }
    }

    /// dq from the surfaces' perturbations at the solution (`e1` on surface 1, `e2` on
    /// surface 2; their points only), for the fallback the plane's tangent `t`, and `s`: the
    /// perturbation of the frozen parameter's value (Frozen), or of the plane equation's
    /// constant, −(p_old·t)′ (fallback); zero where those are the initial model's.
    pub(super) fn forward(&self, e1: &Vector3, e2: &Vector3, t: &Vector3, s: f64) -> Vector3 {
        let df = e1 - e2;
        let mut dy = [0.0; 4];
        match &self.kind {
            PointKind::Frozen { frozen, jinv } => {
                let z = -(jinv * (df + self.column(*frozen) * s));
                let mut k = 0;
                for (c, d) in dy.iter_mut().enumerate() {
                    if c != *frozen {
                        *d = z[k];
                        k += 1;
                    } else {
                        *d = s;
                    }
                }
            }
            PointKind::Plane { jinv } => {
                let rhs = Vector4::new(df.x, df.y, df.z, e1.dot(t) + s);
                let z = -(jinv * rhs);
                dy = [z[0], z[1], z[2], z[3]];
            }
        }
        0.5 * (self.s1.du * dy[0] + self.s1.dv * dy[1] + e1)
            + 0.5 * (self.s2.du * dy[2] + self.s2.dv * dy[3] + e2)
    }

    /// The transpose of [`forward`](Self::forward): the cotangents of the surfaces' points
    /// (ē₁, ē₂) and of `s` from the point's cotangent `q`.
    pub(super) fn reverse(&self, q: &Vector3, t: &Vector3) -> (Vector3, Vector3, f64) {
        let half = 0.5 * q;
        let ybar = [
            self.s1.du.dot(&half),
            self.s1.dv.dot(&half),
            self.s2.du.dot(&half),
            self.s2.dv.dot(&half),
        ];
        let (mut e1, mut e2) = (half, half);
        let sb = match &self.kind {
            PointKind::Frozen { frozen, jinv } => {
                let mut zb = Vector3::zeros();
                let mut k = 0;
                for (c, yb) in ybar.iter().enumerate() {
                    if c != *frozen {
                        zb[k] = *yb;
                        k += 1;
                    }
                }
                let dfb = -(jinv.transpose() * zb);
                e1 += dfb;
                e2 -= dfb;
                ybar[*frozen] + self.column(*frozen).dot(&dfb)
            }
            PointKind::Plane { jinv } => {
                let zb = Vector4::new(ybar[0], ybar[1], ybar[2], ybar[3]);
                let rb = -(jinv.transpose() * zb);
                let dfb = Vector3::new(rb[0], rb[1], rb[2]);
                e1 += dfb + t * rb[3];
                e2 -= dfb;
                rb[3]
            }
        };
        (e1, e2, sb)
    }
}

/// A re-intersected curve (every curve with two defining surfaces).
#[derive(Debug, Clone)]
struct CurveLin {
    curve: CurveId,
    surfaces: [SurfaceId; 2],
    /// Arc degrees of the chain (the initial curve's).
    degrees: Vec<usize>,
    /// Arc degrees after the update (raised where the junction was re-fitted).
    final_degrees: Vec<usize>,
    /// The re-fits of the snapped chain, if the update re-fitted the curve.
    refit: Option<RefitLin>,
    points: Vec<PointLin>,
    /// Per point, the plane tangent of the fallback (unused for frozen points).
    tangents: Vec<Vector3>,
    /// The chain's first and last control points snapped to these corners.
    snap: [Option<CornerId>; 2],
}

/// How one corner depends on its curves.
#[derive(Debug, Clone)]
enum CornerLin {
    /// No curve ends at it: it never moves.
    Fixed,
    /// One curve: the corner is c(t).
    Single { curve: CurveId, t: f64 },
    /// Eq. 13 between curves a and b at (t_a, t_b).
    Pair {
        curves: [CurveId; 2],
        t: [f64; 2],
        a: CurveDerivs,
        b: CurveDerivs,
        hinv: Matrix2,
    },
}

/// A component end set by the foot of the normal of its corner on the final curve.
#[derive(Debug, Clone)]
struct CompEnd {
    comp: usize,
    is_end: bool,
    corner: CornerId,
    curve: CurveId,
    t: f64,
    c: CurveDerivs,
    /// c(t) − p.
    gap: Vector3,
    /// 1 / (c′·c′ + (c − p)·c″).
    hinv: f64,
}

/// The model update linearised at one set of control nodes ([`ModelBaseline::linearise`]):
/// forward and reverse products (module doc).
#[derive(Debug, Clone)]
pub struct ModelLinearisation {
    /// The updated model.
    model: GeomDb,
    /// Control nodes of the update's input.
    n_in: usize,
    curves: Vec<CurveLin>,
    /// Index into `curves` per support curve.
    lin_of: Vec<Option<usize>>,
    corners: Vec<CornerLin>,
    ends: Vec<CompEnd>,
    /// Junction nodes: node → (curve index in `curves`, chain index) of the control points
    /// whose mean it is.
    junction_nodes: Vec<(usize, Vec<(usize, usize)>)>,
}

impl ModelBaseline {
    /// The linearisation of [`update`](Self::update) at control nodes `nodes`, where
    /// `updated` is the update's result for them (module doc). Re-solves Eq. 12 at every
    /// control point of the curves with two defining surfaces and Eq. 13 at every corner of
    /// two curves (as the update does), then factorises each linearised system.
    pub fn linearise(&self, nodes: &[Point3], updated: &GeomDb) -> Result<ModelLinearisation> {
        let init = &self.db;
        let db = updated;
        if nodes.len() != init.control_nodes.len()
            || db.curves.len() != init.curves.len()
            || db.corners.len() != init.corners.len()
            || db.curve_components.len() != init.curve_components.len()
        {
            return Err(Error::BadEntity {
                entity: "model".into(),
                reason: format!(
                    "linearisation at {} control nodes of a model of {}, or of an updated model of another topology",
                    nodes.len(),
                    init.control_nodes.len()
                ),
            });
        }
        // the surfaces and node-based curves of the update's first step
        let pre = init.with_control_points(nodes)?;
        let surf_changed: Vec<bool> = pre
            .surfaces
            .iter()
            .zip(&init.surfaces)
            .map(|(a, b)| a.patches != b.patches)
            .collect();
        let so = SsiOptions {
            length_scale: Some(self.scale),
            rel_tol: self.opts.rel_tol,
            ..SsiOptions::default()
        };
        // 2. curves: Eq. 12 at every control point; the curves as the corners saw them
        let mut pre_curves = pre.curves.clone();
        let mut curves = Vec::new();
        let mut lin_of = vec![None; init.curves.len()];
        let mut pre_chains = Vec::new();
        for (ci, seeds) in self.seeds.iter().enumerate() {
            let Some(cs) = seeds else { continue };
            let degrees: Vec<usize> = init.curves[ci].arcs.iter().map(|a| a.degree).collect();
            let final_degrees: Vec<usize> = db.curves[ci].arcs.iter().map(|a| a.degree).collect();
            let label = curve_label(init, CurveId::from_index(ci));
            let (s1, s2) = (
                &pre.surfaces[cs.surfaces[0].index()],
                &pre.surfaces[cs.surfaces[1].index()],
            );
            let up = update_curve_points(&cs.seeds, s1, s2, &so)?;
            let mut points = Vec::with_capacity(up.points.len());
            let mut tangents = Vec::with_capacity(up.points.len());
            for (i, (p, sp)) in up.points.iter().zip(&cs.seeds.points).enumerate() {
                let y = [p.uv1[0], p.uv1[1], p.uv2[0], p.uv2[1]];
                let t = Vector3::new(sp.tangent[0], sp.tangent[1], sp.tangent[2]);
                let d1 = s1.derivs(y[0], y[1]);
                let d2 = s2.derivs(y[2], y[3]);
                points.push(PointLin::new(&label, i, y, d1, d2, p.method, t)?);
                tangents.push(t);
            }
            pre_chains.push(up.new_points());
            if surf_changed[cs.surfaces[0].index()] || surf_changed[cs.surfaces[1].index()] {
                pre_curves[ci].arcs = arcs_from_chain(&degrees, &up.new_points());
            } else {
                pre_curves[ci].arcs = init.curves[ci].arcs.clone();
            }
            lin_of[ci] = Some(curves.len());
            curves.push(CurveLin {
                curve: CurveId::from_index(ci),
                surfaces: cs.surfaces,
                degrees,
                final_degrees,
                refit: None,
                points,
                tangents,
                snap: [None, None],
            });
        }
        // 3. corners
        let copts = CornerOptions {
            length_scale: Some(self.scale),
            rel_tol: 1e-12,
            meet_rel_tol: self.opts.meet_rel_tol,
            extension: self.opts.corner_extension,
            ..CornerOptions::default()
        };
        let mut at_corner: Vec<Vec<(usize, bool, CurveId, f64)>> =
            vec![Vec::new(); init.corners.len()];
        for (k, cc) in init.curve_components.iter().enumerate() {
            at_corner[cc.start.index()].push((k, false, cc.curve, cc.t0));
            at_corner[cc.end.index()].push((k, true, cc.curve, cc.t1));
        }
        let mut corners = Vec::with_capacity(init.corners.len());
        let mut ends = Vec::new();
        for (ki, list) in at_corner.iter().enumerate() {
            let kid = CornerId::from_index(ki);
            let mut distinct: Vec<(CurveId, f64)> = Vec::new();
            for &(_, _, c, t) in list {
                if !distinct.iter().any(|d| d.0 == c) {
                    distinct.push((c, t));
                }
            }
            let lin = match distinct.len() {
                0 => CornerLin::Fixed,
                1 => CornerLin::Single {
                    curve: distinct[0].0,
                    t: distinct[0].1,
                },
                _ => {
                    let mut best = (f64::NEG_INFINITY, 0usize, 1usize);
                    for i in 0..distinct.len() {
                        for j in i + 1..distinct.len() {
                            let ta = pre_curves[distinct[i].0.index()].derivs(distinct[i].1).d1;
                            let tb = pre_curves[distinct[j].0.index()].derivs(distinct[j].1).d1;
                            let s = ta.normalize().cross(&tb.normalize()).norm();
                            if s > best.0 {
                                best = (s, i, j);
                            }
                        }
                    }
                    let (ca, ta) = distinct[best.1];
                    let (cb, tb) = distinct[best.2];
                    let r = solve_corner(
                        &corner_label(init, kid),
                        (&curve_label(init, ca), &pre_curves[ca.index()]),
                        (&curve_label(init, cb), &pre_curves[cb.index()]),
                        Some([ta, tb]),
                        &copts,
                    )?;
                    let a = pre_curves[ca.index()].derivs(r.t[0]);
                    let b = pre_curves[cb.index()].derivs(r.t[1]);
                    let d = a.point - b.point;
                    let c = -a.d1.dot(&b.d1);
                    let h = Matrix2::new(
                        a.d1.dot(&a.d1) + d.dot(&a.d2),
                        c,
                        c,
                        b.d1.dot(&b.d1) - d.dot(&b.d2),
                    );
                    let hinv = h.try_inverse().ok_or_else(|| Error::BadEntity {
                        entity: corner_label(init, kid),
                        reason: "the linearised Eq. 13 is singular (tangent curves)".into(),
                    })?;
                    CornerLin::Pair {
                        curves: [ca, cb],
                        t: r.t,
                        a,
                        b,
                        hinv,
                    }
                }
            };
            corners.push(lin);
            for &(comp, is_end, c, t) in list {
                let n = init.curves[c.index()].arcs.len() as f64;
                let curve_end = t == 0.0 || t == n;
                match lin_of[c.index()] {
                    Some(li) if curve_end => curves[li].snap[usize::from(t == n)] = Some(kid),
                    _ => {
                        let cc = &db.curve_components[comp];
                        let tn = if is_end { cc.t1 } else { cc.t0 };
                        let cd = db.curves[c.index()].derivs(tn);
                        let gap = cd.point - db.corners[ki].point;
                        let h = cd.d1.dot(&cd.d1) + gap.dot(&cd.d2);
                        if !(h.abs() > 0.0 && h.is_finite()) {
                            return Err(Error::BadEntity {
                                entity: corner_label(init, kid),
                                reason: format!(
                                    "the linearised foot on {} is singular",
                                    curve_label(init, c)
                                ),
                            });
                        }
                        ends.push(CompEnd {
                            comp,
                            is_end,
                            corner: kid,
                            curve: c,
                            t: tn,
                            c: cd,
                            gap,
                            hinv: 1.0 / h,
                        });
                    }
                }
            }
        }
        // 4b. re-fits of the snapped chains, replayed (their result is the update's)
        for (cl, chain) in curves.iter_mut().zip(pre_chains) {
            if cl.final_degrees == cl.degrees {
                continue;
            }
            let label = curve_label(init, cl.curve);
            let mut chain = chain;
            for (end, k) in cl.snap.iter().enumerate() {
                if let Some(k) = k {
                    let i = if end == 0 { 0 } else { chain.len() - 1 };
                    chain[i] = db.corners[k.index()].point;
                }
            }
            let s = |k: usize| &pre.surfaces[cl.surfaces[k].index()];
            let (lin, arcs) = RefitLin::new(
                &label,
                cl.surfaces,
                arcs_from_chain(&cl.degrees, &chain),
                &cl.final_degrees,
                self.opts.max_refit_degree,
                (s(0), s(1)),
                &so,
            )?;
            let off = arcs
                .iter()
                .zip(&db.curves[cl.curve.index()].arcs)
                .flat_map(|(a, b)| {
                    let (pa, pb) = (a.control_points(), b.control_points());
                    pa.into_iter()
                        .zip(pb)
                        .map(|(p, q)| (p - q).norm())
                        .collect::<Vec<_>>()
                })
                .fold(0.0f64, f64::max);
            if off.is_nan() || off > 1e-9 * self.scale {
                return Err(Error::BadEntity {
                    entity: label,
                    reason: format!(
                        "the re-fit replayed for the linearisation is {off:.3e} off the update's"
                    ),
                });
            }
            cl.refit = Some(lin);
        }
        // 6. junction nodes: the final curves' control lists
        let mut members: Vec<Vec<(usize, usize)>> = vec![Vec::new(); db.control_nodes.len()];
        for (li, cl) in curves.iter().enumerate() {
            let c = &db.curves[cl.curve.index()];
            let mut k0 = 0;
            for (ids, arc) in c.control.nodes.iter().zip(&c.arcs) {
                for (i, id) in ids.iter().enumerate() {
                    if !self.surface_node.get(id.index()).copied().unwrap_or(false) {
                        members[id.index()].push((li, k0 + i));
                    }
                }
                k0 += arc.degree;
            }
        }
        let junction_nodes = members
            .into_iter()
            .enumerate()
            .filter(|(_, m)| !m.is_empty())
            .collect();
        Ok(ModelLinearisation {
            model: db.clone(),
            n_in: nodes.len(),
            curves,
            lin_of,
            corners,
            ends,
            junction_nodes,
        })
    }
}

/// The per-arc lists of a chain (shared arc ends repeated).
pub(super) fn chain_to_arcs(degrees: &[usize], chain: &[Vector3]) -> Vec<Vec<Vector3>> {
    let mut out = Vec::with_capacity(degrees.len());
    let mut k = 0;
    for &n in degrees {
        out.push(chain[k..=k + n].to_vec());
        k += n;
    }
    out
}

/// A chain's cotangent stored per arc such that [`arcs_to_chain`] gives it back: a shared
/// arc end is kept in the earlier arc, the later arc's copy is zero.
fn chain_cotangent_to_arcs(degrees: &[usize], chain: &[Vector3]) -> Vec<Vec<Vector3>> {
    let mut out = chain_to_arcs(degrees, chain);
    for a in out.iter_mut().skip(1) {
        a[0] = Vector3::zeros();
    }
    out
}

/// The transpose of [`chain_to_arcs`]: per-arc cotangents summed into the chain.
pub(super) fn arcs_to_chain(arcs: &[Vec<Vector3>]) -> Vec<Vector3> {
    let total: usize = arcs.iter().map(|a| a.len() - 1).sum();
    let mut chain = vec![Vector3::zeros(); total + 1];
    let mut k = 0;
    for a in arcs {
        for (i, v) in a.iter().enumerate() {
            chain[k + i] += v;
        }
        k += a.len() - 1;
    }
    chain
}

impl ModelLinearisation {
    /// The updated model the linearisation belongs to (the layout of its tangents).
    pub fn model(&self) -> &GeomDb {
        &self.model
    }

    /// Number of inputs: control nodes of the update's input.
    pub fn n_inputs(&self) -> usize {
        self.n_in
    }

    /// A zero tangent (or cotangent) of the updated model, with the re-intersected curves
    /// carrying their own control points.
    pub fn zero_tangent(&self) -> ModelTangent {
        let mut t = ModelTangent::zeros(&self.model);
        for cl in &self.curves {
            t.own_curve(&self.model, cl.curve);
        }
        t
    }

    /// The forward product: the updated model's tangent for control-node perturbations `dp`
    /// (one per input node).
    pub fn jvp(&self, dp: &[Vector3]) -> Result<ModelTangent> {
        if dp.len() != self.n_in {
            return Err(Error::BadEntity {
                entity: "model".into(),
                reason: format!(
                    "{} node perturbations for {} control nodes",
                    dp.len(),
                    self.n_in
                ),
            });
        }
        let db = &self.model;
        let mut t = self.zero_tangent();
        t.nodes[..self.n_in].copy_from_slice(dp);
        // 2. chains
        let mut chains: Vec<Vec<Vector3>> = Vec::with_capacity(self.curves.len());
        for cl in &self.curves {
            let chain: Vec<Vector3> = cl
                .points
                .iter()
                .zip(&cl.tangents)
                .map(|(p, tan)| {
                    let e1 = t.surface_at(db, cl.surfaces[0], p.y[0], p.y[1]).point;
                    let e2 = t.surface_at(db, cl.surfaces[1], p.y[2], p.y[3]).point;
                    p.forward(&e1, &e2, tan, 0.0)
                })
                .collect();
            t.curves[cl.curve.index()] = Some(chain_to_arcs(&cl.degrees, &chain));
            chains.push(chain);
        }
        // 3. corners (on the pre-snap curves)
        for (k, lin) in self.corners.iter().enumerate() {
            t.corners[k] = match lin {
                CornerLin::Fixed => Vector3::zeros(),
                CornerLin::Single { curve, t: tc } => t.curve_at(db, *curve, *tc).point,
                CornerLin::Pair {
                    curves,
                    t: tt,
                    a,
                    b,
                    hinv,
                } => {
                    let da = t.curve_at(db, curves[0], tt[0]);
                    let dbb = t.curve_at(db, curves[1], tt[1]);
                    let d = a.point - b.point;
                    let e = da.point - dbb.point;
                    let rhs = nalgebra::Vector2::new(
                        e.dot(&a.d1) + d.dot(&da.d1),
                        -e.dot(&b.d1) - d.dot(&dbb.d1),
                    );
                    let dt = -(hinv * rhs);
                    0.5 * (a.d1 * dt[0] + da.point + b.d1 * dt[1] + dbb.point)
                }
            };
        }
        // 4. snap
        for (cl, chain) in self.curves.iter().zip(&mut chains) {
            if let Some(k) = cl.snap[0] {
                chain[0] = t.corners[k.index()];
            }
            if let Some(k) = cl.snap[1] {
                *chain.last_mut().expect("curve with arcs") = t.corners[k.index()];
            }
            t.curves[cl.curve.index()] = Some(chain_to_arcs(&cl.degrees, chain));
        }
        // 4b. re-fits
        for (cl, chain) in self.curves.iter().zip(&mut chains) {
            if let Some(r) = &cl.refit {
                *chain = r.forward(&t, db, chain);
                t.curves[cl.curve.index()] = Some(chain_to_arcs(&cl.final_degrees, chain));
            }
        }
        // 5. component ends on the final curves
        for e in &self.ends {
            let dc = t.curve_at(db, e.curve, e.t);
            let dpk = t.corners[e.corner.index()];
            let dt = -((dc.point - dpk).dot(&e.c.d1) + e.gap.dot(&dc.d1)) * e.hinv;
            t.ranges[e.comp][usize::from(e.is_end)] = dt;
        }
        // 6. junction nodes
        for (id, m) in &self.junction_nodes {
            let mut s = Vector3::zeros();
            for &(li, k) in m {
                s += chains[li][k];
            }
            t.nodes[*id] = s / m.len() as f64;
        }
        Ok(t)
    }

    /// The reverse product: the control nodes' cotangent (one per input node) for a
    /// cotangent `bar` of the updated model (the layout of [`zero_tangent`](Self::zero_tangent);
    /// a re-intersected curve given as `None` has a zero cotangent).
    pub fn vjp(&self, bar: &ModelTangent) -> Result<Vec<Vector3>> {
        let db = &self.model;
        let mut w = self.zero_tangent();
        if bar.nodes.len() != w.nodes.len()
            || bar.curves.len() != w.curves.len()
            || bar.corners.len() != w.corners.len()
            || bar.ranges.len() != w.ranges.len()
        {
            return Err(Error::BadEntity {
                entity: "model".into(),
                reason: "a cotangent of another model's layout".into(),
            });
        }
        w.nodes.copy_from_slice(&bar.nodes);
        w.corners.copy_from_slice(&bar.corners);
        for (ci, b) in bar.curves.iter().enumerate() {
            match (b, &mut w.curves[ci]) {
                (Some(b), Some(own)) => {
                    if b.len() != own.len()
                        || b.iter().zip(own.iter()).any(|(x, y)| x.len() != y.len())
                    {
                        return Err(Error::BadEntity {
                            entity: curve_label(db, CurveId::from_index(ci)),
                            reason: "a cotangent with other arcs than the updated curve".into(),
                        });
                    }
                    own.clone_from(b);
                }
                (Some(_), None) => {
                    return Err(Error::BadEntity {
                        entity: curve_label(db, CurveId::from_index(ci)),
                        reason:
                            "a cotangent of own control points for a curve that follows its nodes"
                                .into(),
                    });
                }
                _ => {}
            }
        }
        // 5ᵀ component ends
        for e in &self.ends {
            let rb = bar.ranges[e.comp][usize::from(e.is_end)];
            if rb == 0.0 {
                continue;
            }
            let s = -rb * e.hinv;
            let cb = CurveTangent {
                point: e.c.d1 * s,
                d1: e.gap * s,
                d2: Vector3::zeros(),
            };
            w.add_curve_at(db, e.curve, e.t, &cb);
            w.corners[e.corner.index()] -= e.c.d1 * s;
        }
        // 6ᵀ junction nodes into the chains
        let mut chains: Vec<Vec<Vector3>> = self
            .curves
            .iter()
            .map(|cl| arcs_to_chain(w.curves[cl.curve.index()].as_ref().expect("own curve")))
            .collect();
        for (id, m) in &self.junction_nodes {
            let share = w.nodes[*id] / m.len() as f64;
            for &(li, k) in m {
                chains[li][k] += share;
            }
            w.nodes[*id] = Vector3::zeros();
        }
        // 4bᵀ re-fits
        for (cl, chain) in self.curves.iter().zip(&mut chains) {
            if let Some(r) = &cl.refit {
                *chain = r.reverse(&mut w, db, chain);
            }
        }
        // 4ᵀ snap
        for (cl, chain) in self.curves.iter().zip(&mut chains) {
            let last = chain.len() - 1;
            if let Some(k) = cl.snap[1] {
                w.corners[k.index()] += chain[last];
                chain[last] = Vector3::zeros();
            }
            if let Some(k) = cl.snap[0] {
                w.corners[k.index()] += chain[0];
                chain[0] = Vector3::zeros();
            }
            w.curves[cl.curve.index()] = Some(chain_cotangent_to_arcs(&cl.degrees, chain));
        }
        // 3ᵀ corners (onto the pre-snap curves)
        for (k, lin) in self.corners.iter().enumerate() {
            let cb = w.corners[k];
            match lin {
                CornerLin::Fixed => {}
                CornerLin::Single { curve, t } => {
                    let bar = CurveTangent {
                        point: cb,
                        ..CurveTangent::default()
                    };
                    w.add_curve_at(db, *curve, *t, &bar);
                }
                CornerLin::Pair {
                    curves,
                    t,
                    a,
                    b,
                    hinv,
                } => {
                    let half = 0.5 * cb;
                    let tb = nalgebra::Vector2::new(a.d1.dot(&half), b.d1.dot(&half));
                    let rb = -(hinv.transpose() * tb);
                    let d = a.point - b.point;
                    let ea = a.d1 * rb[0] - b.d1 * rb[1];
                    let ba = CurveTangent {
                        point: half + ea,
                        d1: d * rb[0],
                        d2: Vector3::zeros(),
                    };
                    let bb = CurveTangent {
                        point: half - ea,
                        d1: -d * rb[1],
                        d2: Vector3::zeros(),
                    };
                    w.add_curve_at(db, curves[0], t[0], &ba);
                    w.add_curve_at(db, curves[1], t[1], &bb);
                }
            }
        }
        // 2ᵀ chains onto the surfaces
        for cl in &self.curves {
            let chain = arcs_to_chain(w.curves[cl.curve.index()].as_ref().expect("own curve"));
            for ((p, tan), q) in cl.points.iter().zip(&cl.tangents).zip(&chain) {
                let (e1, e2, _) = p.reverse(q, tan);
                let b1 = SurfaceTangent {
                    point: e1,
                    ..SurfaceTangent::default()
                };
                let b2 = SurfaceTangent {
                    point: e2,
                    ..SurfaceTangent::default()
                };
                w.add_surface_at(db, cl.surfaces[0], p.y[0], p.y[1], &b1);
                w.add_surface_at(db, cl.surfaces[1], p.y[2], p.y[3], &b2);
            }
        }
        w.nodes.truncate(self.n_in);
        Ok(w.nodes)
    }

    /// The support curves re-intersected (differentiated by Eq. 12).
    pub fn intersection_curves(&self) -> Vec<CurveId> {
        self.curves.iter().map(|c| c.curve).collect()
    }

    /// True when curve `c` carries its own control points in the tangents.
    pub fn owns_curve(&self, c: CurveId) -> bool {
        self.lin_of.get(c.index()).is_some_and(|l| l.is_some())
    }
}
