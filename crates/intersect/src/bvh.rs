//! Axis-aligned bounding boxes and a bounding-volume hierarchy over them (global seeding of
//! the foot-of-the-normal search, Eq. 11).

use geom_db::prelude::Point3;
use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// An axis-aligned box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub min: [f64; 3],
    /// Upper corner.
    pub max: [f64; 3],
}

impl Aabb {
    /// The empty box (union identity).
    pub const EMPTY: Aabb = Aabb {
        min: [f64::INFINITY; 3],
        max: [f64::NEG_INFINITY; 3],
    };

    /// Grows the box to contain `p`.
    pub fn add(&mut self, p: &Point3) {
        for k in 0..3 {
            self.min[k] = self.min[k].min(p[k]);
            self.max[k] = self.max[k].max(p[k]);
        }
    }

    /// The union of two boxes.
    pub fn union(&self, o: &Aabb) -> Aabb {
        let mut b = *self;
        for k in 0..3 {
            b.min[k] = b.min[k].min(o.min[k]);
            b.max[k] = b.max[k].max(o.max[k]);
        }
        b
    }

    /// The box grown by `r` on every side.
    pub fn inflated(&self, r: f64) -> Aabb {
        let mut b = *self;
        for k in 0..3 {
            b.min[k] -= r;
            b.max[k] += r;
        }
        b
    }

    /// Length of the diagonal (0 for the empty box).
    pub fn diagonal(&self) -> f64 {
        if self.min[0] > self.max[0] {
            return 0.0;
        }
        (0..3)
            .map(|k| (self.max[k] - self.min[k]).powi(2))
            .sum::<f64>()
            .sqrt()
    }

    /// Squared distance from `p` to the box (0 inside).
    pub fn dist2(&self, p: &Point3) -> f64 {
        let mut d = 0.0;
        for k in 0..3 {
            let e = (self.min[k] - p[k]).max(p[k] - self.max[k]).max(0.0);
            d += e * e;
        }
        d
    }

    fn centre(&self, k: usize) -> f64 {
        0.5 * (self.min[k] + self.max[k])
    }
}

#[derive(Debug, Clone)]
struct Node {
    bbox: Aabb,
    /// Leaf: first index into `order`; inner: index of the left child (right = left + 1).
    first: u32,
    /// Leaf: number of items (> 0); inner: 0.
    count: u32,
}

/// A bounding-volume hierarchy over a fixed list of boxes (median split on the longest axis).
#[derive(Debug, Clone)]
pub struct Bvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
    boxes: Vec<Aabb>,
}

/// Heap entry ordered by increasing key (a min-heap on top of `BinaryHeap`); ties broken by
/// the index so that traversal order is deterministic.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Entry(f64, u32);
impl Eq for Entry {}
impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Entry {
    fn cmp(&self, other: &Self) -> Ordering {
        other
            .0
            .total_cmp(&self.0)
            .then_with(|| other.1.cmp(&self.1))
    }
}

const LEAF_SIZE: usize = 4;

impl Bvh {
    /// Builds the hierarchy over `boxes` (item i is `boxes[i]`).
    pub fn new(boxes: Vec<Aabb>) -> Self {
        let mut order: Vec<u32> = (0..boxes.len() as u32).collect();
        let mut nodes = vec![Node {
            bbox: Aabb::EMPTY,
            first: 0,
            count: 0,
        }];
        if !boxes.is_empty() {
            Self::build(&boxes, &mut order, &mut nodes, 0, 0, boxes.len());
        }
        Self {
            nodes,
            order,
            boxes,
        }
    }

    fn build(
        boxes: &[Aabb],
        order: &mut [u32],
        nodes: &mut Vec<Node>,
        node: usize,
        lo: usize,
        hi: usize,
    ) {
        let mut bbox = Aabb::EMPTY;
        let mut cbox = Aabb::EMPTY;
        for &i in &order[lo..hi] {
            let b = &boxes[i as usize];
            bbox = bbox.union(b);
            cbox.add(&Point3::new(b.centre(0), b.centre(1), b.centre(2)));
        }
        nodes[node].bbox = bbox;
        if hi - lo <= LEAF_SIZE {
            nodes[node].first = lo as u32;
            nodes[node].count = (hi - lo) as u32;
            return;
        }
        let axis = (0..3)
            .max_by(|&a, &b| (cbox.max[a] - cbox.min[a]).total_cmp(&(cbox.max[b] - cbox.min[b])))
            .unwrap_or(0);
        let mid = (lo + hi) / 2;
        order[lo..hi].select_nth_unstable_by(mid - lo, |&a, &b| {
            boxes[a as usize]
                .centre(axis)
                .total_cmp(&boxes[b as usize].centre(axis))
                .then(a.cmp(&b))
        });
        let left = nodes.len();
        nodes.push(Node {
            bbox: Aabb::EMPTY,
            first: 0,
            count: 0,
        });
        nodes.push(Node {
            bbox: Aabb::EMPTY,
            first: 0,
            count: 0,
        });
        nodes[node].first = left as u32;
        nodes[node].count = 0;
        Self::build(boxes, order, nodes, left, lo, mid);
        Self::build(boxes, order, nodes, left + 1, mid, hi);
    }

