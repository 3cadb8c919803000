//! Adaptation matrices R (paper §4.2, Eqs. 25–26): per skin element from its deformed and
//! initial frames, projected to the nearest rotation, averaged to skin nodes.
//!
//! Frames. A skin triangle with edges e₁ = x₁ − x₀, e₂ = x₂ − x₀ has the 3×2 map [e₁ e₂] from
//! its parametric plane; it is completed to a square matrix with the unit normal scaled by the
//! element size, S = [e₁ e₂ √|e₁×e₂| n̂], and R_e = S S̄⁻¹ (Eq. 25) with S̄ the initial frame.
//! A skin segment (2D grids) uses [e₁ ẑ×e₁ ẑ]. For a rigid motion Q the frames map exactly:
//! S = Q S̄, so R_e = Q.
//!
//! Projection. R_e also carries the element's stretch and shear; only its rotation part is
//! propagated (the polar factor, nearest rotation in the Frobenius norm, from the SVD
//! R = U Σ Vᵀ → U diag(1, 1, det(U Vᵀ)) Vᵀ). A sum of rotations is not a rotation, so every
//! average (element → node, the propagated field of Eq. 26, the two end nodes of an edge) is
//! followed by the same projection: the result is always a proper rotation, and a uniform
//! rotation Q is reproduced exactly up to round-off.

use nalgebra::{Matrix3, Vector3};

/// The rotation nearest to `m` in the Frobenius norm (polar factor with det = +1). Returns the
/// identity for a zero matrix.
///
/// For det(m) > 0 (every frame map of a non-inverted element) the polar factor comes from an
/// iteration that converges quadratically to it: for m near a rotation (‖mᵀm − I‖_F ≤ ½,
/// strains up to about 20 %, the usual case) the Newton–Schulz iteration X ← X (3I − XᵀX)/2,
/// products only; otherwise the scaled Newton iteration X ← ½(γX + γ⁻¹X⁻ᵀ),
/// γ = (‖X⁻¹‖/‖X‖)^½ (Higham), with 3×3 inverses; if neither converges, or det(m) ≤ 0, the
/// SVD below.
pub fn nearest_rotation(m: &Matrix3<f64>) -> Matrix3<f64> {
    if m.iter().all(|v| *v == 0.0) {
        return Matrix3::identity();
    }
    if m.determinant() > 0.0
        && let Some(r) = schulz_polar(m).or_else(|| newton_polar(m))
    {
        return r;
    }
    svd_rotation(m)
}

/// Newton–Schulz iteration for the polar factor of `m` (det > 0); `None` when m is too far
/// from a rotation for it (‖XᵀX − I‖_F > ½) or it has not converged.
///
/// With X = U H, a singular value σ = 1 + δ of X becomes σ (3 − σ²)/2 = 1 − 3δ²/2 + O(δ³), so
/// E = XᵀX − I goes to about −¾E²: from ‖E‖ ≤ ½ the iteration converges monotonically, and
/// the step taken once ‖E‖_F ≤ 1e-8 leaves X orthogonal to round-off.
fn schulz_polar(m: &Matrix3<f64>) -> Option<Matrix3<f64>> {
    let mut x = *m;
    for _ in 0..12 {
        let e = x.transpose() * x - Matrix3::identity();
        let e2 = e.norm_squared();
        if e2 > 0.25 {
            return None;
        }
        x -= x * e * 0.5;
        if e2 <= 1e-16 {
            return Some(x);
        }
    }
    None
}

/// Scaled Newton iteration for the polar factor of `m` (det > 0); `None` if it fails.
fn newton_polar(m: &Matrix3<f64>) -> Option<Matrix3<f64>> {
    let mut x = *m;
    for _ in 0..30 {
        let inv = x.try_inverse()?;
        let (nx, ni) = (x.norm(), inv.norm());
        // Scaling speeds the first steps up; near convergence γ → 1 and is dropped.
        let g = (ni / nx).sqrt();
        let g = if (g - 1.0).abs() < 1e-3 { 1.0 } else { g };
        let next = (x * g + inv.transpose() / g) * 0.5;
        let change = (next - x).norm();
        x = next;
        // Quadratic convergence: the error of `next` is about ½ change² ‖X⁻¹‖, at round-off
        // once the change is below 1e-8 (relative; the unscaled step only).
        if g == 1.0 && change <= 1e-8 * x.norm() {
            return Some(x);
        }
    }
    None
}

/// [`nearest_rotation`] by the SVD (any sign of the determinant).
fn svd_rotation(m: &Matrix3<f64>) -> Matrix3<f64> {
    let svd = m.svd(true, true);
    let (Some(u), Some(vt)) = (svd.u, svd.v_t) else {
        return Matrix3::identity();
    };
    let mut d = Matrix3::identity();
    if (u * vt).determinant() < 0.0 {
        // Flip the direction of the smallest singular value.
        let (k, _) =
            svd.singular_values
                .iter()
                .enumerate()
                .fold(
                    (0, f64::INFINITY),
                    |a, (i, &s)| if s < a.1 { (i, s) } else { a },
                );
        d[(k, k)] = -1.0;
    }
    u * d * vt
}

