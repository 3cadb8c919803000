//! The geometric database as RON text (`docs/formats/geom-ron.md`): parse and validate,
//! write.

use std::io::{BufRead, Write};

use crate::error::{Entity, Error, Result};

use super::GeomDb;
use super::validate::invalid;

impl GeomDb {
    /// Parses and validates a database from RON text; `path` names the file in messages.
    ///
    /// Errors: [`Error::Syntax`] with line and column for text that is not a database,
    /// [`Error::UnsupportedVersion`], or [`Error::Invalid`] naming the first inconsistent
    /// entity. Never panics.
    pub fn from_ron_str(text: &str, path: &str) -> Result<Self> {
        let opts = ron::Options::default();
        let mut db: GeomDb = opts.from_str(text).map_err(|e| Error::Syntax {
            path: path.to_string(),
            line: e.span.start.line,
            column: e.span.start.col,
            message: e.code.to_string(),
        })?;
        db.validate().map_err(|e| e.with_path(path))?;
        db.refresh_baseline();
        Ok(db)
    }

    /// Reads and validates a database from a reader (see [`from_ron_str`](Self::from_ron_str)).
    pub fn read_ron(mut reader: impl BufRead, path: &str) -> Result<Self> {
        let mut text = String::new();
        reader
            .read_to_string(&mut text)
            .map_err(|e| invalid(Entity::Model, format!("cannot read: {e}")).with_path(path))?;
        Self::from_ron_str(&text, path)
    }

    /// The database as pretty-printed RON.
    pub fn to_ron_string(&self) -> String {
        let cfg = ron::ser::PrettyConfig::new()
            .struct_names(false)
            .compact_arrays(true)
            .indentor(" ".to_string());
        // Serialising plain data (f64, strings, vectors) cannot fail.
        ron::ser::to_string_pretty(self, cfg).unwrap_or_else(|e| format!("// {e}"))
    }

    /// Writes the database as RON.
    pub fn write_ron(&self, mut w: impl Write) -> std::io::Result<()> {
        w.write_all(self.to_ron_string().as_bytes())?;
        w.write_all(b"\n")
    }
}
