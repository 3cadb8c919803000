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

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, PoisonError};
use std::time::Instant;

use geom_db::GeomDb;
use geom_db::prelude::Point3;
use mesh::{ElementKind, Elements, Marker, Mesh};
use param::{MasterSources, Prepared};
use serde::Serialize;
use surfgrid::{ClassifyOptions, NodeSupport, SurfaceGrid};

use crate::case::{Case, CaseError};

/// Errors of building or evaluating a study; each names the file or phase.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum StudyError {
    /// The case file is bad.
    #[error(transparent)]
    Case(#[from] CaseError),
    /// A file cannot be read or parsed.
    #[error("{path}: {message}")]
    File {
        /// The file.
        path: String,
        /// What went wrong.
        message: String,
    },
    /// The case is inconsistent (e.g. no grid, a wall marker missing from the grid).
    #[error("{path}: {message}")]
    Setup {
        /// The case file.
        path: String,
        /// What is wrong.
        message: String,
    },
    /// A phase of an evaluation failed.
    #[error("{phase}: {message}")]
    Phase {
        /// `param`, `model update`, `surface grid` or `deform`.
        phase: &'static str,
        /// The error of that phase.
        message: String,
    },
}

/// Result alias of this module.
pub type Result<T, E = StudyError> = std::result::Result<T, E>;

fn phase<E: std::fmt::Display>(phase: &'static str) -> impl FnOnce(E) -> StudyError {
    move |e| StudyError::Phase {
        phase,
        message: e.to_string(),
    }
}

/// Quality of a grid by the DESIGN measure (tetrahedron mean ratio, signed).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Quality {
    /// Smallest cell quality.
    pub min: f64,
    /// Mean cell quality.
    pub mean: f64,
    /// 1st percentile.
    pub p1: f64,
    /// Cells with q ≤ 0.
    pub inverted: usize,
    /// Cells measured.
    pub cells: usize,
}

impl Quality {
    fn of(q: &[f64]) -> Self {
        deform::QualitySummary::of(q).into()
    }
}

impl From<deform::QualitySummary> for Quality {
    fn from(s: deform::QualitySummary) -> Self {
        Self {
            min: s.min,
            mean: s.mean,
            p1: s.p1,
            inverted: s.inverted,
            cells: s.measured,
        }
    }
}

/// Time and figures of the parametrisation phase.
#[derive(Debug, Clone, Serialize)]
pub struct ParamPhase {
    /// Seconds.
    pub seconds: f64,
    /// Control nodes that moved.
    pub nodes_moved: usize,
    /// Largest control-node displacement.
    pub max_move: f64,
}

/// Time and figures of the model update.
#[derive(Debug, Clone, Serialize)]
pub struct ModelPhase {
    /// Seconds.
    pub seconds: f64,
    /// Support surfaces re-solved.
    pub surfaces_changed: usize,
    /// Support curves re-intersected.
    pub curves_reintersected: usize,
    /// Corners moved.
    pub corners_updated: usize,
    /// Largest curve control-point residual |r₁ − r₂| (Eq. 12), e.g. the wing/body junction.
    pub junction_residual: f64,
    /// The same relative to the model's reference length.
    pub junction_residual_rel: f64,
    /// Largest corner residual (Eq. 13).
    pub corner_residual: f64,
    /// Largest deviation of an updated curve from its surfaces between control points.
    pub curve_deviation: Option<f64>,
}

/// Time and figures of the surface-grid update.
#[derive(Debug, Clone, Serialize)]
pub struct SurfacePhase {
    /// Seconds.
    pub seconds: f64,
    /// Wall nodes that moved.
    pub moved_nodes: usize,
    /// Largest wall-node displacement.
    pub max_displacement: f64,
    /// Components re-mapped because their boundary moved in the parametric plane.
    pub remapped_components: usize,
    /// Worst triangle mean ratio over the components after smoothing.
    pub worst_triangle: f64,
}

/// Time and figures of the volume deformation.
#[derive(Debug, Clone, Serialize)]
pub struct DeformPhase {
    /// Seconds.
    pub seconds: f64,
    /// Skipped (no wall node moved: the zero solution).
    pub skipped: bool,
    /// Linear-solver iterations (all increments).
    pub iterations: usize,
    /// Rotation (R) iterations.
    pub rotation_iterations: usize,
    /// Largest final relative residual.
    pub residual: f64,
    /// Increments used by the quality guard.
    pub increments: usize,
    /// Unknowns of the spring system.
    pub unknowns: usize,
    /// Sliding nodes.
    pub sliding: usize,
    /// Notes of the solver (guard retries).
    pub notes: Vec<String>,
}

