//! [`DistributedStudy`] (cargo feature `mpi`): the [`Study`](super::Study) over the ranks of
//! an MPI job. The geometry phases run on every rank (they are small and deterministic, so
//! every rank finds the same wall displacements); the grid lives on rank 0 and the volume
//! deformation runs distributed (`deform::distributed::Deformer::from_root`: the partition
//! made on rank 0, the serial boundary conditions), its result gathered on rank 0.
//!
//! Set-up ([`DistributedStudy::new`], collective):
//! 1. every rank reads the case and the geometry, binds the parametrisation and seeds the
//!    model update;
//! 2. rank 0 reads the grid and checks the case's markers in it, as the serial study does,
//!    and sends every rank the wall: the nodes of the `wall` markers (ascending grid
//!    numbers) with their coordinates and the markers' elements;
//! 3. every rank ties that wall to the geometry (`surfgrid::classify_wall` on the wall
//!    alone, numbered as [`DistributedStudy::wall_nodes`]); rank 0 finds the nodes held
//!    fixed as the serial set-up does.
//!
//! Evaluation ([`DistributedStudy::evaluate`], collective): param, model update and surface
//! grid on every rank; then the deformation with the wall nodes' displacements (and the
//! slide and fixed markers) of the serial study; the grid gathered on rank 0, the wall
//! nodes put exactly at their new places on the geometry. The distributed set-up (the
//! partition made on rank 0 and scattered, the nodes' roles, the unknowns and halos) is
//! made at the first evaluation and kept: the next ones pass their wall displacements to
//! it (`Deformer::deform_with`) as long as rank 0's list of prescribed nodes is the same,
//! and make it anew when it is not. With `deform.warm_start` (the case's default), the
//! solves of a deformation on the kept set-up start from the previous one's solutions
//! (`Deformer::deform_from`), as the serial study's do; otherwise from the baseline, bit for
//! bit the history-independent answer.
//!
//! Every fallible step ends with the ranks agreeing on its outcome: an error on one rank is
//! returned on every rank with the same text ([`StudyError::Distributed`] on the others)
//! before any other exchange, so nothing hangs.

use std::cell::RefCell;
use std::path::{Path, PathBuf};
use std::time::Instant;

use deform::distributed::{Comm, Deformer, DistDeformed, DistReport, mpi};
use geom_db::GeomDb;
use geom_db::prelude::Point3;
use mesh::{ALL_KINDS, Elements, Marker, Mesh};
use mpi::collective::SystemOperation;
use mpi::traits::*;
use param::Prepared;
use surfgrid::{ClassifyOptions, NodeSupport, SurfaceGrid};

use super::error::{Result, StudyError};
use super::report::{
    DeformPhase, ModelPhase, ParamPhase, Quality, Report, SetupReport, SurfacePhase,
};
use crate::case::Case;

/// What rank 0 holds besides the other ranks' share: the whole grid.
struct RootPart {
    grid: Mesh,
    /// Nodes of `fixed` markers (and unnamed ones touching a sliding marker) that are not
    /// wall nodes; sorted (the serial set-up's `fixed_nodes`).
    fixed_nodes: Vec<u32>,
    /// Baseline cell quality.
    quality: Vec<f64>,
}

/// The study over the ranks of a communicator; see the module doc.
pub struct DistributedStudy<'c> {
    comm: &'c Comm,
    case: Case,
    grid_path: PathBuf,
    db: GeomDb,
    model: intersect::update::ModelBaseline,
    prepared: Prepared,
    /// The wall grid tied to the geometry, numbered as `wall_nodes`.
    surface: SurfaceGrid,
    surface_updater: surfgrid::Updater,
    /// The grid node of each wall-grid node (ascending).
    wall_nodes: Vec<u32>,
    root: Option<RootPart>,
    quality_before: Quality,
    coarse_parts: usize,
    setup: SetupReport,
    /// The distributed set-up of the last evaluation and, on rank 0, the grid nodes of its
    /// prescribed displacements, in order (empty on the other ranks).
    deformer: RefCell<Option<(Vec<u32>, Deformer<'c>)>>,
    /// This rank's result of the last deformation on that set-up, kept for the warm start
    /// of the next (with `deform.warm_start`).
    last: RefCell<Option<DistDeformed>>,
}

