//! Sensitivity files of a flow solver's adjoint: dJ/dX per grid node, read for
//! `aeroshape gradient` (issue 22), in SU2's own ASCII layouts:
//!
//! * **volume** (`RESTART_ASCII`, SU2's `CSU2FileWriter`): a header of quoted names,
//!   `"PointID","x","y","z",…,"Sensitivity_x","Sensitivity_y","Sensitivity_z",…`, then one
//!   row per grid node: its global index, then the values, separated by `", "`;
//! * **surface** (`SURFACE_CSV`, SU2's `CCSVFileWriter`, e.g. `surface_sens.csv`): the same
//!   with the first column `"Point"`, one row per node of the written markers.
//!
//! * **VTU** (`.vtu`: SU2's `PARAVIEW_XML` volume output, or any VTK XML writer): a
//!   point-data vector named `Sensitivity` (2 or 3 components), one per grid node in the
//!   grid's node order (read by `mesh::vtu::read_with_point_data`). A VTU has no point IDs:
//!   its points are returned ([`Sensitivity::points`]) and [`check_points`] compares them
//!   with the grid's nodes.
//!
//! Node indices are the grid's, from 0 (SU2's global point index of the same `.su2` grid).
//! A volume file must give every node exactly once; a surface file every wall node exactly
//! once (and nothing else). Any other file is an error naming the file and the first bad
//! line (1-based) or point. Without a `Sensitivity_z` column (a 2-D solver) z is zero.

use std::path::{Path, PathBuf};

/// What a sensitivity file covers.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Layout {
    /// Every grid node (`"PointID"` first).
    Volume,
    /// The wall nodes (`"Point"` first).
    Surface,
}

/// A sensitivity file read and checked against a grid.
#[derive(Debug, Clone, PartialEq)]
pub struct Sensitivity {
    /// Its layout.
    pub layout: Layout,
    /// dJ/dX per grid node (zero where the file gives nothing: off the wall of a surface
    /// file).
    pub values: Vec<[f64; 3]>,
    /// Rows read (points of a VTU).
    pub rows: usize,
    /// The file's point coordinates, where it gives them instead of point IDs (a VTU), in
    /// the grid's node order: to be checked against the grid ([`check_points`]).
    pub points: Option<Vec<[f64; 3]>>,
}

/// Errors of [`read`]; each names the file and, where there is one, the line.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SensitivityError {
    /// The file could not be read.
    #[error("{}: {source}", file.display())]
    Read {
        /// The file.
        file: PathBuf,
        /// The error.
        #[source]
        source: std::io::Error,
    },
    /// A line that does not fit the layout.
    #[error("{}:{line}: {reason}", file.display())]
    Line {
        /// The file.
        file: PathBuf,
        /// The line (1-based).
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// A VTU file that does not fit the grid (its points or its `Sensitivity` array).
    #[error("{}: {reason}", file.display())]
    Points {
        /// The file.
        file: PathBuf,
        /// What is wrong, naming the first bad point.
        reason: String,
    },
    /// A VTU file that is not a valid VTK XML unstructured grid.
    #[error(transparent)]
    Vtu(#[from] mesh::Error),
}

fn bad(file: &Path, line: usize, reason: impl Into<String>) -> SensitivityError {
    SensitivityError::Line {
        file: file.to_path_buf(),
        line,
        reason: reason.into(),
    }
}

/// Reads the sensitivity file `file` for a grid of `n_nodes` nodes whose wall nodes are
/// `wall` (one flag per node). See the module doc.
pub fn read(file: &Path, n_nodes: usize, wall: &[bool]) -> Result<Sensitivity, SensitivityError> {
    if file
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("vtu"))
    {
        return read_vtu(file, n_nodes);
    }
    let text = std::fs::read_to_string(file).map_err(|source| SensitivityError::Read {
        file: file.to_path_buf(),
        source,
    })?;
    parse(&text, file, n_nodes, wall)
}

