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
//! of the point nearest to its tentative position x + δ: the foot of the normal (Eq. 11) by
//! geom-db's point inversion ([`geom_db::invert`]: the shared safeguarded Newton, started at
//! the node's parameters, bounded to the parameter domain, converged to a tolerance the
//! caller derives from the model size). The node therefore lies exactly on r(u, v). See
//! [`crate::deform_on_supports`] for the outer iteration that repeats the
//! spring solve with the new tangent spaces.
//!
//! Node classification from a grid ([`Supports::from_classes`]) follows the convention of
//! `surfgrid::SurfaceGrid::to_mesh` (Gmsh-like classes, tags are ids + 1): a node of entity
//! dimension 0 is a corner (frozen), dimension 1 with tag k lies on curve component k − 1 at
//! global parameter t of its support curve, dimension 2 with tag k lies in surface component
//! k − 1 at global parameters (u, v) of its support surface.

use geom_db::eval::{ParamCurve, ParamSurface};
use geom_db::invert::{
    CurveInverter, InvertOptions, SurfaceInverter, foot_on_curve, foot_on_surface,
};
use geom_db::newton::{NewtonReport, Settings};
use geom_db::prelude::Point3;
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
    /// (`mesh.parametric == false`), the parameters are the foot of the normal from the node
    /// on its support (geom-db's point inversion, seeded by sampling, tolerance relative to
    /// the model size). Errors name the node and the entity.
    pub fn from_classes(mesh: &Mesh, db: &'a GeomDb) -> Result<Self> {
        let Some(classes) = &mesh.classes else {
            return Err(Error::Support {
                node: None,
                entity: "grid".into(),
                reason: "the grid has no node classification (use MSH 4.1 with entities)".into(),
            });
        };
        let mut nodes = Vec::new();
        let mut finders = Finders::new(db);
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
                        finders.curve(curve, i, mesh.coords[i]).map_err(bad)?[0]
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
                        finders.surface(surface, i, mesh.coords[i]).map_err(bad)?
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

/// Point inversions on the supports, built on first use (for grids without parametric
/// coordinates).
struct Finders<'a> {
    db: &'a GeomDb,
    opts: InvertOptions,
    curves: Vec<Option<CurveInverter<'a, geom_db::SupportCurve>>>,
    surfaces: Vec<Option<SurfaceInverter<'a, geom_db::SupportSurface>>>,
}

impl<'a> Finders<'a> {
    fn new(db: &'a GeomDb) -> Self {
        Self {
            db,
            opts: InvertOptions::for_model(db),
            curves: (0..db.curves.len()).map(|_| None).collect(),
            surfaces: (0..db.surfaces.len()).map(|_| None).collect(),
        }
    }

    /// The parameter t of the foot of the normal from node `node` at `x` on curve `c`.
    fn curve(
        &mut self,
        c: CurveId,
        node: usize,
        x: [f64; 3],
    ) -> std::result::Result<[f64; 1], String> {
        let (db, opts) = (self.db, self.opts);
        let inv = match &mut self.curves[c.index()] {
            Some(inv) => inv,
            slot => slot.insert(
                CurveInverter::new(entity_name(db, SupKind::Curve(c)), db.curve(c), &opts)
                    .map_err(|e| e.to_string())?,
            ),
        };
        let f = inv
            .project_indexed(&Point3::from(x), node)
            .map_err(|e| e.to_string())?;
        Ok([f.t])
    }

    /// The parameters (u, v) of the foot of the normal from node `node` at `x` on surface
    /// `s`.
    fn surface(
        &mut self,
        s: SurfaceId,
        node: usize,
        x: [f64; 3],
    ) -> std::result::Result<[f64; 2], String> {
        let (db, opts) = (self.db, self.opts);
        let inv = match &mut self.surfaces[s.index()] {
            Some(inv) => inv,
            slot => slot.insert(
                SurfaceInverter::new(entity_name(db, SupKind::Surface(s)), db.surface(s), &opts)
                    .map_err(|e| e.to_string())?,
            ),
        };
        let f = inv
            .project_indexed(&Point3::from(x), node)
            .map_err(|e| e.to_string())?;
        Ok(f.uv)
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

/// r(p) on the support.
pub(crate) fn point(db: &GeomDb, kind: SupKind, p: [f64; 2]) -> [f64; 3] {
    let q: Point3 = match kind {
        SupKind::Curve(c) => db.curve(c).point(p[0]),
        SupKind::Surface(s) => db.surface(s).point(p[0], p[1]),
    };
    [q.x, q.y, q.z]
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

/// Places a node on its support nearest to `target`, starting from parameters `p`: the foot
/// of the normal from `target` (Eq. 11, geom-db's point inversion: the shared safeguarded
/// Newton, parameters bounded to the support's domain) converged to the tangential residual
/// `tol` (absolute; the callers derive it from the model size). Returns the parameters
/// ([t, 0] on a curve); a Newton that does not converge is an error naming the node and the
/// entity, with the iterations and the residual.
pub(crate) fn place(
    db: &GeomDb,
    node: u32,
    kind: SupKind,
    p: [f64; 2],
    target: [f64; 3],
    tol: f64,
) -> Result<[f64; 2]> {
    let tgt = Point3::from(target);
    let settings = Settings { tol, max_iters: 60 };
    let (x, report) = match kind {
        SupKind::Curve(c) => {
            let curve = db.curve(c);
            let (a, b) = curve.domain();
            let o = foot_on_curve(curve, &tgt, p[0].clamp(a, b), a, b, settings);
            ([o.x[0], 0.0], o.report)
        }
        SupKind::Surface(s) => {
            let surf = db.surface(s);
            let (du, dv) = surf.domain();
            let p0 = [p[0].clamp(du[0], du[1]), p[1].clamp(dv[0], dv[1])];
            let o = foot_on_surface(surf, &tgt, p0, [du[0], dv[0]], [du[1], dv[1]], settings);
            (o.x, o.report)
        }
    };
    if !report.converged {
        return Err(not_placed(db, node, kind, report));
    }
    Ok(x)
}

fn not_placed(db: &GeomDb, node: u32, kind: SupKind, r: NewtonReport) -> Error {
    let reason = if r.residual.is_finite() {
        format!(
            "the foot of the normal from the node's new position did not converge after {} \
             iterations (residual {:e}, tolerance {:e})",
            r.iterations, r.residual, r.tolerance
        )
    } else {
        "the parameter iteration diverged (non-finite point)".into()
    };
    Error::Support {
        node: Some(node),
        entity: entity_name(db, kind),
        reason,
    }
}