/// The result of [`DistributedStudy::evaluate`].
#[derive(Debug, Clone)]
pub struct DistEvaluation {
    /// The updated geometric database (every rank).
    pub geometry: GeomDb,
    /// The updated wall grid, numbered as [`DistributedStudy::wall_nodes`] (every rank).
    pub surface: SurfaceGrid,
    /// The distributed deformation's report (every rank; `None` when no wall node moved).
    pub distributed: Option<DistReport>,
    /// The deformed grid, its cell quality and the report (rank 0).
    pub root: Option<RootEvaluation>,
}

/// Rank 0's part of a [`DistEvaluation`].
#[derive(Debug, Clone)]
pub struct RootEvaluation {
    /// The deformed grid (the baseline's cells and markers, the wall nodes' updated
    /// parameters, new coordinates).
    pub grid: Mesh,
    /// Cell quality of the deformed grid (DESIGN measure).
    pub cell_quality: Vec<f64>,
    /// The report, as the serial study's; `deform.report` is `None` (the distributed
    /// deformation's report is [`DistEvaluation::distributed`]) and the far-field
    /// displacement is not measured (NaN).
    pub report: Report,
}

/// `local` on every rank when it is `Ok` on every rank; otherwise the lowest failing rank's
/// error there and the same text as [`StudyError::Distributed`] elsewhere (collective).
fn agree<T>(comm: &Comm, local: Result<T>) -> Result<T> {
    match deform::distributed::first_failure(comm, &local, |e| e.to_string()) {
        Some((rank, reason)) if rank != comm.rank() => {
            Err(StudyError::Distributed { rank, reason })
        }
        _ => local,
    }
}

/// Broadcasts rank 0's vector (its length first); collective.
fn broadcast<T: Equivalence + Default + Clone>(comm: &Comm, v: &mut Vec<T>) {
    let root = comm.process_at_rank(0);
    let mut len = v.len() as u64;
    root.broadcast_into(&mut len);
    v.resize(len as usize, T::default());
    root.broadcast_into(&mut v[..]);
}

/// The wall of `grid` as sent to every rank: `[dim, nodes, cells, n_wall, wall nodes…,
/// then per wall marker: groups, then per group: kind, length, nodes (wall numbering)…]`
/// and the wall nodes' coordinates.
fn encode_wall(grid: &Mesh, wall: &[String]) -> (Vec<u64>, Vec<f64>) {
    let markers: Vec<&Marker> = wall.iter().filter_map(|m| grid.marker(m)).collect();
    let mut nodes: Vec<u32> = markers.iter().flat_map(|m| m.elements.node_set()).collect();
    nodes.sort_unstable();
    nodes.dedup();
    let mut local = vec![u32::MAX; grid.n_nodes()];
    for (k, &v) in nodes.iter().enumerate() {
        local[v as usize] = k as u32;
    }
    let mut ints = vec![
        u64::from(grid.dim),
        grid.n_nodes() as u64,
        grid.cells.len() as u64,
        nodes.len() as u64,
    ];
    ints.extend(nodes.iter().map(|&v| u64::from(v)));
    for m in &markers {
        ints.push(m.elements.groups().len() as u64);
        for g in m.elements.groups() {
            let kind = ALL_KINDS.iter().position(|&k| k == g.kind).unwrap_or(0);
            ints.push(kind as u64);
            ints.push(g.nodes.len() as u64);
            ints.extend(g.nodes.iter().map(|&v| u64::from(local[v as usize])));
        }
    }
    let floats = nodes
        .iter()
        .flat_map(|&v| grid.coords[v as usize])
        .collect();
    (ints, floats)
}

