//! Node-to-node adjacency (the grid's edge graph) in compressed sparse row form.
//!
//! Built once, in parallel, without per-node heap allocation: a node-to-element table is
//! made by counting, prefix sum and a sequential fill (so each row lists its elements in
//! increasing order); then every node gathers the edge neighbours from its elements into a
//! per-thread scratch buffer, sorts and deduplicates them — first to count, then to fill its
//! own slice of the output. The result is independent of the number of threads.

use rayon::prelude::*;

use crate::grid::{ElementKind, Elements, Mesh};

/// Symmetric node adjacency: the neighbours of node `i` are
/// `indices[offsets[i]..offsets[i + 1]]`, sorted increasingly, without `i` itself.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Adjacency {
    /// Row offsets, `n_nodes + 1` entries.
    pub offsets: Vec<usize>,
    /// Neighbour node indices.
    pub indices: Vec<u32>,
}

/// Element-local neighbour lists: for each local node of a kind, the local nodes it shares
/// an edge with.
fn local_neighbours(kind: ElementKind, local: usize, out: &mut [u8; 4]) -> usize {
    let mut n = 0;
    for e in kind.edges() {
        if usize::from(e[0]) == local {
            out[n] = e[1];
            n += 1;
        } else if usize::from(e[1]) == local {
            out[n] = e[0];
            n += 1;
        }
    }
    n
}

/// Node-to-element incidence: for node `i`, the (group index, element index, local node)
/// triples packed as global element slots.
struct Incidence {
    offsets: Vec<usize>,
    /// For each incidence, the flat position of the node in its group's connectivity,
    /// tagged with the group index in the top 3 bits.
    slots: Vec<u64>,
}

fn incidence(n_nodes: usize, cells: &Elements) -> Incidence {
    let mut counts = vec![0usize; n_nodes + 1];
    for g in cells.groups() {
        for &v in &g.nodes {
            counts[v as usize + 1] += 1;
        }
    }
    for i in 0..n_nodes {
        counts[i + 1] += counts[i];
    }
    let offsets = counts;
    let mut cursor = offsets.clone();
    let mut slots = vec![0u64; offsets[n_nodes]];
    for (gi, g) in cells.groups().iter().enumerate() {
        for (pos, &v) in g.nodes.iter().enumerate() {
            let c = &mut cursor[v as usize];
            slots[*c] = ((gi as u64) << 61) | pos as u64;
            *c += 1;
        }
    }
    Incidence { offsets, slots }
}

/// Pushes the edge neighbours of `node` into `scratch` (unsorted, with repeats).
fn gather(node: usize, inc: &Incidence, cells: &Elements, scratch: &mut Vec<u32>) {
    scratch.clear();
    let groups = cells.groups();
    for &slot in &inc.slots[inc.offsets[node]..inc.offsets[node + 1]] {
        let g = &groups[(slot >> 61) as usize];
        let pos = (slot & ((1 << 61) - 1)) as usize;
        let nn = g.kind.n_nodes();
        let (elem, local) = (pos / nn, pos % nn);
        let conn = &g.nodes[elem * nn..elem * nn + nn];
        let mut loc = [0u8; 4];
        let k = local_neighbours(g.kind, local, &mut loc);
        for &l in &loc[..k] {
            let v = conn[usize::from(l)];
            if v as usize != node {
                scratch.push(v);
            }
        }
    }
    scratch.sort_unstable();
    scratch.dedup();
}

impl Adjacency {
    /// Builds the adjacency of the grid's cells (edges of volume elements in 3D, of
    /// triangles and quads in 2D). Node indices must be in range ([`Mesh::validate`]).
    ///
    /// ```
    /// let m = mesh::generate::box_tets(1, 1, 1, [0.0; 3], [1.0; 3]);
    /// let a = mesh::Adjacency::build(&m);
    /// // 12 cube edges + 6 face diagonals + 1 body diagonal.
    /// assert_eq!(a.n_edges(), 19);
    /// assert_eq!(a.neighbours(0), &[1, 2, 3, 4, 5, 6, 7]);
    /// ```
    pub fn build(mesh: &Mesh) -> Self {
        Self::from_elements(mesh.n_nodes(), &mesh.cells)
    }

    /// Builds the adjacency of any element set over `n_nodes` nodes.
    pub fn from_elements(n_nodes: usize, cells: &Elements) -> Self {
        let inc = incidence(n_nodes, cells);
        let degrees: Vec<usize> = (0..n_nodes)
            .into_par_iter()
            .map_init(Vec::new, |scratch, i| {
                gather(i, &inc, cells, scratch);
                scratch.len()
            })
            .collect();
        let mut offsets = Vec::with_capacity(n_nodes + 1);
        offsets.push(0usize);
        let mut acc = 0;
        for d in &degrees {
            acc += d;
            offsets.push(acc);
        }
        drop(degrees);
        let mut indices = vec![0u32; acc];
        // Split the output into one slice per node, then fill in parallel.
        let mut rows: Vec<&mut [u32]> = Vec::with_capacity(n_nodes);
        let mut rest: &mut [u32] = &mut indices;
        for i in 0..n_nodes {
            let (row, tail) = rest.split_at_mut(offsets[i + 1] - offsets[i]);
            rows.push(row);
            rest = tail;
        }
        rows.par_iter_mut()
            .enumerate()
            .for_each_init(Vec::new, |scratch, (i, row)| {
                gather(i, &inc, cells, scratch);
                row.copy_from_slice(scratch);
            });
        drop(rows);
        Adjacency { offsets, indices }
    }

    /// Number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.offsets.len() - 1
    }

    /// Number of undirected edges.
    pub fn n_edges(&self) -> usize {
        self.indices.len() / 2
    }

    /// The sorted neighbours of node `i`.
    pub fn neighbours(&self, i: usize) -> &[u32] {
        &self.indices[self.offsets[i]..self.offsets[i + 1]]
    }

    /// The undirected edges `[i, j]` with `i < j`, sorted.
    pub fn edges(&self) -> Vec<[u32; 2]> {
        let mut out = Vec::with_capacity(self.n_edges());
        for i in 0..self.n_nodes() {
            for &j in self.neighbours(i) {
                if (i as u32) < j {
                    out.push([i as u32, j]);
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::ElementKind;

    #[test]
    fn local_neighbour_counts_match_vertex_degrees() {
        let mut b = [0u8; 4];
        assert_eq!(local_neighbours(ElementKind::Tetra, 2, &mut b), 3);
        assert_eq!(local_neighbours(ElementKind::Pyramid, 4, &mut b), 4);
        assert_eq!(local_neighbours(ElementKind::Hexa, 6, &mut b), 3);
        assert_eq!(local_neighbours(ElementKind::Prism, 5, &mut b), 3);
        assert_eq!(local_neighbours(ElementKind::Quad, 0, &mut b), 2);
    }

    #[test]
    fn hexahedron_has_no_diagonals() {
        let mut cells = Elements::new();
        cells.push(ElementKind::Hexa, &[0, 1, 2, 3, 4, 5, 6, 7], None);
        let a = Adjacency::from_elements(8, &cells);
        assert_eq!(a.n_edges(), 12);
        assert_eq!(a.neighbours(0), &[1, 3, 4]);
        assert_eq!(a.neighbours(6), &[2, 5, 7]);
    }
}
