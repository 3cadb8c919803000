//! The control nodes of the geometric database (§3): move them and re-solve the
//! coefficients (Eqs. 4, 9), restore the baseline bit for bit, and create shared nodes
//! from the coefficients.

use std::sync::Arc as Shared;

use crate::control::{self, MAX_DEGREE};
use crate::error::{Entity, Error, Result};
use crate::ids::{ControlNodeId, CurveId, SurfaceId};
use crate::merge::PointMerger;
use crate::prelude::Point3;
use crate::surface::SupportSurface;

use super::validate::{check_point, invalid};
use super::{Baseline, GeomDb, PerPiece};

impl GeomDb {
    /// Records the current coefficients and control points as the baseline that
    /// [`set_control_points`](Self::set_control_points) restores bit for bit when given the
    /// same control points again. Loading and [`assign_control_nodes`](Self::assign_control_nodes)
    /// call it.
    pub fn refresh_baseline(&mut self) {
        self.baseline = Some(Shared::new(Baseline {
            control_nodes: self.control_nodes.clone(),
            curves: self
                .curves
                .iter()
                .map(|c| c.arcs.iter().map(|a| a.coeffs.clone()).collect())
                .collect(),
            surfaces: self
                .surfaces
                .iter()
                .map(|s| s.patches.iter().map(|p| p.coeffs.clone()).collect())
                .collect(),
        }));
    }

    /// The control node positions (§3).
    pub fn control_points(&self) -> &[Point3] {
        &self.control_nodes
    }

    /// The control node positions with every node of support surface `s` replaced by
    /// `f(node)`, each shared node once (e.g. a fuselage radius change); the other nodes
    /// unchanged. Feed the result to [`with_control_points`](Self::with_control_points) or
    /// a model update.
    ///
    /// ```
    /// # let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/geom/sphere.ron")).unwrap();
    /// # let db = geom_db::GeomDb::from_ron_str(&text, "sphere.ron").unwrap();
    /// let pts = db.control_points_with_surface_moved(geom_db::SurfaceId(0), |p| p * 2.0);
    /// assert_eq!(pts.len(), db.control_points().len());
    /// ```
    pub fn control_points_with_surface_moved(
        &self,
        s: SurfaceId,
        f: impl Fn(&Point3) -> Point3,
    ) -> Vec<Point3> {
        let mut pts = self.control_nodes.clone();
        let mut done = vec![false; pts.len()];
        for ids in &self.surface(s).control.nodes {
            for id in ids {
                if !done[id.index()] {
                    pts[id.index()] = f(&pts[id.index()]);
                    done[id.index()] = true;
                }
            }
        }
        pts
    }

    /// Moves the control nodes to `pts` and re-solves the coefficients A of every arc and
    /// patch that has control nodes (A = V⁻¹R, Eq. 4; A = V_u⁻¹ R V_v⁻ᵀ, Eq. 9).
    ///
    /// An arc or patch whose control points all equal (bit for bit) those of the baseline
    /// (see [`refresh_baseline`](Self::refresh_baseline)) gets its baseline coefficients
    /// back, so moving and then restoring the control points restores the model exactly.
    pub fn set_control_points(&mut self, pts: &[Point3]) -> Result<()> {
        if pts.len() != self.control_nodes.len() {
            return Err(Error::ControlPointCount {
                expected: self.control_nodes.len(),
                found: pts.len(),
            });
        }
        self.check_control_lists()?;
        for (i, p) in pts.iter().enumerate() {
            check_point(
                Entity::ControlNode(ControlNodeId::from_index(i)),
                "coordinate ",
                p,
            )?;
        }
        let base = self.baseline.clone().filter(|b| {
            b.control_nodes.len() == pts.len()
                && b.curves.len() == self.curves.len()
                && b.surfaces.len() == self.surfaces.len()
        });
        let unchanged = |ids: &[ControlNodeId]| match &base {
            Some(b) => ids.iter().all(|id| {
                let (p, q) = (pts[id.index()], b.control_nodes[id.index()]);
                (0..3).all(|c| p[c].to_bits() == q[c].to_bits())
            }),
            None => false,
        };
        for (ci, c) in self.curves.iter_mut().enumerate() {
            for (ai, (ids, a)) in c.control.nodes.iter().zip(c.arcs.iter_mut()).enumerate() {
                let restored = base
                    .as_ref()
                    .and_then(|b| b.curves[ci].get(ai))
                    .filter(|bc| bc.len() == a.degree + 1 && unchanged(ids));
                a.coeffs = match restored {
                    Some(bc) => bc.clone(),
                    None => {
                        let r: Vec<Point3> = ids.iter().map(|id| pts[id.index()]).collect();
                        control::coeffs_from_points_1d(&r)
                    }
                };
            }
        }
        for (si, s) in self.surfaces.iter_mut().enumerate() {
            let SupportSurface {
                control, patches, ..
            } = s;
            for (pi, (ids, p)) in control.nodes.iter().zip(patches.iter_mut()).enumerate() {
                let restored = base
                    .as_ref()
                    .and_then(|b| b.surfaces[si].get(pi))
                    .filter(|bc| bc.len() == p.coeffs.len() && unchanged(ids));
                p.coeffs = match restored {
                    Some(bc) => bc.clone(),
                    None => {
                        let r: Vec<Point3> = ids.iter().map(|id| pts[id.index()]).collect();
                        control::coeffs_from_points_2d(p.deg_u, p.deg_v, &r)
                    }
                };
            }
        }
        self.control_nodes.clear();
        self.control_nodes.extend_from_slice(pts);
        Ok(())
    }

