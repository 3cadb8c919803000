//! The harmonic re-map of a component's interior parameters (§3.3): the graph Laplace
//! problem Σ_{j ∈ N(i)} (δ_j − δ_i) = 0 on the free nodes with the boundary displacements as
//! Dirichlet data.
//!
//! The matrix (node degree on the diagonal, −1 per free neighbour) depends only on the
//! triangulation, so it is factorised once per component and reused by every update: the
//! free nodes are put in reverse Cuthill–McKee order and the matrix is factorised by an
//! envelope (skyline) Cholesky, which creates no entry outside the envelope of that order;
//! each update is then one forward and one backward substitution per coordinate. A
//! component whose envelope would be too large for a direct factorisation (cost estimate
//! above [`MAX_FACTOR_FLOPS`]) is solved by conjugate gradients to a relative residual of
//! 1e-8 instead (smoothing follows the map, so a more accurate map buys nothing there).

/// Largest estimated cost (multiply–adds) of a direct factorisation; above it the map is
/// solved iteratively.
pub const MAX_FACTOR_FLOPS: f64 = 4e8;

/// The Laplacian of one component's free nodes and its solver.
#[derive(Debug, Clone)]
pub struct HarmonicMap {
    n_fixed: usize,
    /// Free-node adjacency (free indices, CSR) and the fixed neighbours of each free node.
    free_ptr: Vec<usize>,
    free_adj: Vec<u32>,
    fixed_ptr: Vec<usize>,
    fixed_adj: Vec<u32>,
    degree: Vec<f64>,
    factor: Option<Envelope>,
}

/// Envelope Cholesky factor L (A = L Lᵀ) in the order `order` (position → free index).
#[derive(Debug, Clone)]
struct Envelope {
    order: Vec<u32>,
    /// First column of row p of L.
    first: Vec<usize>,
    /// Start of row p in `l` (row p holds columns first[p]..=p).
    start: Vec<usize>,
    l: Vec<f64>,
}

impl HarmonicMap {
    /// The map of a component with `n` nodes of which the first `n_fixed` are fixed (its
    /// boundary), triangles `tris` (local indices).
    pub fn new(tris: &[[u32; 3]], n: usize, n_fixed: usize) -> Self {
        let mut edges: Vec<(u32, u32)> = Vec::with_capacity(6 * tris.len());
        for t in tris {
            for i in 0..3 {
                let (a, b) = (t[i], t[(i + 1) % 3]);
                edges.push((a, b));
                edges.push((b, a));
            }
        }
        edges.sort_unstable();
        edges.dedup();
        let m = n - n_fixed;
        let mut degree = vec![0.0; m];
        let (mut free_ptr, mut fixed_ptr) = (vec![0usize; m + 1], vec![0usize; m + 1]);
        let (mut free_adj, mut fixed_adj) = (Vec::new(), Vec::new());
        let mut e = edges.iter().peekable();
        for v in 0..n {
            while let Some(&&(a, b)) = e.peek() {
                if a as usize != v {
                    break;
                }
                e.next();
                if v >= n_fixed {
                    degree[v - n_fixed] += 1.0;
                    if (b as usize) < n_fixed {
                        fixed_adj.push(b);
                    } else {
                        free_adj.push(b - n_fixed as u32);
                    }
                }
            }
            if v >= n_fixed {
                free_ptr[v - n_fixed + 1] = free_adj.len();
                fixed_ptr[v - n_fixed + 1] = fixed_adj.len();
            }
        }
        let mut map = Self {
            n_fixed,
            free_ptr,
            free_adj,
            fixed_ptr,
            fixed_adj,
            degree,
            factor: None,
        };
        map.factor = map.factorise();
        map
    }

    /// Whether the map is solved by the direct factorisation.
    pub fn is_direct(&self) -> bool {
        self.factor.is_some()
    }

    fn free_neighbours(&self, i: usize) -> &[u32] {
        &self.free_adj[self.free_ptr[i]..self.free_ptr[i + 1]]
    }

