//! The R field (paper Eqs. 25–26): the rotation of every moving skin element (Eq. 25, see
//! [`crate::rotation`]), averaged to the skin nodes as unit quaternions (area-weighted sum,
//! normalised, scalar part w ≥ 0), propagated by Eq. 26 solved for the quaternions' vector
//! part u (one three-component solve) with the skin values and R = I (u = 0) on fixed nodes
//! held, starting from R = I; each node's rotation is the unit quaternion with that vector
//! part, w = √(1 − |u|²) (|u| ≤ 1 by the discrete maximum principle, A being an M-matrix;
//! clamped against round-off). This replaces a second solve for w followed by
//! normalisation: both are exact for a uniform rotation and differ by O(θ³) for angles θ in
//! between (docs/crates/deform.md, "R: adaptation matrices"). R_ij is the normalised sum of
//! the two end nodes' quaternions — the geodesic midpoint of R_i and R_j, a proper rotation,
//! at the cost of a few flops per edge instead of an SVD per edge.
//!
//! With a reach ([`crate::DeformOptions::rotation_reach`]) every node's quaternion is then
//! blended to the identity by its weight φ ([`blend`]): the skin's before Eq. 26 (they are
//! its boundary values), the unknowns' after.

use mesh::Mesh;
use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use rayon::prelude::*;
use sparse::{Constraints, V3};

use crate::assembly::{System, rhs};
use crate::bc::Classified;
use crate::operator::Operator;
use crate::options::{DeformOptions, weight_at};
use crate::rotation::rotation_from_frame;

/// The rotations of one increment: per node, the unit quaternion of R_i (identity where
/// nothing rotates), and what the Eq. 26 solve did.
pub(crate) struct RField {
    /// Vector part u of each node's quaternion.
    pub qv: Vec<V3>,
    /// Scalar part w of each node's quaternion.
    pub qw: Vec<f64>,
    /// False when every R_i is the identity (no R term in the right-hand side).
    pub any: bool,
    /// The Eq. 26 solution per unknown, before the clamp to |u| ≤ 1 (the warm start of a
    /// later call; empty when nothing was solved).
    pub solution: Vec<V3>,
    /// Iterations of the Eq. 26 solve.
    pub iterations: usize,
}

/// The skin elements' rotations of one increment (Eq. 25): per element of
/// [`Classified::skin`], its rotation from the frame at `cur` (S̄, kept in `op`) to the frame
/// at `target` as a unit quaternion [x, y, z, w] (w ≥ 0; about z only in 2D) and its size
/// (the weight of its rotation at its nodes); `None` for a degenerate element.
pub(crate) fn element_quaternions(
    mesh: &Mesh,
    cls: &Classified,
    op: &Operator,
    cur: &[[f64; 3]],
    target: &[[f64; 3]],
) -> Vec<Option<([f64; 4], f64)>> {
    // Per element (in parallel; the sums of `node_quaternions` run in element order).
    cls.skin
        .par_iter()
        .zip(&op.skin)
        .with_min_len(256)
        .map(|(e, f)| {
            let (inv0, size) = (*f)?;
            let k = e.len().min(3);
            let (p0, p1) = (skin_points(e, cur), skin_points(e, target));
            let r = if p0 == p1 {
                Matrix3::identity()
            } else {
                rotation_from_frame(&inv0, &p1[..k])?
            };
            let mut q = quat(&r);
            if mesh.dim == 2 {
                // Plane grids rotate about z only (drop the round-off of the SVD).
                let l = (q[2] * q[2] + q[3] * q[3]).sqrt();
                q = [0.0, 0.0, q[2] / l, q[3] / l];
            }
            Some((q, size))
        })
        .collect()
}

/// The skin nodes' rotations: the size-weighted sum of their elements' quaternions
/// ([`element_quaternions`]), normalised. Returns the vector and scalar parts per node
/// (identity where no element touches the node or the sum is the identity's direction),
/// the length of each node's sum (0 where the node keeps the identity), and whether any
/// node rotates.
pub(crate) fn node_quaternions(
    cls: &Classified,
    n: usize,
    rots: &[Option<([f64; 4], f64)>],
) -> (Vec<V3>, Vec<f64>, Vec<f64>, bool) {
    let mut qv: Vec<V3> = vec![[0.0; 3]; n];
    let mut qw: Vec<f64> = vec![1.0; n];
    let mut len = vec![0.0; n];
    let mut any_rot = false;
    let mut acc: Vec<[f64; 4]> = vec![[0.0; 4]; n];
    let mut touched = vec![false; n];
    for (e, rot) in cls.skin.iter().zip(rots) {
        let Some((q, w)) = *rot else {
            continue;
        };
        for &v in e {
            let a = &mut acc[v as usize];
            for k in 0..4 {
                a[k] += w * q[k];
            }
            touched[v as usize] = true;
        }
    }
    for i in 0..n {
        if touched[i] {
            let a = acc[i];
            let l = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2] + a[3] * a[3]).sqrt();
            if l > 0.0 && (a[0], a[1], a[2]) != (0.0, 0.0, 0.0) {
                qv[i] = [a[0] / l, a[1] / l, a[2] / l];
                qw[i] = a[3] / l;
                len[i] = l;
                any_rot = true;
            }
        }
    }
    (qv, qw, len, any_rot)
}

