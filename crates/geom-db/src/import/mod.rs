//! IGES → geometric database: conversion of curves and surfaces to power-basis arcs and
//! patches (Eqs. 2–10) and topology by sewing (§2.1).
//!
//! * Exact conversions: 110 lines, 112 spline segments (re-parametrised to [0, 1] per
//!   segment: a_k = c_k h^k), 114 patches (a_{pq} = c_{pq} h_u^p h_v^q), non-rational 126 and
//!   128 by Bézier extraction per knot span ([`convert`](crate::convert)).
//! * Approximations (100, 104, 118, 120, 122, rational 126/128, B-splines restricted to part
//!   of their knot domain): interpolation at the control nodes of each arc (patch), split
//!   until the sampled error is within the tolerance (module `approx`).
//! * Faces: 144 trimmed surfaces (142 boundaries), 143 bounded surfaces (141 boundaries),
//!   510 B-rep faces (508 loops over 504 edges), and untrimmed independent surfaces. Each face
//!   becomes a surface component; each boundary curve piece an edge.
//! * Sewing: edge end points within the sewing tolerance become one corner; edges joining the
//!   same corners whose samples lie within the tolerance of each other become one curve
//!   component, shared by the faces that use it (with opposite orientations once the faces
//!   are oriented consistently). Free and non-manifold edges are reported.
//! * Orientation: each face's inward sign is first chosen so that its outer loop runs
//!   counter-clockwise about the inward normal (the loop convention of
//!   [`topology`](crate::topology)); faces are then flipped, by a breadth-first walk over shared
//!   edges, so that neighbours traverse their common edge in opposite directions; finally
//!   each connected shell is flipped so that its enclosed volume, V = ⅓ ∮ x·n dA computed
//!   with Green's theorem in each face's parameter plane, is negative for the largest shell
//!   (the far field: normals point into the fluid it encloses) and positive for the others
//!   (bodies: normals point away from them). [`ImportOptions::flip`] reverses everything.
//! * Roles ([`recognise`]): each face is recognised as a symmetry plane, the far field, or
//!   part of a wing or another body, and its surface component named `<role>.D<line>`.
//! * The way back ([`to_iges`]): support surfaces as 114 (bicubic or lower) or 128, surface
//!   components as 144 trimmed surfaces with 142 boundaries over 112/126 model curves.

// `!(x > 0.0)` deliberately rejects NaN as well as non-positive values.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod approx;
mod export;
mod geometry;
mod roles;
#[cfg(test)]
mod tests;
mod topo;

use serde::Serialize;

pub use export::to_iges;
pub use roles::{FaceRole, recognise};
pub use topo::import;

/// Errors of the IGES import. Every message is one line naming the file and, where there is
/// one, the entity's directory line.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The IGES file could not be read.
    #[error(transparent)]
    Iges(#[from] iges::Error),
    /// An entity cannot be converted.
    ///
    /// ```
    /// use iges::{Entity, Global, IgesFile, Line};
    /// let mut f = IgesFile::new(Global::default());
    /// f.name = "x.igs".into();
    /// f.push_with(Entity::Line(Line { start: [0.0; 3], end: [1.0, 0.0, 0.0] }), 1, None);
    /// let err = geom_db::import::import(&f, &Default::default()).unwrap_err();
    /// assert!(matches!(err, geom_db::import::Error::Model { .. }), "{err}");
    /// ```
    #[error("{file}: entity at D line {de} (type {entity_type}): {reason}")]
    Entity {
        /// The IGES file.
        file: String,
        /// Sequence number of the entity's first directory line.
        de: u32,
        /// Entity type number.
        entity_type: i32,
        /// What is wrong.
        reason: String,
    },
    /// The model as a whole cannot be imported (no faces, ...).
    #[error("{file}: {reason}")]
    Model {
        /// The IGES file.
        file: String,
        /// What is wrong.
        reason: String,
    },
    /// The database built from the file does not validate.
    #[error("{file}: the imported model does not validate: {source}")]
    Invalid {
        /// The IGES file.
        file: String,
        /// The validation error.
        source: Box<crate::Error>,
    },
}

/// Options of [`import`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImportOptions {
    /// Approximation tolerance in model units; `None`: `rel_tolerance` × model size.
    pub tolerance: Option<f64>,
    /// Approximation tolerance relative to the model size (bounding-box diagonal), default
    /// 1e-7.
    pub rel_tolerance: f64,
    /// Sewing tolerance (corners and coincident edges) in model units; `None`:
    /// `rel_sew_tolerance` × model size, but at least 10 × the approximation tolerance.
    pub sew_tolerance: Option<f64>,
    /// Sewing tolerance relative to the model size, default 1e-6 (the gap tolerance of
    /// [`GeomDb::check`](crate::GeomDb::check)).
    pub rel_sew_tolerance: f64,
    /// Reverse every surface component's orientation after the automatic choice.
    pub flip: bool,
}

impl Default for ImportOptions {
    fn default() -> Self {
        Self {
            tolerance: None,
            rel_tolerance: 1e-7,
            sew_tolerance: None,
            rel_sew_tolerance: 1e-6,
            flip: false,
        }
    }
}

impl ImportOptions {
    /// Sets an absolute approximation tolerance.
    pub fn with_tolerance(mut self, tol: f64) -> Self {
        self.tolerance = Some(tol);
        self
    }

    /// Sets [`flip`](Self::flip).
    pub fn with_flip(mut self, flip: bool) -> Self {
        self.flip = flip;
        self
    }
}

/// How one IGES entity was converted.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EntityConversion {
    /// Directory line of the entity.
    pub de: u32,
    /// Entity type number.
    pub entity_type: i32,
    /// `"exact"` or `"approximated"`.
    pub method: &'static str,
    /// Arcs or patches produced.
    pub pieces: usize,
    /// Largest sampled distance between the entity and its conversion (0 when exact).
    pub max_error: f64,
}

/// One face of the import.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FaceReport {
    /// Directory line of the face entity (144, 143, 510 or the untrimmed surface).
    pub de: u32,
    /// Its type number.
    pub entity_type: i32,
    /// Directory line of its surface.
    pub surface_de: u32,
    /// The surface component built (index).
    pub component: usize,
    /// Number of loops.
    pub loops: usize,
    /// Inward normal: `"positive"` (r_u × r_v) or `"negative"`.
    pub inward: &'static str,
    /// Index of the shell (connected set of faces) it belongs to.
    pub shell: usize,
    /// What the face is ([`FaceRole::name`]): `symmetry`, `farfield`, `wing`, `body`, …
    /// The surface component is named `<role>.D<line>` (e.g. `wing.D31`).
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
    /// Bounding-box diagonal of its faces' edges.
    pub size: f64,
}

/// An edge used by one face only, or by more than two.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EdgeReport {
    /// The curve component.
    pub component: usize,
    /// Directory lines of the IGES curves merged into it.
    pub curves: Vec<u32>,
    /// Directory lines of the faces using it.
    pub faces: Vec<u32>,
}

/// What [`import`] did.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ImportReport {
    /// The IGES file.
    pub file: String,
    /// Model units from the Global section ("mm", "m", ...), if recognised.
    pub units: Option<String>,
    /// Model size (bounding-box diagonal of the faces' surfaces, sampled).
    pub reference_length: f64,
    /// Approximation tolerance used (model units).
    pub tolerance: f64,
    /// Sewing tolerance used (model units).
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
    /// Entities skipped or not fully understood.
    pub warnings: Vec<String>,
}
