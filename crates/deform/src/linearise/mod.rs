//! The linearised deformation (issue 22): forward (Jacobian–vector) and reverse
//! (vector–Jacobian) products of what [`Deformer`] computed, through Eqs. 14–26 with the
//! derivative of R and of its Eq. 26 solve, the sliding conditions (planes and seam lines:
//! fixed projections; Eqs. 27–33: the tangent spaces at the final parameters and the
//! supports' curvature) and every increment that ran (chain rule through each).
//!
//! **Inputs dW**: one 3-vector per prescribed node, in the order of the set-up's
//! [`crate::BoundaryConditions::displacements`] (the order [`Deformer::deform`] and
//! [`Deformer::deform_to`] take): the perturbation of that node's displacement (equally,
//! of its position). Rigid markers' motions, the plane fits and the geometry of the
//! supports are held fixed. **Outputs dX**: one 3-vector per grid node (input numbering):
//! the perturbation of the deformed coordinates (prescribed nodes: dW itself; nodes sliding
//! on a support: tangent to it at their final parameters).
//!
//! The reverse product solves the adjoint systems with the same operator and preconditioner
//! as the forward ones: the linearised Eq. 21, P (A + B) P, is symmetric (A the spring
//! matrix, P the orthogonal projection on the constraints, B the symmetric curvature blocks
//! of the nodes on supports), and so is Eq. 26's A. What is not symmetric — the R term's
//! dependence on the skin and on the unknowns' quaternions, the projection of the
//! right-hand side, the dependence on the increment's start state — is transposed term by
//! term. See docs/crates/deform.md, "Linearisation".

mod edge;
mod skin;
mod step;

use sparse::V3;

use crate::deformer::{Deformed, Deformer};
use crate::error::{Error, Result};
use crate::increment::{Attempt, Context, Increment, place};
use crate::operator::Operator;
use crate::report::{PhaseTimes, Steps};
use crate::rfield::RField;
use step::{Step, StepAdjoint};

/// A product of the linearisation and what its linear solves did.
#[derive(Debug, Clone, PartialEq)]
pub struct Product {
    /// The product: dX per node (input numbering) for [`Linearisation::jvp`], dW̄ per
    /// prescribed node (set-up order) for [`Linearisation::vjp`].
    pub values: Vec<[f64; 3]>,
    /// Conjugate-gradient iterations of all its solves.
    pub iterations: usize,
}

/// The adjoint solutions of a reverse product, per increment: the start of the next one's
/// solves ([`Linearisation::vjp_from`]). `Default` is the cold start.
#[derive(Debug, Clone, Default)]
pub struct AdjointStart {
    steps: Vec<StepAdjoint>,
}

/// The deformation linearised at one result of a [`Deformer`] ([`Deformer::linearise`]):
/// forward and reverse products (module doc: what dW and dX are).
pub struct Linearisation<'d, 's> {
    d: &'d Deformer<'s>,
    steps: Vec<Step>,
    rel_tol: f64,
}

