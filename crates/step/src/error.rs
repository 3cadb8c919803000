//! The error type of `step`: every variant names the file and the line or instance at fault.

/// Everything that can go wrong while reading a STEP file.
///
/// Messages are one line and name the file, then the physical line or the entity instance
/// (`#id`, its line and type) at fault.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The underlying reader failed.
    ///
    /// ```
    /// struct Broken;
    /// impl std::io::Read for Broken {
    ///     fn read(&mut self, _: &mut [u8]) -> std::io::Result<usize> {
    ///         Err(std::io::Error::other("disk on fire"))
    ///     }
    /// }
    /// let err = step::read(std::io::BufReader::new(Broken), "x.stp").unwrap_err();
    /// assert!(matches!(err, step::Error::Io { .. }));
    /// ```
    #[error("{file}: {source}")]
    Io {
        /// The file being read.
        file: String,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The text is not a valid exchange structure at this line (a bad token, a missing
    /// delimiter, a section out of place, the file ends early).
    ///
    /// ```
    /// let text = "ISO-10303-21;\nHEADER;\nENDSEC;\nDATA;\n#1 = LINE('',#2 #3);\nENDSEC;\n";
    /// let err = step::parse(text.as_bytes(), "s.stp").unwrap_err();
    /// assert!(matches!(err, step::Error::Syntax { line: 5, .. }), "{err}");
    /// ```
    #[error("{file}: line {line}: {reason}")]
    Syntax {
        /// The file.
        file: String,
        /// 1-based physical line.
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// An entity instance is malformed: a parameter of the wrong kind, a missing parameter,
    /// a reference to an instance that does not exist or has the wrong type, a name given
    /// twice.
    ///
    /// ```
    /// let text = "ISO-10303-21;\nHEADER;\nENDSEC;\nDATA;\n\
    ///             #1 = CARTESIAN_POINT('',(0.,0.,'x'));\nENDSEC;\nEND-ISO-10303-21;\n";
    /// let err = step::parse(text.as_bytes(), "e.stp").unwrap_err();
    /// assert_eq!(
    ///     err.to_string(),
    ///     "e.stp: #1 (line 5, CARTESIAN_POINT): parameter 2 (coordinates): \
    ///      item 3: expected a real, found 'x'"
    /// );
    /// ```
    #[error("{file}: {id} (line {line}, {entity}): {problem}")]
    Entity {
        /// The file.
        file: String,
        /// The instance.
        id: crate::Id,
        /// The line where it starts.
        line: usize,
        /// Its type name (`(A B C)` for a complex instance).
        entity: String,
        /// What is wrong (boxed: the error stays small on the `Ok` path).
        problem: Box<EntityProblem>,
    },
}

/// What is wrong with one instance (the detail of [`Error::Entity`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum EntityProblem {
    /// A parameter has the wrong kind or value. `path` says where inside a list.
    #[error("parameter {index} ({name}){path}: expected {expected}, found {found}")]
    Param {
        /// 1-based parameter index within its record.
        index: usize,
        /// The attribute name in the schema.
        name: &'static str,
        /// `": item 3"` or `": row 2, item 1"` inside lists, empty otherwise.
        path: String,
        /// What was expected.
        expected: String,
        /// What was found.
        found: String,
    },
    /// The record has fewer parameters than its type needs.
    #[error("{record} has {found} parameters, {expected} expected")]
    Arity {
        /// The record (type) name.
        record: String,
        /// How many it has.
        found: usize,
        /// How many the type needs.
        expected: usize,
    },
    /// A reference names no instance of the file, or one of another type.
    #[error("parameter {index} ({name}): {target} {reason}")]
    Reference {
        /// 1-based parameter index (0 when the reference is met while following another).
        index: usize,
        /// The attribute name.
        name: &'static str,
        /// The instance referred to.
        target: crate::Id,
        /// Why it is wrong.
        reason: String,
    },
    /// A complex instance lacks a partial entity its type needs.
    #[error("complex instance lacks {missing}")]
    Complex {
        /// The partial entity that is missing.
        missing: &'static str,
    },
    /// A value is out of its range (a negative degree, knot counts that disagree, …).
    #[error("{reason}")]
    Invalid {
        /// What is wrong.
        reason: String,
    },
    /// The instance name is used twice.
    #[error("the name is also used at line {other_line}")]
    Duplicate {
        /// Line of the other instance.
        other_line: usize,
    },
}

/// `Result` with [`Error`] as the default error type.
pub type Result<T, E = Error> = std::result::Result<T, E>;
