//! The graph partitioner of a whole grid on rank 0: METIS's multilevel k-way partition of the
//! node graph (the edges of the cells, the graph of the spring matrix), through the `metis`
//! crate (metis-rs) and its vendored METIS 5 built from C. Recursive coordinate bisection
//! ([`mod@super::rcb`]) is the fallback when METIS refuses the graph (more than 2^31 edge ends
//! for its 32-bit indices, out of memory) or leaves a part empty, and an option of its own.
//!
//! METIS minimises the cut edges under a 3 % imbalance of the nodes' weights (the work of
//! each, `work_weights`, when rank 0 cuts for the deformation); the cut edges are what
//! ghost nodes and halo bytes follow (docs/perf-log/2026-12-03-mpi-metis.md compares the two
//! on the wing-body grid). Its result is deterministic (METIS's fixed seed) and does not
//! depend on the thread count.

use mesh::{Adjacency, Mesh};
use rayon::prelude::*;
use sparse::order;

use super::rcb::rcb_weighted;

/// How rank 0 cuts the whole grid into one part per rank ([`cut`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Partitioner {
    /// METIS k-way on the node graph; coordinate bisection when METIS fails.
    #[default]
    Metis,
    /// Recursive coordinate bisection ([`rcb`](super::rcb::rcb)).
    Rcb,
}

impl Partitioner {
    /// Every partitioner.
    pub const ALL: [Partitioner; 2] = [Partitioner::Metis, Partitioner::Rcb];

    /// The name used on the command line and in reports: `metis` or `rcb`.
    pub fn name(self) -> &'static str {
        match self {
            Partitioner::Metis => "metis",
            Partitioner::Rcb => "rcb",
        }
    }
}

impl std::fmt::Display for Partitioner {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Partitioner {
    type Err = String;

    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "metis" => Ok(Partitioner::Metis),
            "rcb" => Ok(Partitioner::Rcb),
            _ => Err(format!("unknown partitioner {s:?} (metis or rcb)")),
        }
    }
}

/// The weight of a node that is an unknown of the solves against one whose position is
/// known (moving with a rigid marker, displaced, fixed). Per rank, at 1M nodes on 2 ranks,
/// about 1 s of the work goes with the nodes and cells (each rank's own part, the quality)
/// and about 5 s with the unknowns (the multigrids' set-ups, the coarse space, the R field
/// and Eq. 21): with 92 % of the nodes unknown, an unknown weighs about 6 known nodes. A
/// partition balancing node counts leaves the unknowns uneven where a part holds much of a
/// wall: 16 % above the mean on the busiest of 8 ranks at 98k nodes with METIS, 3.6 % on 2
/// ranks at 1M (docs/perf-log/2026-12-04-mpi-balance.md).
pub(crate) const UNKNOWN_WEIGHT: u32 = 6;

/// The weight of every node for the cut: [`UNKNOWN_WEIGHT`] for the nodes the solves
/// move (free or sliding), 1 for the others.
pub(crate) fn work_weights(roles: &[crate::bc::NodeRole]) -> Vec<u32> {
    use crate::bc::NodeRole;
    roles
        .iter()
        .map(|r| match r {
            NodeRole::Free | NodeRole::Sliding(_) | NodeRole::OnSupport(_) => UNKNOWN_WEIGHT,
            _ => 1,
        })
        .collect()
}

/// A partition of the nodes of a grid ([`cut`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Cut {
    /// The part (0..parts) of every node.
    pub part: Vec<u32>,
    /// The partitioner that made it.
    pub by: Partitioner,
    /// Why METIS was not used when it was asked for (the partition is then by bisection).
    pub fallback: Option<String>,
}

/// The nodes of `mesh` cut into `parts` parts by `by`; METIS falls back on coordinate
/// bisection, with the reason in [`Cut::fallback`].
pub fn cut(mesh: &Mesh, parts: usize, by: Partitioner) -> Cut {
    cut_in(mesh, parts, by, &order::morton_order(&mesh.coords), &[])
}

/// [`cut`] balancing the nodes' `weight` (empty: every node 1; see [`work_weights`]),
/// METIS working on the grid renumbered by `perm` ([`metis_in`]).
pub(crate) fn cut_in(
    mesh: &Mesh,
    parts: usize,
    by: Partitioner,
    perm: &[u32],
    weight: &[u32],
) -> Cut {
    let bisect = |fallback| Cut {
        part: rcb_weighted(&mesh.coords, parts, weight),
        by: Partitioner::Rcb,
        fallback,
    };
    match by {
        Partitioner::Rcb => bisect(None),
        Partitioner::Metis => match metis_in(mesh, parts, perm, weight) {
            Ok(part) => Cut {
                part,
                by: Partitioner::Metis,
                fallback: None,
            },
            Err(reason) => bisect(Some(reason)),
        },
    }
}

