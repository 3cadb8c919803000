//! Control-node bases (§3): the frozen local parameter values of the control points of an
//! arc or a patch, and the inverse Vandermonde matrices that solve Eq. (4) / Eq. (9) for A.
//!
//! An arc of degree n carries n + 1 control points r_i = r(x_i) at the Chebyshev–Lobatto
//! nodes x_i = sin²(iπ / 2n), i = 0..n (the extrema of the Chebyshev polynomial T_n mapped
//! to [0, 1]). They include both ends x_0 = 0 and x_n = 1 exactly and are symmetric
//! (x_{n−i} = 1 − x_i up to round-off), so the border of an arc or patch is the polynomial
//! fixed by its border control points alone and neighbours that share those points stay C0.
//! Their Lebesgue constant grows like (2/π) ln n, against 2ⁿ / (e n ln n) for equispaced
//! nodes: moving a control point moves the polynomial by a comparable amount, without the
//! Runge oscillation equispaced nodes give at high degree.
//!
//! With V_{ik} = x_i^k (Eq. 6 evaluated at the nodes), Eq. (4) at the nodes reads R = V A, so
//! A = V⁻¹ R; for a patch (Eq. 9) R = V_u A V_vᵀ, so A = V_u⁻¹ R V_v⁻ᵀ. V⁻¹ is precomputed
//! once per degree from the coefficients of the Lagrange polynomials: (V⁻¹)_{ki} is the
//! coefficient of u^k in L_i(u) = Π_{j≠i} (u − x_j)/(x_i − x_j).

use std::sync::OnceLock;

use crate::prelude::{Point3, Vector3};

/// The highest polynomial degree (per direction) the database accepts. The monomial basis
/// becomes ill-conditioned far beyond the degrees CAD uses (≤ 9 typically).
pub const MAX_DEGREE: usize = 24;

struct Table {
    nodes: Vec<f64>,
    /// (n+1)×(n+1), row-major: vinv[k * (n+1) + i].
    vinv: Vec<f64>,
}

fn tables() -> &'static [Table] {
    static TABLES: OnceLock<Vec<Table>> = OnceLock::new();
    TABLES.get_or_init(|| (0..=MAX_DEGREE).map(build_table).collect())
}

fn build_table(n: usize) -> Table {
    let nodes: Vec<f64> = if n == 0 {
        vec![0.0]
    } else {
        (0..=n)
            .map(|i| {
                let s = (i as f64 * std::f64::consts::PI / (2 * n) as f64).sin();
                s * s
            })
            .collect()
    };
    // Lagrange polynomial coefficients.
    let m = n + 1;
    let mut vinv = vec![0.0; m * m];
    for i in 0..m {
        let mut poly = vec![0.0; m];
        poly[0] = 1.0;
        let mut deg = 0;
        for j in 0..m {
            if j == i {
                continue;
            }
            let d = nodes[i] - nodes[j];
            // poly *= (u - x_j) / d
            deg += 1;
            for k in (0..=deg).rev() {
                let lower = if k > 0 { poly[k - 1] } else { 0.0 };
                poly[k] = (lower - nodes[j] * poly[k]) / d;
            }
        }
        for k in 0..m {
            vinv[k * m + i] = poly[k];
        }
    }
    Table { nodes, vinv }
}

/// The n + 1 frozen local parameter values of degree n (Chebyshev–Lobatto nodes on [0, 1]).
///
/// ```
/// let x = geom_db::control::nodes(4);
/// assert_eq!((x[0], x[4]), (0.0, 1.0));
/// assert!((x[2] - 0.5).abs() < 1e-15);
/// ```
///
/// # Panics
/// If `degree > MAX_DEGREE` (the database validates degrees on load).
pub fn nodes(degree: usize) -> &'static [f64] {
    &tables()[degree].nodes
}

/// V⁻¹ of degree n, row-major (n+1)×(n+1): entry `[k * (n+1) + i]` maps control point i to
/// coefficient a_k.
///
/// # Panics
/// If `degree > MAX_DEGREE`.
pub fn inverse_vandermonde(degree: usize) -> &'static [f64] {
    &tables()[degree].vinv
}

/// ‖V⁻¹‖_∞ of degree n (largest absolute row sum): the factor by which the solve for A can
/// amplify relative round-off in the control points. It grows like 5.5ⁿ (2.1e5 at n = 8), a
/// property of the power basis on [0, 1]; degrees beyond ~12 lose many digits.
pub fn inverse_vandermonde_norm(degree: usize) -> f64 {
    let m = degree + 1;
    let v = inverse_vandermonde(degree);
    (0..m)
        .map(|k| (0..m).map(|i| v[k * m + i].abs()).sum::<f64>())
        .fold(0.0, f64::max)
}

/// A = V⁻¹ R for one arc (Eq. 4): power-basis coefficients from control points at the
/// nodes of degree `pts.len() - 1`.
pub fn coeffs_from_points_1d(pts: &[Point3]) -> Vec<Point3> {
    let m = pts.len();
    let vinv = inverse_vandermonde(m - 1);
    (0..m)
        .map(|k| {
            let mut acc = Vector3::zeros();
            for i in 0..m {
                acc += pts[i].coords * vinv[k * m + i];
            }
            Point3::from(acc)
        })
        .collect()
}

/// A = V_u⁻¹ R V_v⁻ᵀ for one patch (Eq. 9); `pts[i * (m+1) + j]` = r(x_i, y_j), result
/// `a[k * (m+1) + l]`.
pub fn coeffs_from_points_2d(deg_u: usize, deg_v: usize, pts: &[Point3]) -> Vec<Point3> {
    let (nu, nv) = (deg_u + 1, deg_v + 1);
    let vu = inverse_vandermonde(deg_u);
    let vv = inverse_vandermonde(deg_v);
    // T = R V_v^{-T}: T[i][l] = Σ_j R[i][j] vv[l][j]
    let mut t = vec![Vector3::zeros(); nu * nv];
    for i in 0..nu {
        for l in 0..nv {
            let mut acc = Vector3::zeros();
            for j in 0..nv {
                acc += pts[i * nv + j].coords * vv[l * nv + j];
            }
            t[i * nv + l] = acc;
        }
    }
    let mut a = vec![Point3::origin(); nu * nv];
    for k in 0..nu {
        for l in 0..nv {
            let mut acc = Vector3::zeros();
            for i in 0..nu {
                acc += t[i * nv + l] * vu[k * nu + i];
            }
            a[k * nv + l] = Point3::from(acc);
        }
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vinv_is_inverse() {
        for n in 1..=12 {
            let x = nodes(n);
            let vinv = inverse_vandermonde(n);
            let m = n + 1;
            for k in 0..m {
                for c in 0..m {
                    // (Vinv V)[k][c] = Σ_i vinv[k][i] x_i^c
                    let s: f64 = (0..m).map(|i| vinv[k * m + i] * x[i].powi(c as i32)).sum();
                    let want = if k == c { 1.0 } else { 0.0 };
                    assert!(
                        (s - want).abs() < 1e-9 * 4f64.powi(n as i32),
                        "n={n} k={k} c={c} {s}"
                    );
                }
            }
        }
    }

    #[test]
    fn nodes_symmetric_and_ordered() {
        for n in 1..=MAX_DEGREE {
            let x = nodes(n);
            assert_eq!(x[0], 0.0);
            assert_eq!(x[n], 1.0);
            for i in 0..n {
                assert!(x[i + 1] > x[i]);
                assert!((x[i] + x[n - i] - 1.0).abs() < 1e-15);
            }
        }
    }
}
