//! `case init`: a ready case from a user's own geometry and grid ([`init_case`]).
//!
//! Stages, each on the previous one's result:
//! 1. the tolerance of the geometry ([`Tolerance`]): the largest of the default relative
//!    tolerance and the CAD's own figures (its resolution, the sewing gaps measured at
//!    import), each printed with its source;
//! 2. the markers' roles by shape alone ([`roles::marker_roles`]): far field fixed, planes
//!    sliding, markers on the geometry wall;
//! 3. the wall tied to the geometry by geometry alone (`surfgrid::classify_wall`), and the
//!    whole volume grid written with parametric wall nodes (`DIR/grid.msh`), the geometry
//!    (`DIR/geometry.ron`) and the case (`DIR/case.ron`);
//! 4. the default design space ([`space`]): per part of the wall ([`parts`]), a wing
//!    master for a wing ([`wing`]), the waist at the wing junction ([`fuselage`]) and the
//!    nose droop and stretch ([`nose`]) for a fuselage, normal bumps otherwise; every
//!    variable that moves no control node left out, and the bounds checked by the study
//!    ([`bounds`]): each variable alone at either bound inverts no cell.
//!
//! A geometry without control nodes (§3) cannot be moved by any design variable: that is
//! an error ([`InitError::NoControlNodes`]) unless [`InitOptions::assign_control_nodes`]
//! asks for them to be made.

use std::path::{Path, PathBuf};

use geom_db::GeomDb;
use mesh::Mesh;
use serde::Serialize;

use crate::boxcheck::BoxCheckOptions;
use crate::case::{CASE_FORMAT_VERSION, Case};
use crate::fsio::write_atomic;
use crate::study::{Study, StudyError};

pub mod bounds;
pub mod cad;
pub mod fuselage;
pub mod nose;
pub mod parts;
pub mod roles;
pub mod space;
pub mod wing;

pub use bounds::VariableCheck;
pub use cad::{Cad, read_cad};
pub use roles::{MarkerRole, Role};