/// What one evaluation did.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// Design variables and their values.
    pub design: Vec<(String, f64)>,
    /// Parametrisation.
    pub param: ParamPhase,
    /// Model update.
    pub model: ModelPhase,
    /// Surface-grid update.
    pub surface: SurfacePhase,
    /// Volume deformation.
    pub deform: DeformPhase,
    /// Total seconds of the evaluation.
    pub seconds: f64,
    /// Baseline grid quality.
    pub quality_before: Quality,
    /// Deformed grid quality.
    pub quality_after: Quality,
    /// Largest distance of a wall node from its support entity on the updated model
    /// (re-evaluated at its parameters), relative to the reference length.
    pub wall_support_rel: f64,
}

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

/// Timings of [`Study::new`].
#[derive(Debug, Clone, Serialize)]
pub struct SetupReport {
    /// Seconds reading and checking the files.
    pub read: f64,
    /// Seconds binding the parametrisation.
    pub param: f64,
    /// Seconds seeding the model update.
    pub model: f64,
    /// Seconds classifying the wall nodes on the geometry.
    pub classify: f64,
    /// Largest wall-node distance found by the classification.
    pub classify_max_distance: f64,
    /// Nodes, cells and wall nodes of the grid.
    pub nodes: usize,
    /// Cells.
    pub cells: usize,
    /// Wall nodes.
    pub wall_nodes: usize,
    /// Seconds building the volume deformation set-up ([`deform::Deformer`]).
    pub deform: f64,
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

/// The boundary conditions of the volume deformation: `slide` markers slide on their plane,
/// `fixed` markers are held; prescribed displacements (here zero: only which nodes are
/// prescribed matters to the set-up) on the wall nodes (index order), then on `fixed_nodes` (nodes of `fixed` markers are held even where they
/// touch a sliding marker: a prescribed displacement takes precedence over sliding in
/// `deform`).
fn deform_bc(case: &Case, wall: &[bool], fixed_nodes: &[u32]) -> deform::BoundaryConditions {
    let mut displacements: Vec<(u32, [f64; 3])> = wall
        .iter()
        .enumerate()
        .filter(|(_, w)| **w)
        .map(|(i, _)| (i as u32, [0.0; 3]))
        .collect();
    displacements.extend(fixed_nodes.iter().map(|&v| (v, [0.0; 3])));
    deform::BoundaryConditions {
        markers: case
            .slide
            .iter()
            .map(|m| (m.clone(), deform::MarkerRole::SlidePlane))
            .chain(
                case.fixed
                    .iter()
                    .map(|m| (m.clone(), deform::MarkerRole::Fixed)),
            )
            .collect(),
        displacements,
    }
}

fn file_err(path: &Path, e: impl std::fmt::Display) -> StudyError {
    StudyError::File {
        path: path.display().to_string(),
        message: e.to_string(),
    }
}

/// The wall triangles of `grid` split by surface component, as a surface `Mesh` over all of
/// the grid's nodes with one marker per component (named as `surfgrid` names them), ready
/// for `surfgrid::classify`. A triangle's component is its element entity tag − 1 when the
/// grid carries entity tags (MSH), else the component whose support surface is nearest to
/// its centroid.
fn wall_surface(db: &GeomDb, grid: &Mesh, wall: &[String], case: &str) -> Result<Mesh> {
    let nc = db.surface_components.len();
    let mut per: Vec<Elements> = (0..nc).map(|_| Elements::new()).collect();
    let mut projectors = None;
    for name in wall {
        let m = grid.marker(name).ok_or_else(|| StudyError::Setup {
            path: case.to_string(),
            message: format!(
                "wall marker {name:?} is not in the grid (markers: {})",
                grid.markers
                    .iter()
                    .map(|m| m.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        })?;
        for g in m.elements.groups() {
            if g.kind != ElementKind::Triangle {
                return Err(StudyError::Setup {
                    path: case.to_string(),
                    message: format!("wall marker {name:?} has {:?} elements", g.kind),
                });
            }
            for (e, t) in g.iter().enumerate() {
                let tagged = g
                    .entity
                    .get(e)
                    .and_then(|&k| usize::try_from(k - 1).ok())
                    .filter(|&k| k < nc);
                let comp = match tagged {
                    Some(k) => k,
                    None => {
                        let pr = match &mut projectors {
                            Some(p) => p,
                            None => projectors.insert(component_projectors(db)?),
                        };
                        nearest_component(db, pr, grid, t)?
                    }
                };
                per[comp].push(ElementKind::Triangle, t, None);
            }
        }
    }
    let mut s = Mesh::new(3);
    s.coords = grid.coords.clone();
    s.markers = per
        .into_iter()
        .enumerate()
        .filter(|(_, e)| !e.is_empty())
        .map(|(k, elements)| Marker {
            name: surfgrid::grid::marker_name(db, geom_db::SurfCompId::from_index(k)),
            tag: None,
            elements,
        })
        .collect();
    Ok(s)
}

type Projectors<'a> = Vec<intersect::project::SurfaceProjector<'a, geom_db::SupportSurface>>;

fn component_projectors(db: &GeomDb) -> Result<Projectors<'_>> {
    let popts =
        intersect::project::ProjectOptions::default().with_length_scale(db.reference_length());
    db.surface_components
        .iter()
        .map(|sc| {
            intersect::project::SurfaceProjector::new(
                sc.name.clone(),
                db.surface(sc.surface),
                &popts,
            )
            .map_err(phase("classification"))
        })
        .collect()
}

fn nearest_component(db: &GeomDb, pr: &Projectors<'_>, grid: &Mesh, t: &[u32]) -> Result<usize> {
    let mut c = [0.0; 3];
    for &v in t {
        for k in 0..3 {
            c[k] += grid.coords[v as usize][k] / 3.0;
        }
    }
    let p = Point3::new(c[0], c[1], c[2]);
    let mut best = (f64::INFINITY, 0);
    for (k, p_) in pr.iter().enumerate() {
        let f = p_.project(&p).map_err(phase("classification"))?;
        if f.distance < best.0 {
            best = (f.distance, k);
        }
    }
    let _ = db;
    Ok(best.1)
}

impl Study {
    /// Reads the case file and builds the study.
    pub fn load(case_path: &Path) -> Result<Self> {
        let case = Case::load(case_path)?;
        Self::new(case, case_path)
    }

    /// Builds the study from a case (`case_path` resolves its relative paths): reads the
    /// geometry and grid, binds the parametrisation, seeds the model update and classifies
    /// the wall nodes on the geometry.
    pub fn new(case: Case, case_path: &Path) -> Result<Self> {
        let shown = case_path.display().to_string();
        let t = Instant::now();
        let gpath = case.geometry_path(case_path);
        let text = std::fs::read_to_string(&gpath).map_err(|e| file_err(&gpath, e))?;
        let db = GeomDb::from_ron_str(&text, &gpath.display().to_string())
            .map_err(|e| file_err(&gpath, e))?;
        let grid_path = case.grid_path(case_path).ok_or_else(|| StudyError::Setup {
            path: shown.clone(),
            message: "the case names no grid (field `grid`)".into(),
        })?;
        let grid = mesh::io::read_path(&grid_path).map_err(|e| file_err(&grid_path, e))?;
        if case.wall.is_empty() {
            return Err(StudyError::Setup {
                path: shown,
                message: "the case names no wall marker (field `wall`)".into(),
            });
        }
        for name in case.slide.iter().chain(&case.fixed) {
            if grid.marker(name).is_none() {
                return Err(StudyError::Setup {
                    path: shown,
                    message: format!("marker {name:?} is not in the grid {}", grid_path.display()),
                });
            }
        }
        let quality = mesh::quality::cell_quality(&grid);
        let read = t.elapsed().as_secs_f64();

        let t = Instant::now();
        let masters = if case.wing_masters.is_empty() {
            MasterSources::new()
        } else {
            wingmaster::master::master_sources(&db, &case.parametrisation, &case.wing_masters)
                .map_err(|e| StudyError::Setup {
                    path: shown.clone(),
                    message: format!("wing masters: {e}"),
                })?
        };
        let prepared = case
            .parametrisation
            .bind(&db, &masters)
            .map_err(|e| StudyError::Setup {
                path: shown.clone(),
                message: format!("parametrisation: {e}"),
            })?;
        let t_param = t.elapsed().as_secs_f64();

        let t = Instant::now();
        let model = intersect::update::ModelBaseline::new(
            &db,
            &intersect::update::UpdateOptions::default(),
        )
        .map_err(|e| StudyError::Setup {
            path: gpath.display().to_string(),
            message: format!("model update seeds: {e}"),
        })?;
        let t_model = t.elapsed().as_secs_f64();

        let t = Instant::now();
        let surf_mesh = wall_surface(&db, &grid, &case.wall, &shown)?;
        let copts = ClassifyOptions {
            rel_tol: case.surface_grid.classify_rel_tol,
        };
        let (surface, crep) =
            surfgrid::classify(&surf_mesh, &db, &copts).map_err(|e| StudyError::Setup {
                path: grid_path.display().to_string(),
                message: format!("classification of the wall on the geometry: {e}"),
            })?;
        let wall: Vec<bool> = surface
            .support
            .iter()
            .map(|s| !matches!(s, NodeSupport::Free))
            .collect();
        let mut fixed_nodes: Vec<u32> = case
            .fixed
            .iter()
            .filter_map(|m| grid.marker(m))
            .flat_map(|m| m.elements.node_set())
            .filter(|&v| !wall[v as usize])
            .collect();
        fixed_nodes.sort_unstable();
        fixed_nodes.dedup();
        let classify_seconds = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let deformer = deform::Deformer::new(
            &grid,
            &deform_bc(&case, &wall, &fixed_nodes),
            &case.deform.options(),
        )
        .map_err(|e| StudyError::Setup {
            path: grid_path.display().to_string(),
            message: format!("volume deformation set-up: {e}"),
        })?;
        let setup = SetupReport {
            read,
            param: t_param,
            model: t_model,
            classify: classify_seconds,
            deform: t.elapsed().as_secs_f64(),
            classify_max_distance: crep.max_distance,
            nodes: grid.n_nodes(),
            cells: grid.cells.len(),
            wall_nodes: wall.iter().filter(|w| **w).count(),
        };
        Ok(Self {
            case,
            case_path: case_path.to_path_buf(),
            db,
            model,
            prepared,
            grid,
            surface_updater: surfgrid::Updater::new(&surface),
            surface,
            wall,
            fixed_nodes,
            deformer,
            last: Mutex::new(None),
            quality_before: Quality::of(&quality),
            quality,
            setup,
        })
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
        self.prepared
            .registry()
            .vector_from_values(values)
            .map_err(phase("design vector"))
    }

    /// Makes the next evaluation start its solves from the baseline (see the module doc).
    pub fn forget_warm_start(&self) {
        *self.last.lock().unwrap_or_else(PoisonError::into_inner) = None;
    }

    /// Runs the chain for the design vector `x` (one value per design variable, in the
    /// registry's order); see the module doc.
    pub fn evaluate(&self, x: &[f64]) -> Result<Evaluation> {
        self.evaluate_with_progress(x, &mut |_| {})
    }

    /// [`Study::evaluate`], calling `progress(phase)` as each phase starts.
    pub fn evaluate_with_progress(
        &self,
        x: &[f64],
        progress: &mut dyn FnMut(&str),
    ) -> Result<Evaluation> {
        let t_all = Instant::now();
        let reg = self.prepared.registry();
        if x.len() != reg.len() {
            return Err(StudyError::Phase {
                phase: "param",
                message: format!(
                    "the design vector has {} values; the case has {} design variables",
                    x.len(),
                    reg.len()
                ),
            });
        }
        // 1. param
        progress("param");
        let t = Instant::now();
        let pts = self.prepared.apply(x).map_err(phase("param"))?;
        let base = self.db.control_points();
        let nodes_moved = pts.iter().zip(base).filter(|(p, q)| p != q).count();
        let max_move = pts
            .iter()
            .zip(base)
            .map(|(p, q)| (p - q).norm())
            .fold(0.0, f64::max);
        let param = ParamPhase {
            seconds: t.elapsed().as_secs_f64(),
            nodes_moved,
            max_move,
        };
        // 2. model update
        progress("model update");
        let t = Instant::now();
        let (geometry, ur) = self.model.update(&pts).map_err(phase("model update"))?;
        let lref = self.db.reference_length();
        let model = ModelPhase {
            seconds: t.elapsed().as_secs_f64(),
            surfaces_changed: ur.surfaces_changed.len(),
            curves_reintersected: ur.curves.iter().filter(|c| c.reintersected).count(),
            corners_updated: ur.corners.iter().filter(|c| c.updated).count(),
            junction_residual: ur.max_curve_residual,
            junction_residual_rel: ur.max_curve_residual / lref,
            corner_residual: ur.max_corner_residual,
            curve_deviation: ur.max_deviation,
        };
        // 3. surface grid at frozen parameters
        progress("surface grid");
        let t = Instant::now();
        let (surface, sr) = self
            .surface_updater
            .update(
                &self.surface,
                &self.db,
                &geometry,
                &self.case.surface_grid.update_options(),
            )
            .map_err(phase("surface grid"))?;
        let surf_phase = SurfacePhase {
            seconds: t.elapsed().as_secs_f64(),
            moved_nodes: sr.moved_nodes,
            max_displacement: sr.max_displacement,
            remapped_components: sr.components.iter().filter(|c| c.remapped).count(),
            worst_triangle: sr
                .components
                .iter()
                .map(|c| c.worst_after)
                .fold(f64::INFINITY, f64::min),
        };
        // 4. volume deformation
        progress("deform");
        let t = Instant::now();
        // Prescribed positions in the order of the set-up's boundary conditions
        // (`deform_bc`): the wall nodes at their new place on the geometry, then the nodes of
        // `fixed` markers where they are.
        let mut positions = Vec::with_capacity(self.deformer.n_displacements());
        let mut any = false;
        for (i, w) in self.wall.iter().enumerate() {
            if *w {
                let (p, p0) = (surface.coords[i], self.surface.coords[i]);
                any |= p != p0;
                positions.push([p.x, p.y, p.z]);
            }
        }
        positions.extend(
            self.fixed_nodes
                .iter()
                .map(|&v| self.grid.coords[v as usize]),
        );
        let mut grid = self.grid.clone();
        let mut deformed_quality = None;
        let warm_start = self.case.deform.warm_start;
        let deform_phase = if any {
            // The set-up is reused; the solves start from the previous solution if warm.
            let warm = if warm_start {
                self.last
                    .lock()
                    .unwrap_or_else(PoisonError::into_inner)
                    .clone()
            } else {
                None
            };
            // The wall nodes come back exactly at `positions`: the cell quality of the
            // deformation is that of the returned grid.
            let mut d = self
                .deformer
                .deform_to(&positions, warm.as_deref())
                .map_err(phase("deform"))?;
            grid.coords = std::mem::take(&mut d.coords);
            deformed_quality = Some((
                std::mem::take(&mut d.cell_quality),
                Quality::from(d.report.quality_after),
            ));
            let phase = DeformPhase {
                seconds: t.elapsed().as_secs_f64(),
                skipped: false,
                iterations: d.report.iterations,
                rotation_iterations: d.report.rotation_iterations,
                residual: d.report.residual,
                increments: d.report.increments,
                unknowns: d.report.unknowns,
                sliding: d.report.sliding,
                notes: d.report.notes.clone(),
            };
            if warm_start {
                // Kept for its solver state only (coordinates and quality taken above).
                *self.last.lock().unwrap_or_else(PoisonError::into_inner) = Some(Arc::new(d));
            }
            phase
        } else {
            // The solution is Δx = 0: the next evaluation starts cold.
            self.forget_warm_start();
            DeformPhase {
                seconds: t.elapsed().as_secs_f64(),
                skipped: true,
                iterations: 0,
                rotation_iterations: 0,
                residual: 0.0,
                increments: 0,
                unknowns: 0,
                sliding: 0,
                notes: vec!["no wall node moved: the baseline grid is the solution".into()],
            }
        };
        // classification with the updated parameters
        if let (Some(cls), true) = (grid.classes.as_mut(), grid.parametric) {
            let nw = cls.len().min(surface.support.len());
            for i in 0..nw {
                match surface.support[i] {
                    NodeSupport::Curve { t, .. } if cls[i].dim == 1 => cls[i].param = [t, 0.0],
                    NodeSupport::Surface { uv, .. } if cls[i].dim == 2 => cls[i].param = uv,
                    _ => {}
                }
            }
        }
        let (cell_quality, quality_after) =
            deformed_quality.unwrap_or_else(|| (self.quality.clone(), self.quality_before));
        let mut wall_support: f64 = 0.0;
        for (i, w) in self.wall.iter().enumerate() {
            if *w {
                let e = surface.evaluate_node(&geometry, i);
                let p = grid.coords[i];
                wall_support = wall_support.max((Point3::new(p[0], p[1], p[2]) - e).norm() / lref);
            }
        }
        let report = Report {
            design: reg
                .names()
                .iter()
                .zip(x)
                .map(|(n, v)| (n.to_string(), *v))
                .collect(),
            param,
            model,
            surface: surf_phase,
            deform: deform_phase,
            seconds: t_all.elapsed().as_secs_f64(),
            quality_before: self.quality_before,
            quality_after,
            wall_support_rel: wall_support,
        };
        Ok(Evaluation {
            geometry,
            grid,
            surface,
            cell_quality,
            report,
        })
    }
}
