//! The error type of `iges`: every variant names the file and the line or entity at fault.

/// Everything that can go wrong while reading or writing an IGES file.
///
/// Messages are one line and name the file, then the physical line, section parameter or
/// directory entry (by its `D` sequence number) at fault.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The underlying reader or writer failed.
    ///
    /// ```
    /// struct Broken;
    /// impl std::io::Read for Broken {
    ///     fn read(&mut self, _: &mut [u8]) -> std::io::Result<usize> {
    ///         Err(std::io::Error::other("disk on fire"))
    ///     }
    /// }
    /// let err = iges::read(std::io::BufReader::new(Broken), "x.igs").unwrap_err();
    /// assert!(matches!(err, iges::Error::Io { .. }));
    /// ```
    #[error("{file}: {source}")]
    Io {
        /// The file being read or written.
        file: String,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The file uses a form of IGES this crate does not read (compressed ASCII, binary).
    ///
    /// ```
    /// let text = format!("{:72}C{:7}\n", "compressed", 1);
    /// let err = iges::read(text.as_bytes(), "c.igs").unwrap_err();
    /// assert!(matches!(err, iges::Error::UnsupportedForm { .. }));
    /// ```
    #[error(
        "{file}: {form} IGES is not supported; re-export the file in the fixed 80-column ASCII form"
    )]
    UnsupportedForm {
        /// The file.
        file: String,
        /// `"compressed ASCII"` or `"binary"`.
        form: &'static str,
    },
    /// A physical line is malformed (too short, unknown section letter, sections out of
    /// order, wrong sequence number).
    ///
    /// ```
    /// let err = iges::read(&b"too short\n"[..], "s.igs").unwrap_err();
    /// assert!(matches!(err, iges::Error::Line { line: 1, .. }));
    /// ```
    #[error("{file}: line {line}: {reason}")]
    Line {
        /// The file.
        file: String,
        /// 1-based physical line number.
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// The file ends early or its Terminate section disagrees with the section sizes.
    ///
    /// ```
    /// let line = |s: &str, c: char, n: usize| format!("{s:72}{c}{n:7}\n");
    /// let text = line("start", 'S', 1) + &line("1H,,1H;;", 'G', 1);
    /// let err = iges::read(text.as_bytes(), "t.igs").unwrap_err();
    /// assert!(matches!(err, iges::Error::Structure { .. }));
    /// ```
    #[error("{file}: {reason}")]
    Structure {
        /// The file.
        file: String,
        /// What is wrong.
        reason: String,
    },
    /// A parameter of the Global section is malformed.
    ///
    /// ```
    /// let line = |s: &str, c: char, n: usize| format!("{s:72}{c}{n:7}\n");
    /// let text = line("start", 'S', 1)
    ///     + &line("1H,,1H;,x,", 'G', 1)
    ///     + &line("S      1G      1D      0P      0", 'T', 1);
    /// let err = iges::read(text.as_bytes(), "g.igs").unwrap_err();
    /// assert!(matches!(err, iges::Error::Global { .. }));
    /// ```
    #[error("{file}: global section: parameter {param}: {reason}")]
    Global {
        /// The file.
        file: String,
        /// 1-based parameter index in the Global section.
        param: usize,
        /// What is wrong.
        reason: String,
    },
    /// A directory entry or its parameter data is malformed, or an entity breaks a rule
    /// while being written.
    ///
    /// ```
    /// let line = |s: &str, c: char, n: usize| format!("{s:72}{c}{n:7}\n");
    /// let de = |a: &str, b: &str, n: usize| format!("{a:72}D{n:7}\n{b:72}D{:7}\n", n + 1);
    /// let text = line("", 'S', 1)
    ///     + &line("1H,,1H;;", 'G', 1)
    ///     + &de("     110       1       0       0       0       0       0       000000000",
    ///           "     110       0       0       1       0", 1)
    ///     + &format!("{:64}{:>8}P{:7}\n", "110,0.,0.,0.,1.,x,0.;", 1, 1)
    ///     + &format!("{:72}T{:7}\n", "S      1G      1D      2P      1", 1);
    /// let err = iges::read(text.as_bytes(), "l.igs").unwrap_err();
    /// assert_eq!(
    ///     err.to_string(),
    ///     "l.igs: entity at D line 1 (type 110): parameter 5: expected a number, found 'x'"
    /// );
    /// ```
    #[error("{file}: entity at D line {de} (type {entity_type}): {problem}")]
    Entity {
        /// The file.
        file: String,
        /// Sequence number of the entity's first directory line.
        de: u32,
        /// The entity type number.
        entity_type: i32,
        /// What is wrong.
        problem: EntityProblem,
    },
}

/// What is wrong with one entity (the detail of [`Error::Entity`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum EntityProblem {
    /// A directory-entry field is malformed.
    #[error("directory field {field} ({name}): {reason}")]
    DirectoryField {
        /// 1-based field number (1–20) of the directory entry.
        field: usize,
        /// Field name.
        name: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// A parameter has the wrong kind or value.
    #[error("parameter {index}: expected {expected}, found '{found}'")]
    Param {
        /// 1-based parameter index (the entity type number is parameter 0).
        index: usize,
        /// What was expected.
        expected: String,
        /// What was found.
        found: String,
    },
    /// The parameter list ends before all required parameters were read.
    #[error("parameter {index}: missing ({what}); the entity has only {available} parameters")]
    Missing {
        /// 1-based index of the first missing parameter.
        index: usize,
        /// What was being read.
        what: String,
        /// How many parameters the entity has.
        available: usize,
    },
    /// A count in the parameters is negative or larger than the data that follows.
    #[error("parameter {index}: {name} = {value} is invalid: {reason}")]
    Count {
        /// 1-based parameter index.
        index: usize,
        /// The count's name in the IGES specification.
        name: &'static str,
        /// The value read.
        value: i64,
        /// Why it is invalid.
        reason: String,
    },
    /// A pointer does not name a directory entry of the file (or names one of the wrong
    /// type).
    #[error("parameter {index}: pointer {pointer} {reason}")]
    Pointer {
        /// 1-based parameter index (0 for the directory entry's own pointers).
        index: usize,
        /// The pointer value.
        pointer: i64,
        /// Why it is invalid.
        reason: String,
    },
    /// The parameter data text cannot be split into parameters.
    #[error("parameter data at P line {line}: {reason}")]
    Syntax {
        /// The `P` sequence number where the entity's parameter data starts.
        line: u32,
        /// What is wrong.
        reason: String,
    },
    /// The transformation-matrix chain starting at this entity loops back on itself.
    #[error("transformation matrix chain loops through D line {at}")]
    TransformCycle {
        /// The directory line where the chain comes back.
        at: u32,
    },
    /// The entity cannot be written as IGES (a count does not match its arrays, a string
    /// is not ASCII, a pointer names no entity...).
    #[error("cannot write: {reason}")]
    Write {
        /// What is wrong.
        reason: String,
    },
}

/// `Result` with [`Error`] as the default error type.
pub type Result<T, E = Error> = std::result::Result<T, E>;
