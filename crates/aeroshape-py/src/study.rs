//! `Study` and `Evaluation`: [`aeroshape::Study`] for Python — built once from a case file,
//! then `evaluate(x)` as often as an optimiser needs, and `write` for the files of
//! `aeroshape run`.
//!
//! The design vector is checked before the chain runs, as `aeroshape run` checks a `DV.ron`:
//! its length, every value finite and within its bounds, the linear constraints
//! (`allow_out_of_bounds` / `allow_infeasible` relax the last two, e.g. for finite-difference
//! steps at a bound).
//!
//! The exact derivative products: `linearise(x)` gives a [`PyLinearisation`] whose `jvp` and
//! `vjp` can be taken many times at that x; `jvp(x, dx)` and `vjp(x, x_bar)` are the one-off
//! forms (each linearises afresh).

use std::path::{Path, PathBuf};
use std::sync::Arc;

use aeroshape::Study;
use aeroshape::fsio::{ensure_not_input, write_atomic};
use mesh::io::Format;
use numpy::PyArray2;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use serde::Serialize;

use crate::arrays;
use crate::errors::{self, Kind};
use crate::grid::PyMesh;
use crate::linearise::PyLinearisation;
use crate::progress::{self, Progress};

/// One design variable of a study (a record; physical units, as in the case file).
#[pyclass(frozen, get_all, module = "aeroshape._native", name = "DesignVariable")]
#[derive(Debug, Clone)]
pub struct PyDesignVariable {
    /// Unique name.
    pub name: String,
    /// Lower bound.
    pub lower: f64,
    /// Upper bound.
    pub upper: f64,
    /// Scale for the optimiser (`scaled = value / scale`).
    pub scale: f64,
    /// The value at which the study gives the baseline shape.
    pub initial: f64,
    /// Group label of the case file (may be empty).
    pub group: String,
    /// The modifier the variable belongs to.
    pub modifier: String,
}

#[pymethods]
impl PyDesignVariable {
    fn __repr__(&self) -> String {
        format!(
            "DesignVariable(name={:?}, lower={}, upper={}, scale={}, initial={}, group={:?}, modifier={:?})",
            self.name, self.lower, self.upper, self.scale, self.initial, self.group, self.modifier
        )
    }
}

/// The linear inequality constraints `a @ x <= b` of a study (x in physical units).
#[pyclass(frozen, module = "aeroshape._native", name = "Constraints")]
#[derive(Debug, Clone)]
pub struct PyConstraints {
    cm: param::ConstraintMatrix,
}

#[pymethods]
impl PyConstraints {
    /// Constraint names (the rows of `a`).
    #[getter]
    fn names(&self) -> Vec<String> {
        self.cm.names.clone()
    }

    /// Design-variable names (the columns of `a`).
    #[getter]
    fn variables(&self) -> Vec<String> {
        self.cm.variables.clone()
    }

    /// The matrix `a` (constraints × design variables), a new array at each access.
    #[getter]
    fn a<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        arrays::matrix(py, &self.cm.a, self.cm.variables.len())
    }

    /// The right-hand sides `b`, a new array at each access.
    #[getter]
    fn b<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        arrays::vector(py, &self.cm.b).into_any()
    }

    fn __len__(&self) -> usize {
        self.cm.names.len()
    }

    /// The constraints violated at `x` (`a·x > b` beyond round-off), as
    /// `[(name, lhs, rhs), ...]`.
    fn violations(&self, x: &Bound<'_, PyAny>) -> PyResult<Vec<(String, f64, f64)>> {
        let x = arrays::read_vector(x, "x")?;
        if x.len() != self.cm.variables.len() {
            return Err(PyValueError::new_err(format!(
                "x has {} values; the constraints have {} variables",
                x.len(),
                self.cm.variables.len()
            )));
        }
        Ok(self
            .cm
            .violations(&x)
            .into_iter()
            .map(|v| (v.name, v.lhs, v.rhs))
            .collect())
    }

    fn __repr__(&self) -> String {
        format!(
            "Constraints({} × {}: {:?})",
            self.cm.names.len(),
            self.cm.variables.len(),
            self.cm.names
        )
    }
}

