//! Distance of every node to the moving boundary along grid edges (Dijkstra with a monotone
//! radix heap): the d_ij of [`crate::Stiffness::WallDistance`].

use mesh::Adjacency;

/// Distance of every node to the nodes flagged `source`, along grid edges (Dijkstra; ∞ where
/// unreachable). The result does not depend on the order in which nodes of equal distance
/// are settled (a node's distance is the smallest of its settled neighbours' d + l, and a
/// neighbour at the same distance cannot lower it), so the monotone [`RadixHeap`] gives the
/// distances of a binary heap bit for bit.
pub(crate) fn edge_distance(adj: &Adjacency, x: &[[f64; 3]], source: &[bool]) -> Vec<f64> {
    let mut d: Vec<f64> = source
        .iter()
        .map(|&s| if s { 0.0 } else { f64::INFINITY })
        .collect();
    settle(adj, x, &mut d);
    d
}

/// Lowers the distances `d` along grid edges from every node of finite distance in it
/// (Dijkstra seeded with those distances; [`edge_distance`] seeds the sources with 0, the
/// distributed distance a rank's part with what the other ranks found).
pub(crate) fn settle(adj: &Adjacency, x: &[[f64; 3]], d: &mut [f64]) {
    let seeds: Vec<u32> = (0..d.len() as u32)
        .filter(|&i| d[i as usize].is_finite())
        .collect();
    settle_from(adj, x, d, &seeds);
}

/// [`settle`] seeded with the nodes `seeds` only: the distances of a settled field after
/// some of them were lowered (`seeds`), the others' being already the smallest over their
/// neighbours. The same fixed point as [`settle`], for the work of the nodes it lowers.
pub(crate) fn settle_from(adj: &Adjacency, x: &[[f64; 3]], d: &mut [f64], seeds: &[u32]) {
    let mut heap = RadixHeap::default();
    for &i in seeds {
        let v = d[i as usize];
        if v.is_finite() {
            // Non-negative f64 bit patterns order like the values.
            heap.push(v.to_bits(), i);
        }
    }
    while let Some((key, i)) = heap.pop() {
        let i = i as usize;
        let di = f64::from_bits(key);
        if di > d[i] {
            continue;
        }
        let a = x[i];
        for &j in adj.neighbours(i) {
            let j = j as usize;
            let b = x[j];
            let l = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2) + (b[2] - a[2]).powi(2)).sqrt();
            let dj = di + l;
            if dj < d[j] {
                d[j] = dj;
                // Non-negative f64 bit patterns order like the values.
                heap.push(dj.to_bits(), j as u32);
            }
        }
    }
}

/// Monotone priority queue on u64 keys (radix heap): every pushed key must be ≥ the last
/// popped one, as in Dijkstra's algorithm. Bucket k holds the keys whose highest bit that
/// differs from the last popped key is bit k − 1 (bucket 0: equal to it); popping refills
/// from the first non-empty bucket, so each entry moves O(64) times at most and typically
/// once or twice.
struct RadixHeap {
    last: u64,
    len: usize,
    buckets: [Vec<(u64, u32)>; 65],
}

impl Default for RadixHeap {
    fn default() -> Self {
        Self {
            last: 0,
            len: 0,
            buckets: std::array::from_fn(|_| Vec::new()),
        }
    }
}

impl RadixHeap {
    #[inline]
    fn bucket(last: u64, key: u64) -> usize {
        (64 - (key ^ last).leading_zeros()) as usize
    }

    #[inline]
    fn push(&mut self, key: u64, v: u32) {
        debug_assert!(key >= self.last);
        self.buckets[Self::bucket(self.last, key)].push((key, v));
        self.len += 1;
    }

    /// A smallest (key, value) entry (among equal keys, any).
    fn pop(&mut self) -> Option<(u64, u32)> {
        if self.len == 0 {
            return None;
        }
        if self.buckets[0].is_empty() {
            let k = (1..65).find(|&k| !self.buckets[k].is_empty())?;
            let items = std::mem::take(&mut self.buckets[k]);
            self.last = items.iter().map(|e| e.0).min()?;
            for &(key, v) in &items {
                self.buckets[Self::bucket(self.last, key)].push((key, v));
            }
            // Keep the allocation of the emptied bucket.
            let mut items = items;
            items.clear();
            self.buckets[k] = items;
        }
        self.len -= 1;
        self.buckets[0].pop()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The textbook Dijkstra with a binary heap, ties by node index (the former
    /// `edge_distance`).
    fn binary_heap_distance(adj: &Adjacency, x: &[[f64; 3]], source: &[bool]) -> Vec<f64> {
        use std::cmp::Reverse;
        use std::collections::BinaryHeap;
        let mut d = vec![f64::INFINITY; x.len()];
        let mut heap = BinaryHeap::new();
        for (i, &s) in source.iter().enumerate() {
            if s {
                d[i] = 0.0;
                heap.push(Reverse((0u64, i as u32)));
            }
        }
        while let Some(Reverse((key, i))) = heap.pop() {
            let i = i as usize;
            let di = f64::from_bits(key);
            if di > d[i] {
                continue;
            }
            for &j in adj.neighbours(i) {
                let j = j as usize;
                let (a, b) = (x[i], x[j]);
                let l =
                    ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2) + (b[2] - a[2]).powi(2)).sqrt();
                if di + l < d[j] {
                    d[j] = di + l;
                    heap.push(Reverse(((di + l).to_bits(), j as u32)));
                }
            }
        }
        d
    }

    #[test]
    fn radix_heap_distances_equal_binary_heap_distances_bit_for_bit() {
        let mut m = mesh::generate::box_tets(14, 11, 9, [0.0; 3], [1.0, 0.8, 0.6]);
        for (i, p) in m.coords.iter_mut().enumerate() {
            let t = i as f64;
            p[0] += 0.01 * (t * 0.7).sin();
            p[1] += 0.01 * (t * 1.3).cos();
        }
        let adj = Adjacency::build(&m);
        let n = m.n_nodes();
        // Sources: a face, and one isolated corner node far from it.
        let source: Vec<bool> = (0..n)
            .map(|i| m.coords[i][2] <= 1e-12 || i == n - 1)
            .collect();
        let a = edge_distance(&adj, &m.coords, &source);
        let b = binary_heap_distance(&adj, &m.coords, &source);
        assert!(a.iter().all(|v| v.is_finite()));
        assert!(a.iter().zip(&b).all(|(p, q)| p.to_bits() == q.to_bits()));
        // No source: every distance is infinite.
        let none = edge_distance(&adj, &m.coords, &vec![false; n]);
        assert!(none.iter().all(|v| v.is_infinite()));
    }
}
