//! Format dispatch by file extension: `.su2`, `.msh` (Gmsh 4.1), `.vtu` (VTK XML).

use std::fs::File;
use std::io::{BufReader, Write};
use std::path::Path;

use crate::error::{Error, Result};
use crate::grid::Mesh;
use crate::msh::Encoding;
use crate::vtu::{VtuEncoding, VtuOptions};

/// A grid file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// SU2 native ASCII.
    Su2,
    /// Gmsh MSH 4.1 in the given encoding (reading detects the encoding itself).
    Msh(Encoding),
    /// VTK XML unstructured grid.
    Vtu(VtuEncoding),
}

impl Format {
    /// The format named by a file's extension (case-insensitive): `.su2`, `.msh` (ASCII
    /// when writing), `.vtu` (raw appended when writing).
    ///
    /// ```
    /// use mesh::io::Format;
    /// assert_eq!(Format::from_path("a/b.SU2".as_ref()), Some(Format::Su2));
    /// assert_eq!(Format::from_path("x.txt".as_ref()), None);
    /// ```
    pub fn from_path(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "su2" => Some(Format::Su2),
            "msh" => Some(Format::Msh(Encoding::Ascii)),
            "vtu" => Some(Format::Vtu(VtuEncoding::AppendedRaw)),
            _ => None,
        }
    }
}

/// Reads a grid file, choosing the reader by extension.
pub fn read_path(path: &Path) -> Result<Mesh> {
    let format = Format::from_path(path).ok_or_else(|| Error::UnknownFormat {
        file: path.display().to_string(),
    })?;
    let f = File::open(path).map_err(|error| Error::Io {
        file: path.display().to_string(),
        error,
    })?;
    let r = BufReader::with_capacity(1 << 18, f);
    match format {
        Format::Su2 => crate::su2::read(r, path),
        Format::Msh(_) => crate::msh::read(r, path),
        Format::Vtu(_) => crate::vtu::read(r, path),
    }
}

/// Writes a grid in the given format (VTU with its default point and cell data).
pub fn write<W: Write + ?Sized>(mesh: &Mesh, format: Format, w: &mut W) -> std::io::Result<()> {
    match format {
        Format::Su2 => crate::su2::write(mesh, w),
        Format::Msh(enc) => crate::msh::write(mesh, enc, w),
        Format::Vtu(enc) => crate::vtu::write(mesh, &VtuOptions::default().with_encoding(enc), w),
    }
}