/// The pipeline built once from a case file (see `aeroshape::study` and docs/python.md).
#[pyclass(frozen, module = "aeroshape._native", name = "Study")]
pub struct PyStudy {
    inner: Arc<Study>,
    case_path: PathBuf,
    constraints: param::ConstraintMatrix,
    wall: Arc<Vec<u32>>,
}

/// The files `write` can produce, by name: those of `aeroshape run --no-pictures`.
const FORMATS: [&str; 6] = ["su2", "msh", "vtu", "baseline", "geometry", "report"];

/// `report.json`, as `aeroshape run` writes it.
#[derive(Serialize)]
struct RunReport<'a> {
    case: String,
    design_vector: Option<String>,
    setup: &'a aeroshape::study::SetupReport,
    evaluation: &'a aeroshape::study::Report,
    outputs: Vec<String>,
}

impl PyStudy {
    /// Checks `x` as `aeroshape run` checks a design vector; see the module doc.
    fn check_design(
        &self,
        py: Python<'_>,
        x: &[f64],
        allow_infeasible: bool,
        allow_out_of_bounds: bool,
    ) -> PyResult<()> {
        let reg = self.inner.registry();
        let bad = |e: param::Error| errors::from_error(py, Kind::DesignVector, &e);
        if allow_out_of_bounds {
            reg.values_from_vector(x).map_err(bad)?;
            for (v, &xi) in reg.variables().iter().zip(x) {
                if !xi.is_finite() {
                    v.check(xi).map_err(bad)?;
                }
            }
        } else {
            reg.check_bounds(x).map_err(bad)?;
        }
        let violations = self.constraints.violations(x);
        if violations.is_empty() {
            return Ok(());
        }
        if !allow_infeasible {
            return Err(errors::raise(
                py,
                Kind::DesignVector,
                format!(
                    "{} linear constraint(s) violated (first: {}); use allow_infeasible=True to evaluate anyway",
                    violations.len(),
                    violations[0]
                ),
            ));
        }
        for v in &violations {
            progress::log(py, progress::WARNING, || v.to_string())?;
        }
        Ok(())
    }