/// [`read`] of text already in memory (`file` names it in messages).
pub fn parse(
    text: &str,
    file: &Path,
    n_nodes: usize,
    wall: &[bool],
) -> Result<Sensitivity, SensitivityError> {
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let Some((h0, header)) = lines.next() else {
        return Err(bad(
            file,
            1,
            "empty file: expected SU2's CSV header (\"PointID\",…)",
        ));
    };
    let names: Vec<String> = header
        .split(',')
        .map(|s| s.trim().trim_matches('"').to_string())
        .collect();
    let layout = match names.first().map(String::as_str) {
        Some("PointID") => Layout::Volume,
        Some("Point") => Layout::Surface,
        other => {
            return Err(bad(
                file,
                h0 + 1,
                format!(
                    "the first column is {:?}; SU2 writes \"PointID\" (volume, RESTART_ASCII) or \"Point\" (surface CSV)",
                    other.unwrap_or("")
                ),
            ));
        }
    };
    let col = |n: &str| names.iter().position(|c| c == n);
    let (Some(cx), Some(cy)) = (col("Sensitivity_x"), col("Sensitivity_y")) else {
        return Err(bad(
            file,
            h0 + 1,
            "no \"Sensitivity_x\" and \"Sensitivity_y\" columns (SU2 writes them with OUTPUT_FILES and the SENSITIVITY volume/surface output)",
        ));
    };
    let cz = col("Sensitivity_z");
    let expected = match layout {
        Layout::Volume => n_nodes,
        Layout::Surface => wall.iter().filter(|w| **w).count(),
    };
    let mut values = vec![[0.0; 3]; n_nodes];
    let mut seen = vec![false; n_nodes];
    let mut rows = 0;
    let mut last_line = h0 + 1;
    for (k, line) in lines {
        last_line = k + 1;
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        if f.len() != names.len() {
            return Err(bad(
                file,
                k + 1,
                format!("{} values for {} columns", f.len(), names.len()),
            ));
        }
        let id: usize = f[0].parse().map_err(|_| {
            bad(
                file,
                k + 1,
                format!("point index {:?} is not an integer", f[0]),
            )
        })?;
        if id >= n_nodes {
            return Err(bad(
                file,
                k + 1,
                format!("point {id} is not a node of the grid ({n_nodes} nodes)"),
            ));
        }
        if layout == Layout::Surface && !wall[id] {
            return Err(bad(file, k + 1, format!("point {id} is not a wall node")));
        }
        if seen[id] {
            return Err(bad(file, k + 1, format!("point {id} given twice")));
        }
        seen[id] = true;
        let num = |c: usize| -> Result<f64, SensitivityError> {
            let v: f64 = f[c].parse().map_err(|_| {
                bad(
                    file,
                    k + 1,
                    format!("{:?} of column {:?} is not a number", f[c], names[c]),
                )
            })?;
            if v.is_finite() {
                Ok(v)
            } else {
                Err(bad(
                    file,
                    k + 1,
                    format!("{} of column {:?} is not finite", f[c], names[c]),
                ))
            }
        };
        values[id] = [num(cx)?, num(cy)?, cz.map_or(Ok(0.0), num)?];
        rows += 1;
    }
    if rows != expected {
        let missing = (0..n_nodes)
            .find(|&i| !seen[i] && (layout == Layout::Volume || wall[i]))
            .map_or(String::new(), |i| format!("; first missing: point {i}"));
        let what = match layout {
            Layout::Volume => "grid nodes",
            Layout::Surface => "wall nodes",
        };
        return Err(bad(
            file,
            last_line,
            format!("{rows} points for {expected} {what}{missing}"),
        ));
    }
    Ok(Sensitivity {
        layout,
        values,
        rows,
        points: None,
    })
}

fn bad_points(file: &Path, reason: impl Into<String>) -> SensitivityError {
    SensitivityError::Points {
        file: file.to_path_buf(),
        reason: reason.into(),
    }
}

/// Reads the `Sensitivity` point-data vector of the VTU `file` for a grid of `n_nodes`
/// nodes (module doc): volume layout, with the file's points.
pub fn read_vtu(file: &Path, n_nodes: usize) -> Result<Sensitivity, SensitivityError> {
    let f = std::fs::File::open(file).map_err(|source| SensitivityError::Read {
        file: file.to_path_buf(),
        source,
    })?;
    let (m, data) = mesh::vtu::read_with_point_data(std::io::BufReader::new(f), file)?;
    let Some(a) = data.iter().find(|a| a.name == "Sensitivity") else {
        let names: Vec<&str> = data.iter().map(|a| a.name.as_str()).collect();
        return Err(bad_points(
            file,
            format!(
                "no point-data array named \"Sensitivity\" (point data: {names:?}; SU2 writes it with the SENSITIVITY volume output)"
            ),
        ));
    };
    if !(a.components == 2 || a.components == 3) {
        return Err(bad_points(
            file,
            format!(
                "\"Sensitivity\" has {} components, not a vector of 2 or 3",
                a.components
            ),
        ));
    }
    let np = m.n_nodes();
    if np != n_nodes {
        let first = if np > n_nodes {
            format!("point {n_nodes} is not a node of the grid")
        } else {
            format!("first missing: point {np}")
        };
        return Err(bad_points(
            file,
            format!("{np} points for {n_nodes} grid nodes; {first}"),
        ));
    }
    let mut values = Vec::with_capacity(np);
    for i in 0..np {
        let v = a.at(i);
        if let Some(c) = v.iter().position(|x| !x.is_finite()) {
            return Err(bad_points(
                file,
                format!("point {i}: \"Sensitivity\" component {c} is {}", v[c]),
            ));
        }
        values.push([v[0], v[1], v.get(2).copied().unwrap_or(0.0)]);
    }
    Ok(Sensitivity {
        layout: Layout::Volume,
        values,
        rows: np,
        points: Some(m.coords),
    })
}

