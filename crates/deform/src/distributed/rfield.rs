//! The R field (Eqs. 25–26) over the ranks: each rank averages the rotations of the skin
//! elements around its owned nodes into unit quaternions (as the serial `rfield`), the ghosts
//! get their owners' values, and Eq. 26 for the quaternions' vector part is one distributed
//! solve with the increment's operator; then every local node has its R_i. With a reach of
//! R, the quaternions are blended to the identity by each node's weight φ as serially: the
//! skin's before Eq. 26, the unknowns' after.

use nalgebra::{Matrix3, UnitQuaternion};
use sparse::{Constraints, V3};

use super::comm::{Comm, max};
use super::halo::Halo;
use super::solve::DistOperator;
use crate::assembly::{System, rhs};
use crate::error::Result;
use crate::operator::check_converged;
use crate::options::DeformOptions;
use crate::options::weight_at;
use crate::rfield::{blend, element_size, skin_points, unknown_quaternion};
use crate::rotation::{frame, rotation_from_frame};

/// Per local node, the unit quaternion (x, y, z, w) of R_i.
pub(crate) struct Rotations {
    pub q: Vec<[f64; 4]>,
    /// False when every R_i is the identity on every rank.
    pub any: bool,
    pub iterations: usize,
    /// The Eq. 26 solution per owned unknown (before the clamp; empty when nothing
    /// rotates).
    pub solution: Vec<V3>,
}

impl Rotations {
    /// (R_ij − I)(x_j − x_i), R_ij the normalised sum of the end nodes' quaternions (the
    /// serial `RField::minus_identity`).
    pub fn minus_identity(&self, i: usize, j: usize, x: &[[f64; 3]]) -> V3 {
        let (a, b) = (self.q[i], self.q[j]);
        let u = [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
        let w = a[3] + b[3];
        let l2 = u[0] * u[0] + u[1] * u[1] + u[2] * u[2] + w * w;
        if l2 == 0.0 {
            return [0.0; 3];
        }
        let d = [x[j][0] - x[i][0], x[j][1] - x[i][1], x[j][2] - x[i][2]];
        crate::rfield::rot_minus_id(u, w, l2, d)
    }
}

/// Unit quaternion [x, y, z, w] of a rotation matrix, w ≥ 0.
fn quat(r: &Matrix3<f64>) -> [f64; 4] {
    if *r == Matrix3::identity() {
        return [0.0, 0.0, 0.0, 1.0];
    }
    let q = UnitQuaternion::from_rotation_matrix(&nalgebra::Rotation3::from_matrix_unchecked(*r));
    let c = q.coords;
    let s = if c[3] < 0.0 { -1.0 } else { 1.0 };
    [s * c[0], s * c[1], s * c[2], s * c[3]]
}

/// What the R field needs of a rank's problem.
pub(crate) struct Ctx<'a> {
    pub comm: &'a Comm,
    pub node_halo: &'a Halo,
    pub unk_halo: &'a Halo,
    pub sys: &'a System,
    pub n_all: usize,
    pub n_owned_nodes: usize,
    pub skin: &'a [Vec<u32>],
    pub dim: u8,
    pub opts: &'a DeformOptions,
    /// The weight φ of R per local node (the reach of R; empty: 1 everywhere).
    pub reach: &'a [f64],
}

/// R for the motion of the skin from `cur` to `target` (local nodes); the Eq. 26 solve
/// starts from `warm` (per owned unknown) when given, else from R = I.
pub(crate) fn rotations(
    c: &Ctx,
    op: &DistOperator,
    cur: &[[f64; 3]],
    target: &[[f64; 3]],
    warm: Option<&[V3]>,
) -> Result<Rotations> {
    let n = cur.len();
    let mut q = vec![[0.0, 0.0, 0.0, 1.0]; n];
    let mut out = Rotations {
        q: Vec::new(),
        any: false,
        iterations: 0,
        solution: Vec::new(),
    };
    if !c.opts.adapt_rotation {
        out.q = q;
        return Ok(out);
    }
    let mut acc = vec![[0.0f64; 4]; n];
    let mut touched = vec![false; n];
    for e in c.skin {
        let k = e.len().min(3);
        let p0 = skin_points(e, cur);
        let Some(inv0) = frame(&p0[..k]).and_then(|f| f.try_inverse()) else {
            continue;
        };
        let size = element_size(&p0[..k]);
        let p1 = skin_points(e, target);
        let r = if p0 == p1 {
            Matrix3::identity()
        } else {
            match rotation_from_frame(&inv0, &p1[..k]) {
                Some(r) => r,
                None => continue,
            }
        };
        let mut qe = quat(&r);
        if c.dim == 2 {
            let l = (qe[2] * qe[2] + qe[3] * qe[3]).sqrt();
            qe = [0.0, 0.0, qe[2] / l, qe[3] / l];
        }
        for &v in e {
            for t in 0..4 {
                acc[v as usize][t] += size * qe[t];
            }
            touched[v as usize] = true;
        }
    }
    let mut any = false;
    // Owned nodes see all their skin elements; ghosts get their owners' values.
    for i in 0..c.n_owned_nodes {
        if touched[i] {
            let a = acc[i];
            let l = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2] + a[3] * a[3]).sqrt();
            if l > 0.0 && (a[0], a[1], a[2]) != (0.0, 0.0, 0.0) {
                q[i] = [a[0] / l, a[1] / l, a[2] / l, a[3] / l];
                any = true;
            }
        }
    }
    if !c.reach.is_empty() {
        // The skin's rotations blended first (they are the Eq. 26 boundary values).
        any = false;
        for (i, qi) in q.iter_mut().enumerate().take(c.n_owned_nodes) {
            let (u, w) = blend([qi[0], qi[1], qi[2]], qi[3], c.reach[i]);
            *qi = [u[0], u[1], u[2], w];
            any |= u != [0.0; 3];
        }
    }
    out.any = max(c.comm, f64::from(u8::from(any))) > 0.0;
    if !out.any {
        out.q = q;
        return Ok(out);
    }
    c.node_halo.exchange(c.comm, &mut q);
    let bv = rhs(
        c.sys,
        &op.couplings,
        |j| [q[j][0], q[j][1], q[j][2]],
        |_, _| [0.0; 3],
    );
    let mut xv = match warm {
        Some(w) if w.len() == bv.len() => w.to_vec(),
        _ => vec![[0.0; 3]; bv.len()],
    };
    let rep = op.solve(
        c.comm,
        c.unk_halo,
        c.n_all,
        &bv,
        &mut xv,
        &Constraints::default(),
        c.opts,
        c.opts.rel_tol,
    );
    check_converged(&rep, "rotation field (Eq. 26)", c.opts)?;
    out.iterations = rep.iterations;
    for (k, &i) in c.sys.node_of.iter().enumerate() {
        let (u, w) = unknown_quaternion(xv[k]);
        let (u, w) = blend(u, w, weight_at(c.reach, i as usize));
        q[i as usize] = [u[0], u[1], u[2], w];
    }
    c.node_halo.exchange(c.comm, &mut q);
    out.q = q;
    out.solution = xv;
    Ok(out)
}
