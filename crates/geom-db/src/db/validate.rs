//! Validation of the geometric database: everything a consumer relies on, the first
//! problem reported naming the entity.

use crate::control::{self, MAX_DEGREE};
use crate::curve::SupportCurve;
use crate::error::{Entity, Error, Result};
use crate::ids::{ControlNodeId, CornerId, CurveCompId, CurveId, SurfCompId, SurfaceId};
use crate::prelude::Point3;
use crate::surface::SupportSurface;
use crate::topology::{CurveComponent, SurfaceComponent};

use super::{FORMAT_VERSION, GeomDb};

pub(super) fn invalid(entity: Entity, reason: impl Into<String>) -> Error {
    Error::Invalid {
        path: String::new(),
        entity,
        reason: reason.into(),
    }
}

pub(super) fn check_point(entity: Entity, what: &str, p: &Point3) -> Result<()> {
    for (c, name) in p.coords.iter().zip(["x", "y", "z"]) {
        if c.is_nan() {
            return Err(invalid(entity, format!("{what}{name} is NaN")));
        }
        if c.is_infinite() {
            return Err(invalid(entity, format!("{what}{name} is infinite")));
        }
    }
    Ok(())
}

pub(super) fn check_id(
    entity: Entity,
    what: &str,
    index: usize,
    len: usize,
    kind: &str,
) -> Result<()> {
    if index >= len {
        Err(invalid(
            entity,
            format!("{what} {index} does not exist (the model has {len} {kind})"),
        ))
    } else {
        Ok(())
    }
}

impl GeomDb {
    // ----------------------------------------------------------------- validation

    /// Checks everything a consumer relies on and returns the first problem, naming the
    /// entity: format version, finite numbers, degrees vs coefficient counts, ids in range,
    /// closed loops, zero-length arcs, degenerate patches, control-node lists and their
    /// consistency with the coefficients.
    pub fn validate(&self) -> Result<()> {
        if self.format_version != FORMAT_VERSION {
            return Err(Error::UnsupportedVersion {
                path: String::new(),
                found: self.format_version,
                supported: FORMAT_VERSION,
            });
        }
        let too_many = [
            self.corners.len(),
            self.curves.len(),
            self.surfaces.len(),
            self.curve_components.len(),
            self.surface_components.len(),
            self.control_nodes.len(),
        ]
        .iter()
        .any(|&n| n > u32::MAX as usize);
        if let Some(l) = self.size
            && !(l.is_finite() && l > 0.0)
        {
            return Err(invalid(
                Entity::Model,
                format!("size {l} is not a positive finite length"),
            ));
        }
        if too_many {
            return Err(invalid(
                Entity::Model,
                "more than 2^32 entities of one kind",
            ));
        }
        for (i, c) in self.corners.iter().enumerate() {
            check_point(
                Entity::Corner(CornerId::from_index(i)),
                "coordinate ",
                &c.point,
            )?;
        }
        for (i, p) in self.control_nodes.iter().enumerate() {
            check_point(
                Entity::ControlNode(ControlNodeId::from_index(i)),
                "coordinate ",
                p,
            )?;
        }
        for (ci, c) in self.curves.iter().enumerate() {
            self.validate_curve_structure(CurveId::from_index(ci), c)?;
        }
        for (si, s) in self.surfaces.iter().enumerate() {
            self.validate_surface_structure(SurfaceId::from_index(si), s)?;
        }
        for (i, cc) in self.curve_components.iter().enumerate() {
            self.validate_curve_component(CurveCompId::from_index(i), cc)?;
        }
        for (i, sc) in self.surface_components.iter().enumerate() {
            self.validate_surface_component(SurfCompId::from_index(i), sc)?;
        }
        self.validate_geometry()
    }

    pub(super) fn validate_curve_structure(&self, id: CurveId, c: &SupportCurve) -> Result<()> {
        if c.arcs.is_empty() {
            return Err(invalid(Entity::Curve(id), "has no arcs"));
        }
        if c.arcs.len() > 1 << 24 {
            return Err(invalid(Entity::Curve(id), "more than 2^24 arcs"));
        }
        for (ai, a) in c.arcs.iter().enumerate() {
            let e = Entity::Arc { curve: id, arc: ai };
            if a.degree == 0 || a.degree > MAX_DEGREE {
                return Err(invalid(
                    e,
                    format!("degree {} is outside 1..={MAX_DEGREE}", a.degree),
                ));
            }
            if a.coeffs.len() != a.degree + 1 {
                return Err(invalid(
                    e,
                    format!(
                        "degree {} needs {} coefficients, {} given",
                        a.degree,
                        a.degree + 1,
                        a.coeffs.len()
                    ),
                ));
            }
            for (k, p) in a.coeffs.iter().enumerate() {
                check_point(e, &format!("coefficient a[{k}] "), p)?;
            }
        }
        if c.defining_surfaces.len() > 2 {
            return Err(invalid(
                Entity::Curve(id),
                format!("{} defining surfaces, at most 2", c.defining_surfaces.len()),
            ));
        }
        for s in &c.defining_surfaces {
            check_id(
                Entity::Curve(id),
                "defining surface",
                s.index(),
                self.surfaces.len(),
                "surfaces",
            )?;
        }
        if !c.control.is_empty() {
            if c.control.nodes.len() != c.arcs.len() {
                return Err(invalid(
                    Entity::Curve(id),
                    format!(
                        "control node lists for {} arcs, the curve has {}",
                        c.control.nodes.len(),
                        c.arcs.len()
                    ),
                ));
            }
            for (ai, (ids, a)) in c.control.nodes.iter().zip(&c.arcs).enumerate() {
                let e = Entity::Arc { curve: id, arc: ai };
                if ids.len() != a.degree + 1 {
                    return Err(invalid(
                        e,
                        format!(
                            "degree {} needs {} control nodes, {} given",
                            a.degree,
                            a.degree + 1,
                            ids.len()
                        ),
                    ));
                }
                self.check_control_nodes(e, ids)?;
            }
        }
        Ok(())
    }

