//! What a deformation did: [`DeformReport`], with the seconds per phase ([`PhaseTimes`]) and
//! per step of the set-up ([`StepTime`]).

use std::time::Instant;

use mesh::quality::Summary;
use serde::Serialize;

use crate::bc::PlaneInfo;
use crate::options::SolverKind;
use crate::solve::AmgInfo;

/// Seconds per phase.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct PhaseTimes {
    /// Node classification, adjacency, renumbering.
    pub setup: f64,
    /// Matrix and right-hand side assembly (all increments).
    pub assemble: f64,
    /// Preconditioner setup (multigrid hierarchy).
    pub precond: f64,
    /// R on the skin and its propagation (Eq. 26).
    pub rotation: f64,
    /// Linear solves of Eq. 21.
    pub solve: f64,
    /// Quality checks.
    pub quality: f64,
}

/// Seconds of one step of the set-up ([`crate::Deformer::setup_steps`]): a finer view of
/// [`PhaseTimes`]' `setup`, `assemble`, `precond` and `quality` for benchmarks.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StepTime {
    /// The step: `copy`, `classify (input numbering)`, `morton order`, `renumber`,
    /// `adjacency`, `level order`, `classify`, `unknowns`, `quality`, `springs`, `assemble`,
    /// `precond`.
    pub step: &'static str,
    /// Seconds.
    pub seconds: f64,
}

/// Records the seconds of consecutive steps.
pub(crate) struct Steps {
    t: Instant,
    pub list: Vec<StepTime>,
}

impl Steps {
    pub fn start() -> Self {
        Self {
            t: Instant::now(),
            list: Vec::new(),
        }
    }

    /// Ends the step `step` (begun at the last mark) and starts the next.
    pub fn mark(&mut self, step: &'static str) {
        self.list.push(StepTime {
            step,
            seconds: self.t.elapsed().as_secs_f64(),
        });
        self.t = Instant::now();
    }

    /// Starts the next step now (time since the last mark is not recorded).
    pub fn restart(&mut self) {
        self.t = Instant::now();
    }
}

/// What [`crate::deform`] did.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DeformReport {
    /// Nodes of the grid.
    pub nodes: usize,
    /// Cells of the grid.
    pub cells: usize,
    /// Unknown nodes (interior + sliding).
    pub unknowns: usize,
    /// Sliding nodes (constrained to a plane or a seam line).
    pub sliding: usize,
    /// Nodes sliding on geometry support curves and surfaces (Eqs. 27–33).
    pub sliding_on_supports: usize,
    /// Outer iterations of the sliding on supports, summed over the increments of the last
    /// attempt (0 without such nodes).
    pub slide_iterations: usize,
    /// Largest node update of the last outer iteration, relative to the largest boundary
    /// displacement of its increment (the convergence measure of the outer iteration).
    pub slide_update: f64,
    /// Nodes with prescribed motion (moving markers and displacements).
    pub moving: usize,
    /// Planes fitted to sliding markers.
    pub planes: Vec<PlaneInfo>,
    /// Increments used (1 unless the guard split the motion).
    pub increments: usize,
    /// Attempts made by the guard (increments tried, in order).
    pub attempts: Vec<usize>,
    /// Iterations of the Eq. 21 solves, summed over the increments of the last attempt.
    pub iterations: usize,
    /// Iterations of the Eq. 26 (R) solves, summed.
    pub rotation_iterations: usize,
    /// Largest final relative residual of the Eq. 21 solves.
    pub residual: f64,
    /// Solver used.
    pub solver: SolverKind,
    /// Multigrid hierarchy of the last increment (when used).
    pub multigrid: Option<AmgInfo>,
    /// Cell quality before (DESIGN.md's measure; `n_nonpositive` counts inverted and flat
    /// cells).
    pub quality_before: Summary,
    /// Cell quality after.
    pub quality_after: Summary,
    /// Seconds per phase (all attempts; with the set-up for the free functions).
    pub seconds: PhaseTimes,
    /// Seconds per step of the set-up (the free functions; empty for
    /// [`crate::Deformer::deform`], whose set-up was done before).
    pub setup_steps: Vec<StepTime>,
    /// Messages of the guard (increments, inverted cells allowed).
    pub notes: Vec<String>,
    /// How far the motion reaches: the largest displacement far from the moving boundary.
    pub far_field: FarField,
    /// The first layer of cells at the moving wall: height ratios and the turn of the
    /// wall-normal edges ([`crate::layer`]; `None` when no moving node has a neighbour off
    /// the wall).
    pub first_layer: Option<crate::layer::FirstLayer>,
}

/// The largest displacement in the far field: among the nodes whose distance from the
/// moving boundary (along grid edges, on the baseline grid; the distance of
/// [`crate::DeformOptions::rotation_reach`]) is at least the moving boundary's bounding-box
/// diagonal (nodes that no moving node reaches included).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct FarField {
    /// The distance from the moving boundary from which a node is in the far field: the
    /// bounding-box diagonal of the moving nodes (0 without moving nodes).
    pub distance: f64,
    /// Nodes in the far field.
    pub nodes: usize,
    /// Largest displacement of a far-field node (0 when there is none).
    pub max_displacement: f64,
    /// That node (input numbering); `None` when the far field is empty.
    pub node: Option<u32>,
    /// Largest displacement of a moving node (prescribed motion), for scale.
    pub wall_max_displacement: f64,
}

impl FarField {
    /// The moving nodes (distance 0 in `d`, the nodes' distances from the moving boundary)
    /// of the nodes `x0` moved to `x`: their bounding box on `x0` (`lo`, `hi`; empty when
    /// `lo > hi`) and their largest displacement.
    pub(crate) fn moving(x0: &[[f64; 3]], x: &[[f64; 3]], d: &[f64]) -> ([f64; 3], [f64; 3], f64) {
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        let mut largest = 0.0f64;
        for (i, _) in d.iter().enumerate().filter(|e| *e.1 == 0.0) {
            for q in 0..3 {
                lo[q] = lo[q].min(x0[i][q]);
                hi[q] = hi[q].max(x0[i][q]);
            }
            largest = largest.max(distance(x0[i], x[i]));
        }
        (lo, hi, largest)
    }

    /// The diagonal of the box `lo`–`hi` ([`FarField::moving`]); 0 for an empty box.
    pub(crate) fn diagonal(lo: [f64; 3], hi: [f64; 3]) -> f64 {
        if lo[0] <= hi[0] {
            distance(lo, hi)
        } else {
            0.0
        }
    }

    /// The far nodes (distance in `d` at least `from`; a node no moving node reaches, ∞,
    /// included) of the nodes `x0` moved to `x`: their count, and the first of them with
    /// the largest displacement with that displacement.
    pub(crate) fn far(
        x0: &[[f64; 3]],
        x: &[[f64; 3]],
        d: &[f64],
        from: f64,
    ) -> (usize, Option<(usize, f64)>) {
        let mut nodes = 0;
        let mut top: Option<(usize, f64)> = None;
        for (i, _) in d.iter().enumerate().filter(|e| *e.1 >= from) {
            nodes += 1;
            let u = distance(x0[i], x[i]);
            if top.is_none_or(|t| u > t.1) {
                top = Some((i, u));
            }
        }
        (nodes, top)
    }
}

/// |b − a|.
fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2) + (b[2] - a[2]).powi(2)).sqrt()
}
