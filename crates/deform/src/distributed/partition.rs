//! One rank's part of a distributed grid ([`LocalGrid`], as a CFD solver hands it over) and
//! its validated form ([`Partition`]): every node owned by exactly one rank, the global ids
//! dense, the ghost layer complete (every cell around an owned node is on its owner), and the
//! node halo built once.
//!
//! The checks run before any exchange that could block, and the ranks agree on their outcome
//! (`comm::agree`): a bad partition gives the same clear error on every rank.

use std::collections::HashMap;

use mesh::{Adjacency, Mesh};
use mpi::traits::*;
use sparse::order;

use super::comm::{Comm, agree, all_to_all, sum_u64};
use super::halo::Halo;
use crate::error::{Error, Result};

/// One rank's part of a grid: its owned nodes, then its ghost nodes (owned by other ranks),
/// the cells around its owned nodes, and the boundary elements of its nodes.
#[derive(Debug, Clone)]
pub struct LocalGrid {
    /// The local grid: nodes (owned first, then ghosts), cells, markers (boundary elements
    /// whose nodes are all local, under the markers' global names).
    pub mesh: Mesh,
    /// Global id of every local node: ids run over 0..N, N the total of owned nodes of all
    /// ranks, and each id is owned by exactly one rank.
    pub global_ids: Vec<u64>,
    /// Number of owned nodes: the first `n_owned` nodes of `mesh`.
    pub n_owned: usize,
}

/// A validated [`LocalGrid`] with the owner of every ghost node and the node halo.
pub struct Partition {
    pub(crate) grid: LocalGrid,
    /// Owner rank of every local node.
    pub(crate) owner: Vec<i32>,
    /// Total number of nodes over the ranks.
    pub(crate) n_global: u64,
    /// The node adjacency of the local grid (complete for owned nodes).
    pub(crate) adj: Adjacency,
    /// Ghost node values from their owners.
    pub(crate) halo: Halo,
    /// The owned nodes were renumbered in locality order ([`Partition::ordered`]).
    pub(crate) in_order: bool,
}

fn fail(comm: &Comm, reason: String) -> Error {
    Error::Distributed {
        rank: comm.rank(),
        reason,
    }
}

impl Partition {
    /// Checks `grid` against the other ranks' parts and builds the halo (collective: every
    /// rank of `comm` calls it). Fails on every rank when a part is inconsistent: a global id
    /// out of range, owned by two ranks or by none, a node listed twice, a cell that names a
    /// node outside its part, or a missing ghost (a cell around an owned node that is not on
    /// the owner).
    pub fn new(comm: &Comm, grid: LocalGrid) -> Result<Self> {
        Self::build(comm, grid, false).map(|p| p.0)
    }

    /// [`Partition::new`], then the owned nodes renumbered as the serial solver numbers a
    /// grid, breadth-first from the interface ([`locality_order`] from [`Start::Interface`];
    /// the ghosts keep their order), for a part whose numbering is the library's own.
    /// Returns the renumbering (`perm[old] = new`, the
    /// convention of `sparse::order`).
    pub(crate) fn ordered(comm: &Comm, grid: LocalGrid) -> Result<(Self, Vec<u32>)> {
        let (p, perm) = Self::build(comm, grid, true)?;
        Ok((p, perm.unwrap_or_default()))
    }

    /// A part made on rank 0 from the whole grid (`super::scatter`), with the owner of each
    /// of its ghosts (`ghost_owner`, in the order of its ghosts) as rank 0 cut them: it is
    /// consistent by construction, so the checks of a given part and the owners' directory
    /// are skipped (0.11 s of each rank's 0.75 s at 1M nodes on 2 ranks). Renumbered as
    /// [`Partition::ordered`] does, from the Morton order rank 0 gave its nodes
    /// ([`Start::InterfaceInMorton`]). Collective.
    pub(crate) fn made(
        comm: &Comm,
        grid: LocalGrid,
        ghost_owner: &[i32],
    ) -> Result<(Self, Vec<u32>)> {
        let n_owned = grid.n_owned;
        let n_global = sum_u64(comm, n_owned as u64);
        let mut owner = vec![comm.rank(); grid.mesh.n_nodes()];
        owner[n_owned..].copy_from_slice(ghost_owner);
        let adj = Adjacency::try_build(&grid.mesh).map_err(|e| fail(comm, e.to_string()));
        let adj = agree(comm, adj)?;
        let (p, perm) = Self::finish(
            comm,
            grid,
            owner,
            n_global,
            adj,
            Some(Start::InterfaceInMorton),
        )?;
        Ok((p, perm.unwrap_or_default()))
    }

