//! The options of a deformation ([`DeformOptions`]) and the choice of linear solver
//! ([`SolverKind`]); the stiffness choice is [`crate::Stiffness`].

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::error::Error;
use crate::stiffness::Stiffness;

/// The linear solver.
///
/// Serialised (case files) as `PcgMultigrid`, `PcgJacobi`, `PointIteration`; parsed from and
/// displayed as the command line's `pcg`, `pcg-jacobi`, `jacobi`.
///
/// ```
/// use deform::SolverKind;
/// assert_eq!("pcg".parse::<SolverKind>().unwrap(), SolverKind::PcgMultigrid);
/// assert_eq!(SolverKind::PointIteration.to_string(), "jacobi");
/// assert!("cg".parse::<SolverKind>().is_err());
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum SolverKind {
    /// Conjugate gradients with the smoothed-aggregation multigrid W-cycle.
    #[default]
    PcgMultigrid,
    /// Conjugate gradients with the Jacobi preconditioner.
    PcgJacobi,
    /// The paper's point iteration (Eq. 22), Jacobi form.
    PointIteration,
}

impl SolverKind {
    /// Every solver, in the order of the command line's list.
    pub const ALL: [SolverKind; 3] = [
        SolverKind::PcgMultigrid,
        SolverKind::PointIteration,
        SolverKind::PcgJacobi,
    ];

    /// The command line's name.
    pub fn name(self) -> &'static str {
        match self {
            SolverKind::PcgMultigrid => "pcg",
            SolverKind::PcgJacobi => "pcg-jacobi",
            SolverKind::PointIteration => "jacobi",
        }
    }
}

impl fmt::Display for SolverKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for SolverKind {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self, Error> {
        Self::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| Error::BadOption {
                reason: format!("unknown solver {s:?} (expected pcg, jacobi or pcg-jacobi)"),
            })
    }
}

/// Options of [`crate::deform`] and [`crate::Deformer`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DeformOptions {
    /// Spring stiffness.
    pub stiffness: Stiffness,
    /// Use the adaptation matrices R (Eqs. 18–26); `false` gives the plain spring system.
    pub adapt_rotation: bool,
    /// How far R reaches from the moving boundary: `None` (default), everywhere R of Eq. 26
    /// (the paper's); `Some(L)`, R blended to the identity with the distance d of each node
    /// from the moving boundary (along grid edges, on the baseline grid; the moving markers
    /// and the prescribed nodes that are not on fixed markers): its rotation angle
    /// θ becomes θ' with sin(θ'/2) = φ sin(θ/2), φ = 1 − 3t² + 2t³ for t = d / L ≤ 1 and
    /// φ = 0 beyond (R = I from d = L on). `Some(0.0)` gives R = I everywhere, as
    /// `adapt_rotation: false`; `Some(f64::INFINITY)` is `None`. See docs/crates/deform.md,
    /// "How far R reaches".
    pub rotation_reach: Option<f64>,
    /// Linear solver.
    pub solver: SolverKind,
    /// Relative residual |b − A Δx| / |b| at which a solve stops.
    pub rel_tol: f64,
    /// Iteration limit of one solve.
    pub max_iters: usize,
    /// The point iteration also stops when the largest node update (Eq. 24) is below this
    /// fraction of the largest boundary displacement of the increment.
    pub step_rel_tol: f64,
    /// Quality guard: the motion is split into increments when a cell has q ≤ 0 or when the
    /// minimum quality falls below this fraction of the initial minimum.
    pub min_quality_ratio: f64,
    /// Largest number of increments tried (1, 2, 4, … up to this).
    pub max_increments: usize,
    /// Return an inverted grid instead of an error (the report says so).
    pub allow_inverted: bool,
    /// Planarity tolerance of sliding markers, relative to the bounding-box diagonal.
    pub plane_rel_tol: f64,
    /// Renumber the grid internally, along a Morton curve and then in breadth-first order
    /// ([`sparse::order::level_order`]), the unknowns in that order (the result is returned
    /// in the input numbering).
    pub renumber: bool,
    /// Sliding on geometry supports (Eqs. 27–33): the outer iteration stops when the largest
    /// node update of an iteration is ≤ this fraction of the largest boundary displacement of
    /// the increment (a length criterion: with 1e-9 and a 0.1 m motion, 1e-10 m).
    pub slide_rel_tol: f64,
    /// Largest number of outer iterations of the sliding on supports per increment.
    pub max_slide_iters: usize,
}

impl Default for DeformOptions {
    fn default() -> Self {
        Self {
            stiffness: Stiffness::default(),
            adapt_rotation: true,
            rotation_reach: None,
            solver: SolverKind::default(),
            rel_tol: 1e-8,
            max_iters: 20_000,
            step_rel_tol: 1e-10,
            min_quality_ratio: 0.2,
            max_increments: 16,
            allow_inverted: false,
            plane_rel_tol: 1e-6,
            renumber: true,
            slide_rel_tol: 1e-9,
            max_slide_iters: 50,
        }
    }
}

/// The weight φ of R at the distance `d` from the moving boundary for the reach `reach`
/// ([`DeformOptions::rotation_reach`]): 1 − 3t² + 2t³ for t = d / reach ≤ 1, 0 beyond; 0
/// everywhere for a reach of 0, 1 everywhere for an infinite reach.
///
/// ```
/// use deform::options::reach_weight;
/// assert_eq!(reach_weight(0.0, 2.0), 1.0);
/// assert_eq!(reach_weight(1.0, 2.0), 0.5);
/// assert_eq!(reach_weight(2.0, 2.0), 0.0);
/// assert_eq!(reach_weight(0.0, 0.0), 0.0);
/// assert_eq!(reach_weight(1e9, f64::INFINITY), 1.0);
/// ```
pub fn reach_weight(d: f64, reach: f64) -> f64 {
    if reach == f64::INFINITY {
        return 1.0;
    }
    if reach <= 0.0 {
        return 0.0;
    }
    let t = d / reach;
    if t >= 1.0 {
        0.0
    } else {
        1.0 - t * t * (3.0 - 2.0 * t)
    }
}

/// The weight φ of R at node `i` for the per-node weights `reach` (empty: 1 everywhere).
#[inline]
pub(crate) fn weight_at(reach: &[f64], i: usize) -> f64 {
    reach.get(i).copied().unwrap_or(1.0)
}
