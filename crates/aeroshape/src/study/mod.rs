//! [`Study`]: the chain of the paper's Figure 5 as a library — built once from a case, then
//! `evaluate(design vector)` as many times as an optimiser needs.
//!
//! One evaluation runs, in order:
//! 1. **param** (§5): the design vector moves the control nodes (node, line, surface and
//!    master levels, Eqs. 34–38);
//! 2. **model update** (§3.1–3.2): support surfaces re-solved from the control nodes (Eq. 9),
//!    support curves re-intersected (Eqs. 11–12), corners (Eq. 13) — `intersect`'s
//!    `ModelBaseline`, seeded once on the baseline model;
//! 3. **surface-grid update** (§3.3): every wall node re-evaluated at its frozen parameters
//!    on the new model (Eqs. 2 and 7), with a harmonic re-map of a component whose boundary
//!    moved in its parametric plane (`surfgrid::update`);
//! 4. **volume deformation** (§4): the spring analogy (Eqs. 14–26) with the wall nodes'
//!    displacements prescribed, the `slide` markers sliding on their planes and the `fixed`
//!    (and unnamed) markers fixed (`deform`); a node of a `fixed` marker that also lies on a
//!    sliding marker (e.g. the far-field box edge on the symmetry plane) stays fixed.
//!
//! Built once in [`Study::new`] and reused by every evaluation: the geometry and its curve
//! seeds for the update, the bound parametrisation, the baseline grid and its classification
//! on the geometry (wall nodes with their support entity and parameters), the baseline cell
//! quality, the volume-deformation set-up (node classification, ordering, baseline spring
//! matrix and its multigrid hierarchy). The harmonic re-map of each surface-grid component is
//! factorised the first time that component is re-mapped and reused afterwards.
//!
//! **Warm start.** An optimiser evaluates nearby design vectors one after the other, so each
//! evaluation starts the solves of the volume deformation (R of Eq. 26, Δx of Eq. 21, the
//! parameters of the nodes sliding on supports) from the solution of the previous one
//! (`deform.warm_start` in the case, on by default). The answer then depends on the call
//! history only below the solver tolerances (relative residual `deform.rel_tol`, sliding
//! update 1e-9 of the wall motion): evaluating the same vector twice gives the same grid to
//! round-off, the second time without a solver iteration. An evaluation where no wall node
//! moves (the initial design vector) returns the baseline grid bit for bit and resets the warm
//! start, so `x`, initial, `x` gives the same grid twice bit for bit. With
//! `warm_start: false` every evaluation starts from the baseline and `evaluate(x)` is bit for
//! bit independent of the history; [`Study::forget_warm_start`] does the same for one call.
//! Evaluations from several threads at once are safe; each starts from whichever solution
//! was stored last.
//!
//! ```no_run
//! use aeroshape::study::Study;
//! let study = Study::load("fixtures/cases/default/case.ron".as_ref()).unwrap();
//! let mut x = study.initial();
//! x[0] += 0.01;
//! let ev = study.evaluate(&x).unwrap();
//! println!("min quality {} → {}", ev.report.quality_before.min, ev.report.quality_after.min);
//! ```
//!
//! A runnable version: `cargo run --release -p aeroshape --example study`.
//!
//! Files: the set-up's stages ([`Study::new`]) in `setup.rs`, the evaluation's stages in
//! `evaluate.rs`, the reports in [`report`], the errors in [`error`].

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, PoisonError};

use geom_db::GeomDb;
use mesh::Mesh;
use param::Prepared;
use surfgrid::SurfaceGrid;

use crate::case::Case;

pub mod constraints;
#[cfg(feature = "mpi")]
pub mod distributed;
pub mod error;
mod evaluate;
pub mod failure;
pub mod linearise;
pub mod report;
mod setup;

pub use constraints::{ConstraintJacobian, ConstraintRow};
pub use error::{Result, StudyError};
pub use linearise::{ChainLinearisation, FdCheck, model_jacobian};
pub use report::{DeformPhase, ModelPhase, ParamPhase, Quality, Report, SetupReport, SurfacePhase};

/// The result of [`Study::evaluate`].
#[derive(Debug, Clone)]
pub struct Evaluation {
    /// The updated geometric database.
    pub geometry: GeomDb,
    /// The deformed grid (the baseline's cells, markers and node classification with the
    /// updated parameters; new coordinates).
    pub grid: Mesh,
    /// The updated wall grid tied to the geometry.
    pub surface: SurfaceGrid,
    /// Cell quality of the deformed grid (DESIGN measure), per cell.
    pub cell_quality: Vec<f64>,
    /// The report.
    pub report: Report,
}

