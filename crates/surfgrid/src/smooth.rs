//! Grid improvement in the parametric plane of one component ("mesh optimisation", §3.3):
//! diagonal swaps that raise the smaller 3-D mean ratio of the two triangles, and Laplacian
//! smoothing of interior nodes' (u, v) accepted only when every incident triangle stays
//! positively oriented in (u, v) and the worst incident 3-D quality does not drop (or, for an
//! invalid neighbourhood, when the number of inverted triangles falls).

use std::collections::HashMap;

use geom_db::prelude::Point3;

type P = [f64; 2];

#[inline]
pub(crate) fn orient(a: P, b: P, c: P) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Unsigned mean ratio 4√3 A / Σ l² of a 3-D triangle.
#[inline]
pub(crate) fn quality3(a: &Point3, b: &Point3, c: &Point3) -> f64 {
    let area = 0.5 * (b - a).cross(&(c - a)).norm();
    let s = (b - a).norm_squared() + (c - b).norm_squared() + (a - c).norm_squared();
    if s == 0.0 {
        0.0
    } else {
        4.0 * 3f64.sqrt() * area / s
    }
}

/// Quality used for improvement: the 3-D mean ratio, negated for a triangle that is not
/// counter-clockwise in (u, v).
#[inline]
fn tri_q(t: &[u32; 3], uv: &[P], x: &[Point3]) -> f64 {
    let [a, b, c] = t.map(|v| v as usize);
    let q = quality3(&x[a], &x[b], &x[c]);
    if orient(uv[a], uv[b], uv[c]) > 0.0 {
        q
    } else {
        -q - 1e-300
    }
}

/// A component's parametric triangulation being improved.
pub(crate) struct Improve<'f> {
    pub uv: Vec<P>,
    pub x: Vec<Point3>,
    pub tris: Vec<[u32; 3]>,
    pub n_fixed: usize,
    /// Nodes no swap may touch (pole copies: each belongs to exactly one triangle); empty
    /// for none.
    pub no_swap: Vec<bool>,
    pub eval: &'f (dyn Fn(P) -> Point3 + Sync),
}

impl Improve<'_> {
    /// Diagonal swaps; returns the number made.
    pub fn swap_pass(&mut self) -> usize {
        let mut edge: HashMap<(u32, u32), (u32, u8)> = HashMap::with_capacity(self.tris.len() * 2);
        for (k, t) in self.tris.iter().enumerate() {
            for i in 0..3u8 {
                edge.insert((t[i as usize], t[(i as usize + 1) % 3]), (k as u32, i));
            }
        }
        let mut touched = vec![false; self.tris.len()];
        let mut swaps = 0;
        for k in 0..self.tris.len() {
            if touched[k] {
                continue;
            }
            for i in 0..3 {
                let t1 = self.tris[k];
                let (a, b, c) = (t1[i], t1[(i + 1) % 3], t1[(i + 2) % 3]);
                let Some(&(k2, j)) = edge.get(&(b, a)) else {
                    continue;
                };
                let k2 = k2 as usize;
                if touched[k2] || k2 == k {
                    continue;
                }
                let d = self.tris[k2][(j as usize + 2) % 3];
                if d == c {
                    continue;
                }
                if !self.no_swap.is_empty()
                    && [a, b, c, d].iter().any(|&v| self.no_swap[v as usize])
                {
                    continue;
                }
                let n1 = [c, a, d];
                let n2 = [d, b, c];
                let old =
                    tri_q(&t1, &self.uv, &self.x).min(tri_q(&self.tris[k2], &self.uv, &self.x));
                let new = tri_q(&n1, &self.uv, &self.x).min(tri_q(&n2, &self.uv, &self.x));
                if new > old + 1e-9 && !edge.contains_key(&(c, d)) && !edge.contains_key(&(d, c)) {
                    self.tris[k] = n1;
                    self.tris[k2] = n2;
                    touched[k] = true;
                    touched[k2] = true;
                    swaps += 1;
                    break;
                }
            }
        }
        swaps
    }

    /// One Laplacian smoothing pass over the free nodes; returns the number moved.
    pub fn smooth_pass(&mut self) -> usize {
        self.smooth_pass_recorded(None)
    }

    /// [`smooth_pass`](Self::smooth_pass), appending each accepted move to `rec` as (node,
    /// step fraction w): the node's (u, v) became (1 − w) (u, v) + w × the mean of its
    /// neighbours' (u, v) at that moment (the linearisation replays them).
    pub fn smooth_pass_recorded(&mut self, mut rec: Option<&mut Vec<(u32, f64)>>) -> usize {
        let n = self.uv.len();
        let mut inc: Vec<Vec<u32>> = vec![Vec::new(); n];
        for (k, t) in self.tris.iter().enumerate() {
            for &v in t {
                inc[v as usize].push(k as u32);
            }
        }
        let mut moved = 0;
        for v in self.n_fixed..n {
            if inc[v].is_empty() {
                continue;
            }
            let mut nb: Vec<u32> = inc[v]
                .iter()
                .flat_map(|&k| self.tris[k as usize])
                .filter(|&w| w as usize != v)
                .collect();
            nb.sort_unstable();
            nb.dedup();
            let mut c = [0.0, 0.0];
            for &w in &nb {
                c[0] += self.uv[w as usize][0];
                c[1] += self.uv[w as usize][1];
            }
            c = [c[0] / nb.len() as f64, c[1] / nb.len() as f64];
            let score = |s: &Self| -> (usize, f64) {
                let mut bad = 0;
                let mut qmin = f64::INFINITY;
                for &k in &inc[v] {
                    let q = tri_q(&s.tris[k as usize], &s.uv, &s.x);
                    if q <= 0.0 {
                        bad += 1;
                    }
                    qmin = qmin.min(q);
                }
                (bad, qmin)
            };
            let (bad0, q0) = score(self);
            let (old_uv, old_x) = (self.uv[v], self.x[v]);
            // try the full Laplacian step, then half of it
            let mut accepted = None;
            for w in [1.0, 0.5] {
                let p = [
                    old_uv[0] + w * (c[0] - old_uv[0]),
                    old_uv[1] + w * (c[1] - old_uv[1]),
                ];
                self.uv[v] = p;
                self.x[v] = (self.eval)(p);
                let (bad1, q1) = score(self);
                if bad1 < bad0 || (bad1 == bad0 && q1 >= q0 - 1e-12 * q0.abs()) {
                    accepted = Some(w);
                    break;
                }
            }
            if let Some(w) = accepted {
                moved += 1;
                if let Some(r) = rec.as_deref_mut() {
                    r.push((v as u32, w));
                }
            } else {
                self.uv[v] = old_uv;
                self.x[v] = old_x;
            }
        }
        moved
    }

    /// Number of triangles not counter-clockwise in (u, v).
    pub fn n_inverted(&self) -> usize {
        self.tris
            .iter()
            .filter(|t| {
                let [a, b, c] = t.map(|v| v as usize);
                orient(self.uv[a], self.uv[b], self.uv[c]) <= 0.0
            })
            .count()
    }
}
