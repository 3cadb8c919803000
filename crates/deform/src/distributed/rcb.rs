//! The geometric partitioner: recursive coordinate bisection of the nodes ([`rcb`]), and the
//! parts of a whole grid cut along it (owned nodes, the cells around them, ghost nodes,
//! boundary elements), as rank 0 makes them before it scatters them.
//!
//! Bisection is the fallback of METIS's graph partition ([`super::metis`]) and an option of
//! its own (`--partition rcb`): ~40 lines, deterministic, any number of parts, no graph. Its
//! straight cuts leave 1.5 to 2 times METIS's ghost nodes on the wing-body grid at 2 to 4
//! ranks (docs/perf-log/2026-12-03-mpi-metis.md).

use mesh::{Elements, Marker, Mesh};
use rayon::prelude::*;

use super::partition::LocalGrid;

/// The part (0..parts) of every node: the nodes are split recursively at the median of the
/// longest side of their bounding box, in proportion to the number of parts on each side
/// (any number of parts; ties broken by node index, so the result is deterministic).
pub fn rcb(coords: &[[f64; 3]], parts: usize) -> Vec<u32> {
    rcb_weighted(coords, parts, &[])
}

/// [`rcb`] with a weight per node (`weight[i]`; empty: every node 1): each split is at the
/// weighted median, so that every part holds the same share of the total weight, to within
/// the largest weight of one node.
pub fn rcb_weighted(coords: &[[f64; 3]], parts: usize, weight: &[u32]) -> Vec<u32> {
    let mut part = vec![0u32; coords.len()];
    let mut idx: Vec<u32> = (0..coords.len() as u32).collect();
    // Every weight 1 (or none given): the plain median.
    let w = (!weight.iter().all(|&w| w == 1))
        .then_some(|i: u32| weight.get(i as usize).map_or(1, |&w| u64::from(w)));
    split(coords, &mut idx, 0, parts.max(1), &mut part, w.as_ref());
    part
}

fn split(
    x: &[[f64; 3]],
    idx: &mut [u32],
    first: u32,
    parts: usize,
    part: &mut [u32],
    w: Option<&impl Fn(u32) -> u64>,
) {
    if parts <= 1 || idx.len() <= 1 {
        for &i in idx.iter() {
            part[i as usize] = first;
        }
        return;
    }
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for &i in idx.iter() {
        for k in 0..3 {
            lo[k] = lo[k].min(x[i as usize][k]);
            hi[k] = hi[k].max(x[i as usize][k]);
        }
    }
    let axis = (0..3)
        .max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])))
        .unwrap_or(0);
    let left = parts / 2;
    let along = |&a: &u32, &b: &u32| {
        x[a as usize][axis]
            .total_cmp(&x[b as usize][axis])
            .then(a.cmp(&b))
    };
    let cut = if let Some(w) = w {
        let total: u64 = idx.iter().map(|&i| w(i)).sum();
        // The weighted median: the first node along the axis whose weight, with the nodes
        // before it, passes the left parts' share. Found by halving the range it lies in,
        // each half put on its side by a linear-time selection; idx[lo..hi] holds the nodes
        // of ranks lo..hi along the axis, the lo first weigh `before` ≤ share, the hi first
        // more than share (share < total: left < parts).
        let share = (u128::from(total) * left as u128 / parts as u128) as u64;
        let (mut lo, mut hi, mut before) = (0usize, idx.len(), 0u64);
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            idx[lo..hi].select_nth_unstable_by(mid - lo, along);
            let w_left = before + idx[lo..mid].iter().map(|&i| w(i)).sum::<u64>();
            if w_left > share {
                hi = mid;
            } else {
                (lo, before) = (mid, w_left);
            }
        }
        // hi = lo + 1: the node of rank lo is the first to pass the share. A node heavier
        // than a part's share would leave a part without nodes: each side keeps at least
        // one node per part.
        let least = left.min(idx.len());
        let most = idx.len().saturating_sub(parts - left).max(least);
        let cut = lo.clamp(least, most);
        if cut != lo && cut < idx.len() {
            idx.select_nth_unstable_by(cut, along);
        }
        cut
    } else {
        // Unit weights: the median, in linear time.
        let cut = idx.len() * left / parts;
        idx.select_nth_unstable_by(cut, along);
        cut
    };
    let (a, b) = idx.split_at_mut(cut);
    split(x, a, first, left, part, w);
    split(x, b, first + left as u32, parts - left, part, w);
}

