//! The error type of `geom-db`.

use crate::ids::{ControlNodeId, CornerId, CurveCompId, CurveId, SurfCompId, SurfaceId};

/// Everything that can go wrong in `geom-db`. Each variant names the entity at fault.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A knot vector is not usable for the requested B-spline basis.
    ///
    /// ```
    /// use geom_db::bspline::KnotVector;
    /// let err = KnotVector::new(3, vec![0.0, 1.0, 0.5]).unwrap_err();
    /// assert!(matches!(err, geom_db::Error::InvalidKnots { .. }));
    /// ```
    #[error("invalid knot vector (degree {degree}): {reason}")]
    InvalidKnots {
        /// Degree of the basis.
        degree: usize,
        /// What is wrong with the knots.
        reason: String,
    },

    /// A RON file could not be parsed into a database (syntax error, missing or unknown
    /// field, wrong type).
    ///
    /// ```
    /// let err = geom_db::GeomDb::from_ron_str("(format_version: 1,\n name: ", "bad.ron")
    ///     .unwrap_err();
    /// assert!(matches!(err, geom_db::Error::Syntax { line: 2, .. }));
    /// ```
    #[error("{path}:{line}:{column}: {message}")]
    Syntax {
        /// The file (for messages).
        path: String,
        /// 1-based line of the problem.
        line: usize,
        /// 1-based column of the problem.
        column: usize,
        /// What the parser says.
        message: String,
    },

    /// The file declares a format version this build does not read.
    ///
    /// ```
    /// let mut db = geom_db::GeomDb::empty("x");
    /// db.format_version = 99;
    /// let text = db.to_ron_string();
    /// let err = geom_db::GeomDb::from_ron_str(&text, "x.ron").unwrap_err();
    /// assert!(matches!(err, geom_db::Error::UnsupportedVersion { found: 99, .. }));
    /// ```
    #[error("{path}: format_version {found} is not supported (this build reads {supported})")]
    UnsupportedVersion {
        /// The file (for messages).
        path: String,
        /// The version in the file.
        found: u32,
        /// The version this build reads and writes.
        supported: u32,
    },

    /// The database is inconsistent: the first problem found, naming the entity.
    ///
    /// ```
    /// use geom_db::{GeomDb, Corner, prelude::Point3};
    /// let mut db = GeomDb::empty("x");
    /// db.corners.push(Corner { point: Point3::new(f64::NAN, 0.0, 0.0), name: String::new() });
    /// let err = db.validate().unwrap_err();
    /// assert_eq!(err.to_string(), "corner 0: coordinate x is NaN");
    /// ```
    #[error("{}{entity}: {reason}", path_prefix(.path))]
    Invalid {
        /// The file, or empty for a database built in memory.
        path: String,
        /// The entity at fault.
        entity: Entity,
        /// What is wrong.
        reason: String,
    },

    /// A list of control points has the wrong length.
    ///
    /// ```
    /// let mut db = geom_db::GeomDb::empty("x");
    /// let err = db.set_control_points(&[geom_db::prelude::Point3::origin()]).unwrap_err();
    /// assert!(matches!(err, geom_db::Error::ControlPointCount { expected: 0, found: 1 }));
    /// ```
    #[error("{found} control points given, the database has {expected} control nodes")]
    ControlPointCount {
        /// Number of control nodes of the database.
        expected: usize,
        /// Number of points given.
        found: usize,
    },

    /// Input to a basis conversion is inconsistent (e.g. control point count vs degree).
    ///
    /// ```
    /// use geom_db::{bspline::KnotVector, convert::bspline_to_power, prelude::Point3};
    /// let kv = KnotVector::bezier(2);
    /// let err = bspline_to_power(&kv, &[Point3::origin(); 2]).unwrap_err();
    /// assert!(matches!(err, geom_db::Error::Conversion { .. }));
    /// ```
    #[error("basis conversion: {reason}")]
    Conversion {
        /// What is wrong.
        reason: String,
    },
    /// Point inversion (the foot of the normal, Eq. 11) found no converged foot.
    ///
    /// ```
    /// use geom_db::invert::{CurveInverter, InvertOptions};
    /// use geom_db::prelude::Point3;
    /// let c = geom_db::SupportCurve::new("c", vec![geom_db::Arc::new(vec![
    ///     Point3::origin(), Point3::new(1.0, 0.0, 0.0), Point3::new(0.0, 1.0, 0.0)])]);
    /// let opts = InvertOptions::new(1.0).with_max_iters(0).with_rel_tol(1e-300);
    /// let inv = CurveInverter::new("curve 3", &c, &opts).unwrap();
    /// let err = inv.project_indexed(&Point3::new(0.4, 0.5, 0.0), 4).unwrap_err();
    /// assert!(matches!(err, geom_db::Error::InversionFailed { point: 4, .. }));
    /// ```
    #[error(
        "{entity}: foot of the normal from point {point} did not converge after {iterations} \
         iterations (residual {residual:e}, tolerance {tolerance:e})"
    )]
    InversionFailed {
        /// The curve or surface (its label).
        entity: String,
        /// Index of the point in the caller's list (0 for a single point).
        point: usize,
        /// Newton iterations of the best failed start.
        iterations: usize,
        /// Its final tangential residual (length units).
        residual: f64,
        /// The tolerance asked for.
        tolerance: f64,
    },

    /// A point inversion cannot start: non-finite point, empty or non-finite domain.
    ///
    /// ```
    /// use geom_db::invert::{CurveInverter, InvertOptions};
    /// use geom_db::prelude::Point3;
    /// let c = geom_db::SupportCurve::new("c", vec![geom_db::Arc::line(
    ///     Point3::origin(), Point3::new(1.0, 0.0, 0.0))]);
    /// let inv = CurveInverter::new("curve 3", &c, &InvertOptions::new(1.0)).unwrap();
    /// let err = inv.project(&Point3::new(f64::NAN, 0.0, 0.0)).unwrap_err();
    /// assert_eq!(err.to_string(), "curve 3: point 0: the point has a non-finite coordinate");
    /// ```
    #[error("{entity}: {}{reason}", point_prefix(*.point))]
    InversionInput {
        /// The curve or surface (its label).
        entity: String,
        /// Index of the point at fault, if a point is.
        point: Option<usize>,
        /// What is wrong.
        reason: String,
    },

    /// An IGES import failed (see [`import::Error`](crate::import::Error)).
    #[error(transparent)]
    Import(#[from] crate::import::Error),
}

