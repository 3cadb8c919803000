//! Geometry update (paper §3.1–3.2): point inversion (Eq. 11), surface–surface update of
//! support curves (Eq. 12), curve–curve corners (Eq. 13), and the model update after
//! control nodes moved.
//!
//! Layer: depends on `geom-db` only. `intersect` never changes a surface: it re-solves curves
//! and corners from the surfaces.
//!
//! The algorithms are written once against the evaluation traits
//! [`geom_db::eval::ParamCurve`] and [`geom_db::eval::ParamSurface`] in *global* parameters
//! (a curve of n arcs has t ∈ [0, n], a surface of n_u × n_v patches (u, v) ∈ [0, n_u] ×
//! [0, n_v]), so they run on the database's power-basis entities and on analytic shapes.
//!
//! * [`project`]: foot of the normal on a surface or a curve (Eq. 11), global seeding by a
//!   bounding-volume hierarchy calling geom-db's point inversion ([`geom_db::invert`],
//!   the safeguarded Newton of [`geom_db::newton`]); batches in parallel.
//! * [`ssi`]: new control points of a support curve from its two defining surfaces (Eq. 12),
//!   with a frozen parameter chosen per point and a normal-plane fallback.
//! * [`corner`]: corners as the minimal-distance points of two curves (Eq. 13).
//! * [`check`]: deviation of a curve from its defining surfaces between control points.
//! * [`measure`]: thickness, volume and area of a model, with their derivatives for a
//!   model perturbation (the constraints of `aeroshape`, issue 46).
//! * [`update`]: the model update — surfaces re-solved, curves re-intersected, corners,
//!   curve-component ranges — in dependency order, with a report.
//!
//! Tolerances are relative to a length scale (the model's bounding-box diagonal) passed in
//! the option structs.

pub mod bvh;
pub mod check;
pub mod corner;
pub mod error;
pub mod measure;
pub mod project;
pub mod ssi;
pub mod update;

pub use error::{Error, Result};
