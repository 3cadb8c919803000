//! Orderings of a graph's nodes and the permutations between numberings: reverse
//! Cuthill–McKee, breadth-first level sets, the Morton curve; inverse, composition and the
//! permuted graph. Every crate that renumbers nodes or unknowns internally uses these.
//!
//! **Convention.** A permutation is a `[u32]` `perm` of length n that gives the *new* index of
//! every *old* one: old index i becomes `perm[i]` (`perm[old] = new`). This is also the
//! convention of `mesh::Mesh::renumber_nodes`. Its [`inverse`] lists the old indices in the
//! new order (`inv[new] = old`): that list is what a solver iterates over when it visits the
//! nodes in their new order, and what gathers a renumbered vector, `v_new[k] = v_old[inv[k]]`.
//!
//! A graph is given by its node count and a `neighbours(i)` function, so that any CSR
//! adjacency (this crate's [`Graph`], `mesh::Adjacency`) can be ordered without a copy.

use std::collections::VecDeque;

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::graph::Graph;
use crate::vec3::{CHUNK, row_chunks};

/// Checks that `perm` is a permutation of `0..n`.
pub fn check_permutation(perm: &[u32], n: usize) -> Result<()> {
    if perm.len() != n {
        return Err(Error::BadPermutation {
            reason: format!("{} entries for {n} indices", perm.len()),
        });
    }
    let mut seen = vec![false; n];
    for (i, &p) in perm.iter().enumerate() {
        let Some(s) = seen.get_mut(p as usize) else {
            return Err(Error::BadPermutation {
                reason: format!("index {i} goes to {p} ≥ {n}"),
            });
        };
        if std::mem::replace(s, true) {
            return Err(Error::BadPermutation {
                reason: format!("index {i} goes to {p}, which an earlier index already has"),
            });
        }
    }
    Ok(())
}

/// The inverse of a permutation: `inverse(p)[p[i] as usize] == i` (the old indices in the
/// new order, see the module doc).
pub fn inverse(perm: &[u32]) -> Vec<u32> {
    let mut inv = vec![0u32; perm.len()];
    for (i, &p) in perm.iter().enumerate() {
        inv[p as usize] = i as u32;
    }
    inv
}

/// The renumbering `first` followed by `second`: index i becomes `second[first[i]]`.
pub fn then(first: &[u32], second: &[u32]) -> Vec<u32> {
    first.iter().map(|&p| second[p as usize]).collect()
}

/// The reverse Cuthill–McKee order of the graph of `n` nodes whose adjacency is
/// `neighbours(i)` (`perm[old] = new`): a bandwidth-reducing numbering. Each connected
/// component starts from a pseudo-peripheral node found by repeated breadth-first searches;
/// neighbours are visited by increasing degree (ties by index), so the result is
/// deterministic.
pub fn reverse_cuthill_mckee<'a, F>(n: usize, neighbours: F) -> Vec<u32>
where
    F: Fn(usize) -> &'a [u32],
{
    let deg = |i: usize| neighbours(i).len();
    let mut visited = vec![false; n];
    let mut order: Vec<u32> = Vec::with_capacity(n);
    let mut level = vec![u32::MAX; n];
    let mut nb: Vec<u32> = Vec::new();
    for seed in 0..n {
        if visited[seed] {
            continue;
        }
        let start = pseudo_peripheral(&neighbours, seed, &mut level);
        let mut queue = VecDeque::new();
        visited[start] = true;
        queue.push_back(start as u32);
        while let Some(i) = queue.pop_front() {
            order.push(i);
            nb.clear();
            nb.extend(
                neighbours(i as usize)
                    .iter()
                    .copied()
                    .filter(|&j| !visited[j as usize]),
            );
            nb.sort_by_key(|&j| (deg(j as usize), j));
            for &j in &nb {
                visited[j as usize] = true;
                queue.push_back(j);
            }
        }
    }
    order.reverse();
    inverse(&order)
}