fn point_prefix(point: Option<usize>) -> String {
    point.map_or(String::new(), |i| format!("point {i}: "))
}

fn path_prefix(path: &str) -> String {
    if path.is_empty() {
        String::new()
    } else {
        format!("{path}: ")
    }
}

impl Error {
    /// Attaches a file path to errors that carry one and have none yet.
    pub fn with_path(mut self, file: &str) -> Self {
        match &mut self {
            Error::Invalid { path, .. }
            | Error::Syntax { path, .. }
            | Error::UnsupportedVersion { path, .. }
                if path.is_empty() =>
            {
                *path = file.to_string()
            }
            _ => {}
        }
        self
    }
}

/// An entity of the database, as named in error messages and reports ("surface 3 patch 2").
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[non_exhaustive]
pub enum Entity {
    /// The database as a whole (header fields, sizes).
    Model,
    /// A corner.
    Corner(CornerId),
    /// A support curve.
    Curve(CurveId),
    /// One arc of a support curve.
    Arc {
        /// The curve.
        curve: CurveId,
        /// Arc index on the curve.
        arc: usize,
    },
    /// A support surface.
    Surface(SurfaceId),
    /// One patch of a support surface (index in the surface's patch order).
    Patch {
        /// The surface.
        surface: SurfaceId,
        /// Patch index.
        patch: usize,
    },
    /// A curve component.
    CurveComp(CurveCompId),
    /// A surface component.
    SurfComp(SurfCompId),
    /// One boundary loop of a surface component.
    Loop {
        /// The surface component.
        comp: SurfCompId,
        /// Loop index.
        index: usize,
    },
    /// A control node.
    ControlNode(ControlNodeId),
}

impl std::fmt::Display for Entity {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Entity::Model => write!(f, "model"),
            Entity::Corner(id) => write!(f, "{id}"),
            Entity::Curve(id) => write!(f, "{id}"),
            Entity::Arc { curve, arc } => write!(f, "{curve} arc {arc}"),
            Entity::Surface(id) => write!(f, "{id}"),
            Entity::Patch { surface, patch } => write!(f, "{surface} patch {patch}"),
            Entity::CurveComp(id) => write!(f, "{id}"),
            Entity::SurfComp(id) => write!(f, "{id}"),
            Entity::Loop { comp, index } => write!(f, "{comp} loop {index}"),
            Entity::ControlNode(id) => write!(f, "{id}"),
        }
    }
}

/// `Result` with [`Error`] as the default error type.
pub type Result<T, E = Error> = std::result::Result<T, E>;