    fn build(comm: &Comm, grid: LocalGrid, reorder: bool) -> Result<(Self, Option<Vec<u32>>)> {
        let n = grid.mesh.n_nodes();
        let me = comm.rank();
        let p = comm.size() as usize;
        // Local checks.
        let local = (|| {
            if grid.global_ids.len() != n || grid.n_owned > n {
                return Err(fail(
                    comm,
                    format!(
                        "{} global ids and {} owned nodes for {n} local nodes",
                        grid.global_ids.len(),
                        grid.n_owned
                    ),
                ));
            }
            for g in grid.mesh.cells.groups() {
                if let Some(&v) = g.nodes.iter().find(|&&v| v as usize >= n) {
                    return Err(fail(
                        comm,
                        format!(
                            "a {:?} cell names local node {v} (the part has {n} nodes)",
                            g.kind
                        ),
                    ));
                }
            }
            let mut local_of = HashMap::with_capacity(n);
            for (i, &g) in grid.global_ids.iter().enumerate() {
                if let Some(j) = local_of.insert(g, i as u32) {
                    return Err(fail(
                        comm,
                        format!("node {g} (global id) is listed twice (local nodes {j} and {i})"),
                    ));
                }
            }
            Ok(local_of)
        })();
        let local_of = agree(comm, local)?;
        let n_global = sum_u64(comm, grid.n_owned as u64);
        let range = match grid.global_ids.iter().find(|&&g| g >= n_global) {
            Some(g) => Err(fail(
                comm,
                format!("node {g} (global id) is out of range: the ranks own {n_global} nodes"),
            )),
            None => Ok(()),
        };
        agree(comm, range)?;
        // Directory of owners: global id g is registered on rank g mod p.
        let mut reg: Vec<Vec<u64>> = vec![Vec::new(); p];
        for &g in &grid.global_ids[..grid.n_owned] {
            reg[(g % p as u64) as usize].push(g);
        }
        let got = all_to_all(comm, &reg);
        let mut dir: HashMap<u64, i32> = HashMap::new();
        let mut dup = Ok(());
        for (r, gs) in got.iter().enumerate() {
            for &g in gs {
                if let Some(r0) = dir.insert(g, r as i32) {
                    dup = Err(fail(
                        comm,
                        format!("node {g} (global id) is owned by ranks {r0} and {r}"),
                    ));
                }
            }
        }
        agree(comm, dup)?;
        // Owners of the ghosts, from the directory.
        let mut ask: Vec<Vec<u64>> = vec![Vec::new(); p];
        for &g in &grid.global_ids[grid.n_owned..] {
            ask[(g % p as u64) as usize].push(g);
        }
        let asked = all_to_all(comm, &ask);
        let answers: Vec<Vec<i32>> = asked
            .iter()
            .map(|gs| {
                gs.iter()
                    .map(|g| dir.get(g).copied().unwrap_or(-1))
                    .collect()
            })
            .collect();
        let answered = all_to_all(comm, &answers);
        let mut owner = vec![me; n];
        let mut at = vec![0usize; p];
        let mut orphan = Ok(());
        for i in grid.n_owned..n {
            let g = grid.global_ids[i];
            let d = (g % p as u64) as usize;
            let o = answered[d][at[d]];
            at[d] += 1;
            if o < 0 || o == me {
                orphan = Err(fail(
                    comm,
                    format!(
                        "ghost node {g} (global id, local {i}) has no owner among the other ranks"
                    ),
                ));
            }
            owner[i] = o;
        }
        agree(comm, orphan)?;
        // The ghost layer: every edge a rank has at a ghost node must be on the node's owner.
        let adj = Adjacency::try_build(&grid.mesh).map_err(|e| fail(comm, e.to_string()));
        let adj = agree(comm, adj)?;
        let mut edges: Vec<Vec<u64>> = vec![Vec::new(); p];
        for i in grid.n_owned..n {
            for &j in adj.neighbours(i) {
                let e = &mut edges[owner[i] as usize];
                e.push(grid.global_ids[i]);
                e.push(grid.global_ids[j as usize]);
            }
        }
        let edges = all_to_all(comm, &edges);
        let mut missing = Ok(());
        'outer: for (r, e) in edges.iter().enumerate() {
            for pair in e.chunks_exact(2) {
                let (gi, gj) = (pair[0], pair[1]);
                let i = local_of[&gi] as usize;
                let has = local_of
                    .get(&gj)
                    .is_some_and(|&j| adj.neighbours(i).binary_search(&j).is_ok());
                if !has {
                    missing = Err(fail(
                        comm,
                        format!(
                            "missing ghost: rank {r} has the edge from node {gi} to node {gj} (global ids), \
                             but rank {me}, the owner of node {gi}, has not (a cell around an owned node is missing)"
                        ),
                    ));
                    break 'outer;
                }
            }
        }
        agree(comm, missing)?;
        drop(local_of);
        let start = reorder.then_some(Start::Interface);
        Self::finish(comm, grid, owner, n_global, adj, start)
    }

    /// The part's renumbering in locality order (with `reorder`) and its node halo, once
    /// its owners and adjacency are known. Collective.
    fn finish(
        comm: &Comm,
        mut grid: LocalGrid,
        mut owner: Vec<i32>,
        n_global: u64,
        mut adj: Adjacency,
        reorder: Option<Start>,
    ) -> Result<(Self, Option<Vec<u32>>)> {
        let n = grid.mesh.n_nodes();
        let perm = reorder.map(|start| {
            let owned: Vec<u32> = (0..grid.n_owned as u32).collect();
            let order = locality_order(&owned, &adj, &grid.mesh.coords, start);
            let mut perm: Vec<u32> = (0..n as u32).collect();
            for (new, &old) in order.iter().enumerate() {
                perm[old as usize] = new as u32;
            }
            perm
        });
        if let Some(perm) = &perm {
            grid.mesh
                .renumber_nodes(perm)
                .map_err(|e| fail(comm, e.to_string()))?;
            let (mut g, mut o) = (vec![0u64; n], vec![0i32; n]);
            for (i, &p) in perm.iter().enumerate() {
                g[p as usize] = grid.global_ids[i];
                o[p as usize] = owner[i];
            }
            (grid.global_ids, owner) = (g, o);
            let g = order::permute_graph(n, |i| adj.neighbours(i), perm);
            adj = Adjacency {
                offsets: g.offsets,
                indices: g.adj,
            };
        }
        let ghosts: Vec<(u32, i32, u64)> = (grid.n_owned..n)
            .map(|i| (i as u32, owner[i], grid.global_ids[i]))
            .collect();
        let owned: HashMap<u64, u32> = (0..grid.n_owned)
            .map(|i| (grid.global_ids[i], i as u32))
            .collect();
        let halo = agree(comm, Halo::build(comm, &ghosts, &owned))?;
        Ok((
            Self {
                grid,
                owner,
                n_global,
                adj,
                halo,
                in_order: reorder.is_some(),
            },
            perm,
        ))
    }

    /// The local grid.
    pub fn grid(&self) -> &LocalGrid {
        &self.grid
    }

    /// Total number of nodes over the ranks.
    pub fn n_global(&self) -> u64 {
        self.n_global
    }
}

