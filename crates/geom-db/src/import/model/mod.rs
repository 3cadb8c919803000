//! The neutral intermediate of the import: exact curves and surfaces, faces bounded by
//! loops of edge uses, and shells — what an IGES or a STEP file defines, before any
//! conversion to the database's power basis.
//!
//! The front ends (`from_iges`, `from_step`) build a [`CadModel`]; the stages of
//! [`import_model`](super::import_model) turn it into a [`GeomDb`](crate::GeomDb). Every item
//! keeps the [`Source`] entity it came from, for messages and the report. Edge uses keep the
//! file's shared-edge identity ([`EdgeUse::edge`]) and parameter-space curve, faces their
//! file orientation, so that later stages can use them.

mod curve;
mod frame;
mod nurbs;
mod surface;

pub use curve::{ConicKind, Curve, Piece};
pub use frame::{Affine, Frame};
pub use nurbs::{NurbsCurve, NurbsSurface};
pub(crate) use nurbs::{canonical_curve, canonical_surface, closure_tol};
pub use surface::{AngleParam, Domain, Surface};

/// Where an item of the model comes from: an IGES directory entry or a STEP instance.
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Source {
    /// `D37` (IGES directory line) or `#37` (STEP instance).
    pub label: String,
    /// The entity type: `128`, `ADVANCED_FACE`, ….
    pub kind: String,
}

impl Source {
    /// `D37 (128)` / `#37 (ADVANCED_FACE)`.
    pub fn describe(&self) -> String {
        format!("{} ({})", self.label, self.kind)
    }
}

/// A length unit: its name (`m`, `mm`, `in`, …) and its length in metres.
#[derive(Debug, Clone, PartialEq)]
pub struct LengthUnit {
    /// Short name.
    pub name: String,
    /// Metres per unit.
    pub metres: f64,
}

impl LengthUnit {
    /// The unit of `name` (`m`, `mm`, `cm`, `in`, `ft`), if known.
    pub fn named(name: &str) -> Option<LengthUnit> {
        let metres = match name {
            "m" => 1.0,
            "mm" => 1e-3,
            "cm" => 1e-2,
            "in" => 0.0254,
            "ft" => 0.3048,
            _ => return None,
        };
        Some(LengthUnit {
            name: name.to_string(),
            metres,
        })
    }

    /// The unit of `metres` metres, named when it is a common one.
    pub fn from_metres(metres: f64) -> LengthUnit {
        const NAMES: [(f64, &str); 8] = [
            (1.0, "m"),
            (1e-3, "mm"),
            (1e-2, "cm"),
            (1e-1, "dm"),
            (1e3, "km"),
            (1e-6, "um"),
            (0.0254, "in"),
            (0.3048, "ft"),
        ];
        let name = NAMES
            .iter()
            .find(|(v, _)| (v - metres).abs() <= 1e-9 * v)
            .map_or_else(|| format!("{metres} m"), |(_, n)| n.to_string());
        LengthUnit { name, metres }
    }
}

/// An exact curve with its source entity.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelCurve {
    /// The entity.
    pub source: Source,
    /// The curve.
    pub curve: Curve,
}

/// An exact surface with its source entity.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelSurface {
    /// The entity.
    pub source: Source,
    /// The surface.
    pub surface: Surface,
}

/// One use of an edge in a face loop: a curve of [`CadModel::curves`] on a parameter range,
/// traversed from `t0` to `t1` (t0 > t1 runs the curve backwards).
#[derive(Debug, Clone, PartialEq)]
pub struct EdgeUse {
    /// Index into [`CadModel::curves`].
    pub curve: usize,
    /// Start parameter.
    pub t0: f64,
    /// End parameter.
    pub t1: f64,
    /// The file's topological edge (a STEP `EDGE_CURVE`, an IGES 504 edge), when the file
    /// has one: uses with the same edge are the same curve of the model.
    pub edge: Option<Source>,
    /// The edge's curve in the face surface's parameters (x = u, y = v), on the same range
    /// and in the same direction, when the file gives one.
    pub pcurve: Option<Curve>,
}

/// A closed loop of edge uses bounding a face, in traversal order.
#[derive(Debug, Clone, PartialEq)]
pub struct CadLoop {
    /// The edge uses.
    pub edges: Vec<EdgeUse>,
    /// The file marks it as the outer loop (STEP `FACE_OUTER_BOUND`, IGES 144 outer, 510
    /// first loop).
    pub outer: bool,
}

/// A face: a region of a surface bounded by loops.
#[derive(Debug, Clone, PartialEq)]
pub struct CadFace {
    /// The face entity (or the surface, for an untrimmed surface).
    pub source: Source,
    /// Index into [`CadModel::surfaces`].
    pub surface: usize,
    /// The loops, outer first; empty for an untrimmed surface (its natural domain bounds it).
    pub loops: Vec<CadLoop>,
    /// Whether the face's outward normal (as the file orients it in its shell) is
    /// S_u × S_v (`Some(true)`), its opposite, or unknown (`None`: IGES trimmed faces).
    /// When known, the loops run counter-clockwise about that normal.
    pub same_sense: Option<bool>,
    /// The boundary in the surface's parameters, as the file gives it, where its
    /// parametrisation is unambiguous (B-splines; IGES 114, 118, 120, 122): curves (x = u,
    /// y = v) on parameter ranges. Empty otherwise: the trimming box then comes from the
    /// 3D edges.
    pub uv_bounds: Vec<(Curve, f64, f64)>,
}

/// A shell of the file (STEP closed/open shell, IGES 514): faces and their orientation.
#[derive(Debug, Clone, PartialEq)]
pub struct CadShell {
    /// The shell entity.
    pub source: Source,
    /// Indices into [`CadModel::faces`].
    pub faces: Vec<usize>,
    /// The file says the shell is closed.
    pub closed: bool,
}

/// The neutral model of a CAD file.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct CadModel {
    /// The file name (for messages).
    pub file: String,
    /// `IGES` or `STEP`.
    pub format: &'static str,
    /// A model name (the IGES product id or start text, the STEP product).
    pub name: String,
    /// The file's length unit, when it says.
    pub unit: Option<LengthUnit>,
    /// The file's resolution (IGES global 19, STEP uncertainty), in its unit.
    pub resolution: Option<f64>,
    /// Exact curves.
    pub curves: Vec<ModelCurve>,
    /// Exact surfaces.
    pub surfaces: Vec<ModelSurface>,
    /// Faces.
    pub faces: Vec<CadFace>,
    /// Shells (possibly empty: IGES trimmed surfaces have none).
    pub shells: Vec<CadShell>,
    /// Entities skipped or not fully understood.
    pub warnings: Vec<String>,
}

impl CadModel {
    /// Scales every length by `s` (a change of unit): curves and surfaces are mapped by
    /// the scaling, so their parameters (and pcurves) are unchanged.
    pub fn scale(&mut self, s: f64) {
        let m = Affine::scaling(s);
        for c in &mut self.curves {
            c.curve.transform(&m);
        }
        for f in &mut self.surfaces {
            f.surface.transform(&m);
        }
        if let Some(r) = &mut self.resolution {
            *r *= s;
        }
    }
}
