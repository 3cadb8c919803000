//! [`Study::new`] as named stages over typed intermediate results: read the case's files
//! ([`Inputs`]), bind the parametrisation, seed the model update, tie the wall to the
//! geometry ([`Wall`]), set up the volume deformation.

use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

use geom_db::GeomDb;
use mesh::Mesh;
use param::{MasterSources, Prepared};
use surfgrid::{ClassifyOptions, NodeSupport, SurfaceGrid};

use super::Study;
use super::error::{Result, StudyError};
use super::report::{Quality, SetupReport};
use crate::case::Case;

/// Stage 1: the case's files, read and checked against the case.
struct Inputs {
    db: GeomDb,
    geometry_path: PathBuf,
    grid: Mesh,
    grid_path: PathBuf,
    /// Baseline cell quality (DESIGN measure).
    quality: Vec<f64>,
}

/// Stage 4: the wall tied to the geometry.
struct Wall {
    /// The wall grid (the volume grid's numbering; other nodes `Free`).
    surface: SurfaceGrid,
    /// True for the wall nodes.
    nodes: Vec<bool>,
    /// Nodes of `fixed` markers, and of markers named nowhere that touch a sliding one
    /// ([`crate::precedence::held_nodes`]), that are not wall nodes; sorted.
    fixed_nodes: Vec<u32>,
    /// Largest wall-node distance from the geometry found by the classification.
    max_distance: f64,
}

/// Runs `f` and returns its value with the seconds it took.
fn timed<T>(f: impl FnOnce() -> Result<T>) -> Result<(T, f64)> {
    let t = Instant::now();
    let v = f()?;
    Ok((v, t.elapsed().as_secs_f64()))
}

/// Stage 1: reads the geometry and the grid, checks that every marker the case names is in
/// the grid, and measures the baseline cell quality.
fn read_inputs(case: &Case, case_path: &Path) -> Result<Inputs> {
    let geometry_path = case.geometry_path(case_path);
    let text = std::fs::read_to_string(&geometry_path).map_err(|source| StudyError::Read {
        path: geometry_path.clone(),
        source,
    })?;
    let db = GeomDb::from_ron_str(&text, &geometry_path.display().to_string())?;
    let (grid, grid_path, quality) = read_grid(case, case_path)?;
    Ok(Inputs {
        db,
        geometry_path,
        grid,
        grid_path,
        quality,
    })
}

/// The case's grid read, with the study's checks (a grid, a wall, every marker
/// the case names present) and the baseline quality.
pub(super) fn read_grid(case: &Case, case_path: &Path) -> Result<(Mesh, PathBuf, Vec<f64>)> {
    let grid_path = case
        .grid_path(case_path)
        .ok_or_else(|| StudyError::NoGrid {
            case: case_path.to_path_buf(),
        })?;
    let grid = mesh::io::read_path(&grid_path)?;
    if case.wall.is_empty() {
        return Err(StudyError::NoWall {
            case: case_path.to_path_buf(),
        });
    }
    for name in case.wall.iter().chain(&case.slide).chain(&case.fixed) {
        if grid.marker(name).is_none() {
            return Err(StudyError::MissingMarker {
                case: case_path.to_path_buf(),
                marker: name.clone(),
                grid: grid_path.clone(),
                available: grid.markers.iter().map(|m| m.name.clone()).collect(),
            });
        }
    }
    let quality = mesh::quality::cell_quality(&grid);
    Ok((grid, grid_path, quality))
}

/// Stage 2: the parametrisation bound to the geometry, with the case's wing masters as the
/// sources of its `External` master modifiers.
///
/// A design variable that moves no control node is an error naming it
/// ([`crate::reach::check_live`]).
pub(super) fn bind_parametrisation(case: &Case, case_path: &Path, db: &GeomDb) -> Result<Prepared> {
    let masters = if case.wing_masters.is_empty() {
        MasterSources::new()
    } else {
        wingmaster::master::master_sources(db, &case.parametrisation, &case.wing_masters)?
    };
    let prepared = case.parametrisation.bind(db, &masters)?;
    crate::reach::check_live(&crate::reach::variable_reach(&prepared)?, case_path)?;
    Ok(prepared)
}

/// Stage 3: the model update seeded on the baseline geometry.
fn seed_model(inputs: &Inputs) -> Result<intersect::update::ModelBaseline> {
    intersect::update::ModelBaseline::new(&inputs.db, &intersect::update::UpdateOptions::default())
        .map_err(|source| StudyError::ModelSeeds {
            geometry: inputs.geometry_path.clone(),
            source: Box::new(source),
        })
}

