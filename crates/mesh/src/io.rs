//! Format dispatch by file extension: `.su2`, `.msh` (Gmsh 4.1), `.vtu` (VTK XML); a
//! directory (an OpenFOAM case or its `constant/polyMesh`) is OpenFOAM.

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
    /// An OpenFOAM case directory ([`crate::foam`]), written back into its case.
    Foam,
}

impl Format {
    /// The format named by a file's extension (case-insensitive): `.su2`, `.msh` (ASCII
    /// when writing), `.vtu` (raw appended when writing); OpenFOAM for an existing
    /// directory and for a name without extension (a case to be written).
    ///
    /// ```
    /// use mesh::io::Format;
    /// assert_eq!(Format::from_path("a/b.SU2".as_ref()), Some(Format::Su2));
    /// assert_eq!(Format::from_path("x.txt".as_ref()), None);
    /// assert_eq!(Format::from_path("cases/wing".as_ref()), Some(Format::Foam));
    /// ```
    pub fn from_path(path: &Path) -> Option<Format> {
        if path.is_dir() {
            return Some(Format::Foam);
        }
        let Some(ext) = path.extension() else {
            return Some(Format::Foam);
        };
        match ext.to_str()?.to_ascii_lowercase().as_str() {
            "su2" => Some(Format::Su2),
            "msh" => Some(Format::Msh(Encoding::Ascii)),
            "vtu" => Some(Format::Vtu(VtuEncoding::AppendedRaw)),
            _ => None,
        }
    }
}

/// Reads a grid file, choosing the reader by extension (a directory: [`crate::foam::read`]).
pub fn read_path(path: &Path) -> Result<Mesh> {
    let format = Format::from_path(path).ok_or_else(|| Error::UnknownFormat {
        file: path.display().to_string(),
    })?;
    if format == Format::Foam {
        return crate::foam::read(path);
    }
    let f = File::open(path).map_err(|error| Error::Io {
        file: path.display().to_string(),
        error,
    })?;
    let r = BufReader::with_capacity(1 << 18, f);
    match format {
        Format::Su2 => crate::su2::read(r, path),
        Format::Msh(_) => crate::msh::read(r, path),
        Format::Vtu(_) => crate::vtu::read(r, path),
        Format::Foam => crate::foam::read(path),
    }
}

/// Writes a grid in the given format (VTU with its default point and cell data). An
/// OpenFOAM case is a directory, written by [`write_path`] ([`crate::foam::write`]); here
/// it is an error.
pub fn write<W: Write + ?Sized>(mesh: &Mesh, format: Format, w: &mut W) -> std::io::Result<()> {
    match format {
        Format::Su2 => crate::su2::write(mesh, w),
        Format::Msh(enc) => crate::msh::write(mesh, enc, w),
        Format::Vtu(enc) => crate::vtu::write(mesh, &VtuOptions::default().with_encoding(enc), w),
        Format::Foam => Err(std::io::Error::other(
            "an OpenFOAM case is a directory: write it with mesh::io::write_path",
        )),
    }
}

/// True when grids of `format` are directories, written by [`write_path`] (OpenFOAM),
/// rather than files to stream into.
pub fn is_directory(format: Format) -> bool {
    format == Format::Foam
}

/// Writes an OpenFOAM grid back into a case at `path` ([`crate::foam::write`]; each file
/// through a temporary name). Other formats are single files: use [`write()`] on a temporary
/// file renamed into place (`aeroshape::fsio::write_atomic`).
pub fn write_path(mesh: &Mesh, format: Format, path: &Path) -> Result<()> {
    match format {
        Format::Foam => crate::foam::write(mesh, path),
        _ => Err(Error::Invalid {
            what: format!(
                "{}: write_path writes OpenFOAM cases; write {format:?} files with mesh::io::write",
                path.display()
            ),
        }),
    }
}
