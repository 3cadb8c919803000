//! The error type of `param`: every variant names the design variable, modifier or entity at
//! fault and carries the numbers.

/// Everything that can go wrong in `param`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A design vector or constraint names a variable the parametrisation does not have.
    ///
    /// ```
    /// let p = param::Parametrisation::default();
    /// let reg = p.registry().unwrap();
    /// let mut dv = param::DesignValues::new();
    /// dv.insert("nope".into(), 1.0);
    /// let err = reg.vector_from_values(&dv).unwrap_err();
    /// assert!(matches!(err, param::Error::UnknownVariable { .. }));
    /// ```
    #[error("{context}: unknown design variable '{name}'")]
    UnknownVariable {
        /// Where the name was used (design vector, constraint name).
        context: String,
        /// The unknown name.
        name: String,
    },

    /// Two design variables share a name.
    ///
    /// ```
    /// use param::*;
    /// let line = |name: &str| Modifier::Line(LineModifier {
    ///     name: name.into(),
    ///     line: LineSupport::Curve(geom_db::CurveId(0)),
    ///     links: Links::default(), range: None,
    ///     basis: Basis::Bernstein { degree: 0 }, active: None,
    ///     direction: Direction::Normal, decay: Decay::Uniform,
    ///     variables: vec![DesignVariable::new("q", -1.0, 1.0)],
    /// });
    /// let p = Parametrisation { modifiers: vec![line("a"), line("b")], constraints: vec![] };
    /// assert!(matches!(p.registry(), Err(Error::DuplicateVariable { .. })));
    /// ```
    #[error("design variable '{name}' is defined twice (modifiers '{first}' and '{second}')")]
    DuplicateVariable {
        /// The name.
        name: String,
        /// Modifier of the first definition.
        first: String,
        /// Modifier of the second definition.
        second: String,
    },

    /// A value is outside the bounds of its design variable.
    ///
    /// ```
    /// let v = param::DesignVariable::new("twist", -0.1, 0.1);
    /// let e = v.check(0.2).unwrap_err();
    /// assert_eq!(e.to_string(), "design variable 'twist' = 0.2 is outside its bounds [-0.1, 0.1]");
    /// ```
    #[error("design variable '{name}' = {value} is outside its bounds [{lower}, {upper}]")]
    OutOfBounds {
        /// The variable.
        name: String,
        /// The offending value.
        value: f64,
        /// Lower bound.
        lower: f64,
        /// Upper bound.
        upper: f64,
    },

    /// A design variable's definition is inconsistent (bounds reversed, scale not positive,
    /// non-finite numbers, empty name).
    #[error("design variable '{name}': {reason}")]
    BadVariable {
        /// The variable.
        name: String,
        /// What is wrong.
        reason: String,
    },

    /// A modifier links to (or uses) an entity the geometry does not have.
    ///
    /// ```
    /// use param::*;
    /// use geom_db::prelude::{Point3, Vector3};
    /// let m = Modifier::Node(NodeModifier {
    ///     name: "tip".into(),
    ///     links: Links { surfaces: vec![geom_db::SurfaceId(3)], ..Links::default() },
    ///     axis: Axis { point: Point3::origin(), direction: Vector3::z() },
    ///     rotation: Some(DesignVariable::new("theta", -1.0, 1.0)),
    ///     translation: [None, None, None],
    /// });
    /// let p = Parametrisation { modifiers: vec![m], constraints: vec![] };
    /// let e = p.bind(&geom_db::GeomDb::empty("x"), &MasterSources::new()).err().unwrap();
    /// assert!(matches!(e, Error::MissingEntity { .. }));
    /// assert!(e.to_string().contains("surface 3"));
    /// ```
    #[error("modifier '{modifier}': {entity} does not exist (the model has {available})")]
    MissingEntity {
        /// The modifier.
        modifier: String,
        /// The missing entity (`surface 7`, `control node 12`).
        entity: String,
        /// How many such entities the model has.
        available: usize,
    },

    /// A modifier's definition is inconsistent (variable count vs basis, bad axis, …).
    #[error("modifier '{modifier}': {reason}")]
    BadModifier {
        /// The modifier.
        modifier: String,
        /// What is wrong.
        reason: String,
    },

    /// A geometric quantity could not be computed at a control node (e.g. the surface normal
    /// at a singular point, a foot of the normal).
    #[error("modifier '{modifier}': {node}: {reason}")]
    NodeGeometry {
        /// The modifier.
        modifier: String,
        /// The node (`control node 12`).
        node: String,
        /// What failed.
        reason: String,
    },

    /// A master modifier names a master source the caller did not supply.
    #[error("modifier '{modifier}': no master source named '{source_name}' was supplied")]
    MissingMasterSource {
        /// The modifier.
        modifier: String,
        /// The source name.
        source_name: String,
    },

    /// A master source produced an unusable grid (wrong node count, non-finite point), or
    /// the built-in station master could not be bound.
    #[error("modifier '{modifier}': master: {reason}")]
    Master {
        /// The modifier.
        modifier: String,
        /// What went wrong.
        reason: String,
    },

    /// A master source failed to generate its grid or its Jacobian; `source` is the source's
    /// own typed error (e.g. `wingmaster::Error`, reached with `downcast_ref`).
    #[error("modifier '{modifier}': master source: {source}")]
    MasterSource {
        /// The modifier.
        modifier: String,
        /// The source's error.
        #[source]
        source: crate::master::MasterError,
    },

    /// A design vector has the wrong length.
    ///
    /// ```
    /// let reg = param::Parametrisation::default().registry().unwrap();
    /// assert!(matches!(reg.check_bounds(&[1.0]), Err(param::Error::VectorLength { .. })));
    /// ```
    #[error("design vector has {found} values, the parametrisation has {expected} variables")]
    VectorLength {
        /// Number of design variables.
        expected: usize,
        /// Number of values given.
        found: usize,
    },

    /// Text that is not the expected RON (design values, parametrisation).
    #[error("{path}:{line}:{column}: {message}")]
    Syntax {
        /// The file.
        path: String,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// The parser's message.
        message: String,
    },

    /// An error of the geometric database (B-spline knots, control points).
    #[error(transparent)]
    Geom(#[from] geom_db::Error),

    /// An error of the geometry update (projection on a support curve).
    #[error(transparent)]
    Intersect(#[from] intersect::Error),
}

/// `Result` with [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