/// The part (0..parts) of every node of `mesh` by METIS's k-way partition of its node graph
/// (every part holding nodes); an error when METIS cannot take the graph or fails, or leaves
/// a part without nodes.
pub fn metis(mesh: &Mesh, parts: usize) -> std::result::Result<Vec<u32>, String> {
    metis_in(mesh, parts, &order::morton_order(&mesh.coords), &[])
}

/// [`metis`] on the node graph of `mesh` renumbered by `perm` (`perm[old] = new`; a Morton
/// order: the graph is then built from nearby memory, where a Gmsh grid's own order reads
/// every node's neighbours from all over the grid); the parts in the numbering of `mesh`.
/// With `weight` (one per node of `mesh`), the parts balance the weights instead of the
/// node counts.
pub(crate) fn metis_in(
    mesh: &Mesh,
    parts: usize,
    perm: &[u32],
    weight: &[u32],
) -> std::result::Result<Vec<u32>, String> {
    let n = mesh.n_nodes();
    if parts <= 1 {
        return Ok(vec![0; n]);
    }
    if n < parts {
        return Err(format!("{n} nodes for {parts} parts"));
    }
    if mesh.cells.len() > mesh::adjacency::MAX_ELEMENTS {
        return Err(format!(
            "{} cells: more than the adjacency takes",
            mesh.cells.len()
        ));
    }
    // The cells renumbered, each group's in the order of their smallest node.
    let mut cells = mesh::Elements::new();
    for g in mesh.cells.groups() {
        let nn = g.kind.n_nodes();
        let mut by_node: Vec<(u32, u32)> = g
            .nodes
            .par_chunks_exact(nn)
            .enumerate()
            .map(|(c, e)| {
                let lo = e.iter().map(|&v| perm[v as usize]).min();
                (lo.unwrap_or(0), c as u32)
            })
            .collect();
        // The keys are distinct: the parallel sort gives the serial order; the cells are
        // then gathered in it in parallel (at 1M nodes the cut took 2.05–2.08 s from the
        // classification, against 2.24 s with the cells pushed one by one).
        by_node.par_sort_unstable();
        cells.group_mut(g.kind).nodes = by_node
            .par_iter()
            .flat_map_iter(|&(_, c)| {
                let c = c as usize;
                g.nodes[c * nn..(c + 1) * nn]
                    .iter()
                    .map(|&v| perm[v as usize])
            })
            .collect();
    }
    let adj = Adjacency::from_elements(n, &cells);
    drop(cells);
    let wide = || {
        format!(
            "{} edge ends: beyond METIS's 32-bit indices",
            adj.indices.len()
        )
    };
    let xadj = adj
        .offsets
        .iter()
        .map(|&o| metis::Idx::try_from(o))
        .collect::<std::result::Result<Vec<_>, _>>()
        .map_err(|_| wide())?;
    let adjncy = adj
        .indices
        .iter()
        .map(|&v| metis::Idx::try_from(v))
        .collect::<std::result::Result<Vec<_>, _>>()
        .map_err(|_| wide())?;
    let nparts = metis::Idx::try_from(parts).map_err(|_| format!("{parts} parts"))?;
    let mut part: Vec<metis::Idx> = vec![0; n];
    // METIS draws from the C library's global random state: two calls at once (two threads
    // of a caller, or of the test harness) would interleave their draws and cut otherwise
    // than alone. One call at a time keeps every cut reproducible.
    static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _alone = ONE_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    // The weights in the graph's numbering.
    let mut vwgt: Vec<metis::Idx> = vec![0; weight.len()];
    for (old, &w) in weight.iter().enumerate() {
        vwgt[perm[old] as usize] = metis::Idx::try_from(w)
            .map_err(|_| format!("node weight {w} beyond METIS's indices"))?;
    }
    let mut graph = metis::Graph::new(1, nparts, &xadj, &adjncy)
        .map_err(|e| format!("METIS refused the node graph: {e}"))?;
    if !vwgt.is_empty() {
        graph = graph.set_vwgt(&vwgt);
    }
    graph
        .part_kway(&mut part)
        .map_err(|e| format!("METIS failed: {e}"))?;
    let mut count = vec![0usize; parts];
    for &q in &part {
        let q = usize::try_from(q)
            .ok()
            .filter(|&q| q < parts)
            .ok_or_else(|| format!("METIS returned part {q} of {parts}"))?;
        count[q] += 1;
    }
    if let Some(q) = count.iter().position(|&c| c == 0) {
        return Err(format!("METIS left part {q} of {parts} without nodes"));
    }
    Ok(perm.iter().map(|&p| part[p as usize] as u32).collect())
}