/// Stage 4: the wall markers' nodes classified on the geometry (`surfgrid::classify_wall`),
/// and the nodes of the `fixed` markers that are not on the wall.
fn tie_wall(case: &Case, inputs: &Inputs) -> Result<Wall> {
    let copts = ClassifyOptions {
        rel_tol: case.surface_grid.classify_rel_tol,
    };
    let (surface, report) = surfgrid::classify_wall(&inputs.db, &inputs.grid, &case.wall, &copts)
        .map_err(|source| StudyError::Classify {
        grid: inputs.grid_path.clone(),
        source: Box::new(source),
    })?;
    let nodes: Vec<bool> = surface
        .support
        .iter()
        .map(|s| !matches!(s, NodeSupport::Free))
        .collect();
    let mut fixed_nodes: Vec<u32> = case
        .fixed
        .iter()
        .filter_map(|m| inputs.grid.marker(m))
        .flat_map(|m| m.elements.node_set())
        .chain(crate::precedence::held_nodes(
            &inputs.grid,
            &case.wall,
            &case.slide,
        ))
        .filter(|&v| !nodes[v as usize])
        .collect();
    fixed_nodes.sort_unstable();
    fixed_nodes.dedup();
    Ok(Wall {
        surface,
        nodes,
        fixed_nodes,
        max_distance: report.max_distance,
    })
}

/// The boundary conditions of the volume deformation: `slide` markers slide on their plane,
/// `fixed` markers are held; prescribed displacements (here zero: only which nodes are
/// prescribed matters to the set-up) on the wall nodes (index order), then on
/// `fixed_nodes` (nodes of `fixed` markers are held even where they touch a sliding marker: a
/// prescribed displacement takes precedence over sliding in `deform`).
fn deform_bc(case: &Case, wall: &Wall) -> deform::BoundaryConditions {
    let mut displacements: Vec<(u32, [f64; 3])> = wall
        .nodes
        .iter()
        .enumerate()
        .filter(|(_, w)| **w)
        .map(|(i, _)| (i as u32, [0.0; 3]))
        .collect();
    displacements.extend(wall.fixed_nodes.iter().map(|&v| (v, [0.0; 3])));
    deform_markers(case, displacements)
}

/// The boundary conditions of [`deform_bc`] with the given prescribed displacements: the
/// case's `slide` markers sliding on their plane, its `fixed` markers held.
pub(super) fn deform_markers(
    case: &Case,
    displacements: Vec<(u32, [f64; 3])>,
) -> deform::BoundaryConditions {
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

/// Stage 5: the volume deformation set up once (classification, ordering, baseline spring
/// matrix and its multigrid hierarchy) with the wall and the fixed nodes prescribed.
fn deform_setup(case: &Case, inputs: &Inputs, wall: &Wall) -> Result<deform::Deformer<'static>> {
    deform::Deformer::new(&inputs.grid, &deform_bc(case, wall), &case.deform.options()).map_err(
        |source| StudyError::DeformSetup {
            grid: inputs.grid_path.clone(),
            source: Box::new(source),
        },
    )
}

impl Study {
    /// Builds the study from a case (`case_path` resolves its relative paths): reads the
    /// geometry and grid, binds the parametrisation, seeds the model update, classifies
    /// the wall nodes on the geometry and sets up the volume deformation.
    pub fn new(case: Case, case_path: &Path) -> Result<Self> {
        let (inputs, read) = timed(|| read_inputs(&case, case_path))?;
        let (prepared, t_param) = timed(|| bind_parametrisation(&case, case_path, &inputs.db))?;
        let (model, t_model) = timed(|| seed_model(&inputs))?;
        let (wall, t_classify) = timed(|| tie_wall(&case, &inputs))?;
        let (deformer, t_deform) = timed(|| deform_setup(&case, &inputs, &wall))?;
        let setup = SetupReport {
            read,
            param: t_param,
            model: t_model,
            classify: t_classify,
            deform: t_deform,
            classify_max_distance: wall.max_distance,
            nodes: inputs.grid.n_nodes(),
            cells: inputs.grid.cells.len(),
            wall_nodes: wall.nodes.iter().filter(|w| **w).count(),
        };
        let Inputs {
            db, grid, quality, ..
        } = inputs;
        Ok(Self {
            case,
            case_path: case_path.to_path_buf(),
            db,
            model,
            prepared,
            grid,
            surface_updater: surfgrid::Updater::new(&wall.surface),
            surface: wall.surface,
            wall: wall.nodes,
            fixed_nodes: wall.fixed_nodes,
            deformer,
            last: Mutex::new(None),
            adjoint: Mutex::new(None),
            recent: Mutex::new(None),
            initial_constraints: std::sync::OnceLock::new(),
            quality_before: Quality::of(&quality),
            quality,
            setup,
        })
    }
}
