//! One increment of the deformation, linearised: what it recorded ([`Step`]) and its forward
//! (Jacobian–vector) and reverse (vector–Jacobian) products. The increment maps the grid at
//! its start c and the prescribed nodes' targets t to the grid y at its end; for every
//! unknown node i it solved
//!
//! G_i = Σ_j K_ij(c) [(y_i − y_j) + R_ij(c, t) (c_j − c_i)] = 0
//!
//! (Eq. 21; y_j = t_j for prescribed j), constrained to the plane or line of a sliding node,
//! or, for a node sliding on a support, Tᵀ G_i = 0 with y_i = r(p_i), T = ∂r/∂p. The
//! linearised equation for the unknowns' dy is P (A + B) P dy = P db: A the spring matrix,
//! P the projection on the constraints at the end of the increment, B the curvature blocks
//! T⁺ᵀ H T⁺ of the nodes on supports (H_ab = ∂²r/∂p_a∂p_b · G_i, T⁺ = (TᵀT)⁻¹Tᵀ), and
//!
//! db_i = Σ_{j prescribed} K_ij dt_j − Σ_j K_ij [dR_ij (c_j − c_i) + R_ij (dc_j − dc_i)]
//!        − Σ_j dK_ij [(y_i − y_j) + R_ij (c_j − c_i)],
//!
//! with dR_ij from the node quaternions' derivatives (skin: [`super::skin`], normalised sums;
//! unknowns: Eq. 26 linearised, A du = Σ_{j prescribed} K_ij du_j − Σ_j dK_ij (u_i − u_j),
//! dw = −u·du / w). The dc and dK terms are absent in the first increment (c = x⁰).

use geom_db::eval::{ParamCurve, ParamSurface};
use rayon::prelude::*;
use sparse::vec3::CHUNK;
use sparse::{Block3, Constraints, V3};

use super::edge::{dk, dk_t, dot, qsum, rot_apply, rot_apply_dq, rot_apply_dq_t, sub};
use super::skin::{SkinJac, skin_jacobian};
use crate::bc::NodeRole;
use crate::deformer::Deformer;
use crate::error::{Error, Result};
use crate::operator::Operator;
use crate::options::weight_at;
use crate::rfield::{RField, element_quaternions, skin_points};
use crate::sliding::constraints;
use crate::support::SupKind;

/// What one increment recorded for its linearisation.
pub(crate) struct Step {
    /// The fraction of the motion the prescribed nodes reach.
    pub s: f64,
    /// The first increment (its start is the baseline: no dependence on the inputs).
    pub first: bool,
    /// The operator at the start state (None: the set-up's).
    pub op: Option<Operator>,
    /// The grid at the start (c) and at the end (y), solver numbering.
    pub c: Vec<[f64; 3]>,
    pub y: Vec<[f64; 3]>,
    /// The node quaternions (u, w) of R.
    pub q: Vec<[f64; 4]>,
    /// The Eq. 26 solution per unknown (zeros when nothing was solved).
    pub u26: Vec<V3>,
    /// Whether R is computed (adaptation on, a skin exists).
    pub rot: bool,
    /// Per skin element, the derivative of its weighted quaternion.
    pub skin: Vec<Option<SkinJac>>,
    /// Per node: the length of its weighted quaternion sum and that sum normalised (skin
    /// nodes; length 0 elsewhere).
    pub node_len: Vec<f64>,
    pub node_q: Vec<[f64; 4]>,
    /// The constraints at the end of the increment and the curvature blocks.
    pub cons: Constraints,
    pub blocks: Vec<(u32, Block3)>,
    /// The stiffness exponent p of K ∝ l^(−p) (used after the first increment).
    pub power: f64,
}

/// The neighbours j of unknown k: (node j, K_kj, unknown index of j if unknown).
fn for_neighbours(
    op: &Operator,
    sys: &crate::assembly::System,
    k: usize,
    mut f: impl FnMut(usize, f64, Option<usize>),
) {
    let (cols, vals) = op.matrix().row(k);
    for (&c, &a) in cols.iter().zip(vals) {
        f(
            sys.node_of[c as usize] as usize,
            -f64::from(a),
            Some(c as usize),
        );
    }
    let (nodes, kij) = op.couplings.row(k);
    for (&j, &kv) in nodes.iter().zip(kij) {
        f(j as usize, kv, None);
    }
}

