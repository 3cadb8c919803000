//! Test and benchmark systems: the spring matrix of a structured grid, with a right-hand
//! side, as the volume deformation assembles it (symmetric positive definite, an M-matrix).

use crate::sym::SymMatrix;
use crate::vec3::V3;

/// Spring matrix of a structured nx × ny × nz grid (spacings 1, 0.7, 1.9; the six axis
/// neighbours and six face diagonals of a tetrahedral split), K = 1/length², boundary nodes
/// prescribed (eliminated, with a smooth displacement moved to the right-hand side): the
/// interior matrix (lexicographic order, rows sorted) and the right-hand side.
pub fn spring_grid(nx: usize, ny: usize, nz: usize) -> (SymMatrix, Vec<V3>) {
    let (hx, hy, hz) = (1.0, 0.7, 1.9);
    let id = |i: usize, j: usize, k: usize| (k * ny + j) * nx + i;
    let interior = |i: usize, j: usize, k: usize| {
        i > 0 && j > 0 && k > 0 && i + 1 < nx && j + 1 < ny && k + 1 < nz
    };
    let mut num = vec![u32::MAX; nx * ny * nz];
    let mut cnt = 0u32;
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                if interior(i, j, k) {
                    num[id(i, j, k)] = cnt;
                    cnt += 1;
                }
            }
        }
    }
    let n = cnt as usize;
    let offs: [(i64, i64, i64); 18] = [
        (1, 0, 0),
        (-1, 0, 0),
        (0, 1, 0),
        (0, -1, 0),
        (0, 0, 1),
        (0, 0, -1),
        (1, 1, 0),
        (-1, -1, 0),
        (1, 0, 1),
        (-1, 0, -1),
        (0, 1, 1),
        (0, -1, -1),
        (1, -1, 0),
        (-1, 1, 0),
        (1, 0, -1),
        (-1, 0, 1),
        (0, 1, -1),
        (0, -1, 1),
    ];
    let mut diag = vec![0.0; n];
    let mut offsets = vec![0usize];
    let mut cols = Vec::new();
    let mut vals = Vec::new();
    let mut b = vec![[0.0; 3]; n];
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let r = num[id(i, j, k)];
                if r == u32::MAX {
                    continue;
                }
                let mut row = Vec::new();
                for &(di, dj, dk) in offs.iter().take(12) {
                    let (ii, jj, kk) = (i as i64 + di, j as i64 + dj, k as i64 + dk);
                    let l2 = (di as f64 * hx).powi(2)
                        + (dj as f64 * hy).powi(2)
                        + (dk as f64 * hz).powi(2);
                    let kij = 1.0 / l2;
                    diag[r as usize] += kij;
                    let c = num[id(ii as usize, jj as usize, kk as usize)];
                    if c == u32::MAX {
                        // Prescribed neighbour: its displacement goes to the right side.
                        let x = ii as f64 * hx;
                        let z = kk as f64 * hz;
                        let d = [0.1 * (x * 0.3).sin(), 0.05 * z, -0.02 * x * z];
                        for q in 0..3 {
                            b[r as usize][q] += kij * d[q];
                        }
                    } else {
                        row.push((c, -kij));
                    }
                }
                row.sort_by_key(|e| e.0);
                for (c, v) in row {
                    cols.push(c);
                    vals.push(v);
                }
                offsets.push(cols.len());
            }
        }
    }
    (
        SymMatrix {
            diag,
            offsets,
            cols,
            vals,
        },
        b,
    )
}
