//! Boundary nodes sliding on the support curves and surfaces of the geometric database
//! (paper §4.3, Eqs. 27–33).
//!
//! A node classified on a support surface carries its global parameters (u, v), one on a
//! support curve its global parameter t. During the deformation such a node is an unknown of
//! the spring system constrained, in each linear solve, to the tangent plane (surface) or the
//! tangent line (curve) of its support at its current parameters. The solve gives a tentative
//! displacement δ in that tangent space; the parameters are updated by Eq. 31 (surfaces:
//! Δ(u, v) = G⁻¹ [r_u r_v]ᵀ δ with G the first fundamental matrix, Eq. 33) or Eq. 28
//! (curves: Δt = r′·δ / r′·r′), and the node is then placed on the support at the parameters
//! of the point nearest to its tentative position x + δ: Eq. 31 is repeated with
//! RH = (x + δ) − r(u, v) (a Gauss–Newton iteration, safeguarded by step halving and by
//! clamping to the parameter domain) until the step is below round-off. The node therefore
//! lies exactly on r(u, v). See [`crate::deform_on_supports`] for the outer iteration that repeats the
//! spring solve with the new tangent spaces.
//!
//! Node classification from a grid ([`Supports::from_classes`]) follows the convention of
//! `surfgrid::SurfaceGrid::to_mesh` (Gmsh-like classes, tags are ids + 1): a node of entity
//! dimension 0 is a corner (frozen), dimension 1 with tag k lies on curve component k − 1 at
//! global parameter t of its support curve, dimension 2 with tag k lies in surface component
//! k − 1 at global parameters (u, v) of its support surface.

use geom_db::eval::{ParamCurve, ParamSurface};
use geom_db::prelude::{Point3, Vector3};
use geom_db::{CurveCompId, CurveId, GeomDb, SurfCompId, SurfaceId};
use mesh::Mesh;
use serde::Serialize;

use crate::error::{Error, Result};
use crate::solve::Constraint;

/// The geometric entity a boundary node lies on.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub enum Support {
    /// A corner: the node is frozen.
    Corner,
    /// On a support curve at global parameter `t` (Eq. 2).
    Curve {
        /// The support curve.
        curve: CurveId,
        /// Global parameter t ∈ [0, n_arcs].
        t: f64,
    },
    /// On a support surface at global parameters `uv` (Eq. 7).
    Surface {
        /// The support surface.
        surface: SurfaceId,
        /// Global parameters (u, v) ∈ [0, n_u] × [0, n_v].
        uv: [f64; 2],
    },
}

/// The supports of the boundary nodes that may slide: the geometric database and, for each
/// classified node, what it lies on. Used with [`crate::MarkerRole::SlideOnSupport`] markers
/// and [`crate::deform_on_supports`].
#[derive(Debug, Clone)]
pub struct Supports<'a> {
    /// The geometric database the curve and surface ids refer to.
    pub db: &'a GeomDb,
    /// (node index as in the grid, support); a node listed twice takes the last entry.
    pub nodes: Vec<(u32, Support)>,
}

impl<'a> Supports<'a> {
    /// No classified node.
    pub fn new(db: &'a GeomDb) -> Self {
        Self {
            db,
            nodes: Vec::new(),
        }
    }