/// The rotation (u, w) (unit quaternion, w ≥ 0) blended to the identity by the weight `phi`
/// of its node ([`crate::options::reach_weight`]): (φ u, √(1 − φ²|u|²)), so that
/// sin(θ'/2) = φ sin(θ/2) about the same axis; unchanged, bit for bit, for φ = 1.
#[inline]
pub(crate) fn blend(u: V3, w: f64, phi: f64) -> (V3, f64) {
    if phi == 1.0 {
        return (u, w);
    }
    let b = [phi * u[0], phi * u[1], phi * u[2]];
    let s2 = b[0] * b[0] + b[1] * b[1] + b[2] * b[2];
    (b, (1.0 - s2).max(0.0).sqrt())
}

/// The rotation of an unknown from its Eq. 26 solution `v` (the quaternion's vector part):
/// (v, √(1 − |v|²)), or (v / |v|, 0) when |v| > 1 (solver round-off: the discrete maximum
/// principle keeps |v| ≤ 1).
#[inline]
pub(crate) fn unknown_quaternion(v: V3) -> (V3, f64) {
    let s2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    if s2 <= 1.0 {
        (v, (1.0 - s2).sqrt())
    } else {
        let l = s2.sqrt();
        ([v[0] / l, v[1] / l, v[2] / l], 0.0)
    }
}

impl RField {
    /// R for the motion of the skin from `cur` to `target`, propagated by Eq. 26 with the
    /// operator `op` of the state `cur`; `warm`: the Eq. 26 solution of an earlier result
    /// (per unknown) to start from; `reach`: the weight φ of R per node (empty: 1).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        mesh: &Mesh,
        cls: &Classified,
        sys: &System,
        op: &Operator,
        cur: &[[f64; 3]],
        target: &[[f64; 3]],
        warm: Option<&[V3]>,
        opts: &DeformOptions,
        reach: &[f64],
    ) -> Self {
        Self::build(mesh, cls, sys, op, cur, target, opts, reach, |bv, nu| {
            // u = 0 (R = I) as the start, or the previous solution when warm.
            let mut xv = match warm {
                Some(w) if w.len() == nu => w.to_vec(),
                _ => vec![[0.0; 3]; nu],
            };
            let rv = op.solve(bv, &mut xv, &Constraints::default(), opts, 1.0);
            (xv, rv.iterations)
        })
    }

    /// The R field of an increment already solved: the skin as in [`RField::new`], the
    /// unknowns from the Eq. 26 solution `solution` of that increment (bit for bit the field
    /// [`RField::new`] gave, when `solution` is its [`RField::solution`]).
    #[allow(clippy::too_many_arguments)]
    pub fn from_solution(
        mesh: &Mesh,
        cls: &Classified,
        sys: &System,
        op: &Operator,
        cur: &[[f64; 3]],
        target: &[[f64; 3]],
        solution: &[V3],
        opts: &DeformOptions,
        reach: &[f64],
    ) -> Self {
        Self::build(mesh, cls, sys, op, cur, target, opts, reach, |_, nu| {
            let x = if solution.len() == nu {
                solution.to_vec()
            } else {
                vec![[0.0; 3]; nu]
            };
            (x, 0)
        })
    }

    /// The skin rotations, then the unknowns' from `solve(Eq. 26 right-hand side, unknowns)`
    /// (its solution and iterations).
    #[allow(clippy::too_many_arguments)]
    fn build(
        mesh: &Mesh,
        cls: &Classified,
        sys: &System,
        op: &Operator,
        cur: &[[f64; 3]],
        target: &[[f64; 3]],
        opts: &DeformOptions,
        reach: &[f64],
        solve: impl FnOnce(&[V3], usize) -> (Vec<V3>, usize),
    ) -> Self {
        let n = cur.len();
        if !opts.adapt_rotation || cls.skin.is_empty() {
            return Self {
                qv: vec![[0.0; 3]; n],
                qw: vec![1.0; n],
                any: false,
                solution: Vec::new(),
                iterations: 0,
            };
        }
        let rots = element_quaternions(mesh, cls, op, cur, target);
        let (mut qv, mut qw, _, mut any_rot) = node_quaternions(cls, n, &rots);
        drop(rots);
        if !reach.is_empty() {
            // The reach of R (`DeformOptions::rotation_reach`): the skin's rotations are
            // blended first (they are the Eq. 26 boundary values), the unknowns' below.
            for i in 0..n {
                (qv[i], qw[i]) = blend(qv[i], qw[i], reach[i]);
            }
            any_rot = qv.iter().any(|u| *u != [0.0; 3]);
        }
        let mut solution = Vec::new();
        let mut iterations = 0;
        if any_rot {
            // Eq. 26 for the quaternions' vector part u (one three-component solve); the
            // scalar part follows from it, w = √(1 − |u|²) ≥ 0 (the discrete maximum
            // principle keeps |u| ≤ 1 up to the solver tolerance: clamped), so no second
            // solve is needed (see the module doc).
            let bv = rhs(sys, &op.couplings, |j| qv[j], |_, _| [0.0; 3]);
            let (xv, it) = solve(&bv, sys.node_of.len());
            drop(bv);
            iterations = it;
            for (k, &i) in sys.node_of.iter().enumerate() {
                let (u, w) = unknown_quaternion(xv[k]);
                let (u, w) = blend(u, w, weight_at(reach, i as usize));
                qv[i as usize] = u;
                qw[i as usize] = w;
            }
            solution = xv;
        }
        Self {
            qv,
            qw,
            any: any_rot,
            solution,
            iterations,
        }
    }

    /// (R_ij − I)(x_j − x_i) for the edge ij at coordinates `x`, R_ij the normalised sum of
    /// the end nodes' quaternions (zero when the sum vanishes).
    #[inline]
    pub fn minus_identity(&self, i: usize, j: usize, x: &[[f64; 3]]) -> V3 {
        let (qv, qw) = (&self.qv, &self.qw);
        let u = [
            qv[i][0] + qv[j][0],
            qv[i][1] + qv[j][1],
            qv[i][2] + qv[j][2],
        ];
        let w = qw[i] + qw[j];
        let l2 = u[0] * u[0] + u[1] * u[1] + u[2] * u[2] + w * w;
        if l2 == 0.0 {
            return [0.0; 3];
        }
        let d = [x[j][0] - x[i][0], x[j][1] - x[i][1], x[j][2] - x[i][2]];
        rot_minus_id(u, w, l2, d)
    }
}