    /// Writes the files named in `formats` for `ev` into `out_dir`; returns their paths.
    fn write_files(
        &self,
        out_dir: &Path,
        ev: &aeroshape::Evaluation,
        formats: &[String],
    ) -> Result<Vec<String>, String> {
        let case = self.inner.case();
        let mut inputs = vec![self.case_path.clone(), case.geometry_path(&self.case_path)];
        inputs.extend(case.grid_path(&self.case_path));
        let input_refs: Vec<&Path> = inputs.iter().map(PathBuf::as_path).collect();
        std::fs::create_dir_all(out_dir).map_err(|e| {
            errors::collapse(&format!(
                "{}: cannot create the output folder: {e}",
                out_dir.display()
            ))
        })?;
        let file = |f: &str| match f {
            "su2" => "deformed.su2",
            "msh" => "deformed.msh",
            "vtu" => "deformed.vtu",
            "baseline" => "baseline.su2",
            "geometry" => "geometry.ron",
            _ => "report.json",
        };
        for f in formats {
            ensure_not_input(&out_dir.join(file(f)), &input_refs)?;
        }
        let mut written = Vec::new();
        let one = |e: &(dyn std::error::Error + 'static)| errors::one_line(e);
        for f in formats.iter().filter(|f| *f != "report") {
            let path = out_dir.join(file(f));
            let r = match f.as_str() {
                "su2" => write_atomic(&path, |w| mesh::io::write(&ev.grid, Format::Su2, w)),
                "msh" => write_atomic(&path, |w| {
                    mesh::io::write(&ev.grid, Format::Msh(mesh::msh::Encoding::Ascii), w)
                }),
                "vtu" => write_atomic(&path, |w| {
                    mesh::io::write(
                        &ev.grid,
                        Format::Vtu(mesh::vtu::VtuEncoding::AppendedRaw),
                        w,
                    )
                }),
                "baseline" => write_atomic(&path, |w| {
                    mesh::io::write(self.inner.baseline(), Format::Su2, w)
                }),
                _ => write_atomic(&path, |w| ev.geometry.write_ron(w)),
            };
            r.map_err(|e| one(&e))?;
            written.push(path.display().to_string());
        }
        if formats.iter().any(|f| f == "report") {
            let path = out_dir.join("report.json");
            written.push(path.display().to_string());
            let rr = RunReport {
                case: self.case_path.display().to_string(),
                design_vector: None,
                setup: self.inner.setup_report(),
                evaluation: &ev.report,
                outputs: written.clone(),
            };
            write_atomic(&path, |w| {
                serde_json::to_writer_pretty(&mut *w, &rr).map_err(std::io::Error::other)?;
                writeln!(w)
            })
            .map_err(|e| one(&e))?;
        }
        Ok(written)
    }
}

/// The formats asked for, checked and in the canonical order of [`FORMATS`].
fn formats(asked: Option<Vec<String>>) -> PyResult<Vec<String>> {
    let Some(asked) = asked else {
        return Ok(FORMATS.iter().map(|s| s.to_string()).collect());
    };
    for a in &asked {
        if !FORMATS.contains(&a.as_str()) {
            return Err(PyValueError::new_err(format!(
                "unknown format '{a}' (use {})",
                FORMATS.join(", ")
            )));
        }
    }
    Ok(FORMATS
        .iter()
        .filter(|f| asked.iter().any(|a| a == *f))
        .map(|s| s.to_string())
        .collect())
}

#[pymethods]
impl PyStudy {
    /// Reads the case file and builds the study (geometry, grid, parametrisation, model
    /// update seeds, wall classification, volume-deformation set-up).
    #[new]
    fn new(py: Python<'_>, case_path: PathBuf) -> PyResult<Self> {
        progress::log(py, progress::INFO, || {
            format!("building the study from {}", case_path.display())
        })?;
        let study = py
            .detach(|| Study::load(&case_path))
            .map_err(|e| errors::from_study(py, &e))?;
        let constraints = study
            .case()
            .parametrisation
            .constraint_matrix()
            .map_err(|e| {
                errors::raise(
                    py,
                    Kind::Case,
                    format!("{}: {}", case_path.display(), errors::one_line(&e)),
                )
            })?;
        let wall: Vec<u32> = study
            .wall_nodes()
            .iter()
            .enumerate()
            .filter(|(_, w)| **w)
            .map(|(i, _)| i as u32)
            .collect();
        let s = study.setup_report();
        progress::log(py, progress::INFO, || {
            format!(
                "grid {} nodes, {} cells, {} wall nodes (classified, max distance {:.2e}); set-up {:.2} s",
                s.nodes,
                s.cells,
                s.wall_nodes,
                s.classify_max_distance,
                s.read + s.param + s.model + s.classify + s.deform
            )
        })?;
        Ok(Self {
            inner: Arc::new(study),
            case_path,
            constraints,
            wall: Arc::new(wall),
        })
    }

    /// The case file, as given.
    #[getter]
    fn case_path(&self) -> String {
        self.case_path.display().to_string()
    }

    /// The design variables, in design-vector order.
    #[getter]
    fn design_variables(&self) -> Vec<PyDesignVariable> {
        let reg = self.inner.registry();
        reg.variables()
            .iter()
            .enumerate()
            .map(|(i, v)| PyDesignVariable {
                name: v.name.clone(),
                lower: v.lower,
                upper: v.upper,
                scale: v.scale,
                initial: v.value,
                group: v.group.clone(),
                modifier: reg.owner(i).to_string(),
            })
            .collect()
    }

    /// The design-variable names, in design-vector order.
    #[getter]
    fn names(&self) -> Vec<String> {
        self.constraints.variables.clone()
    }

    /// The initial design vector (the baseline shape), a new array at each access.
    #[getter]
    fn initial<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        arrays::vector(py, &self.inner.initial()).into_any()
    }

    /// The linear inequality constraints `a @ x <= b`.
    #[getter]
    fn constraints(&self) -> PyConstraints {
        PyConstraints {
            cm: self.constraints.clone(),
        }
    }

