//! The linearised skin rotations (Eq. 25): the derivative of an element's weighted
//! quaternion size · q(R_e), R_e the polar factor of X = S S̄⁻¹, with respect to its nodes'
//! positions at the end (S) and at the start (S̄ and the size) of the increment.
//!
//! - Frame: S = [e₁ e₂ c/√|c|], c = e₁ × e₂ (3D); [e₁ ẑ×e₁ ẑ|e₁|] (2D).
//! - dX = (dS − X dS̄) S̄⁻¹.
//! - Polar factor X = R H (H symmetric positive definite): with M = Rᵀ dX, the rotation's
//!   derivative is dR = R [ω]×, where (tr H · I − H) ω = vec(M − Mᵀ) (vec of a skew matrix
//!   K: [K₃₂, K₁₃, K₂₁]); this follows from M − Mᵀ = [ω]× H + H [ω]× = [(tr H · I − H) ω]×.
//! - Quaternion q = (v, w) of R (w ≥ 0): dq = ½ q ⊗ (ω, 0) = ½ (w ω + v × ω, −v · ω).
//! - 2D: q = (0, 0, q_z, q_w) / |(q_z, q_w)|, differentiated as a normalisation.

use nalgebra::{Matrix3, Vector3};

use crate::rfield::quat;
use crate::rotation::{frame, nearest_rotation};

/// The derivative of one skin element's weighted quaternion size · q: column 3a + b is the
/// derivative with respect to coordinate b of node a at the end of the increment (the
/// target), column 9 + 3a + b the same at the start (a < the element's node count; the other
/// columns are zero).
pub(crate) type SkinJac = [[f64; 4]; 18];

fn v3(a: [f64; 3]) -> Vector3<f64> {
    Vector3::new(a[0], a[1], a[2])
}

/// The frame S of the points `p` (2 or 3), with what its derivatives share: S's
/// directional derivative along a perturbation of one coordinate is [`FrameD::along`].
struct FrameD {
    e1: Vector3<f64>,
    e2: Vector3<f64>,
    /// 3D: c = e₁ × e₂, |c| and √|c|; 2D: |e₁| in `a`.
    c: Vector3<f64>,
    a: f64,
    sa: f64,
    tri: bool,
}

impl FrameD {
    fn new(p: &[[f64; 3]]) -> Option<(Matrix3<f64>, Self)> {
        let s = frame(p)?;
        let e1 = v3(p[1]) - v3(p[0]);
        let f = if p.len() >= 3 {
            let e2 = v3(p[2]) - v3(p[0]);
            let c = e1.cross(&e2);
            let a = c.norm();
            Self {
                e1,
                e2,
                c,
                a,
                sa: a.sqrt(),
                tri: true,
            }
        } else {
            Self {
                e1,
                e2: Vector3::zeros(),
                c: Vector3::zeros(),
                a: e1.norm(),
                sa: 0.0,
                tri: false,
            }
        };
        Some((s, f))
    }

    /// dS for the perturbation of coordinate `b` of point `a` by 1.
    fn along(&self, a: usize, b: usize) -> Matrix3<f64> {
        let mut dp = [Vector3::zeros(); 3];
        dp[a][b] = 1.0;
        let de1 = dp[1] - dp[0];
        if self.tri {
            let de2 = dp[2] - dp[0];
            let (c, a) = (self.c, self.a);
            let dc = de1.cross(&self.e2) + self.e1.cross(&de2);
            let da = c.dot(&dc) / a;
            let dn = dc / self.sa - c * (0.5 * da / (a * self.sa));
            Matrix3::from_columns(&[de1, de2, dn])
        } else {
            let z = Vector3::z();
            Matrix3::from_columns(&[de1, z.cross(&de1), z * (self.e1.dot(&de1) / self.a)])
        }
    }

    /// The element size's (area of a triangle, length of a segment) derivative for the
    /// perturbation of coordinate `b` of point `a` by 1.
    fn size_along(&self, a: usize, b: usize) -> f64 {
        let mut dp = [Vector3::zeros(); 3];
        dp[a][b] = 1.0;
        let de1 = dp[1] - dp[0];
        if self.tri {
            let de2 = dp[2] - dp[0];
            0.5 * self.c.dot(&(de1.cross(&self.e2) + self.e1.cross(&de2))) / self.a
        } else {
            self.e1.dot(&de1) / self.a
        }
    }
}

/// The quaternion q = (v, w) of R and its derivative for dR = R [ω]×.
fn quat_d(q: [f64; 4], omega: Vector3<f64>) -> [f64; 4] {
    let v = Vector3::new(q[0], q[1], q[2]);
    let dv = (omega * q[3] + v.cross(&omega)) * 0.5;
    [dv.x, dv.y, dv.z, -0.5 * v.dot(&omega)]
}

/// The rotation derivative ω of the polar factor R of X for dX, with `gi` the inverse of
/// tr H · I − H (H = Rᵀ X; None: singular, ω = 0).
fn polar_d(r: &Matrix3<f64>, gi: Option<&Matrix3<f64>>, dx: &Matrix3<f64>) -> Vector3<f64> {
    let m = r.transpose() * dx;
    let k = m - m.transpose();
    let rhs = Vector3::new(k[(2, 1)], k[(0, 2)], k[(1, 0)]);
    gi.map_or_else(Vector3::zeros, |gi| gi * rhs)
}