    /// The box of item `i`.
    pub fn item_box(&self, i: usize) -> &Aabb {
        &self.boxes[i]
    }

    /// The box of everything.
    pub fn root_box(&self) -> &Aabb {
        &self.nodes[0].bbox
    }

    /// Branch and bound for the nearest item: visits items in order of increasing box
    /// distance, calling `upper(i)` (an upper bound of the squared distance from the query
    /// point to the geometry inside item i, e.g. its nearest sample point) on each, and
    /// returns in `out` every item whose lower bound is not farther than the best upper bound
    /// found (and than `init_best`, an upper bound known beforehand), as `(squared lower
    /// bound, item)` sorted by increasing bound then item index. `refine(i, d)` may raise the
    /// box bound d of item i to a tighter lower bound (e.g. an oriented box).
    pub fn candidates(
        &self,
        p: &Point3,
        init_best: f64,
        mut refine: impl FnMut(usize, f64) -> f64,
        mut upper: impl FnMut(usize) -> f64,
        out: &mut Vec<(f64, u32)>,
    ) {
        out.clear();
        if self.boxes.is_empty() {
            return;
        }
        let mut best = init_best;
        let mut heap = BinaryHeap::with_capacity(32);
        heap.push(Entry(self.nodes[0].bbox.dist2(p), 0));
        while let Some(Entry(lb, n)) = heap.pop() {
            if lb > best {
                break;
            }
            let node = &self.nodes[n as usize];
            if node.count > 0 {
                let (a, b) = (node.first as usize, (node.first + node.count) as usize);
                for &it in &self.order[a..b] {
                    let d = self.boxes[it as usize].dist2(p);
                    if d > best {
                        continue;
                    }
                    let d = refine(it as usize, d);
                    if d <= best {
                        out.push((d, it));
                        best = best.min(upper(it as usize));
                    }
                }
            } else {
                for c in [node.first, node.first + 1] {
                    let d = self.nodes[c as usize].bbox.dist2(p);
                    if d <= best {
                        heap.push(Entry(d, c));
                    }
                }
            }
        }
        out.retain(|&(d, _)| d <= best);
        out.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn candidates_contain_the_nearest_box() {
        // 1000 unit boxes on a line; the query is nearest to box 437.
        let boxes: Vec<Aabb> = (0..1000)
            .map(|i| {
                let x = i as f64 * 2.0;
                Aabb {
                    min: [x, 0.0, 0.0],
                    max: [x + 1.0, 1.0, 1.0],
                }
            })
            .collect();
        let bvh = Bvh::new(boxes.clone());
        let p = Point3::new(874.5, 0.5, 3.0);
        let mut out = Vec::new();
        // upper bound: distance to the box centre
        bvh.candidates(
            &p,
            f64::INFINITY,
            |_, d| d,
            |i| {
                let b = &boxes[i];
                (0..3).map(|k| (b.centre(k) - p[k]).powi(2)).sum()
            },
            &mut out,
        );
        assert_eq!(out[0].1, 437);
        assert!(out.iter().all(|&(d, _)| d <= 2.5f64.powi(2) + 1e-12));
        // brute force: every box closer than the best centre is listed
        let best = 2.5f64.powi(2);
        let brute: Vec<u32> = (0..1000u32)
            .filter(|&i| boxes[i as usize].dist2(&p) <= best)
            .collect();
        let mut got: Vec<u32> = out.iter().map(|x| x.1).collect();
        got.sort();
        assert_eq!(got, brute);
    }

    #[test]
    fn box_distance() {
        let b = Aabb {
            min: [0.0; 3],
            max: [1.0; 3],
        };
        assert_eq!(b.dist2(&Point3::new(0.5, 0.5, 0.5)), 0.0);
        assert_eq!(b.dist2(&Point3::new(2.0, 0.5, -1.0)), 2.0);
    }
}