    /// The supports of the grid's classified nodes (`mesh.classes`), by the convention of
    /// `surfgrid` (module doc): dimension 0 → corner, 1 → curve component tag − 1 on its
    /// support curve, 2 → surface component tag − 1 on its support surface; dimension 3
    /// (volume) nodes are not listed. When the grid carries no parametric coordinates
    /// (`mesh.parametric == false`), the parameters are found by projecting the node onto
    /// its support (Newton, seeded by sampling). Errors name the node and the entity.
    pub fn from_classes(mesh: &Mesh, db: &'a GeomDb) -> Result<Self> {
        let Some(classes) = &mesh.classes else {
            return Err(Error::Support {
                node: None,
                entity: "grid".into(),
                reason: "the grid has no node classification (use MSH 4.1 with entities)".into(),
            });
        };
        let mut nodes = Vec::new();
        for (i, c) in classes.iter().enumerate() {
            let bad = |reason: String| Error::Support {
                node: Some(i as u32),
                entity: format!("entity ({}, {})", c.dim, c.entity),
                reason,
            };
            let idx = usize::try_from(c.entity - 1).ok();
            let s = match c.dim {
                0 => Support::Corner,
                1 => {
                    let comp = idx
                        .filter(|&k| k < db.curve_components.len())
                        .ok_or_else(|| {
                            bad(format!(
                                "no curve component {} in the geometry ({} curve components)",
                                c.entity - 1,
                                db.curve_components.len()
                            ))
                        })?;
                    let curve = db.curve_component(CurveCompId::from_index(comp)).curve;
                    let t = if mesh.parametric {
                        c.param[0]
                    } else {
                        project_curve(db.curve(curve), Vector3::from(mesh.coords[i]), None).0
                    };
                    Support::Curve { curve, t }
                }
                2 => {
                    let comp = idx
                        .filter(|&k| k < db.surface_components.len())
                        .ok_or_else(|| {
                            bad(format!(
                                "no surface component {} in the geometry ({} surface components)",
                                c.entity - 1,
                                db.surface_components.len()
                            ))
                        })?;
                    let surface = db.surface_component(SurfCompId::from_index(comp)).surface;
                    let uv = if mesh.parametric {
                        c.param
                    } else {
                        project_surface(db.surface(surface), Vector3::from(mesh.coords[i]), None).0
                    };
                    Support::Surface { surface, uv }
                }
                _ => continue,
            };
            if let Support::Curve { t, .. } = s
                && !t.is_finite()
            {
                return Err(bad(format!("parameter t = {t} is not finite")));
            }
            if let Support::Surface { uv, .. } = s
                && !(uv[0].is_finite() && uv[1].is_finite())
            {
                return Err(bad(format!("parameters {uv:?} are not finite")));
            }
            nodes.push((i as u32, s));
        }
        Ok(Self { db, nodes })
    }
}

/// What a sliding node lies on, resolved against the database.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum SupKind {
    Curve(CurveId),
    Surface(SurfaceId),
}

/// A node sliding on a support: node, entity, current parameters ([t, 0] on a curve).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SupNode {
    pub node: u32,
    pub kind: SupKind,
    pub param: [f64; 2],
}

/// Entity name for messages.
pub(crate) fn entity_name(db: &GeomDb, kind: SupKind) -> String {
    match kind {
        SupKind::Curve(c) => {
            let n = &db.curve(c).name;
            if n.is_empty() {
                format!("support curve {}", c.0)
            } else {
                format!("support curve {} ({n})", c.0)
            }
        }
        SupKind::Surface(s) => {
            let n = &db.surface(s).name;
            if n.is_empty() {
                format!("support surface {}", s.0)
            } else {
                format!("support surface {} ({n})", s.0)
            }
        }
    }
}

/// Checks that an id exists.
pub(crate) fn check_kind(db: &GeomDb, node: u32, kind: SupKind) -> Result<()> {
    let (ok, what) = match kind {
        SupKind::Curve(c) => (
            c.index() < db.curves.len(),
            format!("support curve {}", c.0),
        ),
        SupKind::Surface(s) => (
            s.index() < db.surfaces.len(),
            format!("support surface {}", s.0),
        ),
    };
    if ok {
        Ok(())
    } else {
        Err(Error::Support {
            node: Some(node),
            entity: what,
            reason: "does not exist in the geometry".into(),
        })
    }
}

fn clamp_param(kind: SupKind, db: &GeomDb, p: [f64; 2]) -> [f64; 2] {
    match kind {
        SupKind::Curve(c) => {
            let (a, b) = db.curve(c).domain();
            [p[0].clamp(a, b), 0.0]
        }
        SupKind::Surface(s) => {
            let (du, dv) = db.surface(s).domain();
            [p[0].clamp(du[0], du[1]), p[1].clamp(dv[0], dv[1])]
        }
    }
}

/// r(p) on the support.
pub(crate) fn point(db: &GeomDb, kind: SupKind, p: [f64; 2]) -> [f64; 3] {
    let q: Point3 = match kind {
        SupKind::Curve(c) => db.curve(c).point(p[0]),
        SupKind::Surface(s) => db.surface(s).point(p[0], p[1]),
    };
    [q.x, q.y, q.z]
}