/// The derivative of size · q of the skin element at the start points `pc` (frame inverse
/// `inv0` and `size` as in the operator) and the end points `pt`, in the plane (z rotations
/// only) when `plane`. `None` when the end frame is degenerate (the element then carries no
/// rotation, as in the forward computation).
pub(crate) fn skin_jacobian(
    pc: &[[f64; 3]],
    pt: &[[f64; 3]],
    inv0: &Matrix3<f64>,
    size: f64,
    plane: bool,
) -> Option<SkinJac> {
    let k = pc.len();
    let (st, ft) = FrameD::new(pt)?;
    let (_, fc) = FrameD::new(pc)?;
    let x = st * inv0;
    let r = nearest_rotation(&x);
    let h = r.transpose() * x;
    let h = (h + h.transpose()) * 0.5;
    // Shared by every column: tr H · I − H inverted, the quaternion of R.
    let gi = (Matrix3::identity() * h.trace() - h).try_inverse();
    let q0 = quat(&r);
    let mut jac = [[0.0; 4]; 18];
    for col in 0..18 {
        let (a, b) = ((col % 9) / 3, col % 3);
        if a >= k {
            continue;
        }
        // dX = (dS − X dS̄) S̄⁻¹; the size depends on the start points only.
        let (dx, dsize) = if col < 9 {
            (ft.along(a, b) * inv0, 0.0)
        } else {
            (-(x * fc.along(a, b)) * inv0, fc.size_along(a, b))
        };
        let omega = polar_d(&r, gi.as_ref(), &dx);
        let (mut q, mut dq) = (q0, quat_d(q0, omega));
        if plane {
            let l = (q[2] * q[2] + q[3] * q[3]).sqrt();
            let (qz, qw) = (q[2] / l, q[3] / l);
            // d(a / |a|) = (I − â âᵀ) da / |a|.
            let p = (qz * dq[2] + qw * dq[3]) / l;
            dq = [0.0, 0.0, dq[2] / l - qz * p, dq[3] / l - qw * p];
            q = [0.0, 0.0, qz, qw];
        }
        for c in 0..4 {
            jac[col][c] = size * dq[c] + dsize * q[c];
        }
    }
    Some(jac)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rfield::element_size;
    use crate::rotation::rotation_from_frame;

    /// size · q at start points `pc` and end points `pt`, as the forward computation.
    fn weighted(pc: &[[f64; 3]], pt: &[[f64; 3]], plane: bool) -> [f64; 4] {
        let inv0 = frame(pc).unwrap().try_inverse().unwrap();
        let r = rotation_from_frame(&inv0, pt).unwrap();
        let mut q = quat(&r);
        if plane {
            let l = (q[2] * q[2] + q[3] * q[3]).sqrt();
            q = [0.0, 0.0, q[2] / l, q[3] / l];
        }
        let s = element_size(pc);
        [s * q[0], s * q[1], s * q[2], s * q[3]]
    }

    fn check(pc: &[[f64; 3]], pt: &[[f64; 3]], plane: bool) {
        let inv0 = frame(pc).unwrap().try_inverse().unwrap();
        let jac = skin_jacobian(pc, pt, &inv0, element_size(pc), plane).unwrap();
        let h = 1e-6;
        let mut worst = 0.0f64;
        let mut largest = 0.0f64;
        for col in 0..18 {
            let (a, b) = ((col % 9) / 3, col % 3);
            if a >= pc.len() || (plane && b == 2) {
                continue;
            }
            let (mut cp, mut cm) = (pc.to_vec(), pc.to_vec());
            let (mut tp, mut tm) = (pt.to_vec(), pt.to_vec());
            if col < 9 {
                tp[a][b] += h;
                tm[a][b] -= h;
            } else {
                cp[a][b] += h;
                cm[a][b] -= h;
            }
            let (fp, fm) = (weighted(&cp, &tp, plane), weighted(&cm, &tm, plane));
            for c in 0..4 {
                let fd = (fp[c] - fm[c]) / (2.0 * h);
                worst = worst.max((fd - jac[col][c]).abs());
                largest = largest.max(fd.abs());
            }
        }
        assert!(largest > 0.1, "derivative too small to test: {largest}");
        assert!(worst < 1e-8 * largest, "worst {worst:e} of {largest:e}");
    }

    #[test]
    fn skin_jacobian_matches_central_differences() {
        let pc = [[0.1, 0.2, 0.3], [1.3, 0.1, -0.2], [0.4, 0.9, 0.8]];
        // Stretched, sheared and turned.
        let pt = [[0.15, 0.1, 0.35], [1.2, 0.3, 0.1], [0.2, 1.0, 0.9]];
        check(&pc, &pt, false);
        // At the identity (no motion).
        check(&pc, &pc, false);
        // A segment of a plane grid.
        let sc = [[0.1, 0.2, 0.0], [1.1, 0.5, 0.0]];
        let st = [[0.0, 0.3, 0.0], [0.9, 0.9, 0.0]];
        check(&sc, &st, true);
    }
}
