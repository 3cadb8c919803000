//! `section_fit`, `section_build` and `write_section`: the wing-section parametrisation of
//! the paper's §6.1 (Eq. 39 thickness, B-spline camber) as `aeroshape section fit|build`.
//! `SectionFit.as_dict()` is the object `aeroshape section fit --json` prints.

use std::io::BufReader;
use std::path::PathBuf;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use wingmaster::{Airfoil, FitOptions, SectionFit, SectionParams};

use crate::arrays;
use crate::errors::{self, Kind};

/// A fitted section: the parameters, the fit's figures and the input points.
#[pyclass(frozen, module = "aeroshape._native", name = "SectionFit")]
pub struct PySectionFit {
    fit: SectionFit,
    airfoil_name: String,
    warnings: Vec<String>,
}

/// Points per surface of a sampled section: at least 100, as the command line asks.
fn check_points(points: usize) -> PyResult<()> {
    if points < 100 {
        return Err(PyValueError::new_err(format!(
            "points {points}: at least 100 per surface"
        )));
    }
    Ok(())
}

#[pymethods]
impl PySectionFit {
    /// The airfoil's name (first line of the file).
    #[getter]
    fn name(&self) -> String {
        self.fit.params.name.trim().to_string()
    }

    /// The ten thickness parameters of Eq. (39) by name (r0, z1, z2, xtmax, tmax, crv4, x6,
    /// z6, phi_te, d78).
    #[getter]
    fn thickness<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let t = &self.fit.params.thickness;
        let d = PyDict::new(py);
        for (k, v) in [
            ("r0", t.r0),
            ("z1", t.z1),
            ("z2", t.z2),
            ("xtmax", t.xtmax),
            ("tmax", t.tmax),
            ("crv4", t.crv4),
            ("x6", t.x6),
            ("z6", t.z6),
            ("phi_te", t.phi_te),
            ("d78", t.d78),
        ] {
            d.set_item(k, v)?;
        }
        Ok(d)
    }

    /// Camber control points Q_j (`m × 2`, chord frame).
    #[getter]
    fn camber<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        arrays::points2(py, &self.fit.params.camber).into_any()
    }

    /// Extra thickness control points (`k × 2`, may be empty).
    #[getter]
    fn thickness_extra<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        arrays::points2(py, &self.fit.params.thickness.extra).into_any()
    }

    /// Trailing-edge thickness in chords.
    #[getter]
    fn te_thickness(&self) -> f64 {
        self.fit.params.te_thickness
    }

    /// Largest normal distance of the input points from the fit, in chords.
    #[getter]
    fn max_error(&self) -> f64 {
        self.fit.max_error
    }

    /// RMS normal distance, in chords.
    #[getter]
    fn rms_error(&self) -> f64 {
        self.fit.rms_error
    }

    /// Iterations of the fit.
    #[getter]
    fn iterations(&self) -> usize {
        self.fit.iterations
    }

    /// Number of fitted parameters.
    #[getter]
    fn n_design_variables(&self) -> usize {
        self.fit.n_design_variables
    }

    /// The input points in the chord frame (`n × 2`).
    #[getter]
    fn points<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        arrays::points2(py, &self.fit.points).into_any()
    }

    /// Signed normal distance of each input point from the fit, in chords.
    #[getter]
    fn distances<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        arrays::vector(py, &self.fit.distances).into_any()
    }

    /// Remarks of the airfoil reader.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }

    /// The section parameters as a dict (the PARAMS.ron fields; input of `section_build`).
    fn params<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        arrays::to_python(py, &self.fit.params)
    }

    /// The object `aeroshape section fit --json` prints.
    fn as_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let json = self.fit.summary_json();
        arrays::to_python(py, &json)
    }

    /// The fitted section in the input's coordinates (`(2·points + 1) × 2`, Selig order), as
    /// `aeroshape section fit --out` writes it.
    #[pyo3(signature = (points=120))]
    fn coordinates<'py>(&self, py: Python<'py>, points: usize) -> PyResult<Bound<'py, PyAny>> {
        check_points(points)?;
        let pts = py
            .detach(|| -> wingmaster::Result<Vec<[f64; 2]>> {
                let sec = self.fit.section()?;
                Ok(sec
                    .sample(points)
                    .into_iter()
                    .map(|p| self.fit.frame.to_global(p))
                    .collect())
            })
            .map_err(|e| errors::from_error(py, Kind::Section, &e))?;
        Ok(arrays::points2(py, &pts).into_any())
    }

    /// The name `aeroshape section fit --out` writes on the first line.
    #[getter]
    fn fitted_name(&self) -> String {
        format!("{} (aeroshape section fit)", self.airfoil_name.trim())
    }

    fn __repr__(&self) -> String {
        format!(
            "SectionFit({:?}: max error {:.3e}, rms {:.3e}, {} parameters)",
            self.fit.params.name.trim(),
            self.fit.max_error,
            self.fit.rms_error,
            self.fit.n_design_variables
        )
    }
}

