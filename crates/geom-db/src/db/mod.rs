//! The geometric database (§2.1, §3) as one serde type: the type, its tolerances and sizes,
//! and access to its entities. Validation (`validate.rs`), RON text (`ron_io.rs`) and the
//! control nodes (`control_nodes.rs`) are in the files of this folder.

use std::sync::Arc as Shared;

use serde::{Deserialize, Serialize};

use crate::control::MAX_DEGREE;
use crate::curve::SupportCurve;
use crate::ids::{CornerId, CurveCompId, CurveId, SurfCompId, SurfaceId};
use crate::prelude::Point3;
use crate::surface::SupportSurface;
use crate::topology::{Corner, CurveComponent, SurfaceComponent};

mod control_nodes;
mod ron_io;
mod validate;

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
    /// The model's size as declared by whoever made it (the CAD import: the bounding-box
    /// diagonal of the trimmed faces), the [`reference_length`](Self::reference_length)
    /// when present. Support surfaces may reach well past their faces (a symmetry plane's
    /// margin, the cut-away half of a periodic fuselage), so the bounding box of the
    /// supports is not the model's size.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub size: Option<f64>,
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
    /// Control node positions, indexed by [`ControlNodeId`](crate::ControlNodeId) (§3).
    #[serde(default)]
    pub control_nodes: Vec<Point3>,
    #[serde(skip)]
    baseline: Option<Shared<Baseline>>,
}

impl GeomDb {
    /// An empty database of the current format version.
    pub fn empty(name: impl Into<String>) -> Self {
        Self {
            format_version: FORMAT_VERSION,
            name: name.into(),
            units: None,
            size: None,
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

    /// The reference length: the declared [`size`](Self::size) when present (an imported
    /// model), else the bounding-box diagonal (1 for an empty or point-like model).
    ///
    /// Without a declared size it is computed on each call from [`bbox`](Self::bbox) (every
    /// arc and patch evaluated on its control-node grid, O(model size)): call it once per
    /// operation, not per point.
    pub fn reference_length(&self) -> f64 {
        if let Some(l) = self.size.filter(|l| l.is_finite() && *l > 0.0) {
            return l;
        }
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

    /// (start, end) corners of a curve component as traversed in a loop.
    pub fn oriented_ends(&self, oc: crate::topology::OrientedCurve) -> (CornerId, CornerId) {
        let cc = &self.curve_components[oc.comp.index()];
        if oc.reversed {
            (cc.end, cc.start)
        } else {
            (cc.start, cc.end)
        }
    }

    /// Evaluates a curve component at fraction s ∈ [0, 1] from its start to its end.
    pub fn curve_component_point(&self, id: CurveCompId, s: f64) -> Point3 {
        use crate::eval::ParamCurve;
        let cc = self.curve_component(id);
        self.curve(cc.curve).point(cc.param_at(s))
    }
}
