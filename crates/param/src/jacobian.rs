//! The Jacobian d(control node coordinates)/d(design variables) as a [`sprs::CsMat`] in
//! compressed sparse rows, the workspace's interchange type for sparse matrices.
//!
//! Row 3k + c is coordinate c (x, y, z) of control node k; column l is design variable l in
//! design-vector order, in physical units (multiply column l by its scale for the scaled
//! variables, [`scaled`]). Within a row the columns increase.

use std::collections::BTreeMap;
use std::io::Write;

use geom_db::prelude::Vector3;
use serde::Serialize;
use sprs::CsMat;

/// The Jacobian (CSR, `3 × control nodes` rows, one column per design variable).
pub type Jacobian = CsMat<f64>;

/// Builds the CSR matrix from per-node rows: `rows[k]` maps a column to d(node k)/dx_col.
pub(crate) fn from_node_rows(rows: &[BTreeMap<usize, Vector3>], n_cols: usize) -> Jacobian {
    let mut row_ptr = Vec::with_capacity(3 * rows.len() + 1);
    let mut col_idx = Vec::new();
    let mut values = Vec::new();
    row_ptr.push(0);
    for r in rows {
        for c in 0..3 {
            for (&col, v) in r {
                if v[c] != 0.0 {
                    col_idx.push(col);
                    values.push(v[c]);
                }
            }
            row_ptr.push(col_idx.len());
        }
    }
    // The columns of a row come sorted and unique from the map, and every column is below
    // `n_cols` (the registry's size), so the structure is valid by construction.
    CsMat::new((3 * rows.len(), n_cols), row_ptr, col_idx, values)
}

/// Column `col` of `j` as a dense vector.
pub fn column(j: &Jacobian, col: usize) -> Vec<f64> {
    (0..j.rows())
        .map(|r| j.get(r, col).copied().unwrap_or(0.0))
        .collect()
}

/// The Jacobian with respect to scaled variables x_l / scale_l (column l times scale_l).
pub fn scaled(j: &Jacobian, scales: &[f64]) -> Jacobian {
    let mut out = j.clone();
    let cols = out.indices().to_vec();
    for (v, c) in out.data_mut().iter_mut().zip(cols) {
        *v *= scales[c];
    }
    out
}

/// Writes the Jacobian as one JSON object: `n_rows`, `n_cols`, `row_ptr`, `col_idx`,
/// `values` (the CSR arrays), plus `variables` (column names) and `rows` = "3 * node +
/// coordinate".
pub fn write_json(j: &Jacobian, names: &[&str], mut w: impl Write) -> std::io::Result<()> {
    #[derive(Serialize)]
    struct Out<'a> {
        rows: &'static str,
        variables: &'a [&'a str],
        n_rows: usize,
        n_cols: usize,
        row_ptr: &'a [usize],
        col_idx: &'a [usize],
        values: &'a [f64],
    }
    let indptr = j.indptr();
    let row_ptr = indptr.to_proper();
    serde_json::to_writer(
        &mut w,
        &Out {
            rows: "3 * control_node + coordinate (0 = x, 1 = y, 2 = z)",
            variables: names,
            n_rows: j.rows(),
            n_cols: j.cols(),
            row_ptr: &row_ptr,
            col_idx: j.indices(),
            values: j.data(),
        },
    )?;
    writeln!(w)
}
