//! Node-to-node adjacency (the grid's edge graph) in compressed sparse row form.
//!
//! Built once, in parallel, without per-node heap allocation: a node-to-element table
//! (element number across the kind groups and local node in one `u32`) is made by counting,
//! prefix sum and a fill, the counting and the fill in parallel over node ranges (each range scans the whole
//! connectivity in element order, so each row lists its elements in increasing order
//! whatever the split); then every node gathers the edge neighbours from its elements
//! (through a per-kind table of local neighbours)
//! into a per-task scratch buffer, sorts and deduplicates them, and appends them to its
//! block of nodes; the blocks are concatenated in order. The result is independent of the
//! number of threads.

use rayon::prelude::*;

use crate::error::{Error, Result};
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

/// Node-to-element incidence: for node `i`, `slots[offsets[i]..offsets[i + 1]]` holds its
/// elements in increasing order (numbered across the groups in order), each with the node's
/// position in it: `element << 3 | local`.
struct Incidence {
    offsets: Vec<usize>,
    slots: Vec<u32>,
    /// Number of the first element of each group.
    group_start: Vec<u32>,
}

impl Incidence {
    /// The group of element `e` and its index within the group.
    #[inline]
    fn locate(&self, e: u32) -> (usize, usize) {
        let mut gi = 0;
        while gi + 1 < self.group_start.len() && self.group_start[gi + 1] <= e {
            gi += 1;
        }
        (gi, (e - self.group_start[gi]) as usize)
    }
}

/// Most elements an element set may have for [`Adjacency::from_elements`] (the element
/// number and the local node share a `u32` of the incidence table): 2^29, 536 M (a grid of
/// that size would hold 8.6 GB of tetrahedron connectivity).
pub const MAX_ELEMENTS: usize = 1 << 29;

/// Refuses more than [`MAX_ELEMENTS`] cells (the check of [`Mesh::validate`] and
/// [`Adjacency::try_build`]).
pub(crate) fn check_element_count(n: usize) -> Result<()> {
    if n > MAX_ELEMENTS {
        return Err(Error::Invalid {
            what: format!("{n} cells: at most {MAX_ELEMENTS} are supported"),
        });
    }
    Ok(())
}

/// Node ranges of the parallel incidence passes: one per thread (each pass scans all the
/// connectivity and handles the nodes of its range, so the result does not depend on the
/// split).
fn node_ranges(n_nodes: usize) -> Vec<(usize, usize)> {
    let k = rayon::current_num_threads().clamp(1, 64);
    let step = n_nodes.div_ceil(k).max(1);
    (0..n_nodes)
        .step_by(step)
        .map(|lo| (lo, (lo + step).min(n_nodes)))
        .collect()
}

/// `data` cut into consecutive slices of the given lengths.
fn split_by_lengths<T>(data: &mut [T], lens: impl Iterator<Item = usize>) -> Vec<&mut [T]> {
    let mut out = Vec::new();
    let mut rest = data;
    for len in lens {
        let (part, tail) = rest.split_at_mut(len);
        out.push(part);
        rest = tail;
    }
    out
}

