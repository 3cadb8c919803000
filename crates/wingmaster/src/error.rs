//! The error type of `wingmaster`: bad airfoil files, invalid section parameters, fits that
//! fail, inconsistent planform data.

/// Errors of the wing parametrisation.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A coordinate file could not be read.
    ///
    /// ```
    /// let r = wingmaster::Airfoil::parse("a\nb c\n".as_bytes(), "x.dat");
    /// assert!(matches!(r, Err(wingmaster::Error::Parse { .. })));
    /// ```
    #[error("{path}:{line}: {reason}")]
    Parse {
        /// The file (as given for messages).
        path: String,
        /// 1-based line number (0 when the problem concerns the whole file).
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// A section parameter set does not define a valid thickness polygon.
    ///
    /// ```
    /// let mut p = wingmaster::ThicknessParams::naca_like(0.12);
    /// p.r0 = -1.0;
    /// assert!(matches!(p.polygon(), Err(wingmaster::Error::InvalidSection { .. })));
    /// ```
    #[error("invalid section parameters: {parameter} = {value}: {reason}")]
    InvalidSection {
        /// The parameter (or control point) at fault.
        parameter: String,
        /// Its value.
        value: f64,
        /// Why it is invalid.
        reason: String,
    },
    /// The least-squares fit of a section did not reach an acceptable solution.
    #[error("section fit of '{name}' failed after {iterations} iterations: {reason}")]
    FitFailed {
        /// Name of the airfoil.
        name: String,
        /// Iterations performed.
        iterations: usize,
        /// Why.
        reason: String,
    },
    /// The points given to the Eq. (40) modifier do not match the fitted section.
    #[error("section modification: {reason}")]
    Modify {
        /// What does not match.
        reason: String,
    },
    /// A planform parameter set is over- or under-determined or inconsistent.
    ///
    /// ```
    /// use wingmaster::planform::{Planform, PlanformSpec};
    /// let spec = PlanformSpec {
    ///     area: Some(10.0), aspect_ratio: Some(8.0), span: Some(3.0),
    ///     stations: vec![1.0], taper: vec![0.4], ..Default::default()
    /// };
    /// assert!(matches!(Planform::resolve(&spec), Err(wingmaster::Error::Planform { .. })));
    /// ```
    #[error("planform: {reason}")]
    Planform {
        /// Which quantities conflict or are missing.
        reason: String,
    },
    /// A wing master could not be bound or evaluated (names the key section, station or
    /// variable at fault).
    #[error("wing master: {reason}")]
    Master {
        /// What is wrong.
        reason: String,
    },
    /// A key section of a wing master has invalid section parameters at the design vector.
    #[error("key section {key}: {source}")]
    KeySection {
        /// The key section (index in the spec's `keys`).
        key: usize,
        /// Why its section is invalid (an [`Error::InvalidSection`]).
        #[source]
        source: Box<Error>,
    },
    /// A B-spline basis could not be built.
    #[error(transparent)]
    Geom(#[from] geom_db::Error),
}

/// `Result` with this crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