/// Checks the points of a sensitivity file (`points`, [`Sensitivity::points`]) against the
/// grid's nodes `grid` (at the design vector the sensitivities belong to): the first point
/// farther than `tol` from its node is an error naming the file and the point (a file of
/// another grid, or of this grid in another node order).
pub fn check_points(
    file: &Path,
    points: &[[f64; 3]],
    grid: &[[f64; 3]],
    tol: f64,
) -> Result<(), SensitivityError> {
    if points.len() != grid.len() {
        return Err(bad_points(
            file,
            format!("{} points for {} grid nodes", points.len(), grid.len()),
        ));
    }
    for (i, (p, g)) in points.iter().zip(grid).enumerate() {
        let d = ((p[0] - g[0]).powi(2) + (p[1] - g[1]).powi(2) + (p[2] - g[2]).powi(2)).sqrt();
        if d.is_nan() || d > tol {
            return Err(bad_points(
                file,
                format!(
                    "point {i} at ({:.6e}, {:.6e}, {:.6e}) is {d:.3e} from the grid's node {i} at ({:.6e}, {:.6e}, {:.6e}) (tolerance {tol:.1e}): the file is not of this grid at this design vector, or not in its node order",
                    p[0], p[1], p[2], g[0], g[1], g[2]
                ),
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const VOLUME: &str = "\"PointID\",\"x\",\"y\",\"z\",\"Adjoint_Density\",\"Sensitivity_x\",\"Sensitivity_y\",\"Sensitivity_z\"\n\
        0, 0.000000000000000e+00, 0.000000000000000e+00, 0.000000000000000e+00, 1.0e+00, 1.500000000000000e+00, -2.000000000000000e-01, 3.000000000000000e-03\n\
        2, 1.0e+00, 0.0e+00, 0.0e+00, 1.0e+00, 4.0e+00, 5.0e+00, 6.0e+00\n\
        1, 0.0e+00, 1.0e+00, 0.0e+00, 1.0e+00, 7.0e+00, 8.0e+00, 9.0e+00\n";

    #[test]
    fn reads_su2_volume_layout_in_any_row_order() {
        let s = parse(VOLUME, Path::new("restart.csv"), 3, &[true; 3]).unwrap();
        assert_eq!(s.layout, Layout::Volume);
        assert_eq!(s.values[0], [1.5, -0.2, 0.003]);
        assert_eq!(s.values[2], [4.0, 5.0, 6.0]);
        assert_eq!(s.values[1], [7.0, 8.0, 9.0]);
    }

    #[test]
    fn count_and_index_errors_name_file_and_line() {
        let e = parse(VOLUME, Path::new("restart.csv"), 4, &[true; 4]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "restart.csv:4: 3 points for 4 grid nodes; first missing: point 3"
        );
        let e = parse(VOLUME, Path::new("restart.csv"), 2, &[true; 2]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "restart.csv:3: point 2 is not a node of the grid (2 nodes)"
        );
        let dup = VOLUME.replace("\n2, ", "\n0, ");
        let e = parse(&dup, Path::new("r.csv"), 3, &[true; 3]).unwrap_err();
        assert_eq!(e.to_string(), "r.csv:3: point 0 given twice");
    }

    #[test]
    fn surface_layout_covers_the_wall_only() {
        let s = "\"Point\",\"x\",\"y\",\"z\",\"Sensitivity_x\",\"Sensitivity_y\",\"Sensitivity_z\"\n\
            1, 0.0, 0.0, 0.0, 1.0, 2.0, 3.0\n";
        let wall = [false, true, false];
        let r = parse(s, Path::new("surface_sens.csv"), 3, &wall).unwrap();
        assert_eq!(r.layout, Layout::Surface);
        assert_eq!(r.values, vec![[0.0; 3], [1.0, 2.0, 3.0], [0.0; 3]]);
        let e = parse(s, Path::new("s.csv"), 3, &[true, false, false]).unwrap_err();
        assert_eq!(e.to_string(), "s.csv:2: point 1 is not a wall node");
        let hdr = s.replace("\"Point\"", "\"Node\"");
        assert!(
            parse(&hdr, Path::new("s.csv"), 3, &wall)
                .unwrap_err()
                .to_string()
                .starts_with("s.csv:1: the first column is \"Node\"")
        );
    }
}
