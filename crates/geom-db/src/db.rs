//! The geometric database (§2.1, §3) as one serde type, its validation, RON I/O, tolerances
//! and control nodes.

use std::io::{BufRead, Write};
use std::sync::Arc as Shared;

use serde::{Deserialize, Serialize};

use crate::control::{self, MAX_DEGREE};
use crate::curve::SupportCurve;
use crate::error::{Entity, Error, Result};
use crate::ids::{ControlNodeId, CornerId, CurveCompId, CurveId, SurfCompId, SurfaceId};
use crate::merge::PointMerger;
use crate::prelude::Point3;
use crate::surface::SupportSurface;
use crate::topology::{Corner, CurveComponent, SurfaceComponent};

/// Points per piece (arc or patch) per curve or surface: `x[curve][arc][i]`.
pub type PerPiece = Vec<Vec<Vec<Point3>>>;

/// The format version this build reads and writes.
pub const FORMAT_VERSION: u32 = 1;

/// A tolerance relative to the model size: `abs = rel × reference length`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Tolerances {
    /// Absolute tolerance (model units).
    pub abs: f64,
    /// The same tolerance as a fraction of the reference length.
    pub rel: f64,
}

impl Tolerances {
    /// Default relative tolerance of Newton residuals.
    pub const NEWTON_REL: f64 = 1e-10;
    /// Default relative tolerance for "same point" in topology.
    pub const SAME_POINT_REL: f64 = 1e-7;

    /// `rel` relative to `reference_length`.
    pub fn relative_to(reference_length: f64, rel: f64) -> Self {
        Self {
            abs: rel * reference_length,
            rel,
        }
    }

    /// The Newton residual tolerance (1e-10 of the reference length).
    pub fn newton(reference_length: f64) -> Self {
        Self::relative_to(reference_length, Self::NEWTON_REL)
    }

    /// The "same point" tolerance (1e-7 of the reference length).
    pub fn same_point(reference_length: f64) -> Self {
        Self::relative_to(reference_length, Self::SAME_POINT_REL)
    }
}

/// Tolerances of a model (see [`GeomDb::tolerances`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ModelTolerances {
    /// The reference length (bounding-box diagonal).
    pub reference_length: f64,
    /// Newton residuals.
    pub newton: Tolerances,
    /// "Same point" in topology (corner matching, control-node sharing).
    pub same_point: Tolerances,
}

/// Coefficients and control points as loaded or built, so that restoring the control points
/// restores the coefficients bit for bit.
#[derive(Debug, Clone, Default)]
struct Baseline {
    control_nodes: Vec<Point3>,
    curves: Vec<Vec<Vec<Point3>>>,
    surfaces: Vec<Vec<Vec<Point3>>>,
}

/// The geometric database: corners, support curves and surfaces, topology and control nodes.
///
/// Stored as RON (see `docs/formats/geom-ron.md`). Build one in memory and call
/// [`validate`](Self::validate), or load one with [`from_ron_str`](Self::from_ron_str) /
/// [`read_ron`](Self::read_ron), which validate.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GeomDb {
    /// File format version ([`FORMAT_VERSION`]).
    pub format_version: u32,
    /// Model name.
    #[serde(default)]
    pub name: String,
    /// Length unit, informative ("m", "mm").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub units: Option<String>,
    /// Corners, indexed by [`CornerId`].
    #[serde(default)]
    pub corners: Vec<Corner>,
    /// Support curves, indexed by [`CurveId`].
    #[serde(default)]
    pub curves: Vec<SupportCurve>,
    /// Support surfaces, indexed by [`SurfaceId`].
    #[serde(default)]
    pub surfaces: Vec<SupportSurface>,
    /// Curve components, indexed by [`CurveCompId`].
    #[serde(default)]
    pub curve_components: Vec<CurveComponent>,
    /// Surface components, indexed by [`SurfCompId`].
    #[serde(default)]
    pub surface_components: Vec<SurfaceComponent>,
    /// Control node positions, indexed by [`ControlNodeId`] (§3).
    #[serde(default)]
    pub control_nodes: Vec<Point3>,
    #[serde(skip)]
    baseline: Option<Shared<Baseline>>,
}

fn invalid(entity: Entity, reason: impl Into<String>) -> Error {
    Error::Invalid {
        path: String::new(),
        entity,
        reason: reason.into(),
    }
}