/// The couplings to prescribed nodes transposed: per node, its unknown neighbours (unknown
/// index, K) in increasing unknown order (empty for unknown nodes).
struct CouplingsT {
    offsets: Vec<usize>,
    entries: Vec<(u32, f64)>,
}

impl CouplingsT {
    fn new(op: &Operator, sys: &crate::assembly::System, n: usize) -> Self {
        let cp = &op.couplings;
        let mut offsets = vec![0usize; n + 1];
        for &j in &cp.cols {
            offsets[j as usize + 1] += 1;
        }
        for i in 0..n {
            offsets[i + 1] += offsets[i];
        }
        let mut next = offsets.clone();
        let mut entries = vec![(0u32, 0.0); cp.cols.len()];
        for k in 0..sys.node_of.len() {
            let (nodes, kij) = cp.row(k);
            for (&j, &kv) in nodes.iter().zip(kij) {
                entries[next[j as usize]] = (k as u32, kv);
                next[j as usize] += 1;
            }
        }
        Self { offsets, entries }
    }

    fn row(&self, m: usize) -> &[(u32, f64)] {
        &self.entries[self.offsets[m]..self.offsets[m + 1]]
    }
}

fn add(a: &mut V3, f: f64, b: V3) {
    for q in 0..3 {
        a[q] += f * b[q];
    }
}

