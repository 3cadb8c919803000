//! The crate's error type: every failure names the file and the line (text) or byte offset
//! (binary) where it was found, or the element and node involved.

use std::fmt;

/// Where in an input an error was found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Location {
    /// A 1-based line number in a text file.
    Line(usize),
    /// A 0-based byte offset in a binary file or section.
    Byte(u64),
    /// The end of the input.
    End,
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::Line(l) => write!(f, "line {l}"),
            Location::Byte(b) => write!(f, "byte {b}"),
            Location::End => write!(f, "end of file"),
        }
    }
}

/// Everything that can go wrong in this crate.
#[non_exhaustive]
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The input could not be read.
    ///
    /// ```
    /// let err = mesh::su2::read(std::io::BufReader::new(std::fs::File::open("/").unwrap()), "/".as_ref());
    /// assert!(matches!(err, Err(mesh::Error::Io { .. })));
    /// ```
    #[error("{file}: {error}")]
    Io {
        /// The file being read.
        file: String,
        /// The underlying error (shown in the message, so not repeated as a source).
        error: std::io::Error,
    },
    /// A malformed token, keyword or section.
    ///
    /// ```
    /// let err = mesh::su2::read(&b"NDIME= 3\nNELEM= x\n"[..], "a.su2".as_ref()).unwrap_err();
    /// assert!(matches!(err, mesh::Error::Syntax { .. }));
    /// assert!(err.to_string().starts_with("a.su2: line 2:"));
    /// ```
    #[error("{file}: {at}: {msg}")]
    Syntax {
        /// The file being read.
        file: String,
        /// Where.
        at: Location,
        /// What was expected or found.
        msg: String,
    },
    /// The input ended before a section was complete.
    ///
    /// ```
    /// let err = mesh::su2::read(&b"NDIME= 3\nNELEM= 2\n10 0 1 2 3\n"[..], "a.su2".as_ref()).unwrap_err();
    /// assert!(matches!(err, mesh::Error::Truncated { .. }));
    /// ```
    #[error("{file}: {at}: file ends inside {what}")]
    Truncated {
        /// The file being read.
        file: String,
        /// Where the input ended.
        at: Location,
        /// The section that was being read.
        what: String,
    },
    /// An element type code that this crate does not know.
    ///
    /// ```
    /// let err = mesh::su2::read(&b"NDIME= 3\nNELEM= 1\n11 0 1 2 3\n"[..], "a.su2".as_ref()).unwrap_err();
    /// assert!(matches!(err, mesh::Error::UnknownElementType { code: 11, .. }));
    /// ```
    #[error("{file}: {at}: unknown or unsupported element type {code}")]
    UnknownElementType {
        /// The file being read.
        file: String,
        /// Where.
        at: Location,
        /// The code found in the file.
        code: i64,
    },
    /// An element refers to a node that does not exist.
    ///
    /// ```
    /// let txt = b"NDIME= 2\nNELEM= 1\n5 0 1 7\nNPOIN= 3\n0 0\n1 0\n0 1\nNMARK= 0\n";
    /// let err = mesh::su2::read(&txt[..], "a.su2".as_ref()).unwrap_err();
    /// assert!(matches!(err, mesh::Error::NodeOutOfRange { node: 7, n_nodes: 3, .. }));
    /// ```
    #[error("{file}: {at}: node {node} out of range (the grid has {n_nodes} nodes)")]
    NodeOutOfRange {
        /// The file being read.
        file: String,
        /// Where the reference is.
        at: Location,
        /// The node index or tag found.
        node: u64,
        /// The number of nodes.
        n_nodes: usize,
    },
    /// A grid that breaks an invariant (checked by [`crate::Mesh::validate`]).
    ///
    /// ```
    /// let mut m = mesh::generate::box_tets(1, 1, 1, [0.0; 3], [1.0; 3]);
    /// m.coords.pop();
    /// assert!(matches!(m.validate(), Err(mesh::Error::Invalid { .. })));
    /// ```
    #[error("invalid grid: {what}")]
    Invalid {
        /// What is wrong.
        what: String,
    },
    /// A file name whose extension names no grid format this crate knows.
    ///
    /// ```
    /// let err = mesh::io::read_path("grid.cgns".as_ref()).unwrap_err();
    /// assert!(matches!(err, mesh::Error::UnknownFormat { .. }));
    /// ```
    #[error(
        "{file}: unknown grid format (expected .su2, .msh, .vtu or an OpenFOAM case directory)"
    )]
    UnknownFormat {
        /// The file name.
        file: String,
    },
    /// Two grids that should have the same connectivity do not.
    ///
    /// ```
    /// let a = mesh::generate::box_tets(1, 1, 1, [0.0; 3], [1.0; 3]);
    /// let b = mesh::generate::box_tets(2, 1, 1, [0.0; 3], [1.0; 3]);
    /// assert!(matches!(mesh::quality::compare(&a, &b, 5), Err(mesh::Error::Mismatch { .. })));
    /// ```
    #[error("grids do not match: {what}")]
    Mismatch {
        /// What differs.
        what: String,
    },
}

/// The crate's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;