impl<'s> Deformer<'s> {
    /// The linearisation of this set-up at `result` (a result of this set-up, from
    /// [`Deformer::deform`] or [`Deformer::deform_to`]). A single increment reuses the
    /// result's solution (the skin rotations and their derivatives are computed, nothing is
    /// solved); several increments are run again from the baseline to record each one's
    /// start state and operator. Several increments need the stiffness
    /// [`crate::Stiffness::InverseLength`] or [`crate::Stiffness::InverseLengthSquared`]
    /// (`Error::BadOption` otherwise).
    pub fn linearise<'d>(&'d self, result: &Deformed) -> Result<Linearisation<'d, 's>> {
        let shape = (self.mesh.n_nodes(), self.sys.node_of.len());
        let st = &result.state;
        if st.shape != shape || st.values.len() != self.bc.displacements.len() {
            return Err(Error::BadMotion {
                reason: format!(
                    "linearisation at a deformation of {} nodes and {} unknowns; this set-up has {} and {}",
                    st.shape.0, st.shape.1, shape.0, shape.1
                ),
            });
        }
        let mut bc = self.bc.clone();
        for (e, &v) in bc.displacements.iter_mut().zip(&st.values) {
            e.1 = v;
        }
        let ctx = Context {
            mesh: &self.mesh,
            cls: &self.cls,
            bc: &bc,
            sys: &self.sys,
            adj: &self.adj,
            opts: &self.opts,
            sup: self.sup.as_ref(),
            exact: st.exact.as_deref(),
            reach: &self.reach,
        };
        let x0 = &self.mesh.coords;
        let inc = result.report.increments.max(1);
        let mut steps = Vec::with_capacity(inc);
        let rf = |op: &Operator, c: &[[f64; 3]], t: &[[f64; 3]], sol: &[V3]| {
            RField::from_solution(
                &self.mesh,
                &self.cls,
                &self.sys,
                op,
                c,
                t,
                sol,
                &self.opts,
                &self.reach,
            )
        };
        if inc == 1 {
            let step = Increment {
                s: 1.0,
                op: self.op.as_ref(),
                warm: None,
            };
            let (target, _) = step.targets(&ctx, x0);
            let mut y = x0.clone();
            if st.dx.len() == shape.1 && shape.1 > 0 {
                place(&ctx, ctx.on_supports(), &mut y, &st.dx, &st.params, &target);
            } else {
                y.clone_from(&target);
            }
            let params = if st.params.len() == self.cls.supports.len() {
                st.params.clone()
            } else {
                self.cls.supports.iter().map(|s| s.param).collect()
            };
            let r = match &self.op {
                Some(op) => rf(op, x0, &target, &st.qv),
                None => identity_field(x0.len()),
            };
            steps.push(Step::new(
                self,
                1.0,
                true,
                None,
                x0.clone(),
                y,
                &target,
                &r,
                &params,
            )?);
        } else {
            let mut times = PhaseTimes::default();
            let mut att = Attempt {
                cur: x0.clone(),
                params: self.cls.supports.iter().map(|s| s.param).collect(),
            };
            for m in 1..=inc {
                let s = if m == inc { 1.0 } else { m as f64 / inc as f64 };
                let c = att.cur.clone();
                let own = if m == 1 || shape.1 == 0 {
                    None
                } else {
                    Some(Operator::new(
                        &self.mesh,
                        &self.cls,
                        &self.sys,
                        &self.adj,
                        &c,
                        &self.opts,
                        &mut times,
                        &mut Steps::start(),
                        None,
                    )?)
                };
                let op = own.as_ref().or(self.op.as_ref());
                let step = Increment { s, op, warm: None };
                let (target, _) = step.targets(&ctx, &c);
                let out = step.run(&ctx, &mut att, &mut times)?;
                let r = match op {
                    Some(op) => rf(op, &c, &target, &out.qv),
                    None => identity_field(c.len()),
                };
                let y = att.cur.clone();
                steps.push(Step::new(
                    self,
                    s,
                    m == 1,
                    own,
                    c,
                    y,
                    &target,
                    &r,
                    &att.params,
                )?);
            }
        }
        Ok(Linearisation {
            d: self,
            steps,
            rel_tol: self.opts.rel_tol,
        })
    }
}

/// R = I everywhere (no unknown: nothing rotates in the right-hand sides).
fn identity_field(n: usize) -> RField {
    RField {
        qv: vec![[0.0; 3]; n],
        qw: vec![1.0; n],
        any: false,
        solution: Vec::new(),
        iterations: 0,
    }
}

impl Linearisation<'_, '_> {
    /// The relative residual the products' linear solves stop at (default: the
    /// deformation's `rel_tol`, so the products are as accurate as the deformation).
    pub fn with_rel_tol(mut self, rel_tol: f64) -> Self {
        self.rel_tol = rel_tol;
        self
    }

    /// Number of inputs (prescribed nodes, set-up order).
    pub fn n_inputs(&self) -> usize {
        self.d.bc.displacements.len()
    }

    /// Number of grid nodes.
    pub fn n_nodes(&self) -> usize {
        self.d.mesh.n_nodes()
    }

    /// Number of increments differentiated.
    pub fn increments(&self) -> usize {
        self.steps.len()
    }

