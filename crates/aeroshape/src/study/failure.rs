//! What a design that inverts cells did ([`Study::failed_grid`]), for the user and the
//! optimiser to act on, as DAFoam reports its mesh-quality failures: the grid of the quality
//! guard's last attempt, the cells it inverted with their kinds, where they are, and the
//! design variables that moved them.
//!
//! A variable's share in a cell is measured to first order at the initial design `x0`: the
//! cell's nodes move by `J(x0) e_i (x_i − x0_i)` under variable `i` alone (one forward
//! product of the whole chain each), and what can invert a cell is the part of that motion
//! that is not a common translation, so the share is `max_k |d_k − d̄|` over the cell's nodes
//! `k` (`d̄` their mean motion), in model units. The variables are listed largest first.

use serde::Serialize;

use super::Study;
use super::error::Result;

/// One cell that the design inverted (valid in the baseline grid, `q ≤ 0` after).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct InvertedCell {
    /// Its index in the grid's canonical cell order (as `mesh info` and the VTU number it).
    pub cell: usize,
    /// Its kind ("tetra", "prism", …).
    pub kind: String,
    /// Its quality after the change (≤ 0) and in the baseline.
    pub quality: [f64; 2],
    /// Its centroid after the change.
    pub centroid: [f64; 3],
    /// Its nodes, and which of them lie on the wall (prescribed by the geometry).
    pub nodes: Vec<(u32, bool)>,
    /// The variables that moved it, largest share first (see the module doc): name and
    /// share (model units); variables with no share left out.
    pub moved_by: Vec<(String, f64)>,
}

/// The outcome of [`Study::failed_grid`].
#[derive(Debug, Clone)]
pub struct FailedGrid {
    /// The grid of the guard's last attempt (every increment tried).
    pub grid: mesh::Mesh,
    /// Its cell quality.
    pub cell_quality: Vec<f64>,
    /// The cells inverted beyond the baseline's, worst first (at most the number asked).
    pub cells: Vec<InvertedCell>,
    /// How many cells were inverted in all.
    pub count: usize,
}

impl Study {
    /// The grid that the design `x` gives when the quality guard would refuse it (an
    /// evaluation failing with inverted cells), with its `max_cells` worst inverted cells
    /// and the variables that moved them (module doc). Costs one evaluation, a linearisation
    /// at the initial design and one forward product per variable that `x` moves.
    pub fn failed_grid(&self, x: &[f64], max_cells: usize) -> Result<FailedGrid> {
        super::evaluate::check_length(&self.prepared, x)?;
        let (points, _) = super::evaluate::param_phase(&self.prepared, &self.db, x)?;
        let (_, _, _, positions) = self.wall_positions(&points)?;
        let d = self.deformer.deform_to_keeping_inverted(&positions, None)?;
        let mut grid = self.grid.clone();
        grid.coords = d.coords;
        let q = d.cell_quality;
        let mut bad: Vec<usize> = (0..q.len())
            .filter(|&c| q[c] <= 0.0 && self.quality[c] > 0.0)
            .collect();
        let count = bad.len();
        bad.sort_by(|&a, &b| q[a].total_cmp(&q[b]).then(a.cmp(&b)));
        bad.truncate(max_cells);
        let all: Vec<(mesh::ElementKind, &[u32])> = grid.cells.iter().collect();
        let cell_nodes: Vec<(mesh::ElementKind, Vec<u32>)> =
            bad.iter().map(|&c| (all[c].0, all[c].1.to_vec())).collect();
        let shares = self.shares(x, &cell_nodes)?;
        let names = self.registry().names();
        let cells = bad
            .iter()
            .zip(&cell_nodes)
            .zip(shares)
            .map(|((&c, (kind, nodes)), share)| {
                let mut centroid = [0.0; 3];
                for &v in nodes {
                    for k in 0..3 {
                        centroid[k] += grid.coords[v as usize][k] / nodes.len() as f64;
                    }
                }
                let mut moved_by: Vec<(String, f64)> = names
                    .iter()
                    .zip(share)
                    .filter(|(_, s)| *s > 0.0)
                    .map(|(n, s)| (n.to_string(), s))
                    .collect();
                moved_by.sort_by(|a, b| b.1.total_cmp(&a.1));
                InvertedCell {
                    cell: c,
                    kind: kind.name().to_string(),
                    quality: [q[c], self.quality[c]],
                    centroid,
                    nodes: nodes.iter().map(|&v| (v, self.wall[v as usize])).collect(),
                    moved_by,
                }
            })
            .collect();
        Ok(FailedGrid {
            grid,
            cell_quality: q,
            cells,
            count,
        })
    }

    /// Per cell of `cells`, each variable's share (module doc) of the step from the initial
    /// design to `x`.
    fn shares(&self, x: &[f64], cells: &[(mesh::ElementKind, Vec<u32>)]) -> Result<Vec<Vec<f64>>> {
        let x0 = self.initial();
        let mut out = vec![vec![0.0; x.len()]; cells.len()];
        if cells.is_empty() {
            return Ok(out);
        }
        let lin = self.linearise(&x0)?;
        for i in 0..x.len() {
            let step = x[i] - x0[i];
            if step == 0.0 {
                continue;
            }
            let mut dx = vec![0.0; x.len()];
            dx[i] = step;
            let dv = lin.jvp(&dx)?;
            for ((_, nodes), row) in cells.iter().zip(&mut out) {
                let n = nodes.len() as f64;
                let mut mean = [0.0; 3];
                for &v in nodes {
                    for k in 0..3 {
                        mean[k] += dv[v as usize][k] / n;
                    }
                }
                row[i] = nodes
                    .iter()
                    .map(|&v| {
                        (0..3)
                            .map(|k| (dv[v as usize][k] - mean[k]).powi(2))
                            .sum::<f64>()
                            .sqrt()
                    })
                    .fold(0.0, f64::max);
            }
        }
        Ok(out)
    }
}