impl Step {
    /// Records the increment of fraction `s` from `c` to `y` (targets `target`, R field
    /// `rf`, final support parameters `params`), with the operator `op` at `c` (None: the
    /// set-up's).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        d: &Deformer,
        s: f64,
        first: bool,
        op: Option<Operator>,
        c: Vec<[f64; 3]>,
        y: Vec<[f64; 3]>,
        target: &[[f64; 3]],
        rf: &RField,
        params: &[[f64; 2]],
    ) -> Result<Self> {
        let (mesh, cls, sys, opts) = (&d.mesh, &d.cls, &d.sys, &d.opts);
        let power = match opts.stiffness {
            crate::Stiffness::InverseLength => 1.0,
            crate::Stiffness::InverseLengthSquared => 2.0,
            other if !first => {
                return Err(Error::BadOption {
                    reason: format!(
                        "the linearisation of a deformation in several increments needs the stiffness inverse-length or inverse-length2 (the {other} stiffness's factors are not differentiated)"
                    ),
                });
            }
            _ => 0.0,
        };
        let n = c.len();
        let nu = sys.node_of.len();
        let q: Vec<[f64; 4]> = (0..n)
            .map(|i| [rf.qv[i][0], rf.qv[i][1], rf.qv[i][2], rf.qw[i]])
            .collect();
        let u26 = if rf.solution.len() == nu {
            rf.solution.clone()
        } else {
            vec![[0.0; 3]; nu]
        };
        let rot = opts.adapt_rotation && !cls.skin.is_empty();
        let opr = op.as_ref().or(d.op.as_ref());
        let (mut skin, mut node_len, mut node_q) = (Vec::new(), vec![0.0; n], vec![[0.0; 4]; n]);
        if let (true, Some(o)) = (rot, opr) {
            let plane = mesh.dim == 2;
            skin = cls
                .skin
                .par_iter()
                .zip(&o.skin)
                .map(|(e, f)| {
                    let (inv0, size) = (*f)?;
                    let k = e.len().min(3);
                    let (pc, pt) = (skin_points(e, &c), skin_points(e, target));
                    skin_jacobian(&pc[..k], &pt[..k], &inv0, size, plane)
                })
                .collect();
            let rots = element_quaternions(mesh, cls, o, &c, target);
            let mut acc = vec![[0.0f64; 4]; n];
            for (e, r) in cls.skin.iter().zip(&rots) {
                if let Some((qe, w)) = *r {
                    for &v in e {
                        for t in 0..4 {
                            acc[v as usize][t] += w * qe[t];
                        }
                    }
                }
            }
            for i in 0..n {
                let a = acc[i];
                let l = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2] + a[3] * a[3]).sqrt();
                if l > 0.0 {
                    node_len[i] = l;
                    node_q[i] = [a[0] / l, a[1] / l, a[2] / l, a[3] / l];
                }
            }
        }
        let on_sup = d
            .sup
            .as_ref()
            .filter(|_| sys.sup_unk.iter().any(|&u| u != u32::MAX));
        let mut step = Self {
            s,
            first,
            op,
            c,
            y,
            q,
            u26,
            rot,
            skin,
            node_len,
            node_q,
            cons: sys.cons.clone(),
            blocks: Vec::new(),
            power,
        };
        if let Some(sp) = on_sup {
            step.cons = constraints(cls, sys, Some(sp), params)?;
            let o = step
                .op
                .as_ref()
                .or(d.op.as_ref())
                .expect("unknowns have an operator");
            let mut blocks = Vec::new();
            for (k, sn) in cls.supports.iter().enumerate() {
                let u = sys.sup_unk[k];
                if u == u32::MAX {
                    continue;
                }
                let g = step.residual(d, o, u as usize);
                let p = params[k];
                let b = match sn.kind {
                    SupKind::Surface(sf) => {
                        let dv = sp.db.surface(sf).derivs(p[0], p[1]);
                        let t = [dv.du, dv.dv];
                        let gm = nalgebra::Matrix2::new(
                            t[0].dot(&t[0]),
                            t[0].dot(&t[1]),
                            t[1].dot(&t[0]),
                            t[1].dot(&t[1]),
                        );
                        let gv = nalgebra::Vector3::from(g);
                        let h = nalgebra::Matrix2::new(
                            dv.duu.dot(&gv),
                            dv.duv.dot(&gv),
                            dv.duv.dot(&gv),
                            dv.dvv.dot(&gv),
                        );
                        let tm = nalgebra::Matrix3x2::from_columns(&t);
                        let Some(gi) = gm.try_inverse() else {
                            continue;
                        };
                        let tp = gi * tm.transpose(); // T⁺, 2×3
                        tp.transpose() * h * tp
                    }
                    SupKind::Curve(cv) => {
                        let dv = sp.db.curve(cv).derivs(p[0]);
                        let gv = nalgebra::Vector3::from(g);
                        let l2 = dv.d1.dot(&dv.d1);
                        dv.d1 * dv.d1.transpose() * (dv.d2.dot(&gv) / (l2 * l2))
                    }
                };
                let mut blk = [[0.0; 3]; 3];
                for (r, row) in blk.iter_mut().enumerate() {
                    for (cc, v) in row.iter_mut().enumerate() {
                        *v = 0.5 * (b[(r, cc)] + b[(cc, r)]);
                    }
                }
                blocks.push((u, blk));
            }
            blocks.sort_by_key(|e| e.0);
            step.blocks = blocks;
        }
        Ok(step)
    }

    fn operator<'a>(&'a self, d: &'a Deformer) -> Option<&'a Operator> {
        self.op.as_ref().or(d.op.as_ref())
    }

    /// G_k = Σ_j K_kj [(y_i − y_j) + R_kj (c_j − c_i)] of unknown k at node i (the force
    /// the constraint of a sliding node takes).
    fn residual(&self, d: &Deformer, op: &Operator, k: usize) -> V3 {
        let i = d.sys.node_of[k] as usize;
        let mut g = [0.0; 3];
        for_neighbours(op, &d.sys, k, |j, kij, _| {
            let r = self.edge_rot(i, j, sub(self.c[j], self.c[i]));
            let e = sub(self.y[i], self.y[j]);
            add(&mut g, kij, [e[0] + r[0], e[1] + r[1], e[2] + r[2]]);
        });
        g
    }

    /// R_ij d (d when R is off).
    fn edge_rot(&self, i: usize, j: usize, d: V3) -> V3 {
        if self.rot {
            rot_apply(qsum(self.q[i], self.q[j]), d)
        } else {
            d
        }
    }

    /// The targets' perturbations: s · dw for displaced nodes, 0 for rigid ones, dc for the
    /// other nodes (they stay where they are).
    fn targets(&self, d: &Deformer, dc: &[V3], dw: &[V3]) -> Vec<V3> {
        d.cls
            .roles
            .iter()
            .enumerate()
            .map(|(i, r)| match *r {
                NodeRole::Displaced(k) => {
                    let w = dw[k];
                    [self.s * w[0], self.s * w[1], self.s * w[2]]
                }
                NodeRole::Rigid(_) => [0.0; 3],
                _ => dc[i],
            })
            .collect()
    }

    /// The forward product: dy for the start perturbation `dc` and the inputs `dw`; returns
    /// dy and the solver iterations.
    pub fn forward(
        &self,
        d: &Deformer,
        dc: &[V3],
        dw: &[V3],
        rel_tol: f64,
    ) -> Result<(Vec<V3>, usize)> {
        let sys = &d.sys;
        let dt = self.targets(d, dc, dw);
        let mut dy = dt.clone();
        let Some(op) = self.operator(d) else {
            return Ok((dy, 0));
        };
        let mut iterations = 0;
        let n = self.c.len();
        // The node quaternions' derivatives.
        let mut dq = vec![[0.0f64; 4]; n];
        if self.rot {
            let mut dacc = vec![[0.0f64; 4]; n];
            for (e, jac) in d.cls.skin.iter().zip(&self.skin) {
                let Some(jac) = jac else { continue };
                let mut g = [0.0; 4];
                for (a, &v) in e.iter().enumerate().take(3) {
                    for b in 0..3 {
                        let (xt, xc) = (dt[v as usize][b], dc[v as usize][b]);
                        for t in 0..4 {
                            g[t] += jac[3 * a + b][t] * xt;
                            if !self.first {
                                g[t] += jac[9 + 3 * a + b][t] * xc;
                            }
                        }
                    }
                }
                for &v in e {
                    for t in 0..4 {
                        dacc[v as usize][t] += g[t];
                    }
                }
            }
            for i in 0..n {
                let l = self.node_len[i];
                if l > 0.0 {
                    let (a, qh) = (dacc[i], self.node_q[i]);
                    let p: f64 = (0..4).map(|t| qh[t] * a[t]).sum();
                    for t in 0..4 {
                        dq[i][t] = (a[t] - qh[t] * p) / l;
                    }
                    // The reach: the blended boundary values of Eq. 26.
                    let phi = weight_at(&d.reach, i);
                    if phi != 1.0 {
                        dq[i] = blend_d(self.q[i], [dq[i][0], dq[i][1], dq[i][2]], phi);
                    }
                }
            }
            // Eq. 26 linearised.
            let rhs: Vec<V3> = (0..sys.node_of.len())
                .into_par_iter()
                .with_min_len(CHUNK)
                .map(|k| {
                    let i = sys.node_of[k] as usize;
                    let mut b = [0.0; 3];
                    for_neighbours(op, sys, k, |j, kij, uj| {
                        if uj.is_none() {
                            add(&mut b, kij, [dq[j][0], dq[j][1], dq[j][2]]);
                        }
                        if !self.first {
                            let dkij = dk(
                                kij,
                                self.power,
                                sub(self.c[j], self.c[i]),
                                sub(dc[j], dc[i]),
                            );
                            let vj = match uj {
                                Some(u) => self.u26[u],
                                None => [self.q[j][0], self.q[j][1], self.q[j][2]],
                            };
                            add(&mut b, -dkij, sub(self.u26[k], vj));
                        }
                    });
                    b
                })
                .collect();
            let mut du = vec![[0.0; 3]; sys.node_of.len()];
            let rep = op.solve_linear_or_fallback(
                &rhs,
                &mut du,
                &Constraints::default(),
                &[],
                rel_tol,
                d.opts.max_iters,
            );
            check(&rep, "linearised Eq. 26", rel_tol)?;
            iterations += rep.iterations;
            for (k, &i) in sys.node_of.iter().enumerate() {
                let i = i as usize;
                dq[i] = blend_d(self.q[i], du[k], weight_at(&d.reach, i));
            }
        }
        // Eq. 21 linearised: the right-hand side.
        let mut db: Vec<V3> = (0..sys.node_of.len())
            .into_par_iter()
            .with_min_len(CHUNK)
            .map(|k| {
                let i = sys.node_of[k] as usize;
                let mut b = [0.0; 3];
                for_neighbours(op, sys, k, |j, kij, uj| {
                    if uj.is_none() {
                        add(&mut b, kij, dt[j]);
                    }
                    let dcij = sub(self.c[j], self.c[i]);
                    if self.rot {
                        let qb = qsum(self.q[i], self.q[j]);
                        add(&mut b, -kij, rot_apply_dq(qb, dcij, qsum(dq[i], dq[j])));
                    }
                    if !self.first {
                        let dd = sub(dc[j], dc[i]);
                        add(&mut b, -kij, self.edge_rot(i, j, dd));
                        let dkij = dk(kij, self.power, dcij, dd);
                        let r = self.edge_rot(i, j, dcij);
                        let e = sub(self.y[i], self.y[j]);
                        add(&mut b, -dkij, [e[0] + r[0], e[1] + r[1], e[2] + r[2]]);
                    }
                });
                b
            })
            .collect();
        if d.mesh.dim == 2 {
            for v in db.iter_mut() {
                v[2] = 0.0;
            }
        }
        let mut x = vec![[0.0; 3]; sys.node_of.len()];
        let rep = op.solve_linear_or_fallback(
            &db,
            &mut x,
            &self.cons,
            &self.blocks,
            rel_tol,
            d.opts.max_iters,
        );
        check(&rep, "linearised Eq. 21", rel_tol)?;
        iterations += rep.iterations;
        for (k, &i) in sys.node_of.iter().enumerate() {
            dy[i as usize] = x[k];
        }
        Ok((dy, iterations))
    }

    /// The reverse product: for the output weights `ybar`, adds to `wbar` (per input) and
    /// returns the weights of the start state c̄ (zero for the first increment) and the
    /// solver iterations. The adjoint solves start from `start` (an earlier reverse
    /// product's solutions, where their lengths fit; zero otherwise) and leave their
    /// solutions there.
    pub fn reverse(
        &self,
        d: &Deformer,
        ybar: &[V3],
        wbar: &mut [V3],
        rel_tol: f64,
        start: &mut StepAdjoint,
    ) -> Result<(Vec<V3>, usize)> {
        let sys = &d.sys;
        let n = self.c.len();
        let mut tbar = vec![[0.0; 3]; n];
        let mut cbar = vec![[0.0; 3]; n];
        let mut iterations = 0;
        for i in 0..n {
            if sys.unk_of[i] == u32::MAX {
                tbar[i] = ybar[i];
            }
        }
        if let Some(op) = self.operator(d) {
            let nu = sys.node_of.len();
            let mut yu: Vec<V3> = sys.node_of.iter().map(|&i| ybar[i as usize]).collect();
            self.cons.project(&mut yu);
            let mut bbar = start_or_zero(std::mem::take(&mut start.eq21), nu);
            let rep = op.solve_linear_or_fallback(
                &yu,
                &mut bbar,
                &self.cons,
                &self.blocks,
                rel_tol,
                d.opts.max_iters,
            );
            check(&rep, "adjoint of Eq. 21", rel_tol)?;
            iterations += rep.iterations;
            self.cons.project(&mut bbar);
            if d.mesh.dim == 2 {
                for v in bbar.iter_mut() {
                    v[2] = 0.0;
                }
            }
            // The transpose of db, gathered per node (A is symmetric: node m forms the terms
            // every neighbour's row sends it; in parallel, each node's sum in its own
            // neighbour order, so independent of the thread count).
            let ct = CouplingsT::new(op, sys, n);
            let bof = |j: usize| match sys.unk_of[j] {
                u32::MAX => [0.0; 3],
                u => bbar[u as usize],
            };
            let mut qbar = vec![[0.0f64; 4]; n];
            qbar.par_iter_mut()
                .zip(cbar.par_iter_mut())
                .zip(tbar.par_iter_mut())
                .enumerate()
                .with_min_len(CHUNK)
                .for_each(|(m, ((qm, cm), tm))| {
                    let bm = bof(m);
                    let mut edge = |j: usize, k: f64| {
                        let db = sub(bm, bof(j));
                        let dcmj = sub(self.c[j], self.c[m]);
                        if self.rot {
                            let qb = qsum(self.q[m], self.q[j]);
                            let g = rot_apply_dq_t(qb, dcmj, [-k * db[0], -k * db[1], -k * db[2]]);
                            for t in 0..4 {
                                qm[t] += g[t];
                            }
                        }
                        if !self.first {
                            let rt = if self.rot {
                                super::edge::rot_apply_t(qsum(self.q[m], self.q[j]), db)
                            } else {
                                db
                            };
                            add(cm, k, rt);
                            let r = self.edge_rot(m, j, dcmj);
                            let e = sub(self.y[m], self.y[j]);
                            let kb = -dot(db, [e[0] + r[0], e[1] + r[1], e[2] + r[2]]);
                            add(cm, -1.0, dk_t(k, self.power, dcmj, kb));
                        }
                    };
                    match sys.unk_of[m] {
                        u32::MAX => {
                            for &(u, k) in ct.row(m) {
                                add(tm, k, bbar[u as usize]);
                                edge(sys.node_of[u as usize] as usize, k);
                            }
                        }
                        u => for_neighbours(op, sys, u as usize, |j, k, _| edge(j, k)),
                    }
                });
            if self.rot {
                // Eq. 26: the unknowns' quaternion weights to their vector parts, the adjoint
                // solve, then its right-hand side transposed.
                let ubar: Vec<V3> = sys
                    .node_of
                    .par_iter()
                    .with_min_len(CHUNK)
                    .map(|&i| {
                        let i = i as usize;
                        blend_d_t(self.q[i], qbar[i], weight_at(&d.reach, i))
                    })
                    .collect();
                let mut z = start_or_zero(std::mem::take(&mut start.eq26), nu);
                let rep = op.solve_linear_or_fallback(
                    &ubar,
                    &mut z,
                    &Constraints::default(),
                    &[],
                    rel_tol,
                    d.opts.max_iters,
                );
                check(&rep, "adjoint of Eq. 26", rel_tol)?;
                iterations += rep.iterations;
                // Gathered per node as above: z and the unknowns' u (the prescribed nodes'
                // quaternion vector parts) per node, zero z on prescribed nodes.
                let zof = |j: usize| match sys.unk_of[j] {
                    u32::MAX => ([0.0; 3], [self.q[j][0], self.q[j][1], self.q[j][2]]),
                    u => (z[u as usize], self.u26[u as usize]),
                };
                qbar.par_iter_mut()
                    .zip(cbar.par_iter_mut())
                    .enumerate()
                    .with_min_len(CHUNK)
                    .for_each(|(m, (qm, cm))| {
                        let (zm, vm) = zof(m);
                        let mut edge = |j: usize, k: f64| {
                            if !self.first {
                                let (zj, vj) = zof(j);
                                let kb = -dot(sub(zm, zj), sub(vm, vj));
                                let g = dk_t(k, self.power, sub(self.c[j], self.c[m]), kb);
                                add(cm, -1.0, g);
                            }
                        };
                        match sys.unk_of[m] {
                            u32::MAX => {
                                for &(u, k) in ct.row(m) {
                                    let zu = z[u as usize];
                                    for t in 0..3 {
                                        qm[t] += k * zu[t];
                                    }
                                    edge(sys.node_of[u as usize] as usize, k);
                                }
                            }
                            u => {
                                if !self.first {
                                    for_neighbours(op, sys, u as usize, |j, k, _| edge(j, k));
                                }
                            }
                        }
                    });
                // The skin nodes' blend (the reach), normalisation, then the elements.
                let accbar: Vec<[f64; 4]> = (0..n)
                    .into_par_iter()
                    .with_min_len(CHUNK)
                    .map(|i| {
                        let l = self.node_len[i];
                        if l == 0.0 {
                            return [0.0; 4];
                        }
                        let phi = weight_at(&d.reach, i);
                        let a = if phi == 1.0 {
                            qbar[i]
                        } else {
                            let v = blend_d_t(self.q[i], qbar[i], phi);
                            [v[0], v[1], v[2], 0.0]
                        };
                        let qh = self.node_q[i];
                        let p: f64 = (0..4).map(|t| qh[t] * a[t]).sum();
                        std::array::from_fn(|t| (a[t] - qh[t] * p) / l)
                    })
                    .collect();
                for (e, jac) in d.cls.skin.iter().zip(&self.skin) {
                    let Some(jac) = jac else { continue };
                    let mut g = [0.0; 4];
                    for &v in e {
                        for t in 0..4 {
                            g[t] += accbar[v as usize][t];
                        }
                    }
                    for (a, &v) in e.iter().enumerate().take(3) {
                        for b in 0..3 {
                            let col = &jac[3 * a + b];
                            tbar[v as usize][b] += (0..4).map(|t| col[t] * g[t]).sum::<f64>();
                            if !self.first {
                                let col = &jac[9 + 3 * a + b];
                                cbar[v as usize][b] += (0..4).map(|t| col[t] * g[t]).sum::<f64>();
                            }
                        }
                    }
                }
                start.eq26 = z;
            }
            start.eq21 = bbar;
        }
        // The targets.
        for (i, r) in d.cls.roles.iter().enumerate() {
            match *r {
                NodeRole::Displaced(k) => add(&mut wbar[k], self.s, tbar[i]),
                NodeRole::Rigid(_) => {}
                _ => add(&mut cbar[i], 1.0, tbar[i]),
            }
        }
        Ok((cbar, iterations))
    }
}