/// The wall mesh of [`encode_wall`]'s arrays (markers named as `wall`), the wall nodes'
/// grid numbers and the grid's node and cell counts.
fn decode_wall(ints: &[u64], floats: &[f64], wall: &[String]) -> (Mesh, Vec<u32>, [usize; 2]) {
    let mut it = ints.iter().map(|&v| v as usize);
    let mut next = || it.next().unwrap_or(0);
    let dim = next() as u8;
    let counts = [next(), next()];
    let n = next();
    let nodes: Vec<u32> = (0..n).map(|_| next() as u32).collect();
    let mut m = Mesh::new(dim);
    m.coords = floats.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    for name in wall {
        let mut elements = Elements::new();
        for _ in 0..next() {
            let kind = ALL_KINDS[next().min(ALL_KINDS.len() - 1)];
            let conn: Vec<u32> = (0..next()).map(|_| next() as u32).collect();
            for e in conn.chunks_exact(kind.n_nodes()) {
                elements.push(kind, e, None);
            }
        }
        m.markers.push(Marker {
            name: name.clone(),
            tag: None,
            elements,
        });
    }
    (m, nodes, counts)
}

impl<'c> DistributedStudy<'c> {
    /// Reads the case file (on every rank) and builds the study (collective).
    pub fn load(comm: &'c Comm, case_path: &Path) -> Result<Self> {
        let case = agree(comm, Case::load(case_path).map_err(StudyError::from))?;
        Self::new(comm, case, case_path)
    }

    /// Builds the study from a case on every rank (the same case everywhere; the grid is
    /// read on rank 0 only); see the module doc. Collective.
    pub fn new(comm: &'c Comm, case: Case, case_path: &Path) -> Result<Self> {
        let t = Instant::now();
        let geometry_path = case.geometry_path(case_path);
        let db = agree(
            comm,
            std::fs::read_to_string(&geometry_path)
                .map_err(|source| StudyError::Read {
                    path: geometry_path.clone(),
                    source,
                })
                .and_then(|text| {
                    Ok(GeomDb::from_ron_str(
                        &text,
                        &geometry_path.display().to_string(),
                    )?)
                }),
        )?;
        let root = comm.rank() == 0;
        let read = (root).then(|| super::setup::read_grid(&case, case_path));
        let read = agree(comm, read.transpose())?;
        let (mut ints, mut floats) = match &read {
            Some((grid, ..)) => encode_wall(grid, &case.wall),
            None => (Vec::new(), Vec::new()),
        };
        broadcast(comm, &mut ints);
        broadcast(comm, &mut floats);
        let (wall_mesh, wall_nodes, [nodes, cells]) = decode_wall(&ints, &floats, &case.wall);
        let t_read = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let prepared = agree(
            comm,
            super::setup::bind_parametrisation(&case, case_path, &db),
        )?;
        let t_param = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let model = agree(
            comm,
            intersect::update::ModelBaseline::new(
                &db,
                &intersect::update::UpdateOptions::default(),
            )
            .map_err(|source| StudyError::ModelSeeds {
                geometry: geometry_path.clone(),
                source: Box::new(source),
            }),
        )?;
        let t_model = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let grid_path = case.grid_path(case_path).unwrap_or_default();
        let copts = ClassifyOptions {
            rel_tol: case.surface_grid.classify_rel_tol,
        };
        let (surface, report) = agree(
            comm,
            surfgrid::classify_wall(&db, &wall_mesh, &case.wall, &copts).map_err(|source| {
                StudyError::Classify {
                    grid: grid_path.clone(),
                    source: Box::new(source),
                }
            }),
        )?;
        let t_classify = t.elapsed().as_secs_f64();
        let on_wall: Vec<bool> = surface
            .support
            .iter()
            .map(|s| !matches!(s, NodeSupport::Free))
            .collect();
        let root = read.map(|(grid, _, quality)| {
            let mut wall = vec![false; grid.n_nodes()];
            for (&v, &w) in wall_nodes.iter().zip(&on_wall) {
                wall[v as usize] = w;
            }
            let mut fixed_nodes: Vec<u32> = case
                .fixed
                .iter()
                .filter_map(|m| grid.marker(m))
                .flat_map(|m| m.elements.node_set())
                .chain(crate::precedence::held_nodes(
                    &grid,
                    &case.wall,
                    &case.slide,
                ))
                .filter(|&v| !wall[v as usize])
                .collect();
            fixed_nodes.sort_unstable();
            fixed_nodes.dedup();
            RootPart {
                grid,
                fixed_nodes,
                quality,
            }
        });
        // Rank 0's baseline quality summary, for every rank's report.
        let mut q = root.as_ref().map_or([0.0; 5], |r| {
            let s = Quality::of(&r.quality);
            [s.min, s.mean, s.p1, s.inverted as f64, s.cells as f64]
        });
        comm.process_at_rank(0).broadcast_into(&mut q[..]);
        let quality_before = Quality {
            min: q[0],
            mean: q[1],
            p1: q[2],
            inverted: q[3] as usize,
            cells: q[4] as usize,
        };
        let setup = SetupReport {
            read: t_read,
            param: t_param,
            model: t_model,
            classify: t_classify,
            classify_max_distance: report.max_distance,
            nodes,
            cells,
            wall_nodes: on_wall.iter().filter(|w| **w).count(),
            deform: 0.0,
        };
        Ok(Self {
            comm,
            grid_path,
            db,
            model,
            prepared,
            surface_updater: surfgrid::Updater::new(&surface),
            surface,
            wall_nodes,
            root,
            quality_before,
            coarse_parts: deform::distributed::COARSE_PARTS,
            deformer: RefCell::new(None),
            last: RefCell::new(None),
            setup,
            case,
        })
    }