/// The parts of `mesh` for the node partition `part` (`parts` parts): for each, its owned
/// nodes (increasing global id = node index of `mesh`), then its ghosts (increasing global
/// id), the cells with an owned node, and the marker elements whose nodes are all local.
/// The global ids are the nodes' indices in `mesh`.
pub fn parts(mesh: &Mesh, part: &[u32], parts: usize) -> Vec<LocalGrid> {
    let order: Vec<u32> = (0..mesh.n_nodes() as u32).collect();
    parts_in(mesh, part, parts, &order)
}

/// [`parts`] with each part's owned nodes, and its ghosts, in the order of `order` (the
/// nodes of `mesh` listed in that order, e.g. along a Morton curve: a part's nodes then lie
/// close in memory, and the adjacency each rank builds of its part reads its neighbours
/// from nearby instead of from all over the grid).
pub(crate) fn parts_in(mesh: &Mesh, part: &[u32], parts: usize, order: &[u32]) -> Vec<LocalGrid> {
    let n = mesh.n_nodes();
    // The place of every node in `order`.
    let mut rank_of = vec![0u32; n];
    for (k, &i) in order.iter().enumerate() {
        rank_of[i as usize] = k as u32;
    }
    let cells = cells_of_parts(mesh, part, parts);
    // Each part on its own thread, with its own scratch numbering.
    (0..parts)
        .into_par_iter()
        .map_init(
            || vec![u32::MAX; n],
            |local, q| {
                let mut gids: Vec<u64> = order
                    .iter()
                    .filter(|&&i| part[i as usize] == q as u32)
                    .map(|&i| u64::from(i))
                    .collect();
                let n_owned = gids.len();
                let mut ghosts = Vec::new();
                for (gk, g) in mesh.cells.groups().iter().enumerate() {
                    for &c in &cells[q][gk] {
                        for &v in g.element(c) {
                            if part[v as usize] != q as u32 {
                                ghosts.push(v as u64);
                            }
                        }
                    }
                }
                ghosts.sort_unstable_by_key(|&g| rank_of[g as usize]);
                ghosts.dedup();
                gids.extend(ghosts);
                for (k, &g) in gids.iter().enumerate() {
                    local[g as usize] = k as u32;
                }
                let mut m = Mesh::new(mesh.dim);
                m.coords = gids.iter().map(|&g| mesh.coords[g as usize]).collect();
                for (gk, g) in mesh.cells.groups().iter().enumerate() {
                    // By their smallest local node: a node's cells then lie close in memory.
                    let mut by_node: Vec<(u32, u32)> = cells[q][gk]
                        .iter()
                        .map(|&c| {
                            let lo = g.element(c).iter().map(|&v| local[v as usize]).min();
                            (lo.unwrap_or(0), c as u32)
                        })
                        .collect();
                    by_node.sort_unstable();
                    let nodes = &mut m.cells.group_mut(g.kind).nodes;
                    nodes.reserve(by_node.len() * g.kind.n_nodes());
                    for (_, c) in by_node {
                        nodes.extend(g.element(c as usize).iter().map(|&v| local[v as usize]));
                    }
                }
                m.cells.prune();
                for mk in &mesh.markers {
                    let mut el = Elements::new();
                    for (kind, e) in mk.elements.iter() {
                        if e.iter().all(|&v| local[v as usize] != u32::MAX) {
                            let e: Vec<u32> = e.iter().map(|&v| local[v as usize]).collect();
                            el.push(kind, &e, None);
                        }
                    }
                    m.markers.push(Marker {
                        name: mk.name.clone(),
                        tag: mk.tag,
                        elements: el,
                    });
                }
                for &g in &gids {
                    local[g as usize] = u32::MAX;
                }
                LocalGrid {
                    mesh: m,
                    global_ids: gids,
                    n_owned,
                }
            },
        )
        .collect()
}

