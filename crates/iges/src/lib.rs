//! IGES 5.3 reading and writing, without any geometry kernel.
//!
//! Layer: the top of the workspace; depends on nothing of aeroshape. It turns an IGES file
//! into typed entities (directory entry + parameter data) and back. The conversion of those
//! entities into the geometric database (power-basis arcs and patches, Eqs. 2–10 of the
//! paper; topology by sewing) lives in `geom-db`'s `import` module, so that this crate stays
//! a pure file format that can be tested and fuzzed on its own. It implements no equation of
//! the paper; `docs/formats/iges.md` describes what is read and written.
//!
//! * [`read`] / [`parse`]: the fixed 80-column ASCII form (Start, Global, Directory Entry,
//!   Parameter Data, Terminate sections), the Global section's delimiters, Hollerith
//!   strings, reals with `E` or `D` exponents. The compressed and binary forms are rejected
//!   with a clear message. Every error names the file and the physical line or directory
//!   entry (`"geom.igs: entity at D line 57 (type 128): parameter 12: ..."`); corrupt input
//!   never panics.
//! * [`Entity`]: typed entities 100, 102, 104, 106, 108, 110, 112, 114, 116, 118, 120, 122,
//!   123, 124, 126, 128, 130, 140, 141, 142, 143, 144, 186, 190, 192, 194, 196, 198, 314, 502,
//!   504, 508, 510, 514 ([`SUPPORTED_TYPES`]); other types are kept as raw parameters and
//!   listed in [`IgesFile::warnings`]. Form-dependent layouts (the reference direction of
//!   the form-1 analytic surfaces 190–198) are decoded by the directory entry's form.
//! * [`IgesFile::write`]: the same entities back to the fixed form, with sequence numbers,
//!   parameter-data pointers and back-pointers; reading the output gives the same entities.
//! * [`IgesFile::transform`]: the chain of 124 transformation matrices applying to an
//!   entity.
//!
//! ```
//! use iges::{Entity, Global, IgesFile, Line};
//! let mut f = IgesFile::new(Global::default());
//! let id = f.push(Entity::Line(Line { start: [0.0; 3], end: [1.0, 2.0, 3.0] }));
//! let mut out = Vec::new();
//! f.write(&mut out, "line.igs").unwrap();
//! let back = iges::read(&out[..], "line.igs").unwrap();
//! assert_eq!(back.get(id).unwrap().entity, f.get(id).unwrap().entity);
//! ```

mod directory;
pub mod entity;
mod error;
mod file;
mod global;
mod param;
mod reader;
mod writer;

pub use directory::{DeId, DirectoryEntry, Status};
pub use entity::*;
pub use error::{EntityProblem, Error, Result};
pub use file::{EntityRecord, IgesFile, Layout, Warning};
pub use global::Global;
pub use param::{Param, format_real};
pub use reader::{parse, read};