    /// Sets the aggregates per rank of the distributed deformation's coarse-grid correction
    /// (`deform::distributed::Deformer::coarse_parts`).
    pub fn coarse_parts(mut self, parts: usize) -> Self {
        self.coarse_parts = parts;
        self
    }

    /// The case.
    pub fn case(&self) -> &Case {
        &self.case
    }

    /// The baseline geometric database.
    pub fn geometry(&self) -> &GeomDb {
        &self.db
    }

    /// The baseline grid (rank 0).
    pub fn baseline(&self) -> Option<&Mesh> {
        self.root.as_ref().map(|r| &r.grid)
    }

    /// Baseline cell quality (rank 0).
    pub fn baseline_quality(&self) -> Option<&[f64]> {
        self.root.as_ref().map(|r| r.quality.as_slice())
    }

    /// The baseline wall grid tied to the geometry, numbered as [`Self::wall_nodes`].
    pub fn baseline_surface(&self) -> &SurfaceGrid {
        &self.surface
    }

    /// The grid node of each node of the wall grid (ascending).
    pub fn wall_nodes(&self) -> &[u32] {
        &self.wall_nodes
    }

    /// Timings and sizes of the set-up (the grid's sizes from rank 0).
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

    /// A design vector from named values; unnamed variables keep their initial value.
    pub fn vector_from_values(&self, values: &param::DesignValues) -> Result<Vec<f64>> {
        Ok(self.prepared.registry().vector_from_values(values)?)
    }