    /// Cheap structural check of the control lists (lengths and id ranges), so that the solve
    /// cannot index out of bounds on a database that was modified after validation.
    fn check_control_lists(&self) -> Result<()> {
        let n = self.control_nodes.len();
        for (ci, c) in self.curves.iter().enumerate() {
            if c.control.is_empty() {
                continue;
            }
            let ok = c.control.nodes.len() == c.arcs.len()
                && c.control.nodes.iter().zip(&c.arcs).all(|(ids, a)| {
                    a.degree <= MAX_DEGREE
                        && ids.len() == a.degree + 1
                        && ids.iter().all(|id| id.index() < n)
                });
            if !ok {
                return Err(invalid(
                    Entity::Curve(CurveId::from_index(ci)),
                    "control node lists do not match the arcs (validate the database)",
                ));
            }
        }
        for (si, s) in self.surfaces.iter().enumerate() {
            if s.control.is_empty() {
                continue;
            }
            let ok = s.control.nodes.len() == s.patches.len()
                && s.control.nodes.iter().zip(&s.patches).all(|(ids, p)| {
                    p.deg_u <= MAX_DEGREE
                        && p.deg_v <= MAX_DEGREE
                        && ids.len() == (p.deg_u + 1) * (p.deg_v + 1)
                        && ids.iter().all(|id| id.index() < n)
                });
            if !ok {
                return Err(invalid(
                    Entity::Surface(SurfaceId::from_index(si)),
                    "control node lists do not match the patches (validate the database)",
                ));
            }
        }
        Ok(())
    }

    /// A copy of the database with the control nodes moved to `pts` (see
    /// [`set_control_points`](Self::set_control_points)).
    pub fn with_control_points(&self, pts: &[Point3]) -> Result<GeomDb> {
        let mut db = self.clone();
        db.set_control_points(pts)?;
        Ok(db)
    }

    /// The control points each arc and patch would have from its current coefficients
    /// (R = V A, the inverse of the solve), without merging: per curve, per arc; per surface,
    /// per patch.
    pub fn control_points_from_coeffs(&self) -> (PerPiece, PerPiece) {
        (
            self.curves
                .iter()
                .map(|c| c.arcs.iter().map(|a| a.control_points()).collect())
                .collect(),
            self.surfaces
                .iter()
                .map(|s| s.patches.iter().map(|p| p.control_points()).collect())
                .collect(),
        )
    }

    /// Creates control nodes for every arc and patch from its coefficients (R = V A at the
    /// Chebyshev–Lobatto nodes), sharing one node between all control points that lie within
    /// the "same point" tolerance of each other ([`PointMerger`]: a point joins the nearest
    /// earlier node within the tolerance, so neighbouring patches, arcs and surfaces share
    /// their border control nodes), then re-solves every arc and patch from the shared
    /// nodes so that shared borders are the same polynomial, and records the baseline.
    ///
    /// Coefficients change only where points were merged (by at most the tolerance) and by
    /// round-off elsewhere. Call on a validated database.
    pub fn assign_control_nodes(&mut self) -> Result<()> {
        self.validate_structure_only()?;
        let tol = self.tolerances().same_point.abs;
        let mut merger = PointMerger::new(tol);
        let mut curve_ids = Vec::with_capacity(self.curves.len());
        for c in &self.curves {
            let per_arc: Vec<Vec<ControlNodeId>> = c
                .arcs
                .iter()
                .map(|a| {
                    a.control_points()
                        .into_iter()
                        .map(|p| ControlNodeId::from_index(merger.insert(p).index))
                        .collect()
                })
                .collect();
            curve_ids.push(per_arc);
        }
        let mut surf_ids = Vec::with_capacity(self.surfaces.len());
        for s in &self.surfaces {
            let per_patch: Vec<Vec<ControlNodeId>> = s
                .patches
                .iter()
                .map(|p| {
                    p.control_points()
                        .into_iter()
                        .map(|q| ControlNodeId::from_index(merger.insert(q).index))
                        .collect()
                })
                .collect();
            surf_ids.push(per_patch);
        }
        for (c, ids) in self.curves.iter_mut().zip(curve_ids) {
            c.control.nodes = ids;
        }
        for (s, ids) in self.surfaces.iter_mut().zip(surf_ids) {
            s.control.nodes = ids;
        }
        let pts = merger.into_points();
        self.control_nodes = pts.clone();
        self.baseline = None;
        self.set_control_points(&pts)?;
        self.refresh_baseline();
        Ok(())
    }

    fn validate_structure_only(&self) -> Result<()> {
        // Degrees and counts must be sane before control points can be evaluated.
        for (ci, c) in self.curves.iter().enumerate() {
            let mut c2 = c.clone();
            c2.control = Default::default();
            self.validate_curve_structure(CurveId::from_index(ci), &c2)?;
        }
        for (si, s) in self.surfaces.iter().enumerate() {
            let mut s2 = s.clone();
            s2.control = Default::default();
            self.validate_surface_structure(SurfaceId::from_index(si), &s2)?;
        }
        Ok(())
    }
}
