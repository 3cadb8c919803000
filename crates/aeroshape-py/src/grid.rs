//! `Mesh`, `read_mesh` and `write_mesh`: [`mesh::Mesh`] for Python, its nodes and elements
//! as numpy arrays (coordinates `n × 3` float64; connectivity `m × k` int64 per element kind,
//! 0-based; markers by name), read and written as `aeroshape mesh convert` does.
//!
//! Element kinds are named as the `mesh` crate names them: "line", "triangle", "quad",
//! "tetra", "pyramid", "prism", "hexa" (meshio: "line", "triangle", "quad", "tetra",
//! "pyramid", "wedge", "hexahedron"), in VTK's node orders (meshio's wedge is in Gmsh's:
//! columns 0, 2, 1, 3, 5, 4 give ours). The arrays a `Mesh` hands out are read-only copies:
//! change the coordinates by assigning `mesh.coordinates = new`.

use std::path::PathBuf;

use mesh::io::Format;
use mesh::{ALL_KINDS, ElementKind, Elements, Marker};
use numpy::PyArray1;
use numpy::ndarray::ArrayView1;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arrays;
use crate::errors::{self, Kind};
use crate::progress;

/// An unstructured grid (see the module doc).
#[pyclass(module = "aeroshape._native", name = "Mesh")]
#[derive(Debug, Clone)]
pub struct PyMesh {
    pub(crate) inner: mesh::Mesh,
}

impl PyMesh {
    /// Wraps a Rust grid.
    pub fn from_rust(inner: mesh::Mesh) -> Self {
        Self { inner }
    }
}

fn kind_named(name: &str) -> PyResult<ElementKind> {
    ALL_KINDS
        .into_iter()
        .find(|k| k.name() == name)
        .ok_or_else(|| {
            PyValueError::new_err(format!(
                "unknown element kind '{name}' (use {})",
                ALL_KINDS.map(|k| k.name()).join(", ")
            ))
        })
}

/// Elements from `{kind: m × k array}`.
fn elements(d: &Bound<'_, PyDict>, what: &str) -> PyResult<Elements> {
    let mut set = Elements::new();
    for (k, v) in d.iter() {
        let name: String = k.extract()?;
        let kind = kind_named(&name)?;
        let label = format!("{what}[{name:?}]");
        let (nodes, per) = arrays::read_connectivity(&v, &label)?;
        if per != kind.n_nodes() && !nodes.is_empty() {
            return Err(PyValueError::new_err(format!(
                "{label}: {per} nodes per element; a {name} has {}",
                kind.n_nodes()
            )));
        }
        set.group_mut(kind).nodes.extend_from_slice(&nodes);
    }
    set.prune();
    Ok(set)
}

/// `{kind: read-only m × k int64 array}` of an element set.
fn element_dict<'py>(py: Python<'py>, set: &Elements) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for g in set.groups() {
        let a = arrays::connectivity(py, &g.nodes, g.kind.n_nodes());
        d.set_item(g.kind.name(), arrays::read_only(a)?)?;
    }
    Ok(d)
}

#[pymethods]
impl PyMesh {
    /// A grid from arrays: `coordinates` (`n × 3`), `cells` (`{kind: m × k}` node indices,
    /// 0-based), `markers` (`{name: {kind: m × k}}`, boundary elements), `dim` (3, or 2
    /// with z = 0). The grid is validated (indices in range, kinds of the right dimension).
    #[new]
    #[pyo3(signature = (coordinates, cells, markers=None, dim=3))]
    fn new(
        py: Python<'_>,
        coordinates: &Bound<'_, PyAny>,
        cells: &Bound<'_, PyDict>,
        markers: Option<&Bound<'_, PyDict>>,
        dim: u8,
    ) -> PyResult<Self> {
        let mut m = mesh::Mesh::new(dim);
        m.coords = arrays::read_rows::<3>(coordinates, "coordinates")?;
        m.cells = elements(cells, "cells")?;
        if let Some(markers) = markers {
            for (name, set) in markers.iter() {
                let name: String = name.extract()?;
                let set = set.cast_into::<PyDict>().map_err(|_| {
                    PyValueError::new_err(format!(
                        "markers[{name:?}]: expected a dict {{kind: m × k array}}"
                    ))
                })?;
                let elements = elements(&set, &format!("markers[{name:?}]"))?;
                m.markers.push(Marker {
                    name,
                    tag: None,
                    elements,
                });
            }
        }
        m.validate()
            .map_err(|e| errors::from_error(py, Kind::Mesh, &e))?;
        Ok(Self { inner: m })
    }

    /// Spatial dimension (2 or 3).
    #[getter]
    fn dim(&self) -> u8 {
        self.inner.dim
    }

    /// Number of nodes.
    #[getter]
    fn n_nodes(&self) -> usize {
        self.inner.n_nodes()
    }

    /// Number of cells (all kinds).
    #[getter]
    fn n_cells(&self) -> usize {
        self.inner.cells.len()
    }

