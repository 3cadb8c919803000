//! The harmonic re-map of a component's interior parameters (§3.3): the graph Laplace
//! problem Σ_{j ∈ N(i)} (δ_j − δ_i) = 0 on the free nodes with the boundary displacements as
//! Dirichlet data.
//!
//! The matrix (node degree on the diagonal, −1 per free neighbour) depends only on the
//! triangulation, so it is factorised once per component and reused by every update: the
//! free nodes are put in reverse Cuthill–McKee order and the matrix is factorised by an
//! envelope (skyline) Cholesky ([`sparse::envelope`]), which creates no entry outside the
//! envelope of that order; each update is then one forward and one backward substitution per
//! coordinate. A component whose envelope would be too large for a direct factorisation
//! (cost estimate above [`MAX_FACTOR_FLOPS`]) is solved by Jacobi-preconditioned conjugate
//! gradients (`sparse::pcg`, both coordinates at once) to a relative residual of 1e-8
//! instead (smoothing follows the map, so a more accurate map buys nothing there).

use sparse::envelope::{Envelope, EnvelopeCholesky};
use sparse::{Constraints, Jacobi, SolveOptions, SymMatrix, V3, order, pcg};

/// Largest estimated cost (multiply–adds) of a direct factorisation; above it the map is
/// solved iteratively.
pub const MAX_FACTOR_FLOPS: f64 = 4e8;

/// The Laplacian of one component's free nodes and its solver.
#[derive(Debug, Clone)]
pub struct HarmonicMap {
    n_fixed: usize,
    /// The Laplacian of the free nodes (free indices): degree on the diagonal, −1 per free
    /// neighbour.
    a: SymMatrix,
    /// The fixed neighbours of each free node (CSR).
    fixed_ptr: Vec<usize>,
    fixed_adj: Vec<u32>,
    factor: Option<EnvelopeCholesky>,
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
        let a = SymMatrix {
            diag: degree,
            vals: vec![-1.0; free_adj.len()],
            offsets: free_ptr,
            cols: free_adj,
        };
        let factor = factorise(&a);
        Self {
            n_fixed,
            a,
            fixed_ptr,
            fixed_adj,
            factor,
        }
    }

    /// Whether the map is solved by the direct factorisation.
    pub fn is_direct(&self) -> bool {
        self.factor.is_some()
    }

    /// Solves for the free nodes' displacements: `d[..n_fixed]` holds the boundary data,
    /// `d[n_fixed..]` receives the solution.
    pub fn solve(&self, d: &mut [[f64; 2]]) {
        let m = self.a.n();
        if m == 0 {
            return;
        }
        let Some(f) = &self.factor else {
            let x = self.iterative(d);
            for (i, v) in x.into_iter().enumerate() {
                d[i + self.n_fixed] = [v[0], v[1]];
            }
            return;
        };
        for comp in 0..2 {
            let b: Vec<f64> = self.rhs(d).iter().map(|v| v[comp]).collect();
            let x = f.solve(&b);
            for (i, v) in x.into_iter().enumerate() {
                d[i + self.n_fixed][comp] = v;
            }
        }
    }

    /// The transpose of [`solve`](Self::solve) (the map from the boundary data to the free
    /// nodes' solution is x = A_ff⁻¹ R d_b, R summing each free node's fixed neighbours; its
    /// transpose is Rᵀ A_ff⁻¹, A_ff being symmetric): `bar[n_fixed..]` holds the cotangent of
    /// the free nodes' solution; the cotangent of the boundary data is added to
    /// `bar[..n_fixed]`, and `bar[n_fixed..]` is zeroed.
    pub fn solve_transpose(&self, bar: &mut [[f64; 2]]) {
        let m = self.a.n();
        if m == 0 {
            return;
        }
        let z: Vec<[f64; 2]> = match &self.factor {
            Some(f) => {
                let mut z = vec![[0.0; 2]; m];
                for comp in 0..2 {
                    let b: Vec<f64> = (0..m).map(|i| bar[i + self.n_fixed][comp]).collect();
                    for (zi, v) in z.iter_mut().zip(f.solve(&b)) {
                        zi[comp] = v;
                    }
                }
                z
            }
            None => {
                let b: Vec<V3> = (0..m)
                    .map(|i| [bar[i + self.n_fixed][0], bar[i + self.n_fixed][1], 0.0])
                    .collect();
                self.pcg_solve(&b)
                    .into_iter()
                    .map(|v| [v[0], v[1]])
                    .collect()
            }
        };
        for (i, zi) in z.iter().enumerate() {
            for &w in &self.fixed_adj[self.fixed_ptr[i]..self.fixed_ptr[i + 1]] {
                bar[w as usize][0] += zi[0];
                bar[w as usize][1] += zi[1];
            }
            bar[i + self.n_fixed] = [0.0; 2];
        }
    }

    /// Right-hand side: per free node, the sum of its fixed neighbours' boundary data (both
    /// coordinates; the third component zero).
    fn rhs(&self, d: &[[f64; 2]]) -> Vec<V3> {
        (0..self.a.n())
            .map(|i| {
                let fixed = &self.fixed_adj[self.fixed_ptr[i]..self.fixed_ptr[i + 1]];
                let sum = |c: usize| fixed.iter().map(|&w| d[w as usize][c]).sum();
                [sum(0), sum(1), 0.0]
            })
            .collect()
    }

    /// Jacobi-preconditioned conjugate gradients from zero to a relative residual of 1e-8,
    /// both coordinates at once.
    fn iterative(&self, d: &[[f64; 2]]) -> Vec<V3> {
        self.pcg_solve(&self.rhs(d))
    }

    /// A_ff x = b by Jacobi-preconditioned conjugate gradients (see [`Self::iterative`]).
    fn pcg_solve(&self, b: &[V3]) -> Vec<V3> {
        let m = self.a.n();
        let mut x = vec![[0.0; 3]; m];
        let opts = SolveOptions {
            rel_tol: 1e-8,
            max_iters: (m + 100).min(20_000),
        };
        pcg(
            &self.a,
            b,
            &mut x,
            &Jacobi::new(&self.a),
            &Constraints::default(),
            &opts,
        );
        x
    }
}