    /// The geometry phases (param, model update, surface grid) for `x`, on this rank.
    fn geometry_phases(
        &self,
        x: &[f64],
        progress: &mut dyn FnMut(&str),
    ) -> Result<(GeomDb, SurfaceGrid, ParamPhase, ModelPhase, SurfacePhase)> {
        super::evaluate::check_length(&self.prepared, x)?;
        progress("param");
        let (pts, param) = super::evaluate::param_phase(&self.prepared, &self.db, x)?;
        progress("model update");
        let t = Instant::now();
        let (geometry, r) = self.model.update(&pts)?;
        let model =
            ModelPhase::from_update(&r, self.db.reference_length(), t.elapsed().as_secs_f64());
        progress("surface grid");
        let t = Instant::now();
        let (surface, r) = self.surface_updater.update(
            &self.surface,
            &self.db,
            &geometry,
            &self.case.surface_grid.update_options(),
        )?;
        let phase = SurfacePhase::from_update(&r, t.elapsed().as_secs_f64());
        Ok((geometry, surface, param, model, phase))
    }

    /// Makes the next evaluation start its solves from the baseline (see the module doc).
    /// Local: every rank calls it, or the ranks' next deformation fails on every rank.
    pub fn forget_warm_start(&self) {
        *self.last.borrow_mut() = None;
    }

    /// Runs the chain for the design vector `x` on every rank (collective); see the module
    /// doc. `progress(phase)` is called as each phase starts (`param`, `model update`,
    /// `surface grid`, `deform`).
    pub fn evaluate(&self, x: &[f64], progress: &mut dyn FnMut(&str)) -> Result<DistEvaluation> {
        let t_all = Instant::now();
        let comm = self.comm;
        let (geometry, surface, param, model, surface_phase) =
            agree(comm, self.geometry_phases(x, progress))?;
        progress("deform");
        let t = Instant::now();
        let moved = surface
            .coords
            .iter()
            .zip(&self.surface.coords)
            .any(|(p, p0)| p != p0);
        let mut any = u8::from(moved);
        comm.all_reduce_into(&u8::from(moved), &mut any, SystemOperation::max());
        let distributed = if any > 0 {
            Some(self.deform(&surface)?)
        } else {
            None
        };
        let deform_seconds = t.elapsed().as_secs_f64();
        let root = match (&self.root, &distributed) {
            (None, _) => None,
            (Some(r), d) => {
                let mut grid = r.grid.clone();
                let cell_quality = match d {
                    Some((_, Some(coords))) => {
                        grid.coords.clone_from(coords);
                        for (k, &v) in self.wall_nodes.iter().enumerate() {
                            if !matches!(surface.support[k], NodeSupport::Free) {
                                let p = surface.coords[k];
                                grid.coords[v as usize] = [p.x, p.y, p.z];
                            }
                        }
                        mesh::quality::cell_quality(&grid)
                    }
                    _ => r.quality.clone(),
                };
                self.write_params(&surface, &mut grid);
                let report = Report {
                    design: self
                        .registry()
                        .names()
                        .iter()
                        .zip(x)
                        .map(|(n, v)| (n.to_string(), *v))
                        .collect(),
                    param,
                    model,
                    surface: surface_phase,
                    deform: DeformPhase {
                        seconds: deform_seconds,
                        skipped: d.is_none(),
                        report: None,
                    },
                    seconds: t_all.elapsed().as_secs_f64(),
                    quality_before: self.quality_before,
                    quality_after: Quality::of(&cell_quality),
                    wall_support_rel: self.wall_support(&geometry, &surface, &grid),
                    far_field_max_displacement: match d {
                        Some((rep, _)) => rep.far_field.map_or(f64::NAN, |f| f.max_displacement),
                        None => 0.0,
                    },
                };
                Some(RootEvaluation {
                    grid,
                    cell_quality,
                    report,
                })
            }
        };
        Ok(DistEvaluation {
            geometry,
            surface,
            distributed: distributed.map(|d| d.0),
            root,
        })
    }

