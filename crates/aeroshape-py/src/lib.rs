//! `aeroshape._native`: the Rust half of the Python package `aeroshape` (PyO3, rust-numpy;
//! built by maturin as an abi3 wheel from `crates/aeroshape-py/pyproject.toml`).
//!
//! Layer: the bottom, beside the command-line program; it wraps the library crates and
//! changes none of them. The Python half (`python/aeroshape/`) re-exports these items, holds
//! the exception classes and `aeroshape.openmdao`. The user guide is `docs/python.md`.
//!
//! - [`study`]: `Study` (case file → baseline; `evaluate(x)` → `Evaluation`; `write`).
//! - [`linearise`]: `Linearisation`, the chain's exact `jvp`/`vjp` products at one x.
//! - [`grid`]: `Mesh`, `read_mesh`, `write_mesh`.
//! - [`deformation`]: `deform(mesh, rigid=..., slide=..., fixed=..., ...)`, the keywords of
//!   `aeroshape deform`.
//! - `distributed` (cargo feature `mpi`): `DistributedDeformer`, the distributed deformation
//!   on an mpi4py communicator's processes, set up once and deformed for new displacements
//!   (`aeroshape.distributed.Deformer` and `deform`).
//! - [`section`]: `section_fit` and `section_build`, as `aeroshape section fit|build`.
//! - [`errors`]: Rust errors → Python exceptions carrying the command line's messages.
//! - [`progress`]: progress to a callback or the `logging` logger `"aeroshape"`.
//! - [`arrays`]: numpy arrays in numpy's own memory (no array aliases Rust memory).
//!
//! Every Rust computation runs with the GIL released (`Python::detach`); only the copies into
//! and out of Python objects hold it. No equation of the paper is implemented here.

use pyo3::prelude::*;

pub mod arrays;
pub mod deformation;
#[cfg(feature = "mpi")]
pub mod distributed;
pub mod errors;
pub mod grid;
pub mod linearise;
pub mod progress;
pub mod section;
pub mod study;

/// The extension module `aeroshape._native`.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<study::PyStudy>()?;
    m.add_class::<study::PyEvaluation>()?;
    m.add_class::<linearise::PyLinearisation>()?;
    m.add_class::<study::PyDesignVariable>()?;
    m.add_class::<study::PyConstraints>()?;
    m.add_class::<grid::PyMesh>()?;
    m.add_function(wrap_pyfunction!(grid::read_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(grid::write_mesh, m)?)?;
    m.add_class::<deformation::PyDeformation>()?;
    m.add_function(wrap_pyfunction!(deformation::deform_mesh, m)?)?;
    #[cfg(feature = "mpi")]
    {
        m.add_class::<distributed::PyDistributedDeformation>()?;
        m.add_class::<distributed::PyDistributedDeformer>()?;
    }
    m.add_class::<section::PySectionFit>()?;
    m.add_function(wrap_pyfunction!(section::section_fit, m)?)?;
    m.add_function(wrap_pyfunction!(section::section_build, m)?)?;
    m.add_function(wrap_pyfunction!(section::write_section, m)?)?;
    Ok(())
}