/// A node of (nearly) maximal eccentricity in the component of `seed`: repeat BFS from the
/// farthest node of smallest degree while the depth grows.
fn pseudo_peripheral<'a, F>(neighbours: &F, seed: usize, level: &mut [u32]) -> usize
where
    F: Fn(usize) -> &'a [u32],
{
    let mut start = seed;
    let mut depth = 0;
    for _ in 0..8 {
        let (far, d, touched) = bfs_far(neighbours, start, level);
        for &t in &touched {
            level[t as usize] = u32::MAX;
        }
        if d <= depth {
            break;
        }
        depth = d;
        start = far;
    }
    start
}

fn bfs_far<'a, F>(neighbours: &F, start: usize, level: &mut [u32]) -> (usize, u32, Vec<u32>)
where
    F: Fn(usize) -> &'a [u32],
{
    let mut touched = vec![start as u32];
    level[start] = 0;
    let mut head = 0;
    while head < touched.len() {
        let i = touched[head] as usize;
        head += 1;
        for &j in neighbours(i) {
            if level[j as usize] == u32::MAX {
                level[j as usize] = level[i] + 1;
                touched.push(j);
            }
        }
    }
    let maxl = level[*touched.last().unwrap_or(&(start as u32)) as usize];
    let far = touched
        .iter()
        .rev()
        .take_while(|&&t| level[t as usize] == maxl)
        .min_by_key(|&&t| (neighbours(t as usize).len(), t))
        .map_or(start, |&t| t as usize);
    (far, maxl, touched)
}

/// Breadth-first numbering (Cuthill–McKee's level sets, without its degree sort) of the
/// graph of `n` nodes (`perm[old] = new`): each connected component from its lowest node,
/// neighbours in the order `neighbours` gives them. Applied to a Morton-ordered grid (whose
/// node 0 is at a corner of the domain), it keeps each node's neighbours within about two
/// level sets of it (see docs/crates/deform.md, "Unknown ordering").
pub fn level_order<'a, F>(n: usize, neighbours: F) -> Vec<u32>
where
    F: Fn(usize) -> &'a [u32],
{
    level_order_from(n, &[], neighbours)
}

/// [`level_order`] from the nodes `seeds`, numbered first in the order given, then level set
/// by level set away from them; the nodes they do not reach follow as in [`level_order`].
/// A rank's part of a distributed grid seeded with the nodes next to its ghosts gets its
/// interface in one block at the head of its numbering, so that the work done at the
/// interface reads nearby memory. Every seed must be below `n`.
pub fn level_order_from<'a, F>(n: usize, seeds: &[u32], neighbours: F) -> Vec<u32>
where
    F: Fn(usize) -> &'a [u32],
{
    let mut seen = vec![false; n];
    let mut order: Vec<u32> = Vec::with_capacity(n);
    // Numbers the nodes reached from order[head..], breadth-first.
    let sweep = |order: &mut Vec<u32>, seen: &mut [bool], mut head: usize| {
        while head < order.len() {
            let i = order[head] as usize;
            head += 1;
            for &j in neighbours(i) {
                if !seen[j as usize] {
                    seen[j as usize] = true;
                    order.push(j);
                }
            }
        }
    };
    for &s in seeds {
        if !std::mem::replace(&mut seen[s as usize], true) {
            order.push(s);
        }
    }
    sweep(&mut order, &mut seen, 0);
    for s0 in 0..n {
        if !std::mem::replace(&mut seen[s0], true) {
            let head = order.len();
            order.push(s0 as u32);
            sweep(&mut order, &mut seen, head);
        }
    }
    inverse(&order)
}

