//! Reverse Cuthill–McKee ordering of a graph: a bandwidth-reducing numbering, shared by the
//! crates that renumber unknowns internally (the volume deformation's spring system, the
//! surface grid's harmonic re-map).

use std::collections::VecDeque;

/// Returns the reverse Cuthill–McKee order of the graph of `n` vertices whose adjacency is
/// `neighbours(i)`, as a permutation `perm` (new index k is old vertex `perm[k]`). Each
/// connected component starts from a pseudo-peripheral vertex found by repeated
/// breadth-first searches; neighbours are visited by increasing degree (ties by index), so the
/// result is deterministic.
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
    order
}

/// A vertex of (nearly) maximal eccentricity in the component of `seed`: repeat BFS from the
/// farthest vertex of smallest degree while the depth grows.
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
