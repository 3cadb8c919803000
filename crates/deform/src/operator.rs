//! The linear operator of Eqs. 21 and 26 at one grid state ([`Operator`]): the spring
//! matrix, its preconditioner, the couplings to prescribed nodes and the skin elements'
//! initial frames, built once per state; and the linear solve with the chosen solver.

use std::sync::{Arc, Mutex};
use std::time::Instant;

use mesh::{Adjacency, Mesh};
use nalgebra::Matrix3;
use rayon::prelude::*;
use sparse::{
    Block3, Constraints, Csr, Jacobi, SolveOptions, SolveReport, SymMatrix, V3, WithBlocks, pcg,
    point_iteration,
};

use crate::assembly::{System, assemble, couplings};
use crate::bc::{Classified, NodeRole};
use crate::error::{Error, Result};
use crate::options::{DeformOptions, SolverKind};
use crate::report::{PhaseTimes, Steps};
use crate::rfield::{element_size, skin_points};
use crate::rotation::frame;
use crate::solve::held::held_mask;
use crate::solve::{Amg, AmgOptions};
use crate::stiffness::{Stiffness, springs};

/// A constrained multigrid ([`Amg::new_held`]) and the held mask it was built for.
type HeldAmg = (Vec<u8>, Amg<'static, f32>);

/// The preconditioner of the solves (none for the point iteration).
pub(crate) enum Pre<'a> {
    Amg(Box<Amg<'a, f32>>),
    Jacobi(Jacobi),
    None,
}

/// Everything of Eqs. 21 and 26 that depends only on the grid state an increment starts
/// from, built once per state: the spring matrix, its preconditioner, the couplings to
/// prescribed nodes and the skin elements' initial frames.
pub(crate) struct Operator {
    /// The matrix (None when the multigrid hierarchy owns it).
    a: Option<SymMatrix<f32>>,
    pub pre: Pre<'static>,
    /// [`couplings`] at this state.
    pub couplings: Csr,
    /// Per skin element: S̄⁻¹ of its initial frame (Eq. 25) and its size (the weight of its
    /// rotation at its nodes); None for a degenerate element.
    pub skin: Vec<Option<(Matrix3<f64>, f64)>>,
    /// The constrained multigrid of the last constraints the linearised solves had, built
    /// on first use ([`Amg::new_held`]).
    held: Mutex<Option<Arc<HeldAmg>>>,
}

impl Operator {
    /// Springs at `x`, assembly of A and its preconditioner; `distance`: the wall distance
    /// at `x` when already computed (see [`springs`]). The steps are marked in `steps`.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        mesh: &Mesh,
        cls: &Classified,
        sys: &System,
        adj: &Adjacency,
        x: &[[f64; 3]],
        opts: &DeformOptions,
        times: &mut PhaseTimes,
        steps: &mut Steps,
        distance: Option<Vec<f64>>,
    ) -> Result<Self> {
        let t = Instant::now();
        let moving: Vec<bool> = if opts.stiffness == Stiffness::WallDistance {
            cls.roles
                .iter()
                .map(|r| matches!(r, NodeRole::Rigid(_) | NodeRole::Displaced(_)))
                .collect()
        } else {
            Vec::new()
        };
        steps.restart();
        let sp = springs(mesh, x, opts.stiffness, adj, &moving, distance);
        steps.mark("springs");
        let a = assemble(sys, adj, &sp)?;
        let couplings = couplings(sys, adj, &sp);
        steps.mark("assemble");
        let skin = if opts.adapt_rotation {
            cls.skin
                .par_iter()
                .with_min_len(256)
                .map(|e| {
                    let p = skin_points(e, x);
                    let p = &p[..e.len().min(3)];
                    Some((frame(p)?.try_inverse()?, element_size(p)))
                })
                .collect()
        } else {
            Vec::new()
        };
        times.assemble += t.elapsed().as_secs_f64();
        let t = Instant::now();
        let (a, pre) = match opts.solver {
            SolverKind::PcgMultigrid => (
                None,
                Pre::Amg(Box::new(Amg::new_owned(a, &AmgOptions::default())?)),
            ),
            SolverKind::PcgJacobi => {
                let j = Jacobi::new(&a);
                (Some(a), Pre::Jacobi(j))
            }
            SolverKind::PointIteration => (Some(a), Pre::None),
        };
        times.precond += t.elapsed().as_secs_f64();
        steps.mark("precond");
        Ok(Self {
            a,
            pre,
            couplings,
            skin,
            held: Mutex::new(None),
        })
    }

    /// The spring matrix A.
    pub fn matrix(&self) -> &SymMatrix<f32> {
        match (&self.a, &self.pre) {
            (Some(a), _) => a,
            (None, Pre::Amg(m)) => m.fine(),
            (None, _) => unreachable!("the matrix is kept unless the hierarchy owns it"),
        }
    }

    /// Runs one linear solve A x = b with the chosen solver, to `opts.rel_tol`; `step_len`
    /// is the largest boundary displacement (the point iteration's step criterion).
    pub fn solve(
        &self,
        b: &[V3],
        x: &mut [V3],
        cons: &Constraints,
        opts: &DeformOptions,
        step_len: f64,
    ) -> SolveReport {
        self.solve_to(b, x, cons, opts, step_len, opts.rel_tol)
    }

    /// [`Operator::solve`] to the relative residual `rel_tol`.
    pub fn solve_to(
        &self,
        b: &[V3],
        x: &mut [V3],
        cons: &Constraints,
        opts: &DeformOptions,
        step_len: f64,
        rel_tol: f64,
    ) -> SolveReport {
        let a = self.matrix();
        let so = SolveOptions {
            rel_tol,
            max_iters: opts.max_iters,
        };
        match &self.pre {
            Pre::Amg(m) => pcg(a, b, x, &**m, cons, &so),
            Pre::Jacobi(m) => pcg(a, b, x, m, cons, &so),
            Pre::None => point_iteration(a, b, x, cons, 1.0, opts.step_rel_tol * step_len, &so),
        }
    }
}

