//! `deform(mesh, ...)`: the volume deformation of `aeroshape deform` (paper §4) with the
//! program's options as keywords, each flag's name with `-` → `_` (`--rotate-deg A` →
//! `rotate_deg=A`, `--no-rotation` → `no_rotation=True`); the same defaults, the same
//! choice between sliding on a plane and on the geometry's supports, the same messages.
//!
//! Per-node displacements (`--displacements FILE.csv` on the command line) are given as
//! arrays: `displacements=(nodes, d)` with `nodes` (k,) node indices and `d` (k × 3), or a
//! mapping `{node: (dx, dy, dz)}`.

use std::collections::HashSet;
use std::path::PathBuf;

use ::deform::{RigidMotion, SolverKind, Stiffness};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::arrays;
use crate::errors::{self, Kind};
use crate::grid::PyMesh;
use crate::progress::{self, Progress};

/// The result of `deform`: the deformed grid and what the solver did.
#[pyclass(frozen, module = "aeroshape._native", name = "Deformation")]
pub struct PyDeformation {
    mesh: Py<PyMesh>,
    /// Node coordinates of the deformed grid (`n × 3`).
    #[pyo3(get)]
    coordinates: Py<PyAny>,
    /// Signed quality of every cell of the deformed grid (the field the guard checked).
    #[pyo3(get)]
    cell_quality: Py<PyAny>,
    /// The solver's report (the `deform` object of `aeroshape deform --report`).
    #[pyo3(get)]
    report: Py<PyAny>,
}

#[pymethods]
impl PyDeformation {
    /// The deformed grid: the input's cells, markers and numbering with the new coordinates
    /// (nodes that slid on supports carry their new parameters).
    #[getter]
    fn mesh(&self, py: Python<'_>) -> Py<PyMesh> {
        self.mesh.clone_ref(py)
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        let it = |k: &str| {
            self.report
                .bind(py)
                .get_item(k)
                .map(|v| v.to_string())
                .unwrap_or_default()
        };
        format!(
            "Deformation({} iterations, residual {}, {} increments)",
            it("iterations"),
            it("residual"),
            it("increments")
        )
    }
}

/// A library name (`solver`, `stiffness`) parsed by the library's `FromStr`, its message
/// as the `ValueError`.
fn named<T: std::str::FromStr>(what: &str, name: &str) -> PyResult<T>
where
    T::Err: std::fmt::Display,
{
    name.parse()
        .map_err(|e| PyValueError::new_err(format!("{what}: {e}")))
}

/// The `displacements` argument: `(nodes, d)` or `{node: (dx, dy, dz)}`; checked as the
/// command line checks its CSV file (nodes exist, given once, finite values).
pub(crate) fn displacements(
    obj: &Bound<'_, PyAny>,
    n_nodes: usize,
) -> PyResult<Vec<(u32, [f64; 3])>> {
    let pairs: Vec<(i64, [f64; 3])> = if let Ok(d) = obj.cast::<PyDict>() {
        d.iter()
            .map(|(k, v)| -> PyResult<(i64, [f64; 3])> {
                let node: i64 = k.extract()?;
                let d = arrays::read_vector(&v, &format!("displacements[{node}]"))?;
                let d: [f64; 3] = d.try_into().map_err(|_| {
                    PyValueError::new_err(format!("displacements[{node}]: expected (dx, dy, dz)"))
                })?;
                Ok((node, d))
            })
            .collect::<PyResult<_>>()?
    } else if let Ok(t) = obj.cast::<PyTuple>()
        && t.len() == 2
    {
        let nodes = arrays::read_vector(&t.get_item(0)?, "displacements nodes")?;
        let d = arrays::read_rows::<3>(&t.get_item(1)?, "displacements values")?;
        if nodes.len() != d.len() {
            return Err(PyValueError::new_err(format!(
                "displacements: {} nodes for {} displacements",
                nodes.len(),
                d.len()
            )));
        }
        let mut out = Vec::with_capacity(nodes.len());
        for (&n, d) in nodes.iter().zip(d) {
            if n.fract() != 0.0 {
                return Err(PyValueError::new_err(format!(
                    "displacements: bad node index {n}"
                )));
            }
            out.push((n as i64, d));
        }
        out
    } else {
        return Err(PyValueError::new_err(
            "displacements: expected (nodes, d) or {node: (dx, dy, dz)}",
        ));
    };
    let mut seen = HashSet::new();
    let mut out = Vec::with_capacity(pairs.len());
    for (node, d) in pairs {
        if node < 0 || node as usize >= n_nodes {
            return Err(PyValueError::new_err(format!(
                "displacements: node {node} does not exist (the grid has {n_nodes} nodes)"
            )));
        }
        if d.iter().any(|x| !x.is_finite()) {
            return Err(PyValueError::new_err(format!(
                "displacements: node {node}: bad displacement {d:?}"
            )));
        }
        if !seen.insert(node) {
            return Err(PyValueError::new_err(format!(
                "displacements: node {node} given twice"
            )));
        }
        out.push((node as u32, d));
    }
    Ok(out)
}

