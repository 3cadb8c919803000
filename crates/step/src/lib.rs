//! STEP (ISO 10303-21, "Part 21") reading, without any geometry kernel.
//!
//! Layer: the top of the workspace beside `iges`; depends on nothing of aeroshape. It turns a
//! STEP file into typed entities of the B-rep subset that AP203, AP214 and AP242 write for
//! solids and shells; the conversion into the geometric database lives in `geom-db`'s
//! `import` module. It implements no equation of the paper; `docs/formats/step.md`
//! describes what is read.
//!
//! * [`read`] / [`parse`]: the clear-text encoding — header, data sections, simple and
//!   complex instances `#n = ( A(…) B(…) );`, typed parameters `LENGTH_MEASURE(1.)`,
//!   strings with their `\X\`, `\X2\` escapes, comments. Every reference must name an
//!   instance; every error names the file and the line, or the instance `#n` with its line
//!   and type (`"wing.stp: #37 (line 52, ADVANCED_FACE): parameter 3 (face_geometry):
//!   expected a reference #n, found 1.5"`); corrupt input never panics.
//! * [`Entity`]: typed points, directions, placements, lines, conics, polylines, B-spline
//!   curves and surfaces (with their rational complex forms), trimmed, composite, offset and
//!   surface curves, pcurves, the elementary surfaces, surfaces of revolution and of linear
//!   extrusion, offset surfaces, vertices, edges, loops, faces, shells, solids, shell-based
//!   surface models, representations, contexts, units and measures. Other types are kept as
//!   raw [`Instance`]s ([`Entity::Other`]).
//! * [`StepFile::units`]: the length and plane-angle units of a context in SI, following
//!   conversion-based units (`INCH`, `DEGREE`).
//!
//! # Why the Part 21 parser is written here
//!
//! Two Apache-2.0 crates read STEP in Rust; neither fits:
//!
//! * `ruststep` 0.4 (ricosjp) says of itself "experimental stage, do not use for product";
//!   its typed schemas cover AP201 and AP203 only (no AP214 or AP242), its nom-based parser
//!   reports failures as nom errors without a line or instance, and it brings old duplicate
//!   versions of the workspace's dependencies (thiserror 1, nom 7, syn 1, derive_more 0.99,
//!   itertools 0.10, Inflector with regex): 44 crates, 3 min 12 s for a clean release build
//!   of its parser alone on this machine (69 s of CPU). Its untyped records would still need
//!   the typed B-rep layer written here.
//! * `truck-stepio` 0.3 converts into truck's geometry types (it depends on
//!   truck-geometry, truck-base, cgmath, chrono, ruststep), which the layering forbids for a
//!   file-format crate (geometry belongs to `geom-db`); it reads no length or angle unit
//!   and no offset surface.
//!
//! The Part 21 grammar is small (a recursive descent of a few hundred lines, with line
//! numbers for errors), so it is written here.
//!
//! ```
//! let text = "ISO-10303-21;\nHEADER;\nFILE_SCHEMA(('CONFIG_CONTROL_DESIGN'));\nENDSEC;\nDATA;\n\
//!             #1 = CARTESIAN_POINT('',(1.,2.,3.));\nENDSEC;\nEND-ISO-10303-21;\n";
//! let f = step::parse(text.as_bytes(), "p.stp").unwrap();
//! assert_eq!(f.schemas, vec!["CONFIG_CONTROL_DESIGN".to_string()]);
//! assert_eq!(f.point(step::Id(1), step::Id(1), "point").unwrap(), [1.0, 2.0, 3.0]);
//! ```

pub mod entity;
mod error;
mod file;
mod parse;
mod value;

pub use entity::*;
pub use error::{EntityProblem, Error, Result};
pub use file::{StepFile, Units, length_unit_name, parse, read};
pub use value::{Id, Instance, Record, Value};