/// Errors of `case init`; each names the file, marker or variable.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum InitError {
    /// No marker of the grid lies on the geometry.
    #[error("no marker of the grid lies on the geometry within {tol:.3e} ({})", roles.iter().map(|r| format!("{}: {}", r.marker, r.why)).collect::<Vec<_>>().join("; "))]
    NoWall {
        /// The tolerance.
        tol: f64,
        /// What each marker was found to be.
        roles: Vec<MarkerRole>,
    },
    /// A variable inverts cells, or its evaluation fails, even at its smallest bound tried.
    #[error("design variable {variable:?} fails even at ±{bound:.3e}: {why}")]
    Bounds {
        /// The variable.
        variable: String,
        /// The last bound tried.
        bound: f64,
        /// What failed there.
        why: String,
    },
    /// The geometry has no control nodes, so no design variable can move it.
    ///
    /// ```
    /// let err = aeroshape::init::InitError::NoControlNodes { surfaces: 5 };
    /// assert!(err.to_string().contains("--assign-control-nodes"));
    /// ```
    #[error(
        "the geometry has no control nodes (paper §3; {surfaces} support surfaces), so no \
         design variable can move it: run case init again with --assign-control-nodes (one \
         control node per interpolation point of every arc and patch, shared where they \
         coincide), or give a geometry that has them"
    )]
    NoControlNodes {
        /// Support surfaces of the geometry.
        surfaces: usize,
    },
    /// No design variable of the default space moves the geometry.
    #[error("no design variable of the default space moves the geometry ({})", notes.join("; "))]
    NoVariables {
        /// Why each candidate was left out.
        notes: Vec<String>,
    },
    /// The CAD file's extension is not one `case init` reads.
    #[error("{}: unknown CAD format (use .igs, .iges, .stp, .step or .ron)", path.display())]
    CadFormat {
        /// The file.
        path: PathBuf,
    },
    /// A file could not be read.
    #[error("cannot read {}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The CAD file could not be imported (the message names the file and entity).
    #[error(transparent)]
    Import {
        /// The import's error.
        source: Box<geom_db::import::Error>,
    },
    /// The geometric database could not be read or its control nodes made.
    #[error(transparent)]
    Geometry(#[from] geom_db::Error),
    /// Classification or marker distances on the geometry.
    #[error("classification: {0}")]
    Surfgrid(#[from] surfgrid::Error),
    /// The parametrisation could not be bound.
    #[error("param: {0}")]
    Param(#[from] param::Error),
    /// The study of the new case could not be built or evaluated.
    #[error(transparent)]
    Study(#[from] StudyError),
    /// An output file could not be written.
    #[error(transparent)]
    Write(#[from] crate::fsio::WriteError),
}

/// One figure the geometric tolerance is taken from.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Tolerance {
    /// Where it comes from (e.g. "sewing gaps measured at import (largest × 2)").
    pub source: String,
    /// The distance (model units).
    pub value: f64,
}

/// Options of [`init_case`].
#[derive(Debug, Clone, PartialEq)]
pub struct InitOptions {
    /// A tolerance given by the user, relative to the model's reference length (replaces
    /// the largest of the sources).
    pub rel_tol: Option<f64>,
    /// First bound of each design variable, relative to the wall's box diagonal.
    pub bound_rel: f64,
    /// Largest number of halvings of a bound in the check.
    pub max_halvings: usize,
    /// Make control nodes (`GeomDb::assign_control_nodes`) when the geometry has none,
    /// instead of failing with [`InitError::NoControlNodes`].
    pub assign_control_nodes: bool,
    /// The box checked as a whole after the variables' own checks ([`crate::boxcheck`]):
    /// its samples and how far it may shrink; `None` skips it.
    pub box_check: Option<BoxCheckOptions>,
}

impl Default for InitOptions {
    fn default() -> Self {
        Self {
            rel_tol: None,
            bound_rel: 0.01,
            max_halvings: 8,
            assign_control_nodes: false,
            box_check: Some(BoxCheckOptions {
                samples: 8,
                max_corners: 8,
                seed: 1,
                shrink_steps: 3,
                grow_steps: 1,
            }),
        }
    }
}

/// What the check of the box as a whole found at `case init` ([`crate::boxcheck`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BoxSummary {
    /// Samples evaluated in the whole box (corners and Latin hypercube).
    pub samples: usize,
    /// How many of them gave a valid grid.
    pub valid: usize,
    /// The common scale at which every sample passed (1: the whole box passed; 0: even the
    /// smallest box tried failed).
    pub scale: f64,
    /// Each variable's scale once grown back from the common one (its bounds in the case
    /// are multiplied by it).
    pub scales: Vec<(String, f64)>,
    /// The pairs of variables failing together, worst first: names and valid fraction.
    pub failing_together: Vec<(String, String, f64)>,
}

/// What `case init` found and wrote.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct InitReport {
    /// The tolerance sources considered.
    pub tolerances: Vec<Tolerance>,
    /// The tolerance used (the largest source, or the user's).
    pub tolerance: f64,
    /// Each marker's role.
    pub markers: Vec<MarkerRole>,
    /// The wall's classification.
    pub classify: surfgrid::ClassifyReport,
    /// Control nodes made because the geometry had none (0: it had its own).
    pub control_nodes_assigned: usize,
    /// What each part of the wall got (wing master, waist, bumps), in words.
    pub built: Vec<String>,
    /// The design variables with their checked bounds.
    pub variables: Vec<VariableCheck>,
    /// The case file written.
    pub case: PathBuf,
    /// Candidate variables left out, and why.
    pub notes: Vec<String>,
    /// The check of the box as a whole (`None`: not asked for).
    pub box_check: Option<BoxSummary>,
}

/// Makes the case in `dir` from `db` (whose CAD gave the tolerance sources `cad`) and the
/// volume grid `grid`; see the module doc.
pub fn init_case(
    db: &GeomDb,
    grid: &Mesh,
    cad: &[Tolerance],
    dir: &Path,
    opts: &InitOptions,
) -> Result<InitReport, InitError> {
    let with_nodes;
    let (db, control_nodes_assigned) = if !db.control_nodes.is_empty() {
        (db, 0)
    } else if opts.assign_control_nodes {
        let mut d = db.clone();
        d.assign_control_nodes()?;
        with_nodes = d;
        (&with_nodes, with_nodes.control_nodes.len())
    } else {
        return Err(InitError::NoControlNodes {
            surfaces: db.surfaces.len(),
        });
    };
    let lref = db.reference_length();
    let mut tolerances = vec![Tolerance {
        source: "default: 1e-6 of the model's reference length".into(),
        value: 1e-6 * lref,
    }];
    tolerances.extend_from_slice(cad);
    let tol = match opts.rel_tol {
        Some(r) => r * lref,
        None => tolerances.iter().map(|t| t.value).fold(0.0, f64::max),
    };
    let markers = roles::marker_roles(db, grid, tol)?;
    let of = |role: Role| -> Vec<String> {
        markers
            .iter()
            .filter(|m| m.role == role)
            .map(|m| m.marker.clone())
            .collect()
    };
    let (wall, slide, fixed) = (of(Role::Wall), of(Role::Slide), of(Role::Fixed));
    if wall.is_empty() {
        return Err(InitError::NoWall {
            tol,
            roles: markers,
        });
    }
    let copts = surfgrid::ClassifyOptions {
        rel_tol: tol / lref,
    };
    let (surface, classify) = surfgrid::classify_wall(db, grid, &wall, &copts)?;
    let volume = surface.volume_with_params(grid);
    // the default design space on the wall's surface components, dead variables left out
    let mut walls: Vec<usize> = surface.components.iter().map(|c| c.comp.index()).collect();
    walls.sort_unstable();
    walls.dedup();
    let wall_size = wall_diagonal(grid, &wall);
    let mut space = space::default_space(db, &walls, opts.bound_rel * wall_size);
    space::drop_dead(db, &mut space);
    if space.parametrisation.modifiers.is_empty() {
        return Err(InitError::NoVariables { notes: space.notes });
    }
    let geometry_path = dir.join("geometry.ron");
    let grid_path = dir.join("grid.msh");
    let case_path = dir.join("case.ron");
    write_atomic(&geometry_path, |w| db.write_ron(w))?;
    write_atomic(&grid_path, |w| {
        mesh::io::write(
            &volume,
            mesh::io::Format::Msh(mesh::msh::Encoding::Binary),
            w,
        )
    })?;
    let mut case = Case {
        format_version: CASE_FORMAT_VERSION,
        geometry: "geometry.ron".into(),
        parametrisation: space.parametrisation,
        grid: Some("grid.msh".into()),
        wall,
        slide,
        fixed,
        deform: Default::default(),
        surface_grid: crate::case::SurfaceGridSettings {
            classify_rel_tol: tol / lref,
            ..Default::default()
        },
        wing_masters: space.wing_masters,
        constraints: Vec::new(),
    };
    let study = Study::new(case.clone(), &case_path)?;
    let checked = bounds::check_bounds(&study, opts.max_halvings)?;
    drop(study);
    let variables = checked.kept;
    let mut space = space::Space {
        parametrisation: case.parametrisation,
        wing_masters: case.wing_masters,
        built: space.built,
        notes: space.notes,
    };
    let q0 = mesh::quality::cell_quality_at(grid, &grid.coords);
    let invalid = mesh::quality::summary(&q0).n_nonpositive;
    if invalid > 0 {
        let worst = mesh::quality::worst_cells(&grid.cells, &q0, 3);
        space.notes.push(format!(
            "the grid has {} invalid cells before any change (worst: {}); the checks count only \
             the cells a variable inverts",
            invalid,
            worst
                .iter()
                .map(ToString::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    let failed: Vec<String> = checked.failed.iter().map(|f| f.0.clone()).collect();
    space::leave_out(&mut space, &failed);
    space.notes.extend(
        checked
            .failed
            .into_iter()
            .map(|(_, why)| format!("left out: {why}")),
    );
    if space.parametrisation.modifiers.is_empty() {
        return Err(InitError::NoVariables { notes: space.notes });
    }
    case.parametrisation = space.parametrisation;
    case.wing_masters = space.wing_masters;
    for m in &mut case.parametrisation.modifiers {
        for v in space::variables_mut(m) {
            if let Some(c) = variables.iter().find(|c| c.name == v.name) {
                v.lower = -c.bound;
                v.upper = c.bound;
                v.scale = c.bound / 10.0;
            }
        }
    }
    let box_check = match &opts.box_check {
        Some(bo) => Some(check_box_together(&mut case, &case_path, bo)?),
        None => None,
    };
    if let Some(b) = box_check.as_ref().filter(|b| b.scale == 0.0) {
        space.notes.push(format!(
            "the variables together: {} of {} samples of the box gave a valid grid, and the \
             box still fails at {} of its size; the bounds are left as checked one by one \
             (run `aeroshape case check` on the case for the failing samples)",
            b.valid,
            b.samples,
            0.5f64.powi(opts.box_check.as_ref().map_or(0, |o| o.shrink_steps) as i32)
        ));
    }
    if let Some(b) = box_check
        .as_ref()
        .filter(|b| b.scale > 0.0 && b.scale < 1.0)
    {
        let shrunk: Vec<String> = b
            .scales
            .iter()
            .filter(|(_, s)| *s < 1.0)
            .map(|(n, s)| format!("{n} × {s}"))
            .collect();
        space.notes.push(format!(
            "the variables together: {} of {} samples of the box (corners and a Latin \
             hypercube) gave a valid grid; bounds multiplied so that all pass: {}{}",
            b.valid,
            b.samples,
            shrunk.join(", "),
            match b.failing_together.first() {
                Some((i, j, f)) => format!(
                    " (worst pair: {i} with {j}, {:.0} % valid far out in both)",
                    100.0 * f
                ),
                None => String::new(),
            }
        ));
    }
    let text = format!(
        "// Made by `aeroshape case init` (see docs/guide.md): markers by shape, wall tied to\n\
         // the geometry; per part of the wall a wing master (wing), the waist at the wing\n\
         // junction, nose droop and stretch (fuselage) or normal bumps (other parts), bounds\n\
         // checked by the study.\n{}\n",
        case.to_ron_string()
    );
    write_atomic(&case_path, |w| w.write_all(text.as_bytes()))?;
    Ok(InitReport {
        tolerances,
        tolerance: tol,
        markers,
        classify,
        control_nodes_assigned,
        built: space.built,
        variables,
        case: case_path,
        notes: space.notes,
        box_check,
    })
}

/// Checks the box of `case` (bounds already set variable by variable) as a whole and sets
/// each variable's bounds to those at which all samples pass ([`crate::boxcheck::BoxCheck::apply_bounds`]).
fn check_box_together(
    case: &mut Case,
    case_path: &Path,
    opts: &BoxCheckOptions,
) -> Result<BoxSummary, InitError> {
    let study = Study::new(case.clone(), case_path)?;
    let check = crate::boxcheck::check_box(&study, opts, &mut |_, _, _| {});
    let full = &check.rounds[0];
    let names = &check.pairs.names;
    let summary = BoxSummary {
        samples: full.results.len(),
        valid: full.results.iter().filter(|r| r.valid).count(),
        scale: check.scale,
        scales: names
            .iter()
            .cloned()
            .zip(check.scales.iter().copied())
            .collect(),
        failing_together: check
            .pairs
            .failing_together()
            .into_iter()
            .map(|(i, j, f)| (names[i].clone(), names[j].clone(), f))
            .collect(),
    };
    if check.scale > 0.0 && !check.whole_box() {
        check.apply_bounds(&study, case);
    }
    Ok(summary)
}

/// The diagonal of the box of the `wall` markers' nodes.
fn wall_diagonal(grid: &Mesh, wall: &[String]) -> f64 {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for m in wall.iter().filter_map(|w| grid.marker(w)) {
        for v in m.elements.node_set() {
            for k in 0..3 {
                lo[k] = lo[k].min(grid.coords[v as usize][k]);
                hi[k] = hi[k].max(grid.coords[v as usize][k]);
            }
        }
    }
    (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt()
}