#[cfg(test)]
mod tests {
    use super::super::rcb::rcb;
    use super::*;

    /// Edges of `mesh` whose two nodes are in different parts.
    fn cut_edges(mesh: &Mesh, part: &[u32]) -> usize {
        Adjacency::build(mesh)
            .edges()
            .iter()
            .filter(|e| part[e[0] as usize] != part[e[1] as usize])
            .count()
    }

    #[test]
    fn metis_balances_parts_within_its_tolerance_and_cuts_no_more_than_bisection() {
        // Measured: METIS cuts 175, 291, 339, 582 edges, bisection 225, 382, 447, 760.
        let m = mesh::generate::box_tets(12, 12, 3, [0.0; 3], [2.0, 2.0, 0.5]);
        for parts in [2, 3, 4, 7] {
            let p = metis(&m, parts).expect("METIS partitions a box grid");
            let mut count = vec![0usize; parts];
            for &q in &p {
                count[q as usize] += 1;
            }
            let ideal = m.n_nodes() as f64 / parts as f64;
            let hi = *count.iter().max().unwrap() as f64;
            assert!(hi <= 1.03 * ideal + 1.0, "{parts} parts: {count:?}");
            assert!(count.iter().all(|&c| c > 0), "{parts} parts: {count:?}");
            let (cm, cr) = (cut_edges(&m, &p), cut_edges(&m, &rcb(&m.coords, parts)));
            assert!(
                cm <= cr,
                "{parts} parts: METIS cuts {cm} edges, bisection {cr}"
            );
            // The same partition again (METIS's seed is fixed).
            assert_eq!(metis(&m, parts).unwrap(), p);
        }
    }

    #[test]
    fn metis_balances_the_weights_of_the_nodes() {
        let m = mesh::generate::box_tets(12, 6, 4, [0.0; 3], [2.0, 1.0, 1.0]);
        let roles: Vec<crate::bc::NodeRole> = m
            .coords
            .iter()
            .map(|p| {
                if p[0] < 0.5 {
                    crate::bc::NodeRole::Fixed
                } else {
                    crate::bc::NodeRole::Free
                }
            })
            .collect();
        let weight = work_weights(&roles);
        let total: u64 = weight.iter().map(|&w| u64::from(w)).sum();
        let perm = order::morton_order(&m.coords);
        for parts in [2, 4] {
            let p = metis_in(&m, parts, &perm, &weight).unwrap();
            let (mut w, mut n) = (vec![0u64; parts], vec![0usize; parts]);
            for (&q, &wi) in p.iter().zip(&weight) {
                w[q as usize] += u64::from(wi);
                n[q as usize] += 1;
            }
            let ideal = total as f64 / parts as f64;
            let hi = *w.iter().max().unwrap() as f64;
            assert!(
                hi <= 1.03 * ideal + f64::from(UNKNOWN_WEIGHT),
                "{parts} parts: {w:?}"
            );
            // The fixed nodes weigh less: their parts hold more nodes.
            let unweighted = metis_in(&m, parts, &perm, &[]).unwrap();
            assert_ne!(p, unweighted, "{parts} parts");
            assert!(
                n.iter().max().unwrap() - n.iter().min().unwrap() > m.n_nodes() / 20,
                "{parts} parts: {n:?}"
            );
        }
    }

    #[test]
    fn metis_does_not_depend_on_the_threads() {
        // More cells than one chunk of the parallel sort's work.
        let m = mesh::generate::box_tets(20, 20, 20, [0.0; 3], [2.0, 1.0, 1.0]);
        let on = |threads| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| metis(&m, 3).unwrap())
        };
        assert_eq!(on(1), on(3));
    }

    #[test]
    fn one_part_and_too_few_nodes() {
        let m = mesh::generate::box_tets(1, 1, 1, [0.0; 3], [1.0; 3]);
        assert_eq!(metis(&m, 1).unwrap(), vec![0; m.n_nodes()]);
        let err = metis(&m, 9).unwrap_err();
        assert!(err.contains("8 nodes for 9 parts"), "{err}");
        let c = cut(&m, 9, Partitioner::Metis);
        assert_eq!((c.by, c.part.len()), (Partitioner::Rcb, 8));
        assert!(c.fallback.is_some_and(|r| r.contains("8 nodes")));
        let c = cut(&m, 2, Partitioner::Rcb);
        assert_eq!((c.by, c.fallback), (Partitioner::Rcb, None));
        assert_eq!("metis".parse(), Ok(Partitioner::Metis));
        assert!("scotch".parse::<Partitioner>().is_err());
    }
}
