//! [`StudyError`]: the errors of building and evaluating a [`Study`](super::Study). Each
//! lower crate's error is kept whole (typed, with its fields) and labelled with the phase it
//! came from; set-up errors also name the file they concern.

use std::path::PathBuf;

use crate::case::CaseError;

/// Errors of building or evaluating a study; each names the file or the phase. The lower
/// crates' errors are kept as they are (match on them, or walk `Error::source`).
///
/// ```
/// use aeroshape::study::{Study, StudyError};
/// let case = aeroshape::case::Case::from_ron_str(
///     "(format_version: 1, geometry: \"no-such-file.ron\")", "case.ron").unwrap();
/// let e = Study::new(case, "case.ron".as_ref()).unwrap_err();
/// assert!(matches!(e, StudyError::Read { .. }), "{e}");
/// ```
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum StudyError {
    /// The case file is bad.
    #[error(transparent)]
    Case(#[from] CaseError),
    /// A geometric constraint cannot be measured (its error names it).
    #[error(transparent)]
    Constraint(#[from] crate::constraints::ConstraintError),
    /// A file of the case cannot be read.
    #[error("{}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The geometric database is bad (its error names the file).
    #[error(transparent)]
    Geometry(#[from] geom_db::Error),
    /// The grid cannot be read (its error names the file).
    #[error(transparent)]
    Grid(#[from] mesh::Error),
    /// The case names no grid (field `grid`).
    #[error("{}: the case names no grid (field `grid`)", case.display())]
    NoGrid {
        /// The case file.
        case: PathBuf,
    },
    /// The case names no wall marker (field `wall`).
    #[error("{}: the case names no wall marker (field `wall`)", case.display())]
    NoWall {
        /// The case file.
        case: PathBuf,
    },
    /// A marker the case names (`wall`, `slide`, `fixed`) is not in the grid.
    #[error(
        "{}: marker {marker:?} is not in the grid {} (markers: {})",
        case.display(), grid.display(), available.join(", ")
    )]
    MissingMarker {
        /// The case file.
        case: PathBuf,
        /// The marker.
        marker: String,
        /// The grid file.
        grid: PathBuf,
        /// The grid's markers.
        available: Vec<String>,
    },
    /// A wall marker has elements other than triangles.
    #[error("{}: wall marker {marker:?} has {kind:?} elements (triangles only)", case.display())]
    WallElements {
        /// The case file.
        case: PathBuf,
        /// The marker.
        marker: String,
        /// The element kind found.
        kind: mesh::ElementKind,
    },
    /// A wing master of the case could not be built.
    #[error("wing masters: {0}")]
    WingMaster(#[from] wingmaster::Error),
    /// The parametrisation could not be bound, or applied to a design vector (wrong length,
    /// a master source that failed).
    #[error("param: {0}")]
    Param(#[from] param::Error),
    /// The model update could not be seeded on the baseline geometry.
    #[error("{}: model update seeds: {source}", geometry.display())]
    ModelSeeds {
        /// The geometry file.
        geometry: PathBuf,
        /// The error (boxed: a set-up error is rare, and the enum stays small).
        #[source]
        source: Box<intersect::Error>,
    },
    /// The model update of an evaluation failed.
    #[error("model update: {0}")]
    ModelUpdate(#[from] intersect::Error),
    /// The wall of the grid could not be tied to the geometry.
    #[error("{}: classification of the wall on the geometry: {source}", grid.display())]
    Classify {
        /// The grid file.
        grid: PathBuf,
        /// The error (boxed: a set-up error is rare, and the enum stays small).
        #[source]
        source: Box<surfgrid::Error>,
    },
    /// The surface-grid update of an evaluation failed.
    #[error("surface grid: {0}")]
    SurfaceGrid(#[from] surfgrid::Error),
    /// The volume deformation could not be set up on the grid.
    #[error("{}: volume deformation set-up: {source}", grid.display())]
    DeformSetup {
        /// The grid file.
        grid: PathBuf,
        /// The error (boxed: a set-up error is rare, and the enum stays small).
        #[source]
        source: Box<deform::Error>,
    },
    /// The volume deformation of an evaluation failed.
    #[error("deform: {0}")]
    Deform(#[from] deform::Error),
    /// Another rank of a distributed study (feature `mpi`) failed: its error's text, so
    /// every rank reports the same line.
    #[error("{reason}")]
    Distributed {
        /// The rank that failed.
        rank: i32,
        /// Its error.
        reason: String,
    },
    /// A vector given to a product of the linearised chain has the wrong length.
    #[error("{what}: {found} values, expected {expected}")]
    ProductLength {
        /// What the vector is.
        what: &'static str,
        /// The length expected.
        expected: usize,
        /// The length given.
        found: usize,
    },
}

/// Result alias of this module.
pub type Result<T, E = StudyError> = std::result::Result<T, E>;