/// Parameter step of Eq. 28 (curve) or Eq. 31 (surface) for the physical displacement `rh` at
/// parameters `p`: the least-squares solution of Eq. 27 / Eq. 30. `None` where the support
/// is singular (r′ = 0, or G not invertible).
fn param_step(db: &GeomDb, kind: SupKind, p: [f64; 2], rh: Vector3) -> Option<[f64; 2]> {
    match kind {
        SupKind::Curve(c) => {
            let d = db.curve(c).derivs(p[0]);
            let g = d.d1.dot(&d.d1);
            (g > 0.0 && g.is_finite()).then(|| [d.d1.dot(&rh) / g, 0.0])
        }
        SupKind::Surface(s) => {
            let d = db.surface(s).derivs(p[0], p[1]);
            let g = d.first_fundamental_form(); // Eq. 33
            let rhs = nalgebra::Vector2::new(d.du.dot(&rh), d.dv.dot(&rh));
            let det = g[(0, 0)] * g[(1, 1)] - g[(0, 1)] * g[(1, 0)];
            let scale = g[(0, 0)] * g[(1, 1)];
            if det.is_nan() || det <= 1e-24 * scale || !det.is_finite() {
                return None;
            }
            let du = (g[(1, 1)] * rhs.x - g[(0, 1)] * rhs.y) / det;
            let dv = (g[(0, 0)] * rhs.y - g[(1, 0)] * rhs.x) / det;
            Some([du, dv])
        }
    }
}

/// The sliding constraint at parameters `p`: the tangent plane of a surface (unit normal),
/// the tangent line of a curve (unit tangent).
pub(crate) fn tangent_constraint(
    db: &GeomDb,
    node: u32,
    kind: SupKind,
    p: [f64; 2],
) -> Result<Constraint> {
    let singular = || Error::Support {
        node: Some(node),
        entity: entity_name(db, kind),
        reason: format!("the support is singular at parameters {p:?} (no tangent plane)"),
    };
    match kind {
        SupKind::Curve(c) => {
            let t = db.curve(c).derivs(p[0]).d1;
            let l = t.norm();
            if l.is_nan() || l <= 0.0 || !l.is_finite() {
                return Err(singular());
            }
            Ok(Constraint::Line((t / l).into()))
        }
        SupKind::Surface(s) => {
            let n = db
                .surface(s)
                .derivs(p[0], p[1])
                .unit_normal()
                .ok_or_else(singular)?;
            Ok(Constraint::Plane(n.into()))
        }
    }
}

/// Places a node on its support nearest to `target`, starting from parameters `p`: Eq. 28 /
/// Eq. 31 repeated with RH = target − r(p) (Gauss–Newton on |r(p) − target|²), each step
/// halved until the distance does not grow, parameters clamped to the domain. Stops when the
/// physical step is ≤ `tol`. Returns the parameters; errors name the node and the entity.
pub(crate) fn place(
    db: &GeomDb,
    node: u32,
    kind: SupKind,
    p: [f64; 2],
    target: [f64; 3],
    tol: f64,
) -> Result<[f64; 2]> {
    let tgt = Vector3::from(target);
    let dist2 = |q: [f64; 2]| (Vector3::from(point(db, kind, q)) - tgt).norm_squared();
    let mut p = clamp_param(kind, db, p);
    let mut f = dist2(p);
    for _ in 0..60 {
        let r = Vector3::from(point(db, kind, p));
        let Some(dp) = param_step(db, kind, p, tgt - r) else {
            return Err(Error::Support {
                node: Some(node),
                entity: entity_name(db, kind),
                reason: format!("singular first fundamental form at parameters {p:?}"),
            });
        };
        let mut lam = 1.0;
        let mut accepted = None;
        for _ in 0..30 {
            let q = clamp_param(kind, db, [p[0] + lam * dp[0], p[1] + lam * dp[1]]);
            let fq = dist2(q);
            if fq <= f {
                accepted = Some((q, fq));
                break;
            }
            lam *= 0.5;
        }
        let Some((q, fq)) = accepted else {
            // No descent along the Gauss–Newton direction: a (local) nearest point.
            return Ok(p);
        };
        let moved = (Vector3::from(point(db, kind, q)) - r).norm();
        p = q;
        f = fq;
        if moved <= tol || !f.is_finite() {
            break;
        }
    }
    if !f.is_finite() {
        return Err(Error::Support {
            node: Some(node),
            entity: entity_name(db, kind),
            reason: "the parameter iteration diverged (non-finite point)".into(),
        });
    }
    Ok(p)
}

