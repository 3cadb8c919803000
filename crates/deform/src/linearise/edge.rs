//! The linearised edge terms of Eq. 21: the rotation R_ij of the unnormalised quaternion
//! q̄ = q_i + q_j = (u, w) applied to an edge vector d, f = d + (2w (u×d) + 2u×(u×d)) / L
//! with L = |u|² + w² (as [`crate::rfield`] evaluates it), its derivative in q̄ and the
//! transpose of that derivative; and the derivative of a spring's stiffness in its end
//! nodes' positions.

use sparse::V3;

use crate::rfield::rot_minus_id;

#[inline]
pub(crate) fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[inline]
pub(crate) fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline]
pub(crate) fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// The edge quaternion q̄ = q_i + q_j.
#[inline]
pub(crate) fn qsum(a: [f64; 4], b: [f64; 4]) -> [f64; 4] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2], a[3] + b[3]]
}

fn split(q: [f64; 4]) -> (V3, f64, f64) {
    let u = [q[0], q[1], q[2]];
    (u, q[3], dot(u, u) + q[3] * q[3])
}

/// R(q̄) d.
#[inline]
pub(crate) fn rot_apply(q: [f64; 4], d: V3) -> V3 {
    let (u, w, l2) = split(q);
    if l2 == 0.0 {
        return d;
    }
    let r = rot_minus_id(u, w, l2, d);
    [d[0] + r[0], d[1] + r[1], d[2] + r[2]]
}

/// R(q̄)ᵀ g (the conjugate quaternion's rotation).
#[inline]
pub(crate) fn rot_apply_t(q: [f64; 4], g: V3) -> V3 {
    rot_apply([-q[0], -q[1], -q[2], q[3]], g)
}

/// The derivative of R(q̄) d in q̄ along dq.
#[inline]
pub(crate) fn rot_apply_dq(q: [f64; 4], d: V3, dq: [f64; 4]) -> V3 {
    let (u, w, l2) = split(q);
    if l2 == 0.0 {
        return [0.0; 3];
    }
    let du = [dq[0], dq[1], dq[2]];
    let dw = dq[3];
    let ud = cross(u, d);
    let n = {
        let uud = cross(u, ud);
        [
            2.0 * (w * ud[0] + uud[0]),
            2.0 * (w * ud[1] + uud[1]),
            2.0 * (w * ud[2] + uud[2]),
        ]
    };
    let dud = cross(du, d);
    let a = cross(du, ud);
    let b = cross(u, dud);
    let dl = 2.0 * (dot(u, du) + w * dw);
    let mut out = [0.0; 3];
    for k in 0..3 {
        let dn = 2.0 * (dw * ud[k] + w * dud[k] + a[k] + b[k]);
        out[k] = dn / l2 - n[k] * dl / (l2 * l2);
    }
    out
}

/// The transpose of [`rot_apply_dq`]: the gradient of g · R(q̄) d in q̄.
#[inline]
pub(crate) fn rot_apply_dq_t(q: [f64; 4], d: V3, g: V3) -> [f64; 4] {
    let (u, w, l2) = split(q);
    if l2 == 0.0 {
        return [0.0; 4];
    }
    let ud = cross(u, d);
    let gn = 2.0 * (w * dot(g, ud) + dot(g, cross(u, ud)));
    // ∂(g·N)/∂u = 2w (d×g) + 2 (u×d)×g + 2 d×(g×u); ∂(g·N)/∂w = 2 g·(u×d).
    let dg = cross(d, g);
    let udg = cross(ud, g);
    let dgu = cross(d, cross(g, u));
    let mut out = [0.0; 4];
    for k in 0..3 {
        let gu = 2.0 * (w * dg[k] + udg[k] + dgu[k]);
        out[k] = gu / l2 - gn * 2.0 * u[k] / (l2 * l2);
    }
    out[3] = 2.0 * dot(g, ud) / l2 - gn * 2.0 * w / (l2 * l2);
    out
}

/// The derivative of the stiffness K = K(|d|) ∝ |d|^(−p) of an edge d = x_j − x_i along
/// dd = dx_j − dx_i: −p K (d · dd) / |d|².
#[inline]
pub(crate) fn dk(k: f64, p: f64, d: V3, dd: V3) -> f64 {
    -p * k * dot(d, dd) / dot(d, d)
}

/// The transpose of [`dk`]: the gradient of k̄ · dK in dd (add to x̄_j, subtract from x̄_i).
#[inline]
pub(crate) fn dk_t(k: f64, p: f64, d: V3, kbar: f64) -> V3 {
    let f = -p * k * kbar / dot(d, d);
    [f * d[0], f * d[1], f * d[2]]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotation_derivative_and_its_transpose_match_differences() {
        let q = [0.3, -0.2, 0.5, 1.4];
        let d = [0.7, -1.1, 0.4];
        let dq = [0.2, 0.9, -0.3, 0.5];
        let g = [-0.4, 0.8, 1.3];
        let h = 1e-6;
        let qp: Vec<f64> = (0..4).map(|k| q[k] + h * dq[k]).collect();
        let qm: Vec<f64> = (0..4).map(|k| q[k] - h * dq[k]).collect();
        let (fp, fm) = (
            rot_apply([qp[0], qp[1], qp[2], qp[3]], d),
            rot_apply([qm[0], qm[1], qm[2], qm[3]], d),
        );
        let an = rot_apply_dq(q, d, dq);
        for k in 0..3 {
            let fd = (fp[k] - fm[k]) / (2.0 * h);
            assert!((fd - an[k]).abs() < 1e-8, "{k}: {fd} {}", an[k]);
        }
        // ⟨g, J dq⟩ = ⟨Jᵀ g, dq⟩.
        let t = rot_apply_dq_t(q, d, g);
        let lhs = dot(g, an);
        let rhs: f64 = (0..4).map(|k| t[k] * dq[k]).sum();
        assert!((lhs - rhs).abs() < 1e-14 * lhs.abs().max(1.0));
        assert!(lhs.abs() > 0.1);
        // Rᵀ R d = d.
        let back = rot_apply_t(q, rot_apply(q, d));
        for k in 0..3 {
            assert!((back[k] - d[k]).abs() < 1e-14);
        }
    }
}