    /// Every control node `ids` names exists; the error names `e` and the first missing one.
    fn check_control_nodes(&self, e: Entity, ids: &[ControlNodeId]) -> Result<()> {
        for n in ids {
            check_id(
                e,
                "control node",
                n.index(),
                self.control_nodes.len(),
                "control nodes",
            )?;
        }
        Ok(())
    }

    pub(super) fn validate_surface_structure(
        &self,
        id: SurfaceId,
        s: &SupportSurface,
    ) -> Result<()> {
        let e = Entity::Surface(id);
        if s.n_u == 0 || s.n_v == 0 {
            return Err(invalid(e, format!("{} × {} patches", s.n_u, s.n_v)));
        }
        let n = s.n_u.checked_mul(s.n_v).filter(|&n| n <= 1 << 24);
        if n != Some(s.patches.len()) {
            return Err(invalid(
                e,
                format!(
                    "n_u × n_v = {} × {} but {} patches given",
                    s.n_u,
                    s.n_v,
                    s.patches.len()
                ),
            ));
        }
        for (pi, p) in s.patches.iter().enumerate() {
            let e = Entity::Patch {
                surface: id,
                patch: pi,
            };
            if p.deg_u == 0 || p.deg_u > MAX_DEGREE || p.deg_v == 0 || p.deg_v > MAX_DEGREE {
                return Err(invalid(
                    e,
                    format!(
                        "degree {} × {} is outside 1..={MAX_DEGREE}",
                        p.deg_u, p.deg_v
                    ),
                ));
            }
            let want = (p.deg_u + 1) * (p.deg_v + 1);
            if p.coeffs.len() != want {
                return Err(invalid(
                    e,
                    format!(
                        "degree {} × {} needs {want} coefficients, {} given",
                        p.deg_u,
                        p.deg_v,
                        p.coeffs.len()
                    ),
                ));
            }
            for (idx, c) in p.coeffs.iter().enumerate() {
                let (k, l) = (idx / (p.deg_v + 1), idx % (p.deg_v + 1));
                check_point(e, &format!("coefficient a[{k},{l}] "), c)?;
            }
        }
        if !s.control.is_empty() {
            if s.control.nodes.len() != s.patches.len() {
                return Err(invalid(
                    e,
                    format!(
                        "control node lists for {} patches, the surface has {}",
                        s.control.nodes.len(),
                        s.patches.len()
                    ),
                ));
            }
            for (pi, (ids, p)) in s.control.nodes.iter().zip(&s.patches).enumerate() {
                let e = Entity::Patch {
                    surface: id,
                    patch: pi,
                };
                let want = (p.deg_u + 1) * (p.deg_v + 1);
                if ids.len() != want {
                    return Err(invalid(
                        e,
                        format!(
                            "degree {} × {} needs {want} control nodes, {} given",
                            p.deg_u,
                            p.deg_v,
                            ids.len()
                        ),
                    ));
                }
                self.check_control_nodes(e, ids)?;
            }
        }
        Ok(())
    }

    fn validate_curve_component(&self, id: CurveCompId, cc: &CurveComponent) -> Result<()> {
        let e = Entity::CurveComp(id);
        check_id(e, "curve", cc.curve.index(), self.curves.len(), "curves")?;
        check_id(
            e,
            "start corner",
            cc.start.index(),
            self.corners.len(),
            "corners",
        )?;
        check_id(
            e,
            "end corner",
            cc.end.index(),
            self.corners.len(),
            "corners",
        )?;
        let n = self.curves[cc.curve.index()].arcs.len() as f64;
        for (name, t) in [("t0", cc.t0), ("t1", cc.t1)] {
            if !t.is_finite() || !(0.0..=n).contains(&t) {
                return Err(invalid(
                    e,
                    format!(
                        "{name} = {t} is outside the domain [0, {n}] of {}",
                        cc.curve
                    ),
                ));
            }
        }
        if cc.t0 == cc.t1 {
            return Err(invalid(
                e,
                format!("empty parameter range t0 = t1 = {}", cc.t0),
            ));
        }
        Ok(())
    }