/// Nearest point of a curve: best of a sampling of the domain (or `guess`), then Gauss–Newton
/// steps (Eq. 28 with RH = x − r). Returns (t, distance).
pub fn project_curve(c: &impl ParamCurve, x: Vector3, guess: Option<f64>) -> (f64, f64) {
    let (a, b) = c.domain();
    let mut t = guess.unwrap_or_else(|| {
        let n = 64;
        (0..=n)
            .map(|k| a + (b - a) * k as f64 / n as f64)
            .min_by(|&s, &u| {
                (c.point(s).coords - x)
                    .norm_squared()
                    .total_cmp(&(c.point(u).coords - x).norm_squared())
            })
            .unwrap_or(a)
    });
    for _ in 0..50 {
        let d = c.derivs(t);
        let g = d.d1.norm_squared();
        if g.is_nan() || g <= 0.0 {
            break;
        }
        let f0 = (d.point.coords - x).norm_squared();
        let step = d.d1.dot(&(x - d.point.coords)) / g;
        let mut lam = 1.0;
        let mut moved = false;
        for _ in 0..30 {
            let s = (t + lam * step).clamp(a, b);
            if (c.point(s).coords - x).norm_squared() <= f0 {
                moved = s != t;
                t = s;
                break;
            }
            lam *= 0.5;
        }
        if !moved || (lam * step).abs() * g.sqrt() <= 1e-15 * (1.0 + x.norm()) {
            break;
        }
    }
    (t, (c.point(t).coords - x).norm())
}

/// Nearest point of a surface: best of a sampling of the domain (or `guess`), then
/// Gauss–Newton steps (Eq. 31 with RH = x − r). Returns ((u, v), distance).
pub fn project_surface(
    s: &impl ParamSurface,
    x: Vector3,
    guess: Option<[f64; 2]>,
) -> ([f64; 2], f64) {
    let (du, dv) = s.domain();
    let mut p = guess.unwrap_or_else(|| {
        let n = 24;
        let mut best = ([du[0], dv[0]], f64::INFINITY);
        for i in 0..=n {
            for j in 0..=n {
                let q = [
                    du[0] + (du[1] - du[0]) * i as f64 / n as f64,
                    dv[0] + (dv[1] - dv[0]) * j as f64 / n as f64,
                ];
                let d = (s.point(q[0], q[1]).coords - x).norm_squared();
                if d < best.1 {
                    best = (q, d);
                }
            }
        }
        best.0
    });
    let clamp = |q: [f64; 2]| [q[0].clamp(du[0], du[1]), q[1].clamp(dv[0], dv[1])];
    for _ in 0..50 {
        let d = s.derivs(p[0], p[1]);
        let g = d.first_fundamental_form();
        let rh = x - d.point.coords;
        let (a, b) = (d.du.dot(&rh), d.dv.dot(&rh));
        let det = g[(0, 0)] * g[(1, 1)] - g[(0, 1)] * g[(1, 0)];
        if det.is_nan() || det <= 0.0 {
            break;
        }
        let step = [
            (g[(1, 1)] * a - g[(0, 1)] * b) / det,
            (g[(0, 0)] * b - g[(1, 0)] * a) / det,
        ];
        let f0 = rh.norm_squared();
        let mut lam = 1.0;
        let mut moved = None;
        for _ in 0..30 {
            let q = clamp([p[0] + lam * step[0], p[1] + lam * step[1]]);
            let pq = s.point(q[0], q[1]).coords;
            if (pq - x).norm_squared() <= f0 {
                moved = Some((q, (pq - d.point.coords).norm()));
                break;
            }
            lam *= 0.5;
        }
        let Some((q, len)) = moved else {
            break;
        };
        p = q;
        if len <= 1e-15 * (1.0 + x.norm()) {
            break;
        }
    }
    (p, (s.point(p[0], p[1]).coords - x).norm())
}
