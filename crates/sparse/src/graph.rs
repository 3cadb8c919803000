//! Node graphs in compressed sparse row form (the pattern of a symmetric matrix).

use crate::error::{Error, Result};

/// A node graph: for node i, its neighbours are `adj[offsets[i]..offsets[i + 1]]`.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Graph {
    /// Row offsets, length n + 1.
    pub offsets: Vec<usize>,
    /// Neighbour indices (no self loops).
    pub adj: Vec<u32>,
}

impl Graph {
    /// Builds a symmetric graph from undirected edges (duplicates and self loops removed,
    /// neighbours sorted).
    pub fn from_edges(n: usize, edges: &[[u32; 2]]) -> Result<Self> {
        let mut deg = vec![0usize; n];
        for (k, &[a, b]) in edges.iter().enumerate() {
            if a as usize >= n || b as usize >= n {
                return Err(Error::BadGraph {
                    reason: format!("edge {k} ({a}, {b}) refers to a node ≥ {n}"),
                });
            }
            if a != b {
                deg[a as usize] += 1;
                deg[b as usize] += 1;
            }
        }
        let mut offsets = vec![0usize; n + 1];
        for i in 0..n {
            offsets[i + 1] = offsets[i] + deg[i];
        }
        let mut fill = offsets.clone();
        let mut adj = vec![0u32; offsets[n]];
        for &[a, b] in edges {
            if a != b {
                adj[fill[a as usize]] = b;
                fill[a as usize] += 1;
                adj[fill[b as usize]] = a;
                fill[b as usize] += 1;
            }
        }
        // Sort and deduplicate each row, then compact.
        let mut out_off = vec![0usize; n + 1];
        let mut out = Vec::with_capacity(adj.len());
        for i in 0..n {
            let row = &mut adj[offsets[i]..offsets[i + 1]];
            row.sort_unstable();
            let mut last = u32::MAX;
            for &j in row.iter() {
                if j != last {
                    out.push(j);
                    last = j;
                }
            }
            out_off[i + 1] = out.len();
        }
        Ok(Self {
            offsets: out_off,
            adj: out,
        })
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// True for a graph without nodes.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Neighbours of node i.
    #[inline]
    pub fn neighbours(&self, i: usize) -> &[u32] {
        &self.adj[self.offsets[i]..self.offsets[i + 1]]
    }
}