fn vec3(v: [f64; 3], what: &str) -> PyResult<[f64; 3]> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(v)
    } else {
        Err(PyValueError::new_err(format!(
            "{what}: {v:?} is not three finite numbers"
        )))
    }
}

/// Deforms a volume grid from prescribed boundary motion (spring analogy with adaptation
/// matrices R, paper Eqs. 14–26); the GIL is released while it runs. See the module doc and
/// docs/python.md for the keywords.
#[pyfunction]
#[pyo3(name = "deform", signature = (
    mesh, *, rigid=Vec::new(), rotate_deg=0.0, axis_point=[0.0, 0.0, 0.0],
    axis_dir=[0.0, 0.0, 1.0], translate=[0.0, 0.0, 0.0], displacements=None,
    slide=Vec::new(), geometry=None, fixed=Vec::new(), solver="pcg",
    stiffness="inverse-length2", no_rotation=false, rotation_reach=None, tolerance=1e-8,
    allow_inverted=false, find_planes=false, progress=None
), text_signature = "(mesh, *, rigid=(), rotate_deg=0.0, axis_point=(0.0, 0.0, 0.0), \
    axis_dir=(0.0, 0.0, 1.0), translate=(0.0, 0.0, 0.0), displacements=None, slide=(), \
    geometry=None, fixed=(), solver='pcg', stiffness='inverse-length2', no_rotation=False, \
    rotation_reach=None, tolerance=1e-08, allow_inverted=False, find_planes=False, \
    progress=None)")]
pub fn deform_mesh(
    py: Python<'_>,
    mesh: PyRef<'_, PyMesh>,
    rigid: Vec<String>,
    rotate_deg: f64,
    axis_point: [f64; 3],
    axis_dir: [f64; 3],
    translate: [f64; 3],
    displacements: Option<Bound<'_, PyAny>>,
    slide: Vec<String>,
    geometry: Option<PathBuf>,
    fixed: Vec<String>,
    solver: &str,
    stiffness: &str,
    no_rotation: bool,
    rotation_reach: Option<f64>,
    tolerance: f64,
    allow_inverted: bool,
    find_planes: bool,
    progress: Option<Bound<'_, PyAny>>,
) -> PyResult<PyDeformation> {
    let m = &mesh.inner;
    let motion = Motion {
        rigid,
        rotate_deg,
        axis_point,
        axis_dir,
        translate,
    };
    let mut request = self::request(
        m.n_nodes(),
        motion,
        displacements.as_ref(),
        slide,
        fixed,
        [solver, stiffness],
        Rotation {
            off: no_rotation,
            reach: rotation_reach,
        },
        tolerance,
        allow_inverted,
    )?;
    // as `aeroshape deform`: a node of a fixed marker never moves where it meets a sliding one
    aeroshape::precedence::hold_fixed_nodes(m, &mut request);
    // as `aeroshape deform --find-planes`: a marker not named that is a symmetry plane by its
    // shape slides
    if find_planes {
        let planes = request.symmetry_planes(m);
        if !planes.is_empty() {
            let log = py
                .import("logging")?
                .call_method1("getLogger", ("aeroshape",))?;
            for (name, dev) in planes {
                log.call_method1(
                    "info",
                    (format!(
                        "marker {name} slides on its plane (not named; a plane touching the \
                         moving markers, nodes within {dev:.1e} of it, find_planes=True); \
                         fixed=[\"{name}\"] holds it"
                    ),),
                )?;
                request.slide.push(name);
            }
            aeroshape::precedence::hold_fixed_nodes(m, &mut request);
        }
    }
    let mut prog = Progress::new(py, "deform", progress)?;
    let result = py.detach(|| -> Result<_, (Kind, String)> {
        let geometry = match &geometry {
            Some(p) => {
                let text = std::fs::read_to_string(p)
                    .map_err(|e| (Kind::Geometry, format!("{}: {e}", p.display())))?;
                Some(
                    geom_db::GeomDb::from_ron_str(&text, &p.display().to_string())
                        .map_err(|e| (Kind::Geometry, errors::one_line(&e)))?,
                )
            }
            None => None,
        };
        let mut report = |phase: &str, done: usize, total: usize| prog.report(phase, done, total);
        let d = request
            .run(m, geometry.as_ref(), &mut report)
            .map_err(|e| (Kind::Deform, errors::one_line(&e)))?;
        let mut out = m.clone();
        ::deform::request::apply(&mut out, &d);
        Ok((out, d))
    });
    prog.finish()?;
    let (out, d) = result.map_err(|(k, msg)| errors::raise(py, k, msg))?;
    for note in &d.report.notes {
        progress::log(py, progress::INFO, || format!("note: {note}"))?;
    }
    Ok(PyDeformation {
        coordinates: arrays::coords(py, &out.coords).into_any().unbind(),
        cell_quality: arrays::vector(py, &d.cell_quality).into_any().unbind(),
        report: arrays::to_python(py, &d.report)?.unbind(),
        mesh: Py::new(py, PyMesh::from_rust(out))?,
    })
}