    fn validate_surface_component(&self, id: SurfCompId, sc: &SurfaceComponent) -> Result<()> {
        let e = Entity::SurfComp(id);
        check_id(
            e,
            "surface",
            sc.surface.index(),
            self.surfaces.len(),
            "surfaces",
        )?;
        for (li, lp) in sc.loops.iter().enumerate() {
            let e = Entity::Loop {
                comp: id,
                index: li,
            };
            if lp.is_empty() {
                return Err(invalid(e, "is empty"));
            }
            for oc in lp {
                check_id(
                    e,
                    "curve component",
                    oc.comp.index(),
                    self.curve_components.len(),
                    "curve components",
                )?;
            }
            for k in 0..lp.len() {
                let (a, b) = (lp[k], lp[(k + 1) % lp.len()]);
                let end = self.oriented_ends(a).1;
                let start = self.oriented_ends(b).0;
                if end != start {
                    return Err(invalid(
                        e,
                        format!(
                            "not closed: {} ends at {end} but {} starts at {start}",
                            a.comp, b.comp
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    fn validate_geometry(&self) -> Result<()> {
        let tol = self.tolerances();
        let same = tol.same_point.abs;
        for (ci, c) in self.curves.iter().enumerate() {
            for (ai, a) in c.arcs.iter().enumerate() {
                let pts: Vec<Point3> = (0..=8).map(|i| a.point(i as f64 / 8.0)).collect();
                let len: f64 = pts.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
                if !len.is_finite() {
                    return Err(invalid(
                        Entity::Arc {
                            curve: CurveId::from_index(ci),
                            arc: ai,
                        },
                        "overflows (points are not finite)",
                    ));
                }
                if len <= same {
                    return Err(invalid(
                        Entity::Arc {
                            curve: CurveId::from_index(ci),
                            arc: ai,
                        },
                        format!("zero length ({len:.3e} ≤ tolerance {same:.3e})"),
                    ));
                }
            }
        }
        for (si, s) in self.surfaces.iter().enumerate() {
            for (pi, p) in s.patches.iter().enumerate() {
                let e = Entity::Patch {
                    surface: SurfaceId::from_index(si),
                    patch: pi,
                };
                let mut max_area: f64 = 0.0;
                for i in 0..5 {
                    for j in 0..5 {
                        let d = p.derivs((i as f64 + 0.5) / 5.0, (j as f64 + 0.5) / 5.0);
                        let a = d.du.cross(&d.dv).norm();
                        if !a.is_finite() || !d.point.coords.iter().all(|c| c.is_finite()) {
                            return Err(invalid(e, "overflows (points are not finite)"));
                        }
                        max_area = max_area.max(a);
                    }
                }
                if max_area <= same * same {
                    return Err(invalid(
                        e,
                        format!("degenerate: |r_u × r_v| ≤ {max_area:.3e} (area zero)"),
                    ));
                }
            }
        }
        // Control nodes must sit on the arcs and patches that use them.
        let ctol = 10.0 * same;
        for (ci, c) in self.curves.iter().enumerate() {
            for (ai, (ids, a)) in c.control.nodes.iter().zip(&c.arcs).enumerate() {
                for (i, (&x, id)) in control::nodes(a.degree).iter().zip(ids).enumerate() {
                    let d = (a.point(x) - self.control_nodes[id.index()]).norm();
                    if d.is_nan() || d > ctol {
                        return Err(invalid(
                            Entity::Arc {
                                curve: CurveId::from_index(ci),
                                arc: ai,
                            },
                            format!(
                                "{id} (control point {i}) is {d:.3e} away from the arc (tolerance {ctol:.3e})"
                            ),
                        ));
                    }
                }
            }
        }
        for (si, s) in self.surfaces.iter().enumerate() {
            for (pi, (ids, p)) in s.control.nodes.iter().zip(&s.patches).enumerate() {
                let xu = control::nodes(p.deg_u);
                let xv = control::nodes(p.deg_v);
                for (i, &u) in xu.iter().enumerate() {
                    for (j, &v) in xv.iter().enumerate() {
                        let id = ids[i * xv.len() + j];
                        let d = (p.point(u, v) - self.control_nodes[id.index()]).norm();
                        if d.is_nan() || d > ctol {
                            return Err(invalid(
                                Entity::Patch {
                                    surface: SurfaceId::from_index(si),
                                    patch: pi,
                                },
                                format!(
                                    "{id} (control point [{i},{j}]) is {d:.3e} away from the patch (tolerance {ctol:.3e})"
                                ),
                            ));
                        }
                    }
                }
            }
        }
        Ok(())
    }
}