/// Morton (Z-order) numbering of points from their coordinates (`perm[old] = new`), 21 bits
/// per axis over the bounding box; ties by index, so the order is deterministic. It depends
/// on the coordinates only: a randomly numbered grid gets the same order as a well-ordered
/// one.
pub fn morton_order(coords: &[[f64; 3]]) -> Vec<u32> {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in coords {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let spread = |v: u64| {
        let mut x = v & 0x1f_ffff;
        x = (x | (x << 32)) & 0x1f_0000_0000_ffff;
        x = (x | (x << 16)) & 0x1f_0000_ff00_00ff;
        x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
        x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
        x = (x | (x << 2)) & 0x1249_2492_4924_9249;
        x
    };
    let mut keys: Vec<(u64, u32)> = coords
        .par_iter()
        .enumerate()
        .map(|(i, p)| {
            let mut code = 0u64;
            for k in 0..3 {
                let w = hi[k] - lo[k];
                let q = if w > 0.0 {
                    ((p[k] - lo[k]) / w * 2_097_151.0) as u64
                } else {
                    0
                };
                code |= spread(q) << k;
            }
            (code, i as u32)
        })
        .collect();
    keys.par_sort_unstable();
    let mut perm = vec![0u32; coords.len()];
    for (new, &(_, old)) in keys.iter().enumerate() {
        perm[old as usize] = new as u32;
    }
    perm
}

/// The graph of `n` nodes renumbered by `perm` (`perm[old] = new`), each row sorted: the
/// same as building the adjacency of the renumbered grid. Rows in parallel (blocks of
/// [`CHUNK`]); the result does not depend on the thread count.
pub fn permute_graph<'a, F>(n: usize, neighbours: F, perm: &[u32]) -> Graph
where
    F: Fn(usize) -> &'a [u32] + Sync,
{
    let old_of = inverse(perm);
    let mut offsets = Vec::with_capacity(n + 1);
    offsets.push(0usize);
    let mut total = 0;
    for &o in &old_of {
        total += neighbours(o as usize).len();
        offsets.push(total);
    }
    let mut adj = vec![0u32; total];
    let pieces = row_chunks(&mut adj, n, CHUNK, |r| offsets[r]);
    pieces.into_par_iter().enumerate().for_each(|(k, piece)| {
        let (lo, hi) = (k * CHUNK, ((k + 1) * CHUNK).min(n));
        let base = offsets[lo];
        for r in lo..hi {
            let row = &mut piece[offsets[r] - base..offsets[r + 1] - base];
            for (d, &j) in row.iter_mut().zip(neighbours(old_of[r] as usize)) {
                *d = perm[j as usize];
            }
            row.sort_unstable();
        }
    });
    Graph { offsets, adj }
}

/// Bandwidth `max_i max_{j ∈ N(i)} |perm[i] − perm[j]|` of the graph of `n` nodes under the
/// renumbering `perm` (`perm[old] = new`; diagnostics).
pub fn bandwidth<'a, F>(n: usize, neighbours: F, perm: &[u32]) -> usize
where
    F: Fn(usize) -> &'a [u32],
{
    let mut bw = 0;
    for i in 0..n {
        for &j in neighbours(i) {
            bw = bw.max(perm[i].abs_diff(perm[j as usize]));
        }
    }
    bw as usize
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A random numbering of `n` indices (fixed LCG), `perm[old] = new`.
    fn shuffled(n: usize, seed: u64) -> Vec<u32> {
        let mut lab: Vec<u32> = (0..n as u32).collect();
        let mut s = seed;
        for i in (1..n).rev() {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            lab.swap(i, (s >> 33) as usize % (i + 1));
        }
        lab
    }

    /// The 7-point graph of an nx × ny × nz grid of points, numbered by `lab` (lexicographic
    /// index → node), and the points' coordinates.
    fn grid(nx: usize, ny: usize, nz: usize, lab: &[u32]) -> (Graph, Vec<[f64; 3]>) {
        let id = |i: usize, j: usize, k: usize| lab[(k * ny + j) * nx + i];
        let mut edges = Vec::new();
        let mut coords = vec![[0.0; 3]; nx * ny * nz];
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    coords[id(i, j, k) as usize] = [i as f64, 0.9 * j as f64, 1.1 * k as f64];
                    if i + 1 < nx {
                        edges.push([id(i, j, k), id(i + 1, j, k)]);
                    }
                    if j + 1 < ny {
                        edges.push([id(i, j, k), id(i, j + 1, k)]);
                    }
                    if k + 1 < nz {
                        edges.push([id(i, j, k), id(i, j, k + 1)]);
                    }
                }
            }
        }
        (Graph::from_edges(nx * ny * nz, &edges).unwrap(), coords)
    }

    #[test]
    fn rcm_is_a_permutation_and_reduces_bandwidth() {
        // A 2D grid numbered randomly: RCM must bring the bandwidth back near the short side.
        let (nx, ny) = (30usize, 20usize);
        let (g, _) = grid(nx, ny, 1, &shuffled(nx * ny, 12345));
        let n = g.len();
        let perm = reverse_cuthill_mckee(n, |i| g.neighbours(i));
        check_permutation(&perm, n).unwrap();
        let ident: Vec<u32> = (0..n as u32).collect();
        let before = bandwidth(n, |i| g.neighbours(i), &ident);
        let after = bandwidth(n, |i| g.neighbours(i), &perm);
        assert!(before > 300, "random numbering has bandwidth {before}");
        assert!(after <= 2 * ny + 2, "RCM bandwidth {after}");
    }

    #[test]
    fn morton_then_level_order_keeps_neighbours_close() {
        // A 20 × 18 × 16 grid numbered at random, then Morton-ordered, as `deform` does.
        let (nx, ny, nz) = (20, 18, 16);
        let n = nx * ny * nz;
        let (g, coords) = grid(nx, ny, nz, &shuffled(n, 11));
        let morton = morton_order(&coords);
        check_permutation(&morton, n).unwrap();
        let gm = permute_graph(n, |i| g.neighbours(i), &morton);
        let level = level_order(n, |i| gm.neighbours(i));
        check_permutation(&level, n).unwrap();
        let gl = permute_graph(n, |i| gm.neighbours(i), &level);
        // The two renumberings at once give the same graph.
        let both = then(&morton, &level);
        assert_eq!(permute_graph(n, |i| g.neighbours(i), &both), gl);
        let ident: Vec<u32> = (0..n as u32).collect();
        let (before, after) = (
            bandwidth(n, |i| gm.neighbours(i), &ident),
            bandwidth(n, |i| gl.neighbours(i), &ident),
        );
        // Two level sets (diagonal sections from a corner) hold at most ~3 × 20 × 18 nodes;
        // the Morton curve's jumps reach across most of the grid.
        assert!(
            after < 3 * nx * ny && after * 4 < before,
            "{before} -> {after}"
        );
    }

    #[test]
    fn level_order_from_seeds_numbers_them_and_their_levels_first() {
        // A 12 × 10 grid in lexicographic order, seeded with its column i = 7 (an
        // interface): the seeds come first, then the columns 6 and 8, then 5 and 9, …
        let (nx, ny) = (12usize, 10usize);
        let ident: Vec<u32> = (0..(nx * ny) as u32).collect();
        let (g, _) = grid(nx, ny, 1, &ident);
        let n = g.len();
        let seeds: Vec<u32> = (0..ny).map(|j| (j * nx + 7) as u32).collect();
        let perm = level_order_from(n, &seeds, |i| g.neighbours(i));
        check_permutation(&perm, n).unwrap();
        for (k, &s) in seeds.iter().enumerate() {
            assert_eq!(perm[s as usize] as usize, k);
        }
        let col = |v: usize| (v % nx).abs_diff(7);
        let order = inverse(&perm);
        for w in order.windows(2) {
            assert!(col(w[0] as usize) <= col(w[1] as usize), "{w:?}");
        }
        // No seeds: the plain breadth-first order; a second component is reached after.
        assert_eq!(
            level_order_from(n, &[], |i| g.neighbours(i)),
            level_order(n, |i| g.neighbours(i))
        );
        let two = Graph::from_edges(5, &[[0, 1], [3, 4]]).unwrap();
        assert_eq!(
            level_order_from(5, &[4], |i| two.neighbours(i)),
            vec![2, 3, 4, 1, 0]
        );
    }

    #[test]
    fn inverse_and_composition_follow_the_convention() {
        let p = shuffled(97, 5);
        let inv = inverse(&p);
        for i in 0..97 {
            assert_eq!(inv[p[i] as usize] as usize, i);
        }
        let ident: Vec<u32> = (0..97).collect();
        assert_eq!(then(&p, &inv), ident);
        // A vector renumbered by p is gathered through the inverse.
        let v: Vec<f64> = (0..97).map(|i| i as f64 * 1.5).collect();
        let w: Vec<f64> = inv.iter().map(|&o| v[o as usize]).collect();
        assert!((0..97).all(|i| w[p[i] as usize] == v[i]));
        assert!(check_permutation(&[0, 1, 3], 3).is_err());
        assert!(check_permutation(&[0, 1], 3).is_err());
    }
}
