//! The spring system of Eq. 21 on the unknowns: their numbering ([`System`]), the matrix A
//! (a_ii = Σ_j K_ij, a_ij = −K_ij), the couplings to prescribed nodes and the right-hand
//! sides built from them.

use mesh::Adjacency;
use rayon::prelude::*;
use sparse::vec3::{CHUNK, V3, row_chunks};
use sparse::{Constraints, Csr, SymMatrix};

use crate::bc::{Classified, NodeRole};
use crate::error::{Error, Result};
use crate::stiffness::Springs;

/// Unknown numbering and the solver's view of the grid.
pub(crate) struct System {
    /// Unknown index of each node (u32::MAX for prescribed nodes).
    pub unk_of: Vec<u32>,
    /// Node of each unknown, in solver order.
    pub node_of: Vec<u32>,
    /// The sliding nodes' planes and seam lines.
    pub cons: Constraints,
    /// Unknown index of each entry of [`Classified::supports`] (u32::MAX: not an unknown).
    pub sup_unk: Vec<u32>,
}

/// The unknowns in node order: with `opts.renumber` the grid is in breadth-first order
/// (see [`crate::Deformer`]), and so are the unknowns, with the rows' neighbours close in memory.
pub(crate) fn build_system(cls: &Classified, adj: &Adjacency) -> System {
    let n = cls.roles.len();
    let is_unk = |r: &NodeRole| {
        matches!(
            r,
            NodeRole::Free | NodeRole::Sliding(_) | NodeRole::OnSupport(_)
        )
    };
    let mut node_of: Vec<u32> = Vec::new();
    for (i, r) in cls.roles.iter().enumerate() {
        // A node without edges (unused by the cells) cannot move: it is left where it is.
        if is_unk(r) && !adj.neighbours(i).is_empty() {
            node_of.push(i as u32);
        }
    }
    let mut unk_of = vec![u32::MAX; n];
    for (k, &i) in node_of.iter().enumerate() {
        unk_of[i as usize] = k as u32;
    }
    let mut items = Vec::new();
    for (k, &i) in node_of.iter().enumerate() {
        if let NodeRole::Sliding(c) = cls.roles[i as usize] {
            items.push((k as u32, c));
        }
    }
    let sup_unk = cls
        .supports
        .iter()
        .map(|s| unk_of[s.node as usize])
        .collect();
    System {
        unk_of,
        node_of,
        cons: Constraints { items },
        sup_unk,
    }
}

/// A = spring matrix on the unknowns (rows in solver order, parallel, deterministic).
///
/// Two passes over the rows, both in parallel: the row lengths (unknown neighbours), then,
/// per chunk of [`CHUNK`] rows, each row's entries written straight into its slice of the
/// output and sorted by column there (one scratch buffer per chunk, no allocation per row).
/// a_ii sums K_ij over the neighbours in adjacency order, whatever the thread count.
/// Fails, naming the spring of the lowest row, when a stiffness is not a normal positive f32
/// after scaling (coincident nodes, or lengths spanning ~19 orders of magnitude).
pub(crate) fn assemble(sys: &System, adj: &Adjacency, sp: &Springs) -> Result<SymMatrix<f32>> {
    let nu = sys.node_of.len();
    let is_unk = |j: u32| sys.unk_of[j as usize] != u32::MAX;
    let lens: Vec<usize> = sys
        .node_of
        .par_iter()
        .with_min_len(CHUNK)
        .map(|&i| {
            adj.neighbours(i as usize)
                .iter()
                .filter(|&&j| is_unk(j))
                .count()
        })
        .collect();
    let mut offsets = Vec::with_capacity(nu + 1);
    offsets.push(0usize);
    let mut total = 0;
    for l in lens {
        total += l;
        offsets.push(total);
    }
    let mut diag = vec![0.0; nu];
    let mut cols = vec![0u32; total];
    let mut vals = vec![0.0f32; total];
    // One (first row, diagonal, columns, values) piece per chunk of rows.
    let start = |r: usize| offsets[r];
    let pieces: Vec<_> = row_chunks(&mut diag, nu, CHUNK, |r| r)
        .into_iter()
        .zip(row_chunks(&mut cols, nu, CHUNK, start))
        .zip(row_chunks(&mut vals, nu, CHUNK, start))
        .enumerate()
        .map(|(k, ((d, c), v))| (k * CHUNK, d, c, v))
        .collect();
    // The first bad spring of each piece (pieces in row order: the first of them all).
    let bad = pieces.into_par_iter().find_map_first(|(lo, d, c, v)| {
        let base = offsets[lo];
        let mut bad = None;
        let mut row: Vec<(u32, f32)> = Vec::new();
        for (r, dk) in d.iter_mut().enumerate() {
            let k = lo + r;
            let i = sys.node_of[k] as usize;
            let mut s = 0.0;
            row.clear();
            for &j in adj.neighbours(i) {
                let kij = sp.k(i, j as usize);
                if !(kij as f32).is_normal() && bad.is_none() {
                    bad = Some((i, j, sp.scale * sp.k_exact(i, j as usize)));
                }
                s += kij;
                let u = sys.unk_of[j as usize];
                if u != u32::MAX {
                    row.push((u, -kij as f32));
                }
            }
            // Columns are distinct: the order is unique.
            row.sort_unstable_by_key(|e| e.0);
            *dk = s;
            let at = offsets[k] - base;
            for (q, &(cu, val)) in row.iter().enumerate() {
                c[at + q] = cu;
                v[at + q] = val;
            }
        }
        bad
    });
    if let Some((i, j, k)) = bad {
        return Err(Error::Stiffness {
            nodes: [i as u32, j],
            value: k,
        });
    }
    Ok(SymMatrix {
        diag,
        offsets,
        cols,
        vals,
    })
}

/// b_k = `extra(k, i)` + Σ_{j prescribed} K_ij v(j) for unknown k at node i, for a per-node
/// field v (the springs to prescribed nodes from [`couplings`]).
pub(crate) fn rhs<G, F>(sys: &System, cp: &Csr, v: G, extra: F) -> Vec<V3>
where
    G: Fn(usize) -> V3 + Sync,
    F: Fn(usize, usize) -> V3 + Sync,
{
    (0..sys.node_of.len())
        .into_par_iter()
        .with_min_len(CHUNK)
        .map(|k| {
            let mut s = extra(k, sys.node_of[k] as usize);
            let (nodes, kij) = cp.row(k);
            for (&j, &kij) in nodes.iter().zip(kij) {
                let vj = v(j as usize);
                for q in 0..3 {
                    s[q] += kij * vj[q];
                }
            }
            s
        })
        .collect()
}

/// The springs from each unknown to its prescribed neighbours (moving, fixed): row k (solver
/// order) holds the nodes j and K_ij, the coupling terms of the right-hand sides, evaluated
/// once per grid state. The springs between unknowns are A's off-diagonal entries
/// (a_ij = −K_ij).
pub(crate) fn couplings(sys: &System, adj: &Adjacency, sp: &Springs) -> Csr {
    Csr::from_rows(sys.node_of.len(), sys.unk_of.len(), |k, row| {
        let i = sys.node_of[k] as usize;
        for &j in adj.neighbours(i) {
            if sys.unk_of[j as usize] == u32::MAX {
                row.push((j, sp.k(i, j as usize)));
            }
        }
    })
}