/// Where the airfoil's points come from.
enum Source {
    File(PathBuf),
    Points(Vec<[f64; 2]>),
}

/// Fits the section parametrisation (ten thickness parameters of Eq. 39 plus a B-spline
/// camber line) to an airfoil: a Selig or Lednicer file, or an `n × 2` array of points in
/// Selig order (trailing edge, upper surface, leading edge, lower surface). The GIL is
/// released while it runs.
#[pyfunction]
#[pyo3(signature = (airfoil, *, camber_points=8, thickness_extra=0, name=None))]
pub fn section_fit(
    py: Python<'_>,
    airfoil: &Bound<'_, PyAny>,
    camber_points: usize,
    thickness_extra: usize,
    name: Option<String>,
) -> PyResult<PySectionFit> {
    let source = match airfoil.extract::<PathBuf>() {
        Ok(p) => Source::File(p),
        Err(_) => Source::Points(arrays::read_rows::<2>(airfoil, "airfoil")?),
    };
    let opts = FitOptions::default()
        .with_camber_points(camber_points)
        .with_thickness_extra(thickness_extra);
    let r = py.detach(|| -> Result<(Airfoil, SectionFit), String> {
        let (airfoil, shown) = match source {
            Source::File(p) => {
                let shown = p.display().to_string();
                let file = std::fs::File::open(&p)
                    .map_err(|e| errors::collapse(&format!("{shown}: cannot open: {e}")))?;
                let a = Airfoil::parse(BufReader::new(file), &shown)
                    .map_err(|e| errors::one_line(&e))?;
                (a, shown)
            }
            Source::Points(points) => {
                if let Some(i) = points
                    .iter()
                    .position(|p| !(p[0].is_finite() && p[1].is_finite()))
                {
                    return Err(format!("airfoil: point {i} is not finite"));
                }
                let a = Airfoil {
                    name: name.clone().unwrap_or_default(),
                    points,
                    warnings: Vec::new(),
                };
                (a, "airfoil".to_string())
            }
        };
        let f = wingmaster::fit(&airfoil, &opts).map_err(|e| {
            errors::collapse(&format!("{shown}: fit failed: {}", errors::one_line(&e)))
        })?;
        Ok((airfoil, f))
    });
    let (airfoil, fit) = r.map_err(|m| errors::raise(py, Kind::Section, m))?;
    Ok(PySectionFit {
        fit,
        airfoil_name: airfoil.name,
        warnings: airfoil.warnings,
    })
}

/// Builds a section from its parameters — a dict of the PARAMS.ron fields, a `SectionFit`,
/// or the path of a PARAMS.ron file — and returns `2·points + 1` points (`× 2`) in Selig
/// order, normalised (leading edge at (0, 0), chord 1), as `aeroshape section build` writes.
#[pyfunction]
#[pyo3(signature = (params, *, points=120))]
pub fn section_build<'py>(
    py: Python<'py>,
    params: &Bound<'py, PyAny>,
    points: usize,
) -> PyResult<Bound<'py, PyAny>> {
    check_points(points)?;
    let (params, shown): (SectionParams, String) = if let Ok(f) = params.cast::<PySectionFit>() {
        (f.get().fit.params.clone(), "params".into())
    } else if let Ok(p) = params.extract::<PathBuf>() {
        let shown = p.display().to_string();
        let text = std::fs::read_to_string(&p)
            .map_err(|e| errors::raise(py, Kind::Section, format!("{shown}: cannot read: {e}")))?;
        let params: SectionParams = ron::from_str(&text).map_err(|e| {
            errors::raise(
                py,
                Kind::Section,
                format!(
                    "{shown}:{}:{}: {}",
                    e.span.start.line, e.span.start.col, e.code
                ),
            )
        })?;
        (params, shown)
    } else {
        (arrays::from_python(params, "params")?, "params".into())
    };
    let pts = py
        .detach(|| params.build().map(|sec| sec.sample(points)))
        .map_err(|e| {
            errors::raise(
                py,
                Kind::Section,
                format!("{shown}: {}", errors::one_line(&e)),
            )
        })?;
    Ok(arrays::points2(py, &pts).into_any())
}

/// Writes points (`n × 2`) in Selig format (name line, then `x z` per line), as
/// `aeroshape section build` does; written to a temporary name and renamed.
#[pyfunction]
#[pyo3(signature = (path, coordinates, name="aeroshape section"))]
pub fn write_section(
    py: Python<'_>,
    path: PathBuf,
    coordinates: &Bound<'_, PyAny>,
    name: &str,
) -> PyResult<()> {
    let pts = arrays::read_rows::<2>(coordinates, "coordinates")?;
    py.detach(|| aeroshape::fsio::write_atomic(&path, |w| wingmaster::write_selig(w, name, &pts)))
        .map_err(|e| errors::from_error(py, Kind::Output, &e))
}