fn check_point(entity: Entity, what: &str, p: &Point3) -> Result<()> {
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

fn check_id(entity: Entity, what: &str, index: usize, len: usize, kind: &str) -> Result<()> {
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
    /// An empty database of the current format version.
    pub fn empty(name: impl Into<String>) -> Self {
        Self {
            format_version: FORMAT_VERSION,
            name: name.into(),
            units: None,
            corners: Vec::new(),
            curves: Vec::new(),
            surfaces: Vec::new(),
            curve_components: Vec::new(),
            surface_components: Vec::new(),
            control_nodes: Vec::new(),
            baseline: None,
        }
    }

    // ----------------------------------------------------------------- access
    //
    // The accessors index the arenas: they panic on an id that is not in the database (ids
    // of a validated database are always in range).

    /// The corner `id`.
    pub fn corner(&self, id: CornerId) -> &Corner {
        &self.corners[id.index()]
    }
    /// The support curve `id`.
    pub fn curve(&self, id: CurveId) -> &SupportCurve {
        &self.curves[id.index()]
    }
    /// The support surface `id`.
    pub fn surface(&self, id: SurfaceId) -> &SupportSurface {
        &self.surfaces[id.index()]
    }
    /// The curve component `id`.
    pub fn curve_component(&self, id: CurveCompId) -> &CurveComponent {
        &self.curve_components[id.index()]
    }
    /// The surface component `id`.
    pub fn surface_component(&self, id: SurfCompId) -> &SurfaceComponent {
        &self.surface_components[id.index()]
    }

    // ----------------------------------------------------------------- RON

    /// Parses and validates a database from RON text; `path` names the file in messages.
    ///
    /// Errors: [`Error::Syntax`] with line and column for text that is not a database,
    /// [`Error::UnsupportedVersion`], or [`Error::Invalid`] naming the first inconsistent
    /// entity. Never panics.
    pub fn from_ron_str(text: &str, path: &str) -> Result<Self> {
        let opts = ron::Options::default();
        let mut db: GeomDb = opts.from_str(text).map_err(|e| Error::Syntax {
            path: path.to_string(),
            line: e.span.start.line,
            column: e.span.start.col,
            message: e.code.to_string(),
        })?;
        db.validate().map_err(|e| e.with_path(path))?;
        db.refresh_baseline();
        Ok(db)
    }

    /// Reads and validates a database from a reader (see [`from_ron_str`](Self::from_ron_str)).
    pub fn read_ron(mut reader: impl BufRead, path: &str) -> Result<Self> {
        let mut text = String::new();
        reader
            .read_to_string(&mut text)
            .map_err(|e| invalid(Entity::Model, format!("cannot read: {e}")).with_path(path))?;
        Self::from_ron_str(&text, path)
    }

    /// The database as pretty-printed RON.
    pub fn to_ron_string(&self) -> String {
        let cfg = ron::ser::PrettyConfig::new()
            .struct_names(false)
            .compact_arrays(true)
            .indentor(" ".to_string());
        // Serialising plain data (f64, strings, vectors) cannot fail.
        ron::ser::to_string_pretty(self, cfg).unwrap_or_else(|e| format!("// {e}"))
    }

    /// Writes the database as RON.
    pub fn write_ron(&self, mut w: impl Write) -> std::io::Result<()> {
        w.write_all(self.to_ron_string().as_bytes())?;
        w.write_all(b"\n")
    }

    // ----------------------------------------------------------------- sizes

    /// Axis-aligned bounding box of corners, control nodes and of the arcs and patches
    /// evaluated on their control-node grids; `None` for an empty model.
    pub fn bbox(&self) -> Option<(Point3, Point3)> {
        let mut lo = Point3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY);
        let mut hi = Point3::new(f64::NEG_INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY);
        let mut any = false;
        let mut add = |p: Point3| {
            if p.coords.iter().all(|c| c.is_finite()) {
                lo = lo.inf(&p);
                hi = hi.sup(&p);
                any = true;
            }
        };
        self.corners.iter().for_each(|c| add(c.point));
        self.control_nodes.iter().for_each(|&p| add(p));
        for c in &self.curves {
            for a in &c.arcs {
                if a.degree <= MAX_DEGREE && a.coeffs.len() == a.degree + 1 {
                    a.control_points().into_iter().for_each(&mut add);
                }
            }
        }
        for s in &self.surfaces {
            for p in &s.patches {
                if p.deg_u <= MAX_DEGREE
                    && p.deg_v <= MAX_DEGREE
                    && p.coeffs.len() == (p.deg_u + 1) * (p.deg_v + 1)
                {
                    p.control_points().into_iter().for_each(&mut add);
                }
            }
        }
        any.then_some((lo, hi))
    }

    /// The reference length: the bounding-box diagonal (1 for an empty or point-like model).
    ///
    /// Computed on each call from [`bbox`](Self::bbox) (every arc and patch evaluated on its
    /// control-node grid, O(model size)): call it once per operation, not per point.
    pub fn reference_length(&self) -> f64 {
        match self.bbox() {
            Some((lo, hi)) => {
                let d = (hi - lo).norm();
                if d.is_finite() && d > 0.0 { d } else { 1.0 }
            }
            None => 1.0,
        }
    }

    /// The model's default tolerances (relative to [`reference_length`](Self::reference_length)).
    pub fn tolerances(&self) -> ModelTolerances {
        let l = self.reference_length();
        ModelTolerances {
            reference_length: l,
            newton: Tolerances::newton(l),
            same_point: Tolerances::same_point(l),
        }
    }

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

    fn validate_curve_structure(&self, id: CurveId, c: &SupportCurve) -> Result<()> {
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
                for n in ids {
                    check_id(
                        e,
                        "control node",
                        n.index(),
                        self.control_nodes.len(),
                        "control nodes",
                    )?;
                }
            }
        }
        Ok(())
    }

    fn validate_surface_structure(&self, id: SurfaceId, s: &SupportSurface) -> Result<()> {
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
                for n in ids {
                    check_id(
                        e,
                        "control node",
                        n.index(),
                        self.control_nodes.len(),
                        "control nodes",
                    )?;
                }
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

    /// (start, end) corners of a curve component as traversed in a loop.
    pub fn oriented_ends(&self, oc: crate::topology::OrientedCurve) -> (CornerId, CornerId) {
        let cc = &self.curve_components[oc.comp.index()];
        if oc.reversed {
            (cc.end, cc.start)
        } else {
            (cc.start, cc.end)
        }
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

    // ----------------------------------------------------------------- control nodes

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

    /// Evaluates a curve component at fraction s ∈ [0, 1] from its start to its end.
    pub fn curve_component_point(&self, id: CurveCompId, s: f64) -> Point3 {
        use crate::eval::ParamCurve;
        let cc = self.curve_component(id);
        self.curve(cc.curve).point(cc.param_at(s))
    }
}
