//! Reverse Cuthill–McKee renumbering: a bandwidth-reducing order so that the neighbours of
//! a row sit close together in memory (used internally; files keep the user's numbering).

use std::collections::VecDeque;

use super::csr::Graph;

/// Returns the reverse Cuthill–McKee order as a permutation `perm` (new index k is old node
/// `perm[k]`). Each connected component starts from a pseudo-peripheral node found by
/// repeated breadth-first searches; neighbours are visited by increasing degree (ties by
/// index), so the result is deterministic.
pub fn reverse_cuthill_mckee(g: &Graph) -> Vec<u32> {
    let n = g.len();
    let deg = |i: usize| g.offsets[i + 1] - g.offsets[i];
    let mut visited = vec![false; n];
    let mut order: Vec<u32> = Vec::with_capacity(n);
    let mut level = vec![u32::MAX; n];
    let mut nb: Vec<u32> = Vec::new();
    for seed in 0..n {
        if visited[seed] {
            continue;
        }
        let start = pseudo_peripheral(g, seed, &mut level);
        let mut queue = VecDeque::new();
        visited[start] = true;
        queue.push_back(start as u32);
        while let Some(i) = queue.pop_front() {
            order.push(i);
            nb.clear();
            nb.extend(
                g.neighbours(i as usize)
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

/// A node of (nearly) maximal eccentricity in the component of `seed`: repeat BFS from the
/// farthest node of smallest degree while the depth grows.
fn pseudo_peripheral(g: &Graph, seed: usize, level: &mut [u32]) -> usize {
    let mut start = seed;
    let mut depth = 0;
    for _ in 0..8 {
        let (far, d, touched) = bfs_far(g, start, level);
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

fn bfs_far(g: &Graph, start: usize, level: &mut [u32]) -> (usize, u32, Vec<u32>) {
    let mut touched = vec![start as u32];
    level[start] = 0;
    let mut head = 0;
    while head < touched.len() {
        let i = touched[head] as usize;
        head += 1;
        for &j in g.neighbours(i) {
            if level[j as usize] == u32::MAX {
                level[j as usize] = level[i] + 1;
                touched.push(j);
            }
        }
    }
    let maxl = level[*touched.last().unwrap_or(&(start as u32)) as usize];
    let deg = |i: usize| g.offsets[i + 1] - g.offsets[i];
    let far = touched
        .iter()
        .rev()
        .take_while(|&&t| level[t as usize] == maxl)
        .min_by_key(|&&t| (deg(t as usize), t))
        .map_or(start, |&t| t as usize);
    (far, maxl, touched)
}

/// Bandwidth max_i max_{j ∈ N(i)} |i − j| of a graph under a permutation (diagnostics).
pub fn bandwidth(g: &Graph, perm: &[u32]) -> usize {
    let mut inv = vec![0usize; perm.len()];
    for (k, &o) in perm.iter().enumerate() {
        inv[o as usize] = k;
    }
    let mut bw = 0;
    for i in 0..g.len() {
        for &j in g.neighbours(i) {
            bw = bw.max(inv[i].abs_diff(inv[j as usize]));
        }
    }
    bw
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rcm_is_permutation_and_reduces_bandwidth() {
        // A 2D grid numbered randomly (fixed LCG): RCM must bring the bandwidth back near nx.
        let (nx, ny) = (30usize, 20usize);
        let n = nx * ny;
        let mut lab: Vec<u32> = (0..n as u32).collect();
        let mut s = 12345u64;
        for i in (1..n).rev() {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            lab.swap(i, (s >> 33) as usize % (i + 1));
        }
        let mut edges = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                let a = lab[j * nx + i];
                if i + 1 < nx {
                    edges.push([a, lab[j * nx + i + 1]]);
                }
                if j + 1 < ny {
                    edges.push([a, lab[(j + 1) * nx + i]]);
                }
            }
        }
        let g = Graph::from_edges(n, &edges).unwrap();
        let perm = reverse_cuthill_mckee(&g);
        let mut seen = vec![false; n];
        for &p in &perm {
            assert!(!seen[p as usize]);
            seen[p as usize] = true;
        }
        let ident: Vec<u32> = (0..n as u32).collect();
        let before = bandwidth(&g, &ident);
        let after = bandwidth(&g, &perm);
        assert!(before > 300, "random numbering has bandwidth {before}");
        assert!(after <= 2 * ny + 2, "RCM bandwidth {after}");
    }
}