    /// Envelope Cholesky in RCM order; `None` when too costly or not positive definite (a
    /// free part without a fixed neighbour).
    fn factorise(&self) -> Option<Envelope> {
        let m = self.degree.len();
        if m == 0 {
            return None;
        }
        let order = mesh::order::reverse_cuthill_mckee(m, |i| self.free_neighbours(i));
        let mut pos = vec![0usize; m];
        for (p, &i) in order.iter().enumerate() {
            pos[i as usize] = p;
        }
        let mut first: Vec<usize> = (0..m).collect();
        for (p, &i) in order.iter().enumerate() {
            for &j in self.free_neighbours(i as usize) {
                first[p] = first[p].min(pos[j as usize]);
            }
        }
        let flops: f64 = (0..m).map(|p| ((p - first[p]) as f64).powi(2) / 2.0).sum();
        if flops > MAX_FACTOR_FLOPS {
            return None;
        }
        let mut start = vec![0usize; m + 1];
        for p in 0..m {
            start[p + 1] = start[p] + (p - first[p] + 1);
        }
        let mut l = vec![0.0; start[m]];
        for (p, &i) in order.iter().enumerate() {
            l[start[p] + (p - first[p])] = self.degree[i as usize];
            for &j in self.free_neighbours(i as usize) {
                let q = pos[j as usize];
                if q < p {
                    l[start[p] + (q - first[p])] = -1.0;
                }
            }
        }
        for p in 0..m {
            let fp = first[p];
            for q in fp..=p {
                let fq = first[q];
                let k0 = fp.max(fq);
                let mut s = l[start[p] + (q - fp)];
                let (rp, rq) = (&l[start[p] + (k0 - fp)..], &l[start[q] + (k0 - fq)..]);
                for k in 0..(q - k0) {
                    s -= rp[k] * rq[k];
                }
                if q == p {
                    if s <= 0.0 || !s.is_finite() {
                        return None;
                    }
                    l[start[p] + (p - fp)] = s.sqrt();
                } else {
                    l[start[p] + (q - fp)] = s / l[start[q] + (q - fq)];
                }
            }
        }
        Some(Envelope {
            order,
            first,
            start,
            l,
        })
    }

    /// Solves for the free nodes' displacements: `d[..n_fixed]` holds the boundary data,
    /// `d[n_fixed..]` receives the solution.
    pub fn solve(&self, d: &mut [[f64; 2]]) {
        let m = self.degree.len();
        if m == 0 {
            return;
        }
        for comp in 0..2 {
            let b = self.rhs(d, comp);
            let x = match &self.factor {
                Some(f) => f.solve(&b),
                None => self.cg(&b),
            };
            for (i, v) in x.into_iter().enumerate() {
                d[i + self.n_fixed][comp] = v;
            }
        }
    }

    /// Right-hand side of coordinate `comp`: per free node, the sum of its fixed neighbours'
    /// boundary data.
    fn rhs(&self, d: &[[f64; 2]], comp: usize) -> Vec<f64> {
        (0..self.degree.len())
            .map(|i| {
                self.fixed_adj[self.fixed_ptr[i]..self.fixed_ptr[i + 1]]
                    .iter()
                    .map(|&w| d[w as usize][comp])
                    .sum()
            })
            .collect()
    }

    /// Conjugate gradients from zero to a relative residual of 1e-8.
    fn cg(&self, b: &[f64]) -> Vec<f64> {
        let m = b.len();
        let apply = |x: &[f64], y: &mut [f64]| {
            for i in 0..m {
                let mut s = self.degree[i] * x[i];
                for &w in self.free_neighbours(i) {
                    s -= x[w as usize];
                }
                y[i] = s;
            }
        };
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        let mut x = vec![0.0; m];
        let mut r = b.to_vec();
        let mut p = r.clone();
        let mut ap = vec![0.0; m];
        let mut rr = dot(&r, &r);
        let tol = 1e-16 * dot(b, b).max(1e-300);
        for _ in 0..(m + 100).min(20_000) {
            if rr <= tol {
                break;
            }
            apply(&p, &mut ap);
            let alpha = rr / dot(&p, &ap);
            for i in 0..m {
                x[i] += alpha * p[i];
                r[i] -= alpha * ap[i];
            }
            let rr2 = dot(&r, &r);
            let beta = rr2 / rr;
            rr = rr2;
            for i in 0..m {
                p[i] = r[i] + beta * p[i];
            }
        }
        x
    }
}

