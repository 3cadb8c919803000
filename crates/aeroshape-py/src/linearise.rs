//! `Linearisation`: [`aeroshape::study::ChainLinearisation`] for Python — the chain evaluated
//! and linearised at one design vector, whose exact forward (`jvp`) and reverse (`vjp`)
//! products can then be taken as often as an optimiser or OpenMDAO asks, each for the price
//! of the products alone (one deformation solve for a volume product, none for a wall one).
//!
//! The Rust linearisation borrows its study; here it is kept together with a reference-counted
//! handle on that study in one [`self_cell!`] (a well-kept crate for exactly this
//! owner-and-borrower pair; writing the self-reference by hand would need `unsafe`).
//!
//! Wall arrays are the `Study.wall_nodes` rows only (`n_wall × 3`), as in
//! `Evaluation.wall_coordinates`; volume arrays have one row per grid node.

use std::sync::Arc;

use aeroshape::Study;
use aeroshape::study::ChainLinearisation;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use self_cell::self_cell;

use crate::arrays;
use crate::errors;

self_cell!(
    /// A study and its chain linearised at one x.
    struct Cell {
        owner: Arc<Study>,
        #[covariant]
        dependent: ChainLinearisation,
    }
);

/// The chain linearised at one design vector (`Study.linearise(x)`).
#[pyclass(frozen, module = "aeroshape._native", name = "Linearisation")]
pub struct PyLinearisation {
    cell: Cell,
    /// The wall nodes (increasing), as `Study.wall_nodes`.
    wall: Arc<Vec<u32>>,
}

impl PyLinearisation {
    /// Evaluates and linearises `study` at `x` (the caller releases the GIL).
    pub fn new(
        study: Arc<Study>,
        wall: Arc<Vec<u32>>,
        x: &[f64],
    ) -> Result<Self, aeroshape::study::StudyError> {
        let cell = Cell::try_new(study, |s| s.linearise(x))?;
        Ok(Self { cell, wall })
    }

    fn n_nodes(&self) -> usize {
        self.cell.borrow_owner().baseline().n_nodes()
    }

    /// The forward product in the layout asked for.
    fn forward(
        &self,
        dx: &[f64],
        wall: bool,
    ) -> Result<Vec<[f64; 3]>, aeroshape::study::StudyError> {
        let lin = self.cell.borrow_dependent();
        if wall {
            let all = lin.jvp_wall(dx)?;
            Ok(self.wall.iter().map(|&i| all[i as usize]).collect())
        } else {
            lin.jvp(dx)
        }
    }

    /// The reverse product of a volume seed and/or a wall seed (their sum).
    fn reverse(
        &self,
        volume: Option<&[[f64; 3]]>,
        wall: Option<&[[f64; 3]]>,
    ) -> Result<Vec<f64>, aeroshape::study::StudyError> {
        let lin = self.cell.borrow_dependent();
        let mut out = vec![0.0; lin.x().len()];
        let mut add = |v: Vec<f64>| out.iter_mut().zip(v).for_each(|(o, v)| *o += v);
        if let Some(v) = volume.filter(|v| v.iter().any(|r| *r != [0.0; 3])) {
            add(lin.vjp(v)?);
        }
        if let Some(w) = wall.filter(|w| w.iter().any(|r| *r != [0.0; 3])) {
            let mut all = vec![[0.0; 3]; self.n_nodes()];
            for (&i, r) in self.wall.iter().zip(w) {
                all[i as usize] = *r;
            }
            add(lin.vjp_wall(&all)?);
        }
        Ok(out)
    }
}

/// Checks the number of rows of a seed.
fn rows(what: &str, found: usize, expected: usize) -> PyResult<()> {
    if found == expected {
        Ok(())
    } else {
        Err(PyValueError::new_err(format!(
            "{what} has {found} rows; expected {expected}"
        )))
    }
}

#[pymethods]
impl PyLinearisation {
    /// The design vector linearised at (a new array at each access).
    #[getter]
    fn x<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        arrays::vector(py, self.cell.borrow_dependent().x()).into_any()
    }

    /// The volume grid's coordinates at x (`n_nodes × 3`; the deformation started cold).
    #[getter]
    fn volume_coordinates<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        arrays::coords(py, self.cell.borrow_dependent().coords()).into_any()
    }

    /// dX = J dx: the grid's motion for the design direction `dx` (one value per design
    /// variable): `n_nodes × 3`, or `n_wall × 3` (the `Study.wall_nodes` rows, no volume
    /// solve) with `wall=True`.
    #[pyo3(signature = (dx, *, wall=false))]
    pub(crate) fn jvp<'py>(
        &self,
        py: Python<'py>,
        dx: &Bound<'py, PyAny>,
        wall: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let dx = arrays::read_vector(dx, "dx")?;
        let n = self.cell.borrow_dependent().x().len();
        if dx.len() != n {
            return Err(PyValueError::new_err(format!(
                "dx has {} values; the study has {n} design variables",
                dx.len()
            )));
        }
        let r = py
            .detach(|| self.forward(&dx, wall))
            .map_err(|e| errors::from_study(py, &e))?;
        Ok(arrays::coords(py, &r).into_any())
    }

    /// x̄ = Jᵀ X̄: the gradient with respect to the design variables of an objective whose
    /// gradient with respect to the grid is `x_bar` (`n_nodes × 3`) and/or, with `wall_bar`,
    /// with respect to the wall nodes (`n_wall × 3`, the `Study.wall_nodes` rows). Both seeds
    /// given: the sum of their products. A volume seed costs one adjoint deformation solve; a
    /// wall seed none.
    #[pyo3(signature = (x_bar=None, *, wall_bar=None))]
    pub(crate) fn vjp<'py>(
        &self,
        py: Python<'py>,
        x_bar: Option<&Bound<'py, PyAny>>,
        wall_bar: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let volume = x_bar
            .map(|b| arrays::read_rows::<3>(b, "x_bar"))
            .transpose()?;
        let wall = wall_bar
            .map(|b| arrays::read_rows::<3>(b, "wall_bar"))
            .transpose()?;
        if let Some(v) = &volume {
            rows("x_bar", v.len(), self.n_nodes())?;
        }
        if let Some(w) = &wall {
            rows("wall_bar", w.len(), self.wall.len())?;
        }
        let r = py
            .detach(|| self.reverse(volume.as_deref(), wall.as_deref()))
            .map_err(|e| errors::from_study(py, &e))?;
        Ok(arrays::vector(py, &r).into_any())
    }

    fn __repr__(&self) -> String {
        let lin = self.cell.borrow_dependent();
        format!(
            "Linearisation({} design variables, {} nodes, {} wall nodes, {} increment(s))",
            lin.x().len(),
            self.n_nodes(),
            self.wall.len(),
            lin.increments()
        )
    }
}