    /// Number of grid nodes.
    #[getter]
    fn n_nodes(&self) -> usize {
        self.inner.baseline().n_nodes()
    }

    /// Indices of the wall nodes (on the geometry), increasing: the rows of
    /// `volume_coordinates` that `wall_coordinates` holds.
    #[getter]
    fn wall_nodes<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        arrays::indices(py, &self.wall).into_any()
    }

    /// The baseline grid's node coordinates (`n_nodes × 3`), a new array at each access.
    #[getter]
    fn baseline_coordinates<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        arrays::coords(py, &self.inner.baseline().coords)
    }

    /// The baseline grid as a `Mesh` (a copy).
    #[getter]
    fn baseline(&self) -> PyMesh {
        PyMesh::from_rust(self.inner.baseline().clone())
    }

    /// Timings and sizes of the set-up (the `setup` object of `report.json`).
    #[getter]
    fn setup_report<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        arrays::to_python(py, self.inner.setup_report())
    }

    /// The design vector from named values (`{name: value}`); unnamed variables keep their
    /// initial value; unknown names and values outside the bounds raise
    /// `DesignVectorError`.
    fn vector<'py>(
        &self,
        py: Python<'py>,
        values: std::collections::BTreeMap<String, f64>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let x = self
            .inner
            .registry()
            .vector_from_values(&values)
            .map_err(|e| errors::from_error(py, Kind::DesignVector, &e))?;
        Ok(arrays::vector(py, &x).into_any())
    }

    /// The design vector of a `DV.ron` file (as `aeroshape run --dv`).
    fn read_design_vector<'py>(
        &self,
        py: Python<'py>,
        path: PathBuf,
    ) -> PyResult<Bound<'py, PyAny>> {
        let values = py
            .detach(|| aeroshape::case::load_design_values(&path))
            .map_err(|e| errors::from_error(py, Kind::DesignVector, &e))?;
        let x = self
            .inner
            .registry()
            .vector_from_values(&values)
            .map_err(|e| {
                errors::raise(
                    py,
                    Kind::DesignVector,
                    format!("{}: {}", path.display(), errors::one_line(&e)),
                )
            })?;
        Ok(arrays::vector(py, &x).into_any())
    }

    /// Runs the chain for the design vector `x` (physical units, design-vector order); the
    /// GIL is released while it runs. `progress(phase, done, total)` is called as each phase
    /// starts (default: DEBUG records of the logger "aeroshape").
    #[pyo3(signature = (x, *, progress=None, allow_infeasible=false, allow_out_of_bounds=false))]
    fn evaluate(
        slf: &Bound<'_, Self>,
        x: &Bound<'_, PyAny>,
        progress: Option<Bound<'_, PyAny>>,
        allow_infeasible: bool,
        allow_out_of_bounds: bool,
    ) -> PyResult<PyEvaluation> {
        let py = slf.py();
        let me = slf.get();
        let x = arrays::read_vector(x, "x")?;
        me.check_design(py, &x, allow_infeasible, allow_out_of_bounds)?;
        let mut prog = Progress::new(py, "evaluate", progress)?;
        let study = &me.inner;
        let r = py.detach(|| {
            let mut done = 0;
            study.evaluate_with_progress(&x, &mut |phase| {
                prog.report(phase, done, 4);
                done += 1;
            })
        });
        prog.finish()?;
        let ev = r.map_err(|e| errors::from_study(py, &e))?;
        let wall: Vec<[f64; 3]> = me
            .wall
            .iter()
            .map(|&i| ev.grid.coords[i as usize])
            .collect();
        Ok(PyEvaluation {
            study: slf.clone().unbind(),
            x: arrays::vector(py, &x).into_any().unbind(),
            volume_coordinates: arrays::coords(py, &ev.grid.coords).into_any().unbind(),
            wall_coordinates: arrays::coords(py, &wall).into_any().unbind(),
            report: PyOnceLock::new(),
            inner: Arc::new(ev),
        })
    }

    /// What a design that inverts cells did (`aeroshape::study::failure`): a dict with
    /// "count" (cells inverted beyond the baseline's), "cells" (the `max_cells` worst: cell,
    /// kind, quality [after, baseline], centroid, nodes as [node, on the wall], and
    /// "moved_by", the variables' shares, largest first), "volume_coordinates" (the grid of
    /// the guard's last attempt, `n_nodes × 3`) and "cell_quality". For the `x` that made
    /// `evaluate` raise `EvaluationError` with inverted cells; `x` is checked as there.
    #[pyo3(signature = (x, *, max_cells=20, allow_infeasible=false, allow_out_of_bounds=false))]
    fn failed_grid<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
        max_cells: usize,
        allow_infeasible: bool,
        allow_out_of_bounds: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let x = arrays::read_vector(x, "x")?;
        self.check_design(py, &x, allow_infeasible, allow_out_of_bounds)?;
        let f = py
            .detach(|| self.inner.failed_grid(&x, max_cells))
            .map_err(|e| errors::from_study(py, &e))?;
        let d = pyo3::types::PyDict::new(py);
        d.set_item("count", f.count)?;
        d.set_item("cells", arrays::to_python(py, &f.cells)?)?;
        d.set_item("volume_coordinates", arrays::coords(py, &f.grid.coords))?;
        d.set_item("cell_quality", arrays::vector(py, &f.cell_quality))?;
        Ok(d.into_any())
    }

    /// Evaluates the chain at `x` and linearises every phase there (the deformation started
    /// cold, so the result belongs to x alone): the returned `Linearisation` gives exact
    /// `jvp`/`vjp` products at x as often as asked. `x` is checked as in `evaluate`.
    #[pyo3(signature = (x, *, allow_infeasible=false, allow_out_of_bounds=false))]
    fn linearise(
        &self,
        py: Python<'_>,
        x: &Bound<'_, PyAny>,
        allow_infeasible: bool,
        allow_out_of_bounds: bool,
    ) -> PyResult<PyLinearisation> {
        let x = arrays::read_vector(x, "x")?;
        self.check_design(py, &x, allow_infeasible, allow_out_of_bounds)?;
        let (study, wall) = (Arc::clone(&self.inner), Arc::clone(&self.wall));
        py.detach(|| PyLinearisation::new(study, wall, &x))
            .map_err(|e| errors::from_study(py, &e))
    }

    /// dX = J dx at `x` (`linearise(x).jvp(dx, wall=wall)`): `n_nodes × 3`, or the wall rows
    /// (`n_wall × 3`) with `wall=True`.
    #[pyo3(signature = (x, dx, *, wall=false, allow_infeasible=false, allow_out_of_bounds=false))]
    fn jvp<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
        dx: &Bound<'py, PyAny>,
        wall: bool,
        allow_infeasible: bool,
        allow_out_of_bounds: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        self.linearise(py, x, allow_infeasible, allow_out_of_bounds)?
            .jvp(py, dx, wall)
    }

    /// x̄ = Jᵀ X̄ at `x` (`linearise(x).vjp(...)`): one value per design variable, from the
    /// grid's cotangent `x_bar` (`n_nodes × 3`), or from the wall rows' (`n_wall × 3`) with
    /// `wall=True`.
    #[pyo3(signature = (x, x_bar, *, wall=false, allow_infeasible=false, allow_out_of_bounds=false))]
    fn vjp<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
        x_bar: &Bound<'py, PyAny>,
        wall: bool,
        allow_infeasible: bool,
        allow_out_of_bounds: bool,
    ) -> PyResult<Bound<'py, PyAny>> {
        let lin = self.linearise(py, x, allow_infeasible, allow_out_of_bounds)?;
        if wall {
            lin.vjp(py, None, Some(x_bar))
        } else {
            lin.vjp(py, Some(x_bar), None)
        }
    }

    /// The wall-clock seconds of the library's `evaluate(x)` alone, timed in Rust with the GIL
    /// released (no check of `x`, no Python object made): the baseline of the overhead
    /// measurement in `benches/overhead.py`. Not part of the API.
    fn _rust_evaluate_seconds(&self, py: Python<'_>, x: Vec<f64>) -> PyResult<f64> {
        let study = &self.inner;
        py.detach(|| {
            let t = std::time::Instant::now();
            let ev = study.evaluate(&x)?;
            drop(ev); // as the Python path drops the evaluation it replaces
            Ok(t.elapsed().as_secs_f64())
        })
        .map_err(|e| errors::from_study(py, &e))
    }

    /// Makes the next evaluation start its solves from the baseline instead of the previous
    /// solution (see `aeroshape::study`, "Warm start").
    fn forget_warm_start(&self) {
        self.inner.forget_warm_start();
    }

    /// Writes the files of `aeroshape run --no-pictures` for `evaluation` into `out_dir`
    /// (created if missing): `formats` picks among "su2", "msh", "vtu" (deformed.*),
    /// "baseline" (baseline.su2), "geometry" (geometry.ron), "report" (report.json); default
    /// all. Each file is written to a temporary name and renamed. Returns the paths written.
    #[pyo3(signature = (out_dir, evaluation, *, formats=None))]
    fn write(
        &self,
        py: Python<'_>,
        out_dir: PathBuf,
        evaluation: &PyEvaluation,
        formats: Option<Vec<String>>,
    ) -> PyResult<Vec<String>> {
        let formats = self::formats(formats)?;
        let ev = &evaluation.inner;
        py.detach(|| self.write_files(&out_dir, ev, &formats))
            .map_err(|m| errors::raise(py, Kind::Output, m))
    }

    fn __repr__(&self) -> String {
        format!(
            "Study({:?}: {} design variables, {} constraints, {} nodes, {} wall nodes)",
            self.case_path.display().to_string(),
            self.constraints.variables.len(),
            self.constraints.names.len(),
            self.inner.baseline().n_nodes(),
            self.wall.len()
        )
    }
}