/// The rigid motion keywords of `deform`.
#[derive(Clone)]
pub(crate) struct Motion {
    pub rigid: Vec<String>,
    pub rotate_deg: f64,
    pub axis_point: [f64; 3],
    pub axis_dir: [f64; 3],
    pub translate: [f64; 3],
}

/// The rotation keywords of `deform`: `no_rotation` and `rotation_reach` (None: R reaches
/// everywhere).
#[derive(Clone, Copy)]
pub(crate) struct Rotation {
    pub off: bool,
    pub reach: Option<f64>,
}

/// The deformation request of the keywords of `deform` on a grid of `n_nodes` nodes, checked
/// as the command line checks its flags (`[solver, stiffness]` by their names).
pub(crate) fn request(
    n_nodes: usize,
    motion: Motion,
    displacements: Option<&Bound<'_, PyAny>>,
    slide: Vec<String>,
    fixed: Vec<String>,
    [solver, stiffness]: [&str; 2],
    rotation: Rotation,
    tolerance: f64,
    allow_inverted: bool,
) -> PyResult<::deform::Request> {
    let Motion {
        rigid,
        rotate_deg,
        axis_point,
        axis_dir,
        translate,
    } = motion;
    if rigid.is_empty() && (rotate_deg != 0.0 || translate != [0.0; 3]) {
        return Err(PyValueError::new_err(
            "rotate_deg/translate need a marker to move: give rigid=[MARKER]",
        ));
    }
    if !rotate_deg.is_finite() {
        return Err(PyValueError::new_err(format!(
            "rotate_deg: {rotate_deg} is not a finite number"
        )));
    }
    if let Some(l) = rotation.reach.filter(|l| l.is_nan() || *l < 0.0) {
        return Err(PyValueError::new_err(format!(
            "rotation_reach: {l} is not a length ≥ 0 (inf: R reaches everywhere)"
        )));
    }
    if rotation.off && rotation.reach.is_some() {
        return Err(PyValueError::new_err(
            "rotation_reach: R is off (no_rotation=True); give one or the other",
        ));
    }
    if !(tolerance.is_finite() && tolerance > 0.0) {
        return Err(PyValueError::new_err(format!(
            "tolerance: {tolerance} must be a positive number"
        )));
    }
    let motion = RigidMotion {
        angle_deg: rotate_deg,
        axis_point: vec3(axis_point, "axis_point")?,
        axis_dir: vec3(axis_dir, "axis_dir")?,
        translation: vec3(translate, "translate")?,
    };
    Ok(::deform::Request {
        rigid,
        motion,
        displacements: match displacements {
            Some(d) => self::displacements(d, n_nodes)?,
            None => Vec::new(),
        },
        slide,
        fixed,
        solver: named::<SolverKind>("solver", solver)?,
        stiffness: named::<Stiffness>("stiffness", stiffness)?,
        adapt_rotation: !rotation.off,
        rotation_reach: rotation.reach,
        rel_tol: tolerance,
        allow_inverted,
    })
}
