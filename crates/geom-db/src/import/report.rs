//! What the import reports: units, tolerances, the conversion of every curve and surface
//! entity (method, pieces, sampled error), faces, shells, sewn, free and non-manifold edges.

use serde::Serialize;

/// How one curve or surface entity was converted to the power basis.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EntityConversion {
    /// The entity: `D37` (IGES directory line) or `#37` (STEP instance).
    pub entity: String,
    /// Its type: `128`, `B_SPLINE_SURFACE_WITH_KNOTS`, ….
    pub kind: String,
    /// `"exact"` (polynomial: Bézier extraction or exact coefficients), `"fitted"` (not
    /// polynomial: interpolated at the control nodes, refined until within the tolerance)
    /// or `"reapproximated"` (polynomial, but its exact conversion is ill-conditioned: fitted
    /// as a non-polynomial one, for the reason in `note`).
    pub method: &'static str,
    /// Arcs or patches produced.
    pub pieces: usize,
    /// Largest distance between the entity and its conversion at the same parameter,
    /// sampled between the nodes of every arc (patch) as well as at them (round-off for an
    /// exact conversion).
    pub max_error: f64,
    /// Why a polynomial entity was re-approximated (a degree above 11, knot spans shorter
    /// than the sewing tolerance merged into their neighbours, an exact conversion off by
    /// more than the tolerance), or `None`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

/// One face of the import.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FaceReport {
    /// The face entity (`D31`, `#17`; the surface itself for an untrimmed surface).
    pub entity: String,
    /// Its type (`144`, `510`, `ADVANCED_FACE`, …).
    pub kind: String,
    /// Its surface entity.
    pub surface: String,
    /// The surface component built (index).
    pub component: usize,
    /// Number of loops.
    pub loops: usize,
    /// Inward normal: `"positive"` (r_u × r_v) or `"negative"`.
    pub inward: &'static str,
    /// Index of the shell (connected set of faces) it belongs to.
    pub shell: usize,
    /// Its area (Green's theorem in its parameter plane, like the volume).
    pub area: f64,
    /// What the face is ([`FaceRole::name`](super::FaceRole::name)): `symmetry`, `farfield`,
    /// `wing`, `body`, … The surface component is named `<role>.<entity>` (e.g. `wing.D31`).
    pub role: String,
}

/// A connected set of faces.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ShellReport {
    /// Number of faces.
    pub faces: usize,
    /// True when every edge of the shell is shared by exactly two of its faces.
    pub closed: bool,
    /// Enclosed volume with the final normals (negative: normals point into the volume).
    pub volume: f64,
    /// Bounding-box diagonal of its faces' corners.
    pub size: f64,
}

/// An edge used by one face only, or by more than two.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EdgeReport {
    /// The curve component.
    pub component: usize,
    /// The curve entities merged into it.
    pub curves: Vec<String>,
    /// The faces using it.
    pub faces: Vec<String>,
}

/// A junction: a curve shared by two components that is the intersection of their
/// support surfaces (its two defining surfaces), rebuilt on those supports.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct JunctionReport {
    /// The curve component and its support curve (the same index in an import).
    pub component: usize,
    /// Its two defining support surfaces.
    pub surfaces: [usize; 2],
    /// The parameter its arcs follow (`u` or `v` of the first or second surface: `u1`, `v1`,
    /// `u2`, `v2`); `None` when the curve was kept as read (see the warnings).
    pub driver: Option<&'static str>,
    /// Number of arcs.
    pub arcs: usize,
    /// Largest distance to either support at the fit's check points between the nodes of
    /// every arc (`None` when kept as read).
    pub max_distance: Option<f64>,
    /// Largest move of its end corners onto the supports' intersection.
    pub corner_move: f64,
}

/// What the import did.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ImportReport {
    /// The CAD file.
    pub file: String,
    /// `IGES` or `STEP`.
    pub format: &'static str,
    /// The length unit of the file's numbers (`mm`, `m`, `in`, …): the one it declares, or
    /// the one given to override it ([`ImportOptions::file_units`](super::ImportOptions::file_units)); `None` when neither.
    pub file_units: Option<String>,
    /// The length unit of the database (the file's, or the one asked for).
    pub units: Option<String>,
    /// The factor applied to the file's lengths (1 when not converted).
    pub scale: f64,
    /// Model size (bounding-box diagonal of the faces' surfaces, sampled), in `units`.
    pub reference_length: f64,
    /// Approximation tolerance used.
    pub tolerance: f64,
    /// Sewing tolerance used.
    pub sew_tolerance: f64,
    /// Per converted curve and surface entity.
    pub entities: Vec<EntityConversion>,
    /// Largest conversion error over all entities.
    pub max_error: f64,
    /// Faces, in surface-component order.
    pub faces: Vec<FaceReport>,
    /// Connected shells.
    pub shells: Vec<ShellReport>,
    /// Number of curve components.
    pub curve_components: usize,
    /// Curve components shared by two faces.
    pub sewn_edges: usize,
    /// Largest distance between merged boundary curves or corners.
    pub max_sew_gap: f64,
    /// Edges used by one face only (open model, e.g. a symmetry plane).
    pub free_edges: Vec<EdgeReport>,
    /// Edges used by more than two faces.
    pub non_manifold_edges: Vec<EdgeReport>,
    /// Shared edges whose two faces could not be oriented consistently.
    pub orientation_conflicts: usize,
    /// Curves recorded as junctions: the intersection of the two support surfaces of the
    /// faces that share them, re-intersected by the model update (Eq. 12).
    pub junctions: Vec<JunctionReport>,
    /// Entities skipped or not fully understood, each named.
    pub warnings: Vec<String>,
}
