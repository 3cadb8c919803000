//! Reverse Cuthill–McKee renumbering: a bandwidth-reducing order so that the neighbours of
//! a row sit close together in memory (used internally; files keep the user's numbering).

use super::csr::Graph;

/// Returns the reverse Cuthill–McKee order of `g` as a permutation `perm` (new index k is old
/// node `perm[k]`): [`mesh::order::reverse_cuthill_mckee`] (pseudo-peripheral starts,
/// neighbours by increasing degree; deterministic).
pub fn reverse_cuthill_mckee(g: &Graph) -> Vec<u32> {
    mesh::order::reverse_cuthill_mckee(g.len(), |i| g.neighbours(i))
}

/// The inverse of a permutation: `inverse(p)[p[i] as usize] == i`.
pub fn inverse(perm: &[u32]) -> Vec<u32> {
    let mut inv = vec![0u32; perm.len()];
    for (i, &p) in perm.iter().enumerate() {
        inv[p as usize] = i as u32;
    }
    inv
}

/// Bandwidth max_i max_{j ∈ N(i)} |i − j| of a graph under a permutation (diagnostics).
pub fn bandwidth(g: &Graph, perm: &[u32]) -> usize {
    let inv = inverse(perm);
    let mut bw = 0;
    for i in 0..g.len() {
        for &j in g.neighbours(i) {
            bw = bw.max(inv[i].abs_diff(inv[j as usize]));
        }
    }
    bw as usize
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
