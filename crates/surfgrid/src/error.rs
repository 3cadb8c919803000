//! The crate's error type: every variant names the entity (component, curve, node) and the
//! numbers that made the operation fail.

use geom_db::{CurveCompId, SurfCompId};

/// Errors of surface grid generation, classification and update.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A size-field parameter is not positive and finite.
    #[error("size field: {what} = {value} (must be positive and finite)")]
    BadSize {
        /// Which parameter.
        what: String,
        /// Its value.
        value: f64,
    },
    /// A curve component has zero length or a non-finite metric length.
    #[error("{curve}: metric length {length} cannot be discretised")]
    DegenerateCurve {
        /// The curve component.
        curve: CurveCompId,
        /// Its length in the metric (number of unit segments).
        length: f64,
    },
    /// A boundary node could not be placed on the surface of a component.
    #[error(
        "{component} ({name}): boundary node {node} does not project onto its surface (distance {distance:.3e}, tolerance {tol:.3e})"
    )]
    BoundaryProjection {
        /// The surface component.
        component: SurfCompId,
        /// Its name.
        name: String,
        /// Global node index.
        node: usize,
        /// Distance of the foot from the node.
        distance: f64,
        /// The tolerance.
        tol: f64,
    },
    /// A pole (a point where the surface's parametrisation degenerates) the generator cannot
    /// handle: inside a curve rather than at a node, two poles in a row, a loop made of poles.
    #[error("{component} ({name}): boundary node {node} is at an unsupported pole: {what}")]
    Pole {
        /// The surface component.
        component: SurfCompId,
        /// Its name.
        name: String,
        /// Global node index.
        node: usize,
        /// What is wrong.
        what: String,
    },
    /// The boundary loops of a component are inconsistently oriented in the parametric plane.
    #[error(
        "{component} ({name}): loop {lp} has signed parametric area {area:.3e}, inconsistent with the outer loop"
    )]
    LoopOrientation {
        /// The surface component.
        component: SurfCompId,
        /// Its name.
        name: String,
        /// The loop index.
        lp: usize,
        /// Its signed area in (u, v).
        area: f64,
    },
    /// The advancing front could not be closed.
    #[error(
        "{component} ({name}): advancing front stuck with {remaining} front edges left after {triangles} triangles"
    )]
    FrontStuck {
        /// The surface component.
        component: SurfCompId,
        /// Its name.
        name: String,
        /// Live front edges left.
        remaining: usize,
        /// Triangles generated so far.
        triangles: usize,
    },
    /// A node of an imported grid is farther than the tolerance from every candidate entity.
    #[error("node {node}: distance {distance:.3e} to {entity} exceeds the tolerance {tol:.3e}")]
    NodeOffGeometry {
        /// Node index in the imported grid.
        node: usize,
        /// The nearest entity found.
        entity: String,
        /// Its distance.
        distance: f64,
        /// The tolerance.
        tol: f64,
    },
    /// A marker of an imported grid names no surface component.
    #[error("marker {marker:?} names no surface component of the database")]
    UnknownMarker {
        /// The marker name.
        marker: String,
    },
    /// No surface component's foot of the normal (Eq. 11) converged from a wall triangle's
    /// centroid, so the triangle cannot be given a component.
    #[error(
        "node {node} of marker {marker:?}: no surface component's projection converged from its triangle's centroid ({})",
        attempts.iter().map(|(c, r)| format!("{c}: residual {r:.3e}")).collect::<Vec<_>>().join(", ")
    )]
    NoComponent {
        /// The marker.
        marker: String,
        /// The triangle's first node (index in the grid).
        node: usize,
        /// Per surface component tried: its name and the residual its Newton stopped at.
        attempts: Vec<(String, f64)>,
    },
    /// A wall marker named by the caller is not in the grid.
    #[error("wall marker {marker:?} is not in the grid (markers: {})", available.join(", "))]
    MissingMarker {
        /// The marker name.
        marker: String,
        /// The grid's markers.
        available: Vec<String>,
    },
    /// A wall marker has elements other than triangles.
    #[error("wall marker {marker:?} has {kind:?} elements (triangles only)")]
    WallElements {
        /// The marker name.
        marker: String,
        /// The element kind found.
        kind: mesh::ElementKind,
    },
    /// The grid and the database do not match (different component count, bad node index).
    #[error("grid/database mismatch: {what}")]
    Mismatch {
        /// What does not match.
        what: String,
    },
    /// The update could not make every triangle valid.
    #[error(
        "{component} ({name}): {invalid} triangles still inverted after the re-map and {passes} smoothing passes"
    )]
    UpdateInvalid {
        /// The surface component.
        component: SurfCompId,
        /// Its name.
        name: String,
        /// Inverted triangles left.
        invalid: usize,
        /// Smoothing passes made.
        passes: usize,
    },
    /// A projection of the `intersect` crate failed.
    #[error(transparent)]
    Intersect(#[from] intersect::Error),
}

/// The crate's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;