/// The result of `Study.evaluate`: numpy arrays of its own (copies made at return) and the
/// report (a dict made on first access: an optimiser that never reads it does not pay for
/// it).
#[pyclass(frozen, module = "aeroshape._native", name = "Evaluation")]
pub struct PyEvaluation {
    study: Py<PyStudy>,
    inner: Arc<aeroshape::Evaluation>,
    /// The design vector evaluated.
    #[pyo3(get)]
    x: Py<PyAny>,
    /// Node coordinates of the deformed grid (`n_nodes × 3`).
    #[pyo3(get)]
    volume_coordinates: Py<PyAny>,
    /// Coordinates of the wall nodes (`Study.wall_nodes` rows of `volume_coordinates`).
    #[pyo3(get)]
    wall_coordinates: Py<PyAny>,
    /// The report as a dict, made on first access.
    report: PyOnceLock<Py<PyAny>>,
}

#[pymethods]
impl PyEvaluation {
    /// What the evaluation did (the `evaluation` object of `report.json`), a dict made on
    /// first access (and the same object afterwards).
    #[getter]
    fn report<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.report
            .get_or_try_init(py, || {
                arrays::to_python(py, &self.inner.report).map(Bound::unbind)
            })
            .map(|r| r.bind(py).clone())
    }

    /// The study evaluated.
    #[getter]
    fn study(&self, py: Python<'_>) -> Py<PyStudy> {
        self.study.clone_ref(py)
    }

    /// Cell quality of the deformed grid (signed mean ratio), per cell; a new array at each
    /// access.
    #[getter]
    fn cell_quality<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        arrays::vector(py, &self.inner.cell_quality).into_any()
    }

    /// The deformed grid as a `Mesh` (a copy: cells, markers, node classification with the
    /// updated parameters).
    #[getter]
    fn mesh(&self) -> PyMesh {
        PyMesh::from_rust(self.inner.grid.clone())
    }

    /// `Study.write(out_dir, self, formats=formats)`.
    #[pyo3(signature = (out_dir, *, formats=None))]
    fn write(
        &self,
        py: Python<'_>,
        out_dir: PathBuf,
        formats: Option<Vec<String>>,
    ) -> PyResult<Vec<String>> {
        self.study.get().write(py, out_dir, self, formats)
    }

    fn __repr__(&self) -> String {
        format!(
            "Evaluation({} nodes, min quality {})",
            self.inner.grid.n_nodes(),
            self.inner.report.quality_after.min
        )
    }
}
