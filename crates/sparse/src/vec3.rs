//! Deterministic parallel kernels on arrays of 3-vectors: dot products, norms and fused
//! updates whose results are bit-identical for any number of threads.
//!
//! Every reduction splits the array into fixed-size chunks of [`CHUNK`] entries (independent
//! of the thread count), sums each chunk sequentially, and adds the chunk sums in chunk order.

use rayon::prelude::*;

/// One node's three components (x, y, z).
pub type V3 = [f64; 3];

/// Chunk length of every parallel loop and reduction (fixed, so results do not depend on the
/// number of threads).
pub const CHUNK: usize = 4096;

/// Adds chunk partial sums in chunk order.
pub fn ordered_sum(parts: Vec<f64>) -> f64 {
    parts.into_iter().fold(0.0, |a, b| a + b)
}

/// Runs `f(first index, chunk)` on the fixed chunks of [`CHUNK`] entries of `out` in
/// parallel and adds the values it returns in chunk order: the reduction of every fused
/// kernel that writes a vector and sums over it (deterministic for any thread count).
pub fn chunked_sum<F>(out: &mut [V3], f: F) -> f64
where
    F: Fn(usize, &mut [V3]) -> f64 + Sync + Send,
{
    let parts: Vec<f64> = out
        .par_chunks_mut(CHUNK)
        .enumerate()
        .map(|(c, os)| f(c * CHUNK, os))
        .collect();
    ordered_sum(parts)
}

/// `data` cut into one slice per chunk of `chunk` rows (of `rows`), rows r of which start
/// at `start(r)` in `data` (`start(rows)` is its end): each chunk of a CSR array can then be
/// written by its own task.
pub fn row_chunks<T>(
    data: &mut [T],
    rows: usize,
    chunk: usize,
    start: impl Fn(usize) -> usize,
) -> Vec<&mut [T]> {
    let chunk = chunk.max(1);
    let mut out = Vec::with_capacity(rows.div_ceil(chunk));
    let mut rest = data;
    for lo in (0..rows).step_by(chunk) {
        let hi = (lo + chunk).min(rows);
        let (piece, tail) = rest.split_at_mut(start(hi) - start(lo));
        out.push(piece);
        rest = tail;
    }
    out
}

/// Σ_i a_i · b_i over all nodes and components.
pub fn dot(a: &[V3], b: &[V3]) -> f64 {
    assert_eq!(a.len(), b.len());
    let parts: Vec<f64> = a
        .par_chunks(CHUNK)
        .zip(b.par_chunks(CHUNK))
        .map(|(ca, cb)| {
            let mut s = 0.0;
            for (x, y) in ca.iter().zip(cb) {
                s += x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
            }
            s
        })
        .collect();
    ordered_sum(parts)
}

/// Euclidean norm over all nodes and components.
pub fn norm(a: &[V3]) -> f64 {
    dot(a, a).sqrt()
}

/// Largest Euclidean length of one node's vector (max is order independent).
pub fn max_len(a: &[V3]) -> f64 {
    a.par_chunks(CHUNK)
        .map(|c| {
            c.iter()
                .map(|v| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt())
                .fold(0.0, f64::max)
        })
        .reduce(|| 0.0, f64::max)
}

/// y ← y + α x.
pub fn axpy(alpha: f64, x: &[V3], y: &mut [V3]) {
    y.par_chunks_mut(CHUNK)
        .zip(x.par_chunks(CHUNK))
        .for_each(|(cy, cx)| {
            for (yi, xi) in cy.iter_mut().zip(cx) {
                for k in 0..3 {
                    yi[k] += alpha * xi[k];
                }
            }
        });
}

/// p ← z + β p.
pub fn xpby(z: &[V3], beta: f64, p: &mut [V3]) {
    p.par_chunks_mut(CHUNK)
        .zip(z.par_chunks(CHUNK))
        .for_each(|(cp, cz)| {
            for (pi, zi) in cp.iter_mut().zip(cz) {
                for k in 0..3 {
                    pi[k] = zi[k] + beta * pi[k];
                }
            }
        });
}

/// x ← x + α p, then p ← z + β p, in one pass (conjugate gradients' two updates of the
/// same p; bit for bit [`axpy`] followed by [`xpby`]).
pub fn axpy_xpby(alpha: f64, x: &mut [V3], z: &[V3], beta: f64, p: &mut [V3]) {
    assert!(x.len() == p.len() && z.len() == p.len());
    x.par_chunks_mut(CHUNK)
        .zip(p.par_chunks_mut(CHUNK))
        .zip(z.par_chunks(CHUNK))
        .for_each(|((cx, cp), cz)| {
            for ((xi, pi), zi) in cx.iter_mut().zip(cp.iter_mut()).zip(cz) {
                for k in 0..3 {
                    xi[k] += alpha * pi[k];
                    pi[k] = zi[k] + beta * pi[k];
                }
            }
        });
}

/// Sets every entry to zero.
pub fn fill_zero(a: &mut [V3]) {
    a.par_chunks_mut(CHUNK).for_each(|c| c.fill([0.0; 3]));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fused_cg_update_equals_the_two_updates_bit_for_bit() {
        let n = 3 * CHUNK + 17;
        let v = |s: f64| -> Vec<V3> {
            (0..n)
                .map(|i| {
                    let t = s * (i as f64 + 0.5);
                    [t.sin(), t.cos() * 3.0, (2.0 * t).sin() / 7.0]
                })
                .collect()
        };
        let (x0, p0, z) = (v(0.3), v(1.7), v(2.9));
        let (alpha, beta) = (0.731, -1.37e-2);
        let (mut x1, mut p1) = (x0.clone(), p0.clone());
        axpy(alpha, &p1, &mut x1);
        xpby(&z, beta, &mut p1);
        let (mut x2, mut p2) = (x0, p0);
        axpy_xpby(alpha, &mut x2, &z, beta, &mut p2);
        assert_eq!((x1, p1), (x2, p2));
    }

    #[test]
    fn dot_is_thread_count_independent() {
        let n = 50_000;
        let a: Vec<V3> = (0..n)
            .map(|i| {
                let t = i as f64;
                [(t * 0.37).sin(), (t * 1.1).cos() * 1e3, 1.0 / (1.0 + t)]
            })
            .collect();
        let b: Vec<V3> = a.iter().map(|v| [v[2], v[0], v[1] * 1e-3]).collect();
        let one = testkit::with_threads(1, || dot(&a, &b));
        let three = testkit::with_threads(3, || dot(&a, &b));
        assert_eq!(one.to_bits(), three.to_bits());
        // Same as a sequential chunked sum.
        let mut total = 0.0;
        for (ca, cb) in a.chunks(CHUNK).zip(b.chunks(CHUNK)) {
            let mut s = 0.0;
            for (x, y) in ca.iter().zip(cb) {
                s += x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
            }
            total += s;
        }
        assert_eq!(one.to_bits(), total.to_bits());
    }
}