    /// The forward product dX = J dW (`dw`: one 3-vector per input; dX: one per node, input
    /// numbering).
    pub fn jvp(&self, dw: &[[f64; 3]]) -> Result<Product> {
        check_len(
            dw.len(),
            self.n_inputs(),
            "input perturbations (one per prescribed node)",
        )?;
        let n = self.n_nodes();
        let mut dc = vec![[0.0; 3]; n];
        let mut iterations = 0;
        for s in &self.steps {
            let (dy, it) = s
                .forward(self.d, &dc, dw, self.rel_tol)
                .map_err(|e| naming_seed(e, "input perturbation", "prescribed node", dw))?;
            dc = dy;
            iterations += it;
        }
        let values = match &self.d.perm {
            Some(perm) => perm.iter().map(|&p| dc[p as usize]).collect(),
            None => dc,
        };
        Ok(Product { values, iterations })
    }

    /// The reverse product dW̄ = Jᵀ X̄ (`x_bar`: one 3-vector per node, input numbering;
    /// dW̄: one per input), its adjoint solves started from zero.
    pub fn vjp(&self, x_bar: &[[f64; 3]]) -> Result<Product> {
        self.vjp_from(x_bar, &mut AdjointStart::default())
    }

    /// [`Linearisation::vjp`] with its adjoint solves started from `start`: the solutions
    /// of an earlier reverse product (of this linearisation or of one at a nearby design,
    /// with the same set-up), which this one replaces by its own. In an optimiser's loop
    /// the cotangent and the grid change little from one gradient to the next, and so does
    /// the adjoint solution: fewer iterations to the same relative residual, the same
    /// answer to the solver tolerance. An empty `start` (or one whose increments or
    /// unknowns do not fit) starts from zero.
    pub fn vjp_from(&self, x_bar: &[[f64; 3]], start: &mut AdjointStart) -> Result<Product> {
        let n = self.n_nodes();
        check_len(x_bar.len(), n, "output weights (one per grid node)")?;
        let mut ybar = vec![[0.0; 3]; n];
        match &self.d.perm {
            Some(perm) => {
                for (i, &p) in perm.iter().enumerate() {
                    ybar[p as usize] = x_bar[i];
                }
            }
            None => ybar.copy_from_slice(x_bar),
        }
        let mut wbar = vec![[0.0; 3]; self.n_inputs()];
        let mut iterations = 0;
        start
            .steps
            .resize_with(self.steps.len(), StepAdjoint::default);
        for (s, st) in self.steps.iter().zip(start.steps.iter_mut()).rev() {
            let (cbar, it) = s
                .reverse(self.d, &ybar, &mut wbar, self.rel_tol, st)
                .map_err(|e| naming_seed(e, "seed", "node", x_bar))?;
            ybar = cbar;
            iterations += it;
        }
        Ok(Product {
            values: wbar,
            iterations,
        })
    }
}

fn check_len(got: usize, want: usize, what: &str) -> Result<()> {
    if got == want {
        Ok(())
    } else {
        Err(Error::BadMotion {
            reason: format!("{got} {what} given; the linearisation has {want}"),
        })
    }
}

/// A solve's [`Error::NoConvergence`] with the seed it was for named in `what`: its
/// non-zero entries, the largest (entry `kind` k, component) and its norm, so that a failed
/// product can be reproduced; other errors unchanged.
fn naming_seed(e: Error, what: &str, kind: &str, seed: &[[f64; 3]]) -> Error {
    let Error::NoConvergence {
        what: system,
        solver,
        iterations,
        residual,
    } = e
    else {
        return e;
    };
    let mut nonzero = 0;
    let mut largest = (0, 0, 0.0f64);
    let mut sq = 0.0;
    for (i, v) in seed.iter().enumerate() {
        for (c, &x) in v.iter().enumerate() {
            if x != 0.0 {
                nonzero += 1;
                sq += x * x;
                if x.abs() > largest.2.abs() {
                    largest = (i, c, x);
                }
            }
        }
    }
    let (i, c, x) = largest;
    Error::NoConvergence {
        what: format!(
            "{system} for the {what} with {nonzero} non-zero entries of {} (largest {x:e} at {kind} {i} {}, norm {:e})",
            3 * seed.len(),
            ["x", "y", "z"][c],
            sq.sqrt()
        ),
        solver,
        iterations,
        residual,
    }
}
