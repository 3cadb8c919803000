//! Rust errors as Python exceptions: the classes of `aeroshape._errors` (one per domain, all
//! under `aeroshape.AeroshapeError`), with the message the command line prints after
//! `error: ` — the error and its causes on one line, as `aeroshape` formats them.

use std::error::Error as StdError;

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::PyType;

/// The exception classes of `aeroshape._errors` (see `python/aeroshape/_errors.py`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// `CaseError`: the case file or a file it names is missing or bad, or the case is
    /// inconsistent with its grid or geometry.
    Case,
    /// `DesignVectorError` (also a `ValueError`): wrong length, a non-finite value, a value
    /// outside its bounds, violated linear constraints, unknown names.
    DesignVector,
    /// `MeshError`: a grid file cannot be read or a grid is invalid.
    Mesh,
    /// `GeometryError`: a geometric database cannot be read or used.
    Geometry,
    /// `EvaluationError`: a phase of the chain failed (param, model update, surface grid,
    /// deform).
    Evaluation,
    /// `DeformError`: the volume deformation failed (bad boundary conditions, solver,
    /// inverted cells).
    Deform,
    /// `SectionError`: an airfoil file, a fit or section parameters are bad.
    Section,
    /// `OutputError` (also an `OSError`): an output file cannot be written or would overwrite
    /// an input.
    Output,
}

impl Kind {
    fn class_name(self) -> &'static str {
        match self {
            Kind::Case => "CaseError",
            Kind::DesignVector => "DesignVectorError",
            Kind::Mesh => "MeshError",
            Kind::Geometry => "GeometryError",
            Kind::Evaluation => "EvaluationError",
            Kind::Deform => "DeformError",
            Kind::Section => "SectionError",
            Kind::Output => "OutputError",
        }
    }
}

/// The command line's one-line message of an error (as `aeroshape-cli` prints it): the error,
/// then each cause after `: `, white space collapsed, a cause whose message the line already
/// holds left out.
pub fn one_line(e: &(dyn StdError + 'static)) -> String {
    let mut line = String::new();
    let mut cause: Option<&(dyn StdError + 'static)> = Some(e);
    while let Some(c) = cause {
        let msg = collapse(&c.to_string());
        if !msg.is_empty() && !line.contains(&msg) {
            if !line.is_empty() {
                line.push_str(": ");
            }
            line.push_str(&msg);
        }
        cause = c.source();
    }
    line
}

/// `s` with runs of white space collapsed to one space, as the command line prints.
pub fn collapse(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// A Python exception of class `kind` with message `message`.
pub fn raise(py: Python<'_>, kind: Kind, message: impl Into<String>) -> PyErr {
    let message = message.into();
    let class = py
        .import("aeroshape._errors")
        .and_then(|m| m.getattr(kind.class_name()))
        .and_then(|c| c.cast_into::<PyType>().map_err(PyErr::from));
    match class {
        Ok(ty) => PyErr::from_type(ty, message),
        Err(e) => PyRuntimeError::new_err(format!(
            "{message} (aeroshape._errors.{} is not importable: {e})",
            kind.class_name()
        )),
    }
}

/// [`raise`] with the message of a Rust error ([`one_line`]).
pub fn from_error(py: Python<'_>, kind: Kind, e: &(dyn StdError + 'static)) -> PyErr {
    raise(py, kind, one_line(e))
}

/// The exception of an error of [`aeroshape::study`] (building or evaluating a study): the
/// grid → `MeshError`, the geometry → `GeometryError`, a bad design vector →
/// `DesignVectorError`, a phase of an evaluation → `EvaluationError`, anything else of the
/// case and its set-up → `CaseError`.
pub fn from_study(py: Python<'_>, e: &aeroshape::study::StudyError) -> PyErr {
    use aeroshape::study::StudyError as E;
    let kind = match e {
        E::Grid(_) => Kind::Mesh,
        E::Geometry(_) => Kind::Geometry,
        E::Param(
            param::Error::VectorLength { .. }
            | param::Error::OutOfBounds { .. }
            | param::Error::UnknownVariable { .. },
        ) => Kind::DesignVector,
        E::ModelUpdate(_) | E::SurfaceGrid(_) | E::Deform(_) => Kind::Evaluation,
        _ => Kind::Case,
    };
    from_error(py, kind, e)
}