/// Counting, prefix sum and fill; both passes run in parallel over node ranges, every range
/// scanning the whole connectivity in element order (so each row lists its elements in
/// increasing order).
fn incidence(n_nodes: usize, cells: &Elements) -> Incidence {
    let ranges = node_ranges(n_nodes);
    assert!(
        cells.len() <= MAX_ELEMENTS,
        "Adjacency: {} elements, at most {MAX_ELEMENTS} supported",
        cells.len()
    );
    let mut group_start = Vec::with_capacity(cells.groups().len());
    let mut total = 0;
    for g in cells.groups() {
        group_start.push(total as u32);
        total += g.len();
    }
    // counts[i + 1] = number of elements of node i.
    let mut counts = vec![0usize; n_nodes + 1];
    let parts = split_by_lengths(&mut counts[1..], ranges.iter().map(|&(lo, hi)| hi - lo));
    parts
        .into_par_iter()
        .zip(&ranges)
        .for_each(|(part, &(lo, _))| {
            for g in cells.groups() {
                for &v in &g.nodes {
                    if let Some(c) = (v as usize).checked_sub(lo).and_then(|k| part.get_mut(k)) {
                        *c += 1;
                    }
                }
            }
        });
    for i in 0..n_nodes {
        counts[i + 1] += counts[i];
    }
    let offsets = counts;
    let mut slots = vec![0u32; offsets[n_nodes]];
    let lens = ranges.iter().map(|&(lo, hi)| offsets[hi] - offsets[lo]);
    let parts = split_by_lengths(&mut slots, lens);
    parts
        .into_par_iter()
        .zip(&ranges)
        .for_each(|(part, &(lo, hi))| {
            let base = offsets[lo];
            let mut cursor: Vec<usize> = offsets[lo..hi].iter().map(|&o| o - base).collect();
            for (g, &first) in cells.groups().iter().zip(&group_start) {
                let nn = g.kind.n_nodes();
                for (e, conn) in g.nodes.chunks_exact(nn).enumerate() {
                    let slot = (first + e as u32) << 3;
                    for (local, &v) in conn.iter().enumerate() {
                        if let Some(c) =
                            (v as usize).checked_sub(lo).and_then(|k| cursor.get_mut(k))
                        {
                            part[*c] = slot | local as u32;
                            *c += 1;
                        }
                    }
                }
            }
        });
    Incidence {
        offsets,
        slots,
        group_start,
    }
}

/// Local neighbours of every local node of a kind (at most 4 each) and their counts.
type NeighbourTable = ([[u8; 4]; 8], [u8; 8]);

fn neighbour_table(kind: ElementKind) -> NeighbourTable {
    let mut t = ([[0u8; 4]; 8], [0u8; 8]);
    for local in 0..kind.n_nodes() {
        t.1[local] = local_neighbours(kind, local, &mut t.0[local]) as u8;
    }
    t
}

/// Pushes the edge neighbours of `node` into `scratch`, sorted and without repeats.
///
/// `seen` (one entry per node, zero-initialised, owned by the calling task) drops repeats as
/// they come: `seen[v] == node + 1` once `v` is in the list. Only the distinct neighbours are
/// then sorted (a node of a tetrahedral grid meets each neighbour in ~5 elements).
fn gather(
    node: usize,
    inc: &Incidence,
    cells: &Elements,
    tables: &[NeighbourTable],
    seen: &mut [u32],
    scratch: &mut Vec<u32>,
) {
    scratch.clear();
    let stamp = node as u32 + 1;
    let groups = cells.groups();
    for &slot in &inc.slots[inc.offsets[node]..inc.offsets[node + 1]] {
        let (gi, elem) = inc.locate(slot >> 3);
        let local = (slot & 7) as usize;
        let g = &groups[gi];
        let nn = g.kind.n_nodes();
        let conn = &g.nodes[elem * nn..elem * nn + nn];
        let (loc, cnt) = &tables[gi];
        for &l in &loc[local][..usize::from(cnt[local])] {
            let v = conn[usize::from(l)];
            let s = &mut seen[v as usize];
            if v as usize != node && *s != stamp {
                *s = stamp;
                scratch.push(v);
            }
        }
    }
    scratch.sort_unstable();
}

