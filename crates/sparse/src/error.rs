//! The error type of `sparse`.

/// Everything that can go wrong in `sparse`. Each variant names the entity at fault.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A graph or matrix is malformed (array lengths, an index out of range, asymmetry).
    ///
    /// ```
    /// let e = sparse::Graph::from_edges(3, &[[0, 7]]).unwrap_err();
    /// assert!(matches!(e, sparse::Error::BadGraph { .. }) && e.to_string().contains("edge 0"));
    /// ```
    #[error("malformed graph or matrix: {reason}")]
    BadGraph {
        /// What is wrong.
        reason: String,
    },
    /// A permutation is not one (wrong length, an index out of range or repeated).
    ///
    /// ```
    /// let e = sparse::order::check_permutation(&[0, 2, 2], 3).unwrap_err();
    /// assert!(matches!(e, sparse::Error::BadPermutation { .. }));
    /// ```
    #[error("not a permutation: {reason}")]
    BadPermutation {
        /// What is wrong.
        reason: String,
    },
    /// A factorisation met a pivot that is not positive: the matrix is not symmetric
    /// positive definite.
    ///
    /// ```
    /// use sparse::{SymMatrix, envelope::EnvelopeCholesky};
    /// // [[1, 2], [2, 1]] is indefinite.
    /// let a = SymMatrix { diag: vec![1.0, 1.0], offsets: vec![0, 1, 2], cols: vec![1, 0], vals: vec![2.0, 2.0] };
    /// let e = EnvelopeCholesky::new(&a, &[0, 1]).unwrap_err();
    /// assert!(matches!(e, sparse::Error::NotPositiveDefinite { index: 1, .. }));
    /// ```
    #[error("matrix not positive definite: pivot {index} = {pivot:e}")]
    NotPositiveDefinite {
        /// Row of the failing pivot (in the factorisation's order).
        index: usize,
        /// Value of the pivot.
        pivot: f64,
    },
}

/// `Result` with [`Error`] as the default error type.
pub type Result<T, E = Error> = std::result::Result<T, E>;
