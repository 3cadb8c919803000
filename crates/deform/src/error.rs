//! The error type of `deform`.

/// Everything that can go wrong in `deform`. Each variant names the entity at fault.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A node graph or matrix is malformed.
    #[error("malformed graph or matrix: {reason}")]
    BadGraph {
        /// What is wrong.
        reason: String,
    },
    /// An error of the sparse linear algebra (a malformed matrix or graph).
    #[error(transparent)]
    Sparse {
        /// The `sparse` error.
        #[from]
        source: sparse::Error,
    },
    /// A solver option outside its valid range.
    #[error("invalid solver option: {reason}")]
    BadOption {
        /// What is wrong.
        reason: String,
    },
    /// A matrix that must be symmetric positive definite is not (non-positive pivot).
    #[error("matrix not positive definite: multigrid level {level}, pivot {index} = {pivot:e}")]
    NotPositiveDefinite {
        /// Multigrid level (0 = finest).
        level: usize,
        /// Row of the failing pivot.
        index: usize,
        /// Value of the pivot.
        pivot: f64,
    },
    /// A marker named in the boundary conditions does not exist in the grid.
    ///
    /// ```
    /// let m = deform::generate::box_with_block([3, 3, 3], [0.0; 3], [1.0; 3], [1, 1, 1], [2, 2, 2]);
    /// let bc = deform::BoundaryConditions { markers: vec![("tail".into(), deform::MarkerRole::Fixed)], displacements: vec![] };
    /// let e = deform::deform(&m, &bc, &Default::default()).unwrap_err();
    /// assert!(matches!(e, deform::Error::UnknownMarker { .. }) && e.to_string().contains("tail"));
    /// ```
    #[error("no marker named {name:?} in the grid (markers: {available:?})")]
    UnknownMarker {
        /// The requested name.
        name: String,
        /// The grid's marker names.
        available: Vec<String>,
    },
    /// A sliding marker is not planar within the tolerance.
    ///
    /// ```
    /// let m = deform::generate::box_with_block([3, 3, 3], [0.0; 3], [1.0; 3], [1, 1, 1], [2, 2, 2]);
    /// let bc = deform::BoundaryConditions { markers: vec![("wing".into(), deform::MarkerRole::SlidePlane)], displacements: vec![] };
    /// let e = deform::deform(&m, &bc, &Default::default()).unwrap_err();
    /// assert!(matches!(e, deform::Error::NotPlanar { .. }));
    /// ```
    #[error(
        "marker {marker} is not planar: nodes deviate {deviation:e} from the fitted plane (tolerance {tolerance:e})"
    )]
    NotPlanar {
        /// Marker name.
        marker: String,
        /// Largest distance of a node from the fitted plane.
        deviation: f64,
        /// Allowed distance.
        tolerance: f64,
    },
    /// A prescribed displacement refers to a node that does not exist.
    ///
    /// ```
    /// let m = deform::generate::box_with_block([3, 3, 3], [0.0; 3], [1.0; 3], [1, 1, 1], [2, 2, 2]);
    /// let bc = deform::BoundaryConditions { markers: vec![], displacements: vec![(99_999, [0.0; 3])] };
    /// let e = deform::deform(&m, &bc, &Default::default()).unwrap_err();
    /// assert!(matches!(e, deform::Error::NodeOutOfRange { node: 99_999, .. }));
    /// ```
    #[error("node {node} does not exist (the grid has {nodes} nodes)")]
    NodeOutOfRange {
        /// The node index.
        node: usize,
        /// Number of nodes.
        nodes: usize,
    },
    /// Inconsistent or invalid motion specification.
    ///
    /// ```
    /// let m = deform::generate::box_with_block([3, 3, 3], [0.0; 3], [1.0; 3], [1, 1, 1], [2, 2, 2]);
    /// let bad = deform::RigidMotion { angle_deg: 5.0, axis_point: [0.0; 3], axis_dir: [0.0; 3], translation: [0.0; 3] };
    /// let bc = deform::BoundaryConditions { markers: vec![("wing".into(), deform::MarkerRole::Rigid(bad))], displacements: vec![] };
    /// let e = deform::deform(&m, &bc, &Default::default()).unwrap_err();
    /// assert!(matches!(e, deform::Error::BadMotion { .. }));
    /// ```
    #[error("invalid boundary motion: {reason}")]
    BadMotion {
        /// What is wrong.
        reason: String,
    },
    /// The deformed grid has inverted (or flat) cells even after incremental deformation.
    ///
    /// ```
    /// let m = deform::generate::box_with_block([3, 3, 3], [0.0; 3], [1.0; 3], [1, 1, 1], [2, 2, 2]);
    /// // Push the block through the top of the box.
    /// let up = deform::RigidMotion::translation([0.0, 0.0, 0.9]);
    /// let bc = deform::BoundaryConditions { markers: vec![("wing".into(), deform::MarkerRole::Rigid(up))], displacements: vec![] };
    /// let opts = deform::DeformOptions { max_increments: 1, ..Default::default() };
    /// let e = deform::deform(&m, &bc, &opts).unwrap_err();
    /// assert!(matches!(e, deform::Error::Inverted { .. }));
    /// ```
    #[error("{count} inverted cells after {increments} increments; worst: {worst}")]
    Inverted {
        /// Number of cells with q ≤ 0.
        count: usize,
        /// Increments tried last.
        increments: usize,
        /// The worst cells, "cell id (q = value)".
        worst: String,
    },
    /// A linear solve did not reach its tolerance.
    ///
    /// ```
    /// let m = deform::generate::box_with_block([6, 6, 6], [0.0; 3], [1.0; 3], [2, 2, 2], [4, 4, 4]);
    /// let up = deform::RigidMotion::translation([0.0, 0.0, 0.01]);
    /// let bc = deform::BoundaryConditions { markers: vec![("wing".into(), deform::MarkerRole::Rigid(up))], displacements: vec![] };
    /// let opts = deform::DeformOptions { max_iters: 1, solver: deform::SolverKind::PcgJacobi, ..Default::default() };
    /// let e = deform::deform(&m, &bc, &opts).unwrap_err();
    /// assert!(matches!(e, deform::Error::NoConvergence { .. }));
    /// ```
    #[error(
        "{what}: solver {solver} did not converge in {iterations} iterations (relative residual {residual:e})"
    )]
    NoConvergence {
        /// Which system.
        what: String,
        /// Solver name.
        solver: String,
        /// Iterations done.
        iterations: usize,
        /// Final relative residual.
        residual: f64,
    },
    /// A spring's stiffness is outside single precision's normal range after scaling by the
    /// grid size: coincident nodes, or edge lengths (or wall distances) spanning ~19 orders
    /// of magnitude.
    #[error(
        "spring between nodes {} and {}: stiffness {value:e} (relative to the grid size) is out of range; coincident nodes?",
        nodes[0], nodes[1]
    )]
    Stiffness {
        /// The spring's two nodes (input numbering).
        nodes: [u32; 2],
        /// The scaled stiffness.
        value: f64,
    },
    /// A node sliding on a support curve or surface of the geometry cannot be handled: not
    /// classified, off its support, a singular support, a failed parameter iteration.
    #[error("{}{entity}: {reason}", node.map(|n| format!("node {n} on ")).unwrap_or_default())]
    Support {
        /// The grid node (input numbering), when one is concerned.
        node: Option<u32>,
        /// The entity: support curve / surface, marker or grid.
        entity: String,
        /// What is wrong.
        reason: String,
    },
    /// A distributed deformation (`deform::distributed`, feature `mpi`) cannot go on: a bad
    /// partition (missing ghost, inconsistent global ids) or an option it does not support.
    /// Every rank returns it (the ranks agree on errors before any blocking exchange).
    #[error("distributed deformation: rank {rank}: {reason}")]
    Distributed {
        /// The rank that found the fault.
        rank: i32,
        /// What is wrong, naming the node (global id) or option.
        reason: String,
    },
}

impl Error {
    /// The error with its node numbers taken back to the input numbering: node `k` of the
    /// renumbered grid is input node `inv[k]`.
    pub(crate) fn renumbered(self, inv: &[u32]) -> Self {
        let back = |v: u32| inv.get(v as usize).copied().unwrap_or(v);
        match self {
            Error::Support {
                node: Some(v),
                entity,
                reason,
            } => Error::Support {
                node: Some(back(v)),
                entity,
                reason,
            },
            Error::Stiffness { nodes, value } => Error::Stiffness {
                nodes: nodes.map(back),
                value,
            },
            e => e,
        }
    }
}

/// `Result` with [`Error`] as the default error type.
pub type Result<T, E = Error> = std::result::Result<T, E>;