/// Nodes per task of the parallel gather.
const BLOCK: usize = 4096;

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

    /// [`Adjacency::build`], refusing a grid of more than [`MAX_ELEMENTS`] cells with
    /// [`Error::Invalid`] instead of panicking.
    pub fn try_build(mesh: &Mesh) -> Result<Self> {
        check_element_count(mesh.cells.len())?;
        Ok(Self::build(mesh))
    }

    /// Builds the adjacency of any element set over `n_nodes` nodes.
    ///
    /// # Panics
    /// With more than [`MAX_ELEMENTS`] elements.
    pub fn from_elements(n_nodes: usize, cells: &Elements) -> Self {
        let inc = incidence(n_nodes, cells);
        let tables: Vec<NeighbourTable> = cells
            .groups()
            .iter()
            .map(|g| neighbour_table(g.kind))
            .collect();
        // One (degrees, neighbours) block per BLOCK nodes, gathered once.
        let blocks: Vec<(Vec<u32>, Vec<u32>)> = (0..n_nodes.div_ceil(BLOCK))
            .into_par_iter()
            .map_init(
                || (vec![0u32; n_nodes], Vec::new()),
                |(seen, scratch), b| {
                    let lo = b * BLOCK;
                    let hi = (lo + BLOCK).min(n_nodes);
                    let mut degrees = Vec::with_capacity(hi - lo);
                    let mut out = Vec::new();
                    for i in lo..hi {
                        gather(i, &inc, cells, &tables, seen, scratch);
                        degrees.push(scratch.len() as u32);
                        out.extend_from_slice(scratch);
                    }
                    (degrees, out)
                },
            )
            .collect();
        drop(inc);
        let total: usize = blocks.iter().map(|b| b.1.len()).sum();
        let mut offsets = Vec::with_capacity(n_nodes + 1);
        offsets.push(0usize);
        let mut indices = Vec::with_capacity(total);
        let mut acc = 0;
        for (degrees, out) in blocks {
            for d in degrees {
                acc += d as usize;
                offsets.push(acc);
            }
            indices.extend_from_slice(&out);
        }
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

    /// The adjacency from the element edges through a set (independent of the incidence
    /// table and the blocks).
    fn naive(n: usize, cells: &Elements) -> Vec<Vec<u32>> {
        let mut rows = vec![std::collections::BTreeSet::new(); n];
        for g in cells.groups() {
            let nn = g.kind.n_nodes();
            for conn in g.nodes.chunks_exact(nn) {
                for e in g.kind.edges() {
                    let (a, b) = (conn[usize::from(e[0])], conn[usize::from(e[1])]);
                    if a != b {
                        rows[a as usize].insert(b);
                        rows[b as usize].insert(a);
                    }
                }
            }
        }
        rows.into_iter().map(|r| r.into_iter().collect()).collect()
    }

    #[test]
    fn matches_the_element_edges_on_mixed_grids_across_blocks() {
        // A tetrahedral box with more nodes than one block, plus hexahedra, prisms and
        // pyramids over some of its nodes (connectivity only matters here).
        let m = crate::generate::box_tets(20, 15, 16, [0.0; 3], [1.0; 3]);
        let n = m.n_nodes();
        assert!(n > BLOCK);
        let mut cells = m.cells.clone();
        let nid = |k: usize| ((k * 7919) % n) as u32;
        for k in 0..200 {
            let h: Vec<u32> = (0..8).map(|q| nid(8 * k + q)).collect();
            cells.push(ElementKind::Hexa, &h, None);
            cells.push(ElementKind::Prism, &h[..6], None);
            cells.push(ElementKind::Pyramid, &h[..5], None);
        }
        // Degenerate elements (a node repeated).
        cells.push(ElementKind::Tetra, &[5, 9, 5, 1000], None);
        cells.push(ElementKind::Prism, &[7, 7, 7, 3000, 3001, 3000], None);
        let a = Adjacency::from_elements(n, &cells);
        let want = naive(n, &cells);
        for (i, w) in want.iter().enumerate() {
            assert_eq!(a.neighbours(i), &w[..], "node {i}");
        }
        // The incidence passes split the nodes by thread count: same result for any.
        for threads in [1, 3] {
            let other = testkit::with_threads(threads, || Adjacency::from_elements(n, &cells));
            assert_eq!(other, a);
        }
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