/// What one evaluation at `x` computed that [`Study::linearise`] at the same `x` reuses
/// instead of evaluating again.
pub(crate) struct EvaluatedAt {
    /// The design vector.
    x: Vec<f64>,
    /// The updated model.
    geometry: GeomDb,
    /// The updated wall grid and what its update recorded for its linearisation.
    surface: SurfaceGrid,
    record: surfgrid::UpdateRecord,
    /// The volume deformation (coordinates and quality taken out; None: no wall node moved,
    /// the baseline grid is the answer).
    deformed: Option<Arc<deform::Deformed>>,
    /// The deformed grid's coordinates.
    coords: Vec<[f64; 3]>,
}

/// The pipeline built once from a case; see the module doc.
pub struct Study {
    case: Case,
    case_path: PathBuf,
    db: GeomDb,
    model: intersect::update::ModelBaseline,
    prepared: Prepared,
    grid: Mesh,
    surface: SurfaceGrid,
    /// The surface-grid update's reusable part (factorised re-maps).
    surface_updater: surfgrid::Updater,
    wall: Vec<bool>,
    fixed_nodes: Vec<u32>,
    /// The volume deformation set-up (classification, ordering, baseline stiffness and
    /// multigrid hierarchy), built once; prescribed nodes: the wall nodes in index order, then
    /// `fixed_nodes`.
    deformer: deform::Deformer<'static>,
    /// The last volume deformation, the warm start of the next one (None: start cold).
    last: Mutex<Option<Arc<deform::Deformed>>>,
    /// The last reverse product's adjoint solutions, the start of the next one's (None:
    /// start cold).
    adjoint: Mutex<Option<deform::AdjointStart>>,
    /// The last evaluation's results, reused by [`Study::linearise`] at the same x.
    recent: Mutex<Option<Arc<EvaluatedAt>>>,
    /// The case's constraints measured on the baseline model, once (`Study::constraints`).
    initial_constraints: std::sync::OnceLock<Vec<crate::constraints::Measured>>,
    quality: Vec<f64>,
    quality_before: Quality,
    setup: SetupReport,
}

impl std::fmt::Debug for Study {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Study")
            .field("case", &self.case_path)
            .field("nodes", &self.grid.n_nodes())
            .finish_non_exhaustive()
    }
}

impl Study {
    /// Reads the case file and builds the study.
    pub fn load(case_path: &Path) -> Result<Self> {
        let case = Case::load(case_path)?;
        Self::new(case, case_path)
    }

    /// The case.
    pub fn case(&self) -> &Case {
        &self.case
    }

    /// The baseline geometric database.
    pub fn geometry(&self) -> &GeomDb {
        &self.db
    }

    /// The baseline grid, as read.
    pub fn baseline(&self) -> &Mesh {
        &self.grid
    }

    /// The baseline wall grid tied to the geometry.
    pub fn baseline_surface(&self) -> &SurfaceGrid {
        &self.surface
    }

    /// Baseline cell quality (DESIGN measure).
    pub fn baseline_quality(&self) -> &[f64] {
        &self.quality
    }

    /// True for the grid nodes that lie on the geometry (wall nodes).
    pub fn wall_nodes(&self) -> &[bool] {
        &self.wall
    }

    /// Timings and sizes of the set-up.
    pub fn setup_report(&self) -> &SetupReport {
        &self.setup
    }

    /// The bound parametrisation.
    pub(crate) fn prepared(&self) -> &Prepared {
        &self.prepared
    }

    /// The design-variable registry.
    pub fn registry(&self) -> &param::Registry {
        self.prepared.registry()
    }

    /// The initial design vector (the baseline shape).
    pub fn initial(&self) -> Vec<f64> {
        self.prepared.registry().initial()
    }

    /// A design vector from named values (`DV.ron`); unnamed variables keep their initial
    /// value.
    pub fn vector_from_values(&self, values: &param::DesignValues) -> Result<Vec<f64>> {
        Ok(self.prepared.registry().vector_from_values(values)?)
    }

    /// Makes the next evaluation start its solves from the baseline, and the next reverse
    /// product its adjoint solves from zero (see the module doc).
    pub fn forget_warm_start(&self) {
        *self.last.lock().unwrap_or_else(PoisonError::into_inner) = None;
        *self.adjoint.lock().unwrap_or_else(PoisonError::into_inner) = None;
    }

    /// Runs the chain for the design vector `x` (one value per design variable, in the
    /// registry's order); see the module doc.
    pub fn evaluate(&self, x: &[f64]) -> Result<Evaluation> {
        self.evaluate_with_progress(x, &mut |_| {})
    }
}