    /// The distributed deformation to the wall grid `surface` (collective): its report and,
    /// on rank 0, the gathered coordinates.
    fn deform(&self, surface: &SurfaceGrid) -> Result<(DistReport, Option<Vec<[f64; 3]>>)> {
        let comm = self.comm;
        let bc = self.root.as_ref().map(|r| {
            let x0 = &r.grid.coords;
            let mut displacements: Vec<(u32, [f64; 3])> = self
                .wall_nodes
                .iter()
                .enumerate()
                .filter(|(k, _)| !matches!(surface.support[*k], NodeSupport::Free))
                .map(|(k, &v)| {
                    let (p, q) = (surface.coords[k], x0[v as usize]);
                    (v, [p.x - q[0], p.y - q[1], p.z - q[2]])
                })
                .collect();
            displacements.extend(r.fixed_nodes.iter().map(|&v| (v, [0.0; 3])));
            super::setup::deform_markers(&self.case, displacements)
        });
        let nodes: Vec<u32> = bc
            .as_ref()
            .map(|bc| bc.displacements.iter().map(|d| d.0).collect())
            .unwrap_or_default();
        let mut kept = self.deformer.borrow_mut();
        // Rank 0 decides: the kept set-up serves when its prescribed nodes are these.
        let mut same = u8::from(kept.as_ref().is_some_and(|k| k.0 == nodes));
        comm.process_at_rank(0).broadcast_into(&mut same);
        let mut last = self.last.borrow_mut();
        let d = match kept.take() {
            Some((nodes, d)) if same > 0 => (nodes, d),
            _ => {
                *last = None;
                let whole = self
                    .root
                    .as_ref()
                    .zip(bc.as_ref())
                    .map(|(r, bc)| (&r.grid, bc));
                let opts = self.case.deform.options();
                let d = Deformer::from_root(comm, whole, &opts)
                    .map_err(|source| StudyError::DeformSetup {
                        grid: self.grid_path.clone(),
                        source: Box::new(source),
                    })?
                    .coarse_parts(self.coarse_parts);
                (nodes, d)
            }
        };
        let values: Option<Vec<[f64; 3]>> =
            bc.map(|bc| bc.displacements.iter().map(|d| d.1).collect());
        // A failed deformation (agreed on every rank) keeps the set-up for the next design.
        let warm = self.case.deform.warm_start;
        let out =
            d.1.deform_from(values.as_deref(), last.as_ref().filter(|_| warm));
        let out = out.map(|out| {
            let gathered = d.1.gather(&out.coords);
            let report = out.report.clone();
            *last = warm.then_some(out);
            (report, gathered)
        });
        *kept = Some(d);
        Ok(out?)
    }

    /// The wall nodes' updated parameters written into `grid`'s node classification, as
    /// `SurfaceGrid::write_params` does for a grid-numbered wall grid.
    fn write_params(&self, surface: &SurfaceGrid, grid: &mut Mesh) {
        if let (Some(cls), true) = (grid.classes.as_mut(), grid.parametric) {
            for (&v, s) in self.wall_nodes.iter().zip(&surface.support) {
                let c = &mut cls[v as usize];
                match *s {
                    NodeSupport::Curve { t, .. } if c.dim == 1 => c.param = [t, 0.0],
                    NodeSupport::Surface { uv, .. } if c.dim == 2 => c.param = uv,
                    _ => {}
                }
            }
        }
    }

    /// The largest distance of a wall node of `grid` from its support evaluated anew on
    /// `geometry`, relative to the reference length.
    fn wall_support(&self, geometry: &GeomDb, surface: &SurfaceGrid, grid: &Mesh) -> f64 {
        let lref = self.db.reference_length();
        self.wall_nodes
            .iter()
            .enumerate()
            .filter(|(k, _)| !matches!(surface.support[*k], NodeSupport::Free))
            .map(|(k, &v)| {
                let e = surface.evaluate_node(geometry, k);
                let p = grid.coords[v as usize];
                (Point3::new(p[0], p[1], p[2]) - e).norm() / lref
            })
            .fold(0.0, f64::max)
    }
}