/// Completed frame of a skin element: triangle `[x0, x1, x2]`, or a segment `[x0, x1]` of a
/// 2D grid (z normal). `None` for a degenerate element.
pub fn frame(p: &[[f64; 3]]) -> Option<Matrix3<f64>> {
    let v = |a: [f64; 3]| Vector3::new(a[0], a[1], a[2]);
    let e1 = v(p[1]) - v(p[0]);
    let (e2, n) = if p.len() >= 3 {
        let e2 = v(p[2]) - v(p[0]);
        let c = e1.cross(&e2);
        let a = c.norm();
        if a == 0.0 {
            return None;
        }
        (e2, c * (a.sqrt() / a))
    } else {
        let z = Vector3::z();
        let l = e1.norm();
        if l == 0.0 {
            return None;
        }
        (z.cross(&e1), z * l)
    };
    Some(Matrix3::from_columns(&[e1, e2, n]))
}

/// R_e = S S̄⁻¹ (Eq. 25) for one skin element, projected to the nearest rotation. Exactly the
/// identity when the element did not move (bitwise equal coordinates).
pub fn element_rotation(initial: &[[f64; 3]], current: &[[f64; 3]]) -> Option<Matrix3<f64>> {
    if initial == current {
        return Some(Matrix3::identity());
    }
    rotation_from_frame(&frame(initial)?.try_inverse()?, current)
}

/// [`element_rotation`] with the initial frame given inverted (S̄⁻¹, kept between calls by
/// a caller that rotates the same elements many times).
pub fn rotation_from_frame(
    initial_inv: &Matrix3<f64>,
    current: &[[f64; 3]],
) -> Option<Matrix3<f64>> {
    Some(nearest_rotation(&(frame(current)? * initial_inv)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rot(axis: [f64; 3], ang: f64) -> Matrix3<f64> {
        let a = nalgebra::Unit::new_normalize(Vector3::new(axis[0], axis[1], axis[2]));
        *nalgebra::Rotation3::from_axis_angle(&a, ang).matrix()
    }

    #[test]
    fn rigid_motion_of_a_triangle_gives_its_rotation() {
        let q = rot([0.3, -1.0, 0.5], 0.7);
        let tri = [[0.1, 0.2, 0.3], [1.3, 0.1, -0.2], [0.4, 0.9, 0.8]];
        let moved: Vec<[f64; 3]> = tri
            .iter()
            .map(|p| {
                let r = q * Vector3::new(p[0], p[1], p[2]) + Vector3::new(5.0, -2.0, 1.0);
                [r.x, r.y, r.z]
            })
            .collect();
        let r = element_rotation(&tri, &moved).unwrap();
        for (a, b) in r.iter().zip(q.iter()) {
            testkit::assert_close!(*a, *b, abs = 1e-14);
        }
    }

    #[test]
    fn projection_is_a_rotation_and_fixes_rotations() {
        let q = rot([1.0, 2.0, 3.0], 1.1);
        let p = nearest_rotation(&q);
        for (a, b) in p.iter().zip(q.iter()) {
            testkit::assert_close!(*a, *b, abs = 1e-14);
        }
        // Average of two rotations: not orthogonal; its projection is.
        let m = (rot([0.0, 0.0, 1.0], 0.4) + rot([1.0, 0.0, 0.0], -0.9)) * 0.5;
        let p = nearest_rotation(&m);
        let e = p.transpose() * p - Matrix3::identity();
        assert!(e.norm() < 1e-14 && (p.determinant() - 1.0).abs() < 1e-14);
        // A reflection-like input still yields det = +1.
        let refl = Matrix3::new(1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, -0.5);
        assert!((nearest_rotation(&refl).determinant() - 1.0).abs() < 1e-14);
    }

    #[test]
    fn newton_polar_factor_agrees_with_the_svd() {
        // A stretched, sheared, rotated frame map (det > 0: Newton's iteration), strains of
        // 10 % and 0.1 % (Newton–Schulz) and a rotation.
        let q = rot([0.2, 1.0, -0.4], 0.8);
        let s = Matrix3::new(1.7, 0.3, -0.2, 0.0, 0.6, 0.4, 0.1, 0.0, 1.2);
        let strain = Matrix3::new(0.3, 0.5, -0.2, 0.1, -0.6, 0.4, 0.1, 0.2, 0.7);
        let cases = [
            (q * s, false),
            (q * (Matrix3::identity() + strain * 0.1), true),
            (q * (Matrix3::identity() + strain * 1e-3), true),
            (q, true),
        ];
        for (m, near) in cases {
            assert!(m.determinant() > 0.0);
            assert_eq!(schulz_polar(&m).is_some(), near);
            let (a, b) = (nearest_rotation(&m), svd_rotation(&m));
            assert!((a - b).norm() < 1e-13, "{}", (a - b).norm());
            let n = newton_polar(&m).unwrap();
            assert!((n - b).norm() < 1e-13, "{}", (n - b).norm());
        }
    }

    #[test]
    fn unmoved_element_gives_exact_identity() {
        let tri = [[0.1, 0.2, 0.3], [1.3, 0.1, -0.2], [0.4, 0.9, 0.8]];
        assert_eq!(element_rotation(&tri, &tri).unwrap(), Matrix3::identity());
    }
}
