//! numpy arrays and plain Python values to and from Rust data. Every array handed to Python
//! is allocated by numpy and filled by one copy (`PyArray::from_array`), so it owns its memory
//! (`flags.owndata`) and aliases nothing of Rust's; every array read from Python is copied
//! into a Rust `Vec` before the GIL is released.

use numpy::ndarray::{ArrayView1, ArrayView2};
use numpy::{AllowTypeChange, PyArray1, PyArray2, PyArrayLike1, PyArrayLike2};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::PyDict;
use serde::Serialize;
use serde::de::DeserializeOwned;

/// An `n × 3` float64 array of node coordinates.
pub fn coords<'py>(py: Python<'py>, c: &[[f64; 3]]) -> Bound<'py, PyArray2<f64>> {
    let view =
        ArrayView2::from_shape((c.len(), 3), c.as_flattened()).expect("n × 3 view of n points");
    PyArray2::from_array(py, &view)
}

/// An `n × 2` float64 array of planar points.
pub fn points2<'py>(py: Python<'py>, c: &[[f64; 2]]) -> Bound<'py, PyArray2<f64>> {
    let view =
        ArrayView2::from_shape((c.len(), 2), c.as_flattened()).expect("n × 2 view of n points");
    PyArray2::from_array(py, &view)
}

/// A float64 vector.
pub fn vector<'py>(py: Python<'py>, v: &[f64]) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_array(py, &ArrayView1::from(v))
}

/// An int64 vector of node or element indices.
pub fn indices<'py>(py: Python<'py>, v: &[u32]) -> Bound<'py, PyArray1<i64>> {
    let wide: Vec<i64> = v.iter().map(|&i| i64::from(i)).collect();
    PyArray1::from_array(py, &ArrayView1::from(&wide[..]))
}

/// An int64 vector of global node ids.
pub fn ids<'py>(py: Python<'py>, v: &[u64]) -> PyResult<Bound<'py, PyArray1<i64>>> {
    let wide = v
        .iter()
        .map(|&i| i64::try_from(i))
        .collect::<Result<Vec<i64>, _>>()
        .map_err(|_| PyValueError::new_err("a global id beyond int64"))?;
    Ok(PyArray1::from_array(py, &ArrayView1::from(&wide[..])))
}

/// Reads a 1-D array-like of non-negative integers (global ids) into a `Vec`.
pub fn read_ids(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<u64>> {
    let a: PyArrayLike1<'_, i64, AllowTypeChange> = obj.extract().map_err(|_| {
        PyTypeError::new_err(format!(
            "{what}: expected a one-dimensional array of integers"
        ))
    })?;
    a.as_array()
        .iter()
        .enumerate()
        .map(|(k, &g)| {
            u64::try_from(g).map_err(|_| {
                PyValueError::new_err(format!("{what}: entry {k} is {g}, not a global id"))
            })
        })
        .collect()
}

/// A dense `rows × cols` float64 matrix from its rows (all of length `cols`).
pub fn matrix<'py>(py: Python<'py>, rows: &[Vec<f64>], cols: usize) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = rows.iter().flatten().copied().collect();
    let view = ArrayView2::from_shape((rows.len(), cols), &flat).expect("rows of equal length");
    PyArray2::from_array(py, &view)
}

/// An `m × k` int64 array of connectivity (`k` node indices per element).
pub fn connectivity<'py>(py: Python<'py>, nodes: &[u32], k: usize) -> Bound<'py, PyArray2<i64>> {
    let wide: Vec<i64> = nodes.iter().map(|&v| i64::from(v)).collect();
    let view = ArrayView2::from_shape((wide.len() / k.max(1), k), &wide)
        .expect("k node indices per element");
    PyArray2::from_array(py, &view)
}

/// Marks `array` read-only (`flags.writeable = False`): a copy that writes would not reach
/// the object it came from says so instead of doing nothing.
pub fn read_only<'py, T>(array: Bound<'py, T>) -> PyResult<Bound<'py, PyAny>> {
    let any = array.into_any();
    let kwargs = PyDict::new(any.py());
    kwargs.set_item("write", false)?;
    any.call_method("setflags", (), Some(&kwargs))?;
    Ok(any)
}

/// Reads a 1-D array-like of numbers (list, tuple, any numeric numpy array) into a `Vec`.
pub fn read_vector(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<f64>> {
    let a: PyArrayLike1<'_, f64, AllowTypeChange> = obj.extract().map_err(|_| {
        PyTypeError::new_err(format!(
            "{what}: expected a one-dimensional array of numbers"
        ))
    })?;
    Ok(a.as_array().to_vec())
}

/// Reads an `n × k` array-like of numbers into rows of `K` values.
pub fn read_rows<const K: usize>(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<[f64; K]>> {
    let a: PyArrayLike2<'_, f64, AllowTypeChange> = obj.extract().map_err(|_| {
        PyTypeError::new_err(format!("{what}: expected an n × {K} array of numbers"))
    })?;
    let v = a.as_array();
    if v.ncols() != K {
        return Err(PyValueError::new_err(format!(
            "{what}: expected an n × {K} array, got shape {:?}",
            v.shape()
        )));
    }
    Ok(v.rows()
        .into_iter()
        .map(|r| std::array::from_fn(|k| r[k]))
        .collect())
}

/// Reads an `m × k` array-like of non-negative integers (connectivity) into a flat `Vec`
/// and `k`.
pub fn read_connectivity(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<(Vec<u32>, usize)> {
    let a: PyArrayLike2<'_, i64, AllowTypeChange> = obj.extract().map_err(|_| {
        PyTypeError::new_err(format!("{what}: expected an m × k array of node indices"))
    })?;
    let v = a.as_array();
    let k = v.ncols();
    let mut out = Vec::with_capacity(v.len());
    for (e, row) in v.rows().into_iter().enumerate() {
        for &n in row {
            out.push(u32::try_from(n).map_err(|_| {
                PyValueError::new_err(format!(
                    "{what}: element {e} has node index {n}, not in 0..2^32"
                ))
            })?);
        }
    }
    Ok((out, k))
}

/// A Python value (dict, list, number, string) from a serialisable Rust value, through JSON
/// (`json.loads`), so that it reads exactly as the command line's JSON files do.
pub fn to_python<'py>(py: Python<'py>, value: &impl Serialize) -> PyResult<Bound<'py, PyAny>> {
    static LOADS: PyOnceLock<Py<PyAny>> = PyOnceLock::new();
    let text =
        serde_json::to_string(value).map_err(|e| PyValueError::new_err(format!("json: {e}")))?;
    LOADS.import(py, "json", "loads")?.call1((text,))
}

/// A Rust value from a Python value (dict, list, number, string), through JSON
/// (`json.dumps`); `what` names the argument in errors.
pub fn from_python<T: DeserializeOwned>(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<T> {
    let text: String = obj
        .py()
        .import("json")?
        .call_method1("dumps", (obj,))
        .and_then(|t| t.extract())
        .map_err(|e| PyTypeError::new_err(format!("{what}: not JSON-like ({e})")))?;
    serde_json::from_str(&text).map_err(|e| PyValueError::new_err(format!("{what}: {e}")))
}
