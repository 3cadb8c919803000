//! One increment of the deformation: the prescribed nodes move from the current state to
//! the fraction `s` of their motion, R is computed for that motion (Eqs. 25–26), Eq. 21 is
//! solved from the current state (with the sliding constraints, and the outer iteration of
//! the sliding on supports), and the grid is moved. The guard ([`crate::guard`]) runs one or
//! several increments per attempt.

use std::time::Instant;

use mesh::{Adjacency, Mesh};
use sparse::V3;

use crate::assembly::{System, rhs};
use crate::bc::{BoundaryConditions, Classified, NodeRole};
use crate::deformer::SolverState;
use crate::error::Result;
use crate::operator::{Operator, Pre, check_converged};
use crate::options::DeformOptions;
use crate::report::{PhaseTimes, Steps};
use crate::rfield::RField;
use crate::sliding::{Sliding, constraints};
use crate::solve::AmgInfo;
use crate::support::{Supports, point};

/// What every increment of one deformation reads: the set-up, and the call's prescribed
/// values.
pub(crate) struct Context<'a> {
    /// The grid (solver numbering) at its baseline coordinates x⁰.
    pub mesh: &'a Mesh,
    pub cls: &'a Classified,
    /// The call's boundary conditions (its displacement values).
    pub bc: &'a BoundaryConditions,
    pub sys: &'a System,
    pub adj: &'a Adjacency,
    pub opts: &'a DeformOptions,
    pub sup: Option<&'a Supports<'a>>,
    /// The positions the prescribed nodes must end at, when the call gave positions.
    pub exact: Option<&'a [[f64; 3]]>,
    /// The weight φ of R per node (the reach of R; empty: 1 everywhere).
    pub reach: &'a [f64],
}

impl<'a> Context<'a> {
    /// The supports, when some unknown slides on one.
    pub fn on_supports(&self) -> Option<&'a Supports<'a>> {
        self.sup
            .filter(|_| self.sys.sup_unk.iter().any(|&u| u != u32::MAX))
    }
}

/// The state an attempt carries from one increment to the next.
pub(crate) struct Attempt {
    /// Node coordinates.
    pub cur: Vec<[f64; 3]>,
    /// Parameters of the nodes sliding on supports (classification order).
    pub params: Vec<[f64; 2]>,
}

/// One increment.
pub(crate) struct Increment<'a> {
    /// The fraction of the motion the prescribed nodes reach.
    pub s: f64,
    /// The operator at the increment's starting state when it is known (the set-up's for
    /// the first increment); otherwise it is built.
    pub op: Option<&'a Operator>,
    /// The solution to start the solves from.
    pub warm: Option<&'a SolverState>,
}

/// What an increment did.
pub(crate) struct StepOut {
    /// Final Δx and Eq. 26 solutions (the warm start of a later call; empty when nothing
    /// was solved).
    pub dx: Vec<V3>,
    pub qv: Vec<V3>,
    pub iterations: usize,
    pub rot_iterations: usize,
    pub residual: f64,
    pub amg: Option<AmgInfo>,
    pub slide_iterations: usize,
    pub slide_update: f64,
}