impl Operator {
    /// Solves the linearised system P (A + B) P x = P b (B: the symmetric 3×3 `blocks`, P:
    /// the projection on `cons`) by conjugate gradients preconditioned as the deformation's
    /// solves (the multigrid, or Jacobi; Jacobi also when the deformation used the point
    /// iteration), to the relative residual `rel_tol`.
    pub fn solve_linear(
        &self,
        b: &[V3],
        x: &mut [V3],
        cons: &Constraints,
        blocks: &[(u32, Block3)],
        rel_tol: f64,
        max_iters: usize,
    ) -> SolveReport {
        let op = WithBlocks {
            a: self.matrix(),
            blocks,
        };
        let so = SolveOptions { rel_tol, max_iters };
        match &self.pre {
            // With constraints, the constrained multigrid (docs/crates/deform.md, "The
            // constrained multigrid"); should its set-up fail, the free one (a valid, slower
            // preconditioner of the same system).
            Pre::Amg(m) if !cons.is_empty() => match self.held(cons) {
                Ok(h) => pcg(&op, b, x, &h.1, cons, &so),
                Err(_) => pcg(&op, b, x, &**m, cons, &so),
            },
            Pre::Amg(m) => pcg(&op, b, x, &**m, cons, &so),
            Pre::Jacobi(m) => pcg(&op, b, x, m, cons, &so),
            Pre::None => pcg(&op, b, x, &Jacobi::new(self.matrix()), cons, &so),
        }
    }
}

impl Operator {
    /// [`Operator::solve_linear`] for the linearisation's products, with a fallback: should
    /// the solver not reach `rel_tol` in `max_iters`, Jacobi-preconditioned CG from zero,
    /// with the iteration limit scaled with the problem (at least twice the unknowns' count:
    /// CG's exact-arithmetic bound per component, with room for round-off). The report of
    /// the solve that converged, or of the fallback when neither did; the iterations of
    /// both are counted.
    #[allow(clippy::too_many_arguments)]
    pub fn solve_linear_or_fallback(
        &self,
        b: &[V3],
        x: &mut [V3],
        cons: &Constraints,
        blocks: &[(u32, Block3)],
        rel_tol: f64,
        max_iters: usize,
    ) -> SolveReport {
        let start = x.to_vec();
        let rep = self.solve_linear(b, x, cons, blocks, rel_tol, max_iters);
        if rep.converged {
            return rep;
        }
        let op = WithBlocks {
            a: self.matrix(),
            blocks,
        };
        let so = SolveOptions {
            rel_tol,
            max_iters: max_iters.max(2 * self.matrix().n()),
        };
        // From the caller's start (the multigrid's iterate may have been spoiled by a
        // breakdown); pcg itself drops a start worse than zero.
        x.copy_from_slice(&start);
        let mut fb = pcg(&op, b, x, &Jacobi::new(self.matrix()), cons, &so);
        fb.iterations += rep.iterations;
        fb.solver = format!("{} then {}", rep.solver, fb.solver);
        fb
    }

    /// The constrained multigrid for `cons` (the last one built, when its held components
    /// are the same).
    fn held(&self, cons: &Constraints) -> Result<Arc<HeldAmg>> {
        let mask = held_mask(self.matrix().n(), cons);
        let mut cached = self.held.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(h) = cached.as_ref().filter(|h| h.0 == mask) {
            return Ok(h.clone());
        }
        let a = Amg::new_held(self.matrix().clone(), &AmgOptions::default(), &mask)?;
        let h = Arc::new((mask, a));
        *cached = Some(h.clone());
        Ok(h)
    }
}

/// Fails with [`Error::NoConvergence`] naming `what` when the solve `rep` did not converge
/// (the point iteration: when it used up its iterations).
pub(crate) fn check_converged(rep: &SolveReport, what: &str, opts: &DeformOptions) -> Result<()> {
    let ok = match opts.solver {
        SolverKind::PointIteration => rep.iterations < opts.max_iters,
        _ => rep.converged,
    };
    if ok {
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