    /// Node coordinates, `n × 3` float64 (a read-only copy; assign to change them).
    #[getter]
    fn get_coordinates<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        arrays::read_only(arrays::coords(py, &self.inner.coords))
    }

    /// Replaces the node coordinates (`n × 3`, same `n`, finite).
    #[setter]
    fn set_coordinates(&mut self, value: &Bound<'_, PyAny>) -> PyResult<()> {
        let c = arrays::read_rows::<3>(value, "coordinates")?;
        if c.len() != self.inner.n_nodes() {
            return Err(PyValueError::new_err(format!(
                "coordinates: {} rows for a grid of {} nodes",
                c.len(),
                self.inner.n_nodes()
            )));
        }
        if let Some(i) = c.iter().position(|p| p.iter().any(|x| !x.is_finite())) {
            return Err(PyValueError::new_err(format!(
                "coordinates: node {i} has a non-finite coordinate"
            )));
        }
        self.inner.coords = c;
        Ok(())
    }

    /// Cells by kind: `{kind: m × k int64}` (read-only copies).
    #[getter]
    fn cells<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        element_dict(py, &self.inner.cells)
    }

    /// Boundary markers: `{name: {kind: m × k int64}}` (read-only copies), in file order.
    #[getter]
    fn markers<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for m in &self.inner.markers {
            d.set_item(&m.name, element_dict(py, &m.elements)?)?;
        }
        Ok(d)
    }

    /// Node classification (MSH input), or None: `{"dim": uint8 (n,), "entity": int32 (n,),
    /// "param": float64 (n, 2)}` — entity dimension, entity tag, parametric coordinates.
    #[getter]
    fn node_classes<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let Some(c) = &self.inner.classes else {
            return Ok(None);
        };
        let d = PyDict::new(py);
        let dims: Vec<u8> = c.iter().map(|c| c.dim).collect();
        let ents: Vec<i32> = c.iter().map(|c| c.entity).collect();
        let params: Vec<[f64; 2]> = c.iter().map(|c| c.param).collect();
        d.set_item(
            "dim",
            PyArray1::from_array(py, &ArrayView1::from(&dims[..])),
        )?;
        d.set_item(
            "entity",
            PyArray1::from_array(py, &ArrayView1::from(&ents[..])),
        )?;
        d.set_item("param", arrays::points2(py, &params))?;
        Ok(Some(d))
    }

    /// True when curve and surface nodes carry parametric coordinates (MSH `parametric`).
    #[getter]
    fn parametric(&self) -> bool {
        self.inner.parametric
    }

    /// Remarks of the reader (skipped sections, SU2 trailing sections kept verbatim).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.inner.warnings.clone()
    }

    /// Signed cell quality (DESIGN measure: mean ratio of tetrahedra and triangles; NaN for
    /// kinds not measured), one value per cell in kind order.
    fn cell_quality<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        let q = py.detach(|| mesh::quality::cell_quality(&self.inner));
        arrays::vector(py, &q).into_any()
    }

    /// An independent copy.
    fn copy(&self) -> Self {
        self.clone()
    }

    fn __repr__(&self) -> String {
        let kinds: Vec<String> = self
            .inner
            .cells
            .groups()
            .iter()
            .map(|g| format!("{} {}", g.len(), g.kind.name()))
            .collect();
        format!(
            "Mesh({}-D, {} nodes, cells: {}, markers: {:?})",
            self.inner.dim,
            self.inner.n_nodes(),
            kinds.join(", "),
            self.inner
                .markers
                .iter()
                .map(|m| m.name.as_str())
                .collect::<Vec<_>>()
        )
    }
}

/// Reads a grid file (`.su2`, `.msh` Gmsh 4.1 ASCII or binary, `.vtu`), by extension.
#[pyfunction]
pub fn read_mesh(py: Python<'_>, path: PathBuf) -> PyResult<PyMesh> {
    let m = py
        .detach(|| mesh::io::read_path(&path))
        .map_err(|e| errors::from_error(py, Kind::Mesh, &e))?;
    for w in &m.warnings {
        progress::log(py, progress::WARNING, || w.clone())?;
    }
    Ok(PyMesh::from_rust(m))
}

/// Writes `mesh` to `path` (`.su2`, `.msh`, `.vtu`, by extension) as `aeroshape mesh convert`
/// does: `binary` writes binary MSH (default ASCII), `base64` writes VTU with inline base64
/// arrays (default raw appended). Written to a temporary name and renamed.
#[pyfunction]
#[pyo3(signature = (path, mesh, *, binary=false, base64=false))]
pub fn write_mesh(
    py: Python<'_>,
    path: PathBuf,
    mesh: PyRef<'_, PyMesh>,
    binary: bool,
    base64: bool,
) -> PyResult<()> {
    let format = match Format::from_path(&path) {
        Some(Format::Msh(_)) => Format::Msh(if binary {
            mesh::msh::Encoding::Binary
        } else {
            mesh::msh::Encoding::Ascii
        }),
        Some(Format::Vtu(_)) => Format::Vtu(if base64 {
            mesh::vtu::VtuEncoding::Base64
        } else {
            mesh::vtu::VtuEncoding::AppendedRaw
        }),
        Some(f) => f,
        None => {
            return Err(errors::raise(
                py,
                Kind::Output,
                format!(
                    "{}: unknown output format (use .su2, .msh or .vtu)",
                    path.display()
                ),
            ));
        }
    };
    let m = &mesh.inner;
    py.detach(|| aeroshape::fsio::write_atomic(&path, |w| mesh::io::write(m, format, w)))
        .map_err(|e| errors::from_error(py, Kind::Output, &e))
}