/// Where [`locality_order`] starts its breadth-first order, and whether its nodes need the
/// Morton curve first.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Start {
    /// Nodes in any order: along a Morton curve, then breadth-first from its first node.
    Corner,
    /// A rank's owned nodes in any order (a given part): along a Morton curve, then
    /// breadth-first from the interface.
    Interface,
    /// A part made on rank 0, whose owned nodes come along the whole grid's Morton curve
    /// already: breadth-first from the interface (a Morton order of its own took 0.03 s
    /// and the graph's renumbering in it 0.04 s at 1M nodes on 2 ranks, for the same
    /// iterations).
    InterfaceInMorton,
}

/// The nodes `nodes` renumbered as the serial solver numbers the grid
/// (`crate::Deformer`'s renumbering): along a Morton curve, then breadth-first over the
/// graph of `nodes`, so that a row's neighbours lie close in memory; returns the nodes in
/// their new order. The product, the multigrid's set-up and its cycle then run at the
/// serial solver's speed: in the order of a Gmsh-made grid's nodes (scattered over the
/// volume) one rank took ~3× the serial time per iteration
/// (docs/perf-log/2026-12-03-mpi-round2.md).
///
/// From the interface ([`Start::Interface`]), the breadth-first order starts from the nodes
/// with a neighbour outside `nodes` (for a part's owned nodes, those next to its ghosts), in
/// Morton order: the interface, where the halo packs its messages and the interface
/// smoother (`super::interface`) works on a few percent of the rows, is then one block of
/// memory. At 1M nodes on 2 ranks the smoother took 0.10–0.13 s per solve against
/// 0.18–0.24 s in the order from a corner, with the same iterations
/// (docs/perf-log/2026-12-05-mpi-interface-first.md).
pub(crate) fn locality_order(
    nodes: &[u32],
    adj: &Adjacency,
    coords: &[[f64; 3]],
    start: Start,
) -> Vec<u32> {
    let m = nodes.len();
    if m < 2 {
        return nodes.to_vec();
    }
    let mut at = vec![u32::MAX; coords.len()];
    for (k, &i) in nodes.iter().enumerate() {
        at[i as usize] = k as u32;
    }
    let (mut off, mut nb) = (Vec::with_capacity(m + 1), Vec::new());
    off.push(0usize);
    for &i in nodes {
        nb.extend(
            adj.neighbours(i as usize)
                .iter()
                .map(|&j| at[j as usize])
                .filter(|&a| a != u32::MAX),
        );
        off.push(nb.len());
    }
    // The nodes' Morton order (None: they come in it) and their graph in that order.
    let morton = (start != Start::InterfaceInMorton).then(|| {
        let xs: Vec<[f64; 3]> = nodes.iter().map(|&i| coords[i as usize]).collect();
        order::morton_order(&xs)
    });
    let (off, nb) = match &morton {
        Some(perm) => {
            let g = order::permute_graph(m, |k| &nb[off[k]..off[k + 1]], perm);
            (g.offsets, g.adj)
        }
        None => (off, nb),
    };
    let mut seeds: Vec<u32> = Vec::new();
    if start != Start::Corner {
        seeds.extend(
            nodes
                .iter()
                .enumerate()
                .filter(|&(_, &i)| {
                    adj.neighbours(i as usize)
                        .iter()
                        .any(|&j| at[j as usize] == u32::MAX)
                })
                .map(|(k, _)| morton.as_ref().map_or(k as u32, |p| p[k])),
        );
        seeds.sort_unstable();
    }
    let level = order::level_order_from(m, &seeds, |a| &nb[off[a]..off[a + 1]]);
    let new = match &morton {
        Some(perm) => order::then(perm, &level),
        None => level,
    };
    let mut out = vec![0u32; m];
    for (&i, &p) in nodes.iter().zip(&new) {
        out[p as usize] = i;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn locality_order_from_the_interface_numbers_the_interface_first() {
        // The nodes with x < 1 of a box: those next to a node with x ≥ 1 are the interface.
        let m = mesh::generate::box_tets(8, 5, 4, [0.0; 3], [2.0, 1.0, 1.0]);
        let adj = Adjacency::build(&m);
        let inside = |i: u32| m.coords[i as usize][0] < 1.0 - 1e-9;
        let owned: Vec<u32> = (0..m.n_nodes() as u32).filter(|&i| inside(i)).collect();
        let edge = |i: &u32| adj.neighbours(*i as usize).iter().any(|&j| !inside(j));
        let n_edge = owned.iter().filter(|i| edge(i)).count();
        assert!(n_edge > 0 && n_edge < owned.len());
        // The same nodes along the grid's Morton curve, as rank 0 sends a made part.
        let morton = order::morton_order(&m.coords);
        let mut in_morton = owned.clone();
        in_morton.sort_unstable_by_key(|&i| morton[i as usize]);
        for (nodes, start) in [
            (&owned, Start::Interface),
            (&in_morton, Start::InterfaceInMorton),
        ] {
            let out = locality_order(nodes, &adj, &m.coords, start);
            let mut sorted = out.clone();
            sorted.sort_unstable();
            assert_eq!(sorted, owned, "{start:?}: not a renumbering of the nodes");
            assert!(
                out[..n_edge].iter().all(edge),
                "{start:?}: interface not first"
            );
        }
        // From a corner, the interface is spread over the numbering.
        let out = locality_order(&owned, &adj, &m.coords, Start::Corner);
        assert!(!out[..n_edge].iter().all(edge));
    }
}