impl Increment<'_> {
    /// The prescribed nodes' positions at the fraction `s` of the motion (the other nodes at
    /// `cur`) and the largest displacement from `cur`.
    pub fn targets(&self, ctx: &Context, cur: &[[f64; 3]]) -> (Vec<[f64; 3]>, f64) {
        let (x0, cls, s) = (&ctx.mesh.coords, ctx.cls, self.s);
        let mut target: Vec<[f64; 3]> = cur.to_vec();
        let mut max_disp = 0.0f64;
        for i in 0..cur.len() {
            let t = match cls.roles[i] {
                NodeRole::Rigid(m) => cls.motions[m].apply(x0[i], s),
                NodeRole::Displaced(k) => {
                    let d = ctx.bc.displacements[k].1;
                    if s == 1.0 {
                        ctx.exact
                            .map_or([x0[i][0] + d[0], x0[i][1] + d[1], x0[i][2] + d[2]], |p| {
                                p[k]
                            })
                    } else {
                        [
                            x0[i][0] + s * d[0],
                            x0[i][1] + s * d[1],
                            x0[i][2] + s * d[2],
                        ]
                    }
                }
                _ => continue,
            };
            target[i] = t;
            // The displacement target − cur (recomputed, not stored, by the right-hand side).
            let d = [t[0] - cur[i][0], t[1] - cur[i][1], t[2] - cur[i][2]];
            max_disp = max_disp.max((d[0].powi(2) + d[1].powi(2) + d[2].powi(2)).sqrt());
        }
        (target, max_disp)
    }

    /// Moves `st` from its state to the prescribed state of this increment.
    pub fn run(&self, ctx: &Context, st: &mut Attempt, times: &mut PhaseTimes) -> Result<StepOut> {
        let (mesh, cls, sys, opts) = (ctx.mesh, ctx.cls, ctx.sys, ctx.opts);
        let (target, max_disp) = self.targets(ctx, &st.cur);
        let mut out = StepOut {
            dx: Vec::new(),
            qv: Vec::new(),
            iterations: 0,
            rot_iterations: 0,
            residual: 0.0,
            amg: None,
            slide_iterations: 0,
            slide_update: 0.0,
        };
        if max_disp == 0.0 {
            // Nothing moves: the grid is unchanged, bit for bit.
            return Ok(out);
        }
        if sys.node_of.is_empty() {
            // Every node is prescribed: nothing to solve.
            st.cur.copy_from_slice(&target);
            return Ok(out);
        }
        let owned;
        let op = match self.op {
            Some(op) => op,
            None => {
                let mut steps = Steps::start();
                owned = Operator::new(
                    mesh, cls, sys, ctx.adj, &st.cur, opts, times, &mut steps, None,
                )?;
                &owned
            }
        };
        if let Pre::Amg(m) = &op.pre {
            out.amg = Some(m.info());
        }

        // R: unit quaternions per node.
        let t = Instant::now();
        let warm_qv = self.warm.map(|w| w.qv.as_slice());
        let rf = RField::new(
            mesh, cls, sys, op, &st.cur, &target, warm_qv, opts, ctx.reach,
        );
        out.rot_iterations = rf.iterations;
        times.rotation += t.elapsed().as_secs_f64();

        // Eq. 21 right-hand side.
        let t = Instant::now();
        let b = spring_rhs(mesh.dim, sys, op, &rf, &st.cur, &target);
        out.qv = rf.solution;
        times.assemble += t.elapsed().as_secs_f64();

        let t = Instant::now();
        let nu = sys.node_of.len();
        let mut dx = match self.warm {
            Some(w) if w.dx.len() == nu => w.dx.clone(),
            _ => vec![[0.0; 3]; nu],
        };
        // The starting guess: the outer iteration of the sliding measures its updates from it.
        let dx0 = dx.clone();
        let on_supports = ctx.on_supports();
        let cons = if on_supports.is_some() {
            constraints(cls, sys, ctx.sup, &st.params)?
        } else {
            sys.cons.clone()
        };
        let rep = op.solve(&b, &mut dx, &cons, opts, max_disp);
        check_converged(&rep, "spring system (Eq. 21)", opts)?;
        out.iterations = rep.iterations;
        out.residual = rep.rel_residual;
        if let Some(sp) = on_supports {
            let sliding = Sliding {
                cls,
                sys,
                sup: sp,
                op,
                opts,
                scale: mesh.bbox_diagonal(),
                max_disp,
            };
            let so = sliding.iterate(&st.cur, &b, &mut dx, dx0, &mut st.params)?;
            out.slide_iterations = so.iterations;
            out.slide_update = so.update;
            out.iterations += so.solver_iterations;
        }
        times.solve += t.elapsed().as_secs_f64();
        out.dx = dx;
        place(ctx, on_supports, &mut st.cur, &out.dx, &st.params, &target);
        Ok(out)
    }
}

/// The right-hand side of Eq. 21 for the unknowns of the state `cur` moving the prescribed
/// nodes to `target`, with the R field `rf`:
/// b_i = Σ_{j prescribed} K_ij (t_j − x_j) − Σ_j K_ij (R_ij − I)(x_j − x_i) (z components
/// zero in a plane grid).
pub(crate) fn spring_rhs(
    dim: u8,
    sys: &System,
    op: &Operator,
    rf: &RField,
    cur: &[[f64; 3]],
    target: &[[f64; 3]],
) -> Vec<V3> {
    let a = op.matrix();
    let disp = |j: usize| {
        let (t, c) = (target[j], cur[j]);
        [t[0] - c[0], t[1] - c[1], t[2] - c[2]]
    };
    // −Σ_j K_ij (R_ij − I)(x_j − x_i) over every neighbour j of node i: the unknown ones
    // from A's row k (a_kl = −K_ij), then the prescribed ones.
    let mut b = rhs(sys, &op.couplings, disp, |k, i| {
        let mut s = [0.0; 3];
        if !rf.any {
            return s;
        }
        let (cols, vals) = a.row(k);
        for (&c, &akl) in cols.iter().zip(vals) {
            let akl = f64::from(akl);
            let r = rf.minus_identity(i, sys.node_of[c as usize] as usize, cur);
            for q in 0..3 {
                s[q] += akl * r[q];
            }
        }
        let (nodes, kij) = op.couplings.row(k);
        for (&j, &kij) in nodes.iter().zip(kij) {
            let r = rf.minus_identity(i, j as usize, cur);
            for q in 0..3 {
                s[q] -= kij * r[q];
            }
        }
        s
    });
    if dim == 2 {
        // Plane grids stay in their plane.
        for v in b.iter_mut() {
            v[2] = 0.0;
        }
    }
    b
}

/// Moves the grid `cur` by the solved increment: the unknowns by `dx`, the nodes sliding on
/// supports (when `on_supports`) exactly onto their supports at `params`, the prescribed
/// nodes to `target`.
pub(crate) fn place(
    ctx: &Context,
    on_supports: Option<&Supports>,
    cur: &mut [[f64; 3]],
    dx: &[V3],
    params: &[[f64; 2]],
    target: &[[f64; 3]],
) {
    let (cls, sys) = (ctx.cls, ctx.sys);
    for (k, &i) in sys.node_of.iter().enumerate() {
        let c = &mut cur[i as usize];
        for q in 0..3 {
            c[q] += dx[k][q];
        }
    }
    if let Some(sp) = on_supports {
        // Exactly on the support.
        for (k, sn) in cls.supports.iter().enumerate() {
            if sys.sup_unk[k] != u32::MAX {
                cur[sn.node as usize] = point(sp.db, sn.kind, params[k]);
            }
        }
    }
    for i in 0..cur.len() {
        if matches!(cls.roles[i], NodeRole::Rigid(_) | NodeRole::Displaced(_)) {
            cur[i] = target[i];
        }
    }
}