/// Envelope Cholesky of `a` in reverse Cuthill–McKee order; `None` when too costly
/// ([`MAX_FACTOR_FLOPS`]) or not positive definite (a free part without a fixed neighbour):
/// the map is then solved iteratively.
fn factorise(a: &SymMatrix) -> Option<EnvelopeCholesky> {
    let m = a.n();
    if m == 0 {
        return None;
    }
    let perm = order::reverse_cuthill_mckee(m, |i| a.row(i).0);
    let env = Envelope::new(m, |i| a.row(i).0, &perm);
    if env.flops() > MAX_FACTOR_FLOPS {
        return None;
    }
    EnvelopeCholesky::factor(env, a).ok()
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
    fn transpose_solve_is_the_transpose() {
        let (tris, uv, nb) = square(7);
        let map = HarmonicMap::new(&tris, uv.len(), nb);
        let n = uv.len();
        let r = |k: usize, c: usize| ((k * 7 + c * 3) as f64 * 0.37).sin();
        let mut d: Vec<[f64; 2]> = (0..n)
            .map(|k| if k < nb { [r(k, 0), r(k, 1)] } else { [0.0; 2] })
            .collect();
        let db = d.clone();
        map.solve(&mut d);
        let ybar: Vec<[f64; 2]> = (0..n)
            .map(|k| if k < nb { [0.0; 2] } else { [r(k, 5), r(k, 2)] })
            .collect();
        let mut xb = ybar.clone();
        map.solve_transpose(&mut xb);
        let lhs: f64 = (nb..n)
            .map(|k| d[k][0] * ybar[k][0] + d[k][1] * ybar[k][1])
            .sum();
        let rhs: f64 = (0..nb)
            .map(|k| db[k][0] * xb[k][0] + db[k][1] * xb[k][1])
            .sum();
        assert!(
            (lhs - rhs).abs() < 1e-12 * lhs.abs().max(1.0),
            "{lhs} vs {rhs}"
        );
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
        let x = map.iterative(&d);
        for (k, v) in x.iter().enumerate() {
            it[k + nb] = [v[0], v[1]];
        }
        for k in nb..uv.len() {
            let e = f(uv[k]);
            assert!((d[k][0] - e[0]).abs() < 1e-13 && (d[k][1] - e[1]).abs() < 1e-13);
            assert!((it[k][0] - e[0]).abs() < 1e-7 && (it[k][1] - e[1]).abs() < 1e-7);
        }
    }
}