/// The solutions of one increment's adjoint solves (Eq. 21, Eq. 26; empty when not
/// solved), kept as the start of a later reverse product's solves.
#[derive(Debug, Clone, Default)]
pub(crate) struct StepAdjoint {
    pub eq21: Vec<V3>,
    pub eq26: Vec<V3>,
}

/// `v` as the start of a solve of `n` unknowns: zero unless it has their length.
fn start_or_zero(v: Vec<V3>, n: usize) -> Vec<V3> {
    if v.len() == n { v } else { vec![[0.0; 3]; n] }
}

/// The derivative of a node's blended quaternion `q` = (φ u, w) (`crate::rfield::blend`,
/// w = √(1 − φ²|u|²); for φ = 1 the unblended w = √(1 − |u|²) of an unknown) for the
/// derivative `du` of its unblended vector part u: (φ du, −φ u·du / w) with φ u the vector
/// part of `q` (0 for w = 0).
fn blend_d(q: [f64; 4], du: V3, phi: f64) -> [f64; 4] {
    let v = [phi * du[0], phi * du[1], phi * du[2]];
    let dw = if q[3] > 0.0 {
        -dot([q[0], q[1], q[2]], v) / q[3]
    } else {
        0.0
    };
    [v[0], v[1], v[2], dw]
}

/// The transpose of [`blend_d`]: the weight of du for the weights `qbar` of the blended
/// quaternion's four parts.
fn blend_d_t(q: [f64; 4], qbar: [f64; 4], phi: f64) -> V3 {
    let f = if q[3] > 0.0 { qbar[3] / q[3] } else { 0.0 };
    [
        phi * (qbar[0] - f * q[0]),
        phi * (qbar[1] - f * q[1]),
        phi * (qbar[2] - f * q[2]),
    ]
}

/// Fails when a linear solve of the linearisation did not converge.
fn check(rep: &sparse::SolveReport, what: &str, rel_tol: f64) -> Result<()> {
    if rep.converged || rep.rel_residual <= rel_tol {
        Ok(())
    } else {
        Err(Error::NoConvergence {
            what: what.into(),
            solver: rep.solver.clone(),
            iterations: rep.iterations,
            residual: rep.rel_residual,
        })
    }
}