/// The cells of each part (those with a node it owns), by group (cell indices within the
/// group, increasing): chunks of cells on parallel threads, joined in order.
fn cells_of_parts(mesh: &Mesh, part: &[u32], parts: usize) -> Vec<Vec<Vec<usize>>> {
    const CHUNK: usize = 1 << 15;
    let groups = mesh.cells.groups();
    let mut cells: Vec<Vec<Vec<usize>>> = vec![vec![Vec::new(); groups.len()]; parts];
    for (gk, g) in groups.iter().enumerate() {
        let n = g.len();
        let chunks: Vec<Vec<Vec<usize>>> = (0..n.div_ceil(CHUNK))
            .into_par_iter()
            .map(|ch| {
                let mut mine = vec![Vec::new(); parts];
                for c in ch * CHUNK..(n.min((ch + 1) * CHUNK)) {
                    let e = g.element(c);
                    let mut seen = [u32::MAX; 8];
                    for (k, &v) in e.iter().enumerate() {
                        let q = part[v as usize];
                        if !seen[..k.min(8)].contains(&q) {
                            mine[q as usize].push(c);
                        }
                        if k < 8 {
                            seen[k] = q;
                        }
                    }
                }
                mine
            })
            .collect();
        for mine in chunks {
            for (q, c) in mine.into_iter().enumerate() {
                cells[q][gk].extend(c);
            }
        }
    }
    cells
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bisection_balances_parts_and_cut_keeps_every_cell_on_its_nodes_owners() {
        let m = mesh::generate::box_tets(4, 3, 2, [0.0; 3], [2.0, 1.0, 1.0]);
        for parts in [1, 2, 3, 5] {
            let p = rcb(&m.coords, parts);
            let mut count = vec![0usize; parts];
            for &q in &p {
                count[q as usize] += 1;
            }
            let (lo, hi) = (count.iter().min().unwrap(), count.iter().max().unwrap());
            assert!(hi - lo <= 1 + m.n_nodes() / 20, "{parts} parts: {count:?}");
            let grids = super::parts(&m, &p, parts);
            let owned: usize = grids.iter().map(|g| g.n_owned).sum();
            assert_eq!(owned, m.n_nodes());
            // Every cell is on the part of each of its nodes, with the same global nodes.
            for g in &grids {
                for (_, e) in g.mesh.cells.iter() {
                    let any_owned = e.iter().any(|&v| (v as usize) < g.n_owned);
                    assert!(any_owned);
                }
            }
            let cells: usize = m.tets().len();
            let on_parts: usize = grids.iter().map(|g| g.mesh.tets().len()).sum();
            assert!(on_parts >= cells);
        }
    }

    /// The total weight of each part.
    fn part_weights(part: &[u32], weight: &[u32], parts: usize) -> Vec<u64> {
        let mut w = vec![0u64; parts];
        for (&q, &wi) in part.iter().zip(weight) {
            w[q as usize] += u64::from(wi);
        }
        w
    }

    #[test]
    fn weighted_bisection_balances_the_weights_not_the_nodes() {
        let m = mesh::generate::box_tets(12, 6, 4, [0.0; 3], [2.0, 1.0, 1.0]);
        // The nodes of the left quarter weigh 6, the others 1.
        let weight: Vec<u32> = m
            .coords
            .iter()
            .map(|p| if p[0] < 0.5 { 6 } else { 1 })
            .collect();
        for parts in [2, 3, 5] {
            let p = rcb_weighted(&m.coords, parts, &weight);
            let w = part_weights(&p, &weight, parts);
            let (lo, hi) = (*w.iter().min().unwrap(), *w.iter().max().unwrap());
            // Each split is off its share by less than one node's weight, at each level.
            assert!(hi - lo <= 6 * 3, "{parts} parts: weights {w:?}");
            let n = part_weights(&p, &vec![1; weight.len()], parts);
            assert!(
                n.iter().max() > n.iter().min(),
                "{parts} parts: nodes {n:?}"
            );
            // Equal weights cut as the unweighted bisection (unit weights take its
            // selection, weights of 2 the weighted search, with ties at the share).
            for w in [1, 2] {
                assert_eq!(
                    rcb_weighted(&m.coords, parts, &vec![w; weight.len()]),
                    rcb(&m.coords, parts),
                    "{parts} parts, weights {w}"
                );
            }
            // The cut of the sorted order: the first node whose weight with those before
            // it passes the share (two parts: one split along x, the longest side).
            if parts == 2 {
                let mut idx: Vec<u32> = (0..m.n_nodes() as u32).collect();
                idx.sort_by(|&a, &b| {
                    m.coords[a as usize][0]
                        .total_cmp(&m.coords[b as usize][0])
                        .then(a.cmp(&b))
                });
                let total: u64 = weight.iter().map(|&w| u64::from(w)).sum();
                let mut before = 0;
                let cut = idx
                    .iter()
                    .position(|&i| {
                        before += u64::from(weight[i as usize]);
                        before > total / 2
                    })
                    .unwrap();
                for (k, &i) in idx.iter().enumerate() {
                    assert_eq!(p[i as usize], u32::from(k >= cut), "node {i}");
                }
            }
        }
    }

    #[test]
    fn a_heavy_node_does_not_empty_a_part() {
        let x = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
        assert_eq!(rcb_weighted(&x[..2], 2, &[6, 1]), vec![0, 1]);
        assert_eq!(rcb_weighted(&x, 3, &[1, 1, 60]), vec![0, 1, 2]);
        assert_eq!(rcb_weighted(&x, 2, &[60, 1, 1]), vec![0, 1, 1]);
        // Weights summing to the node count are not all 1: the weighted median.
        let x: Vec<[f64; 3]> = (0..6).map(|i| [f64::from(i), 0.0, 0.0]).collect();
        assert_eq!(
            rcb_weighted(&x, 2, &[0, 0, 0, 0, 3, 3]),
            vec![0, 0, 0, 0, 0, 1]
        );
    }

    /// The cells of a grid as sorted lists of global nodes.
    fn global_cells(g: &LocalGrid) -> Vec<Vec<u64>> {
        let mut cells: Vec<Vec<u64>> = g
            .mesh
            .cells
            .iter()
            .map(|(_, e)| {
                let mut c: Vec<u64> = e.iter().map(|&v| g.global_ids[v as usize]).collect();
                c.sort_unstable();
                c
            })
            .collect();
        cells.sort_unstable();
        cells
    }

    #[test]
    fn parts_hold_exactly_their_cells_and_do_not_depend_on_the_threads() {
        // 48 000 tetrahedra: more than one chunk of `cells_of_parts`.
        let m = mesh::generate::box_tets(20, 20, 20, [0.0; 3], [2.0, 1.0, 1.0]);
        assert!(m.cells.len() > 1 << 15);
        let parts = 3;
        let p = rcb(&m.coords, parts);
        let on = |threads| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| super::parts(&m, &p, parts))
        };
        let (one, three) = (on(1), on(3));
        for (q, (a, b)) in one.iter().zip(&three).enumerate() {
            assert_eq!(a.global_ids, b.global_ids, "part {q}");
            assert_eq!(a.mesh.coords, b.mesh.coords, "part {q}");
            assert_eq!(a.mesh.cells, b.mesh.cells, "part {q}");
            // Exactly the whole grid's cells with a node the part owns.
            let mut want: Vec<Vec<u64>> = m
                .cells
                .iter()
                .filter(|(_, e)| e.iter().any(|&v| p[v as usize] == q as u32))
                .map(|(_, e)| {
                    let mut c: Vec<u64> = e.iter().map(|&v| u64::from(v)).collect();
                    c.sort_unstable();
                    c
                })
                .collect();
            want.sort_unstable();
            assert_eq!(global_cells(a), want, "part {q}");
        }
    }
}