impl Envelope {
    /// x = A⁻¹ b (b and x indexed by free node).
    fn solve(&self, b: &[f64]) -> Vec<f64> {
        let m = b.len();
        // L y = b (in band order).
        let mut y: Vec<f64> = self.order.iter().map(|&i| b[i as usize]).collect();
        for p in 0..m {
            let fp = self.first[p];
            let row = &self.l[self.start[p]..self.start[p + 1]];
            let mut s = y[p];
            for (k, lk) in row[..p - fp].iter().enumerate() {
                s -= lk * y[fp + k];
            }
            y[p] = s / row[p - fp];
        }
        // Lᵀ x = y (column sweep over the rows of L).
        for p in (0..m).rev() {
            let fp = self.first[p];
            let row = &self.l[self.start[p]..self.start[p + 1]];
            y[p] /= row[p - fp];
            let v = y[p];
            for (k, lk) in row[..p - fp].iter().enumerate() {
                y[fp + k] -= lk * v;
            }
        }
        let mut x = vec![0.0; m];
        for (p, &i) in self.order.iter().enumerate() {
            x[i as usize] = y[p];
        }
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A structured triangulation of an (n+1)×(n+1) node square; boundary nodes first.
    fn square(n: usize) -> (Vec<[u32; 3]>, Vec<[f64; 2]>, usize) {
        let idx = |i: usize, j: usize| i + (n + 1) * j;
        let on_b = |i: usize, j: usize| i == 0 || j == 0 || i == n || j == n;
        let mut order: Vec<usize> = (0..(n + 1) * (n + 1))
            .filter(|&k| on_b(k % (n + 1), k / (n + 1)))
            .collect();
        let nb = order.len();
        order.extend((0..(n + 1) * (n + 1)).filter(|&k| !on_b(k % (n + 1), k / (n + 1))));
        let mut local = vec![0u32; order.len()];
        for (l, &g) in order.iter().enumerate() {
            local[g] = l as u32;
        }
        let mut tris = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let (a, b, c, d) = (idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1));
                tris.push([local[a], local[b], local[c]]);
                tris.push([local[a], local[c], local[d]]);
            }
        }
        let uv = order
            .iter()
            .map(|&g| {
                [
                    (g % (n + 1)) as f64 / n as f64,
                    (g / (n + 1)) as f64 / n as f64,
                ]
            })
            .collect();
        (tris, uv, nb)
    }

    #[test]
    fn direct_and_iterative_maps_reproduce_a_linear_field() {
        // A linear boundary displacement has the linear field as its discrete harmonic
        // extension on this triangulation (every interior node is the mean of its six
        // neighbours, symmetric about it).
        let (tris, uv, nb) = square(12);
        let map = HarmonicMap::new(&tris, uv.len(), nb);
        assert!(map.is_direct());
        let f = |p: [f64; 2]| [0.1 + 0.3 * p[0] - 0.2 * p[1], -0.05 * p[0] + 0.4 * p[1]];
        let mut d: Vec<[f64; 2]> = (0..uv.len())
            .map(|k| if k < nb { f(uv[k]) } else { [0.0; 2] })
            .collect();
        map.solve(&mut d);
        let mut it = d.clone();
        let x = map.cg(&map.rhs(&d, 0));
        for (k, v) in x.iter().enumerate() {
            it[k + nb][0] = *v;
        }
        for k in nb..uv.len() {
            let e = f(uv[k]);
            assert!((d[k][0] - e[0]).abs() < 1e-13 && (d[k][1] - e[1]).abs() < 1e-13);
            assert!((it[k][0] - e[0]).abs() < 1e-7);
        }
    }
}