/// (R − I) d for the rotation of the quaternion (u, w) scaled by any l > 0, l² = |u|² + w²
/// given: (2w (u×d) + 2 u×(u×d)) / l² — the unit quaternion's formula without the square
/// root of its normalisation.
#[inline]
pub(crate) fn rot_minus_id(u: [f64; 3], w: f64, l2: f64, d: [f64; 3]) -> V3 {
    let c = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let ud = c(u, d);
    let uud = c(u, ud);
    let f = 2.0 / l2;
    [
        f * (w * ud[0] + uud[0]),
        f * (w * ud[1] + uud[1]),
        f * (w * ud[2] + uud[2]),
    ]
}

/// The (up to three) nodes of skin element `e` at coordinates `x` (unused slots zero).
#[inline]
pub(crate) fn skin_points(e: &[u32], x: &[[f64; 3]]) -> [[f64; 3]; 3] {
    let mut p = [[0.0; 3]; 3];
    for (q, &v) in p.iter_mut().zip(e) {
        *q = x[v as usize];
    }
    p
}

/// The size of a skin element: its area (triangle), its length (segment).
pub(crate) fn element_size(p: &[[f64; 3]]) -> f64 {
    let v = |a: [f64; 3]| Vector3::from(a);
    if p.len() >= 3 {
        0.5 * (v(p[1]) - v(p[0])).cross(&(v(p[2]) - v(p[0]))).norm()
    } else {
        (v(p[1]) - v(p[0])).norm()
    }
}

/// Unit quaternion [x, y, z, w] of a rotation matrix, with w ≥ 0.
pub(crate) fn quat(r: &Matrix3<f64>) -> [f64; 4] {
    if *r == Matrix3::identity() {
        return [0.0, 0.0, 0.0, 1.0];
    }
    let q = UnitQuaternion::from_rotation_matrix(&nalgebra::Rotation3::from_matrix_unchecked(*r));
    let c = q.coords; // (i, j, k, w)
    let s = if c[3] < 0.0 { -1.0 } else { 1.0 };
    [s * c[0], s * c[1], s * c[2], s * c[3]]
}
