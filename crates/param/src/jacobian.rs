//! The Jacobian d(control node coordinates)/d(design variables) in compressed sparse rows.
//!
//! Row 3k + c is coordinate c (x, y, z) of control node k; column l is design variable l in
//! design-vector order, in physical units (multiply column l by its scale for the scaled
//! variables, [`Jacobian::scaled`]).

use std::collections::BTreeMap;
use std::io::Write;

use geom_db::prelude::Vector3;
use serde::Serialize;

/// A sparse Jacobian (CSR).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Jacobian {
    /// Number of rows (3 × control nodes).
    pub n_rows: usize,
    /// Number of columns (design variables).
    pub n_cols: usize,
    /// Row start offsets into `col_idx` / `values` (`n_rows + 1` entries).
    pub row_ptr: Vec<usize>,
    /// Column of each stored entry, increasing within a row.
    pub col_idx: Vec<usize>,
    /// Value of each stored entry.
    pub values: Vec<f64>,
}

impl Jacobian {
    /// Builds the CSR matrix from per-node rows: `rows[k]` maps a column to d(node k)/dx_col.
    pub(crate) fn from_node_rows(rows: &[BTreeMap<usize, Vector3>], n_cols: usize) -> Self {
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
        Self {
            n_rows: 3 * rows.len(),
            n_cols,
            row_ptr,
            col_idx,
            values,
        }
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.values.len()
    }

    /// Entry (row, col) (0 when not stored).
    pub fn get(&self, row: usize, col: usize) -> f64 {
        let (a, b) = (self.row_ptr[row], self.row_ptr[row + 1]);
        match self.col_idx[a..b].binary_search(&col) {
            Ok(k) => self.values[a + k],
            Err(_) => 0.0,
        }
    }

    /// The dense matrix, row-major (`n_rows × n_cols`).
    pub fn to_dense(&self) -> Vec<Vec<f64>> {
        let mut d = vec![vec![0.0; self.n_cols]; self.n_rows];
        for (r, row) in d.iter_mut().enumerate() {
            for k in self.row_ptr[r]..self.row_ptr[r + 1] {
                row[self.col_idx[k]] = self.values[k];
            }
        }
        d
    }

    /// Column `col` as a dense vector.
    pub fn column(&self, col: usize) -> Vec<f64> {
        (0..self.n_rows).map(|r| self.get(r, col)).collect()
    }

    /// The Jacobian with respect to scaled variables x_l / scale_l (column l times scale_l).
    pub fn scaled(&self, scales: &[f64]) -> Self {
        let mut j = self.clone();
        for (v, &c) in j.values.iter_mut().zip(&j.col_idx) {
            *v *= scales[c];
        }
        j
    }

    /// Writes the Jacobian as one JSON object: `n_rows`, `n_cols`, `row_ptr`, `col_idx`,
    /// `values`, plus `variables` (column names) and `rows` = "3 * node + coordinate".
    pub fn write_json(&self, names: &[&str], mut w: impl Write) -> std::io::Result<()> {
        #[derive(Serialize)]
        struct Out<'a> {
            rows: &'static str,
            variables: &'a [&'a str],
            #[serde(flatten)]
            j: &'a Jacobian,
        }
        serde_json::to_writer(
            &mut w,
            &Out {
                rows: "3 * control_node + coordinate (0 = x, 1 = y, 2 = z)",
                variables: names,
                j: self,
            },
        )?;
        writeln!(w)
    }
}
