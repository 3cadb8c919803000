//! [`Study::evaluate_with_progress`] as named stages over typed intermediate results:
//! param (control nodes), model update (geometry), surface grid (wall nodes on the new
//! geometry), volume deformation (grid), then the deformed grid's classification and the
//! wall check.

use std::sync::{Arc, PoisonError};
use std::time::Instant;

use geom_db::GeomDb;
use geom_db::prelude::Point3;
use mesh::Mesh;
use rayon::prelude::*;
use surfgrid::SurfaceGrid;

use super::error::Result;
use super::report::{DeformPhase, ModelPhase, ParamPhase, Quality, Report, SurfacePhase};
use super::{EvaluatedAt, Evaluation, Study};

/// Stage 4's result (`None` when no wall node moved: the baseline grid is the solution).
struct Volume {
    deformed: Option<Moved>,
    phase: DeformPhase,
}

/// A deformation's outcome: the node coordinates, the cell quality and its summary, and the
/// deformation's result (coordinates and quality taken out).
struct Moved {
    coords: Vec<[f64; 3]>,
    quality: Vec<f64>,
    summary: Quality,
    result: Arc<deform::Deformed>,
}

impl Study {
    /// [`Study::evaluate`], calling `progress(phase)` as each phase starts (`param`,
    /// `model update`, `surface grid`, `deform`).
    pub fn evaluate_with_progress(
        &self,
        x: &[f64],
        progress: &mut dyn FnMut(&str),
    ) -> Result<Evaluation> {
        let t_all = Instant::now();
        check_length(&self.prepared, x)?;
        progress("param");
        let (points, param) = self.move_control_nodes(x)?;
        progress("model update");
        let (geometry, model) = self.update_model(&points)?;
        progress("surface grid");
        let (surface, surface_phase, record) = self.update_surface(&geometry)?;
        progress("deform");
        let volume = self.deform_volume(&surface)?;
        let mut grid = self.grid.clone();
        let (cell_quality, quality_after, deformed) = match volume.deformed {
            Some(m) => {
                grid.coords = m.coords;
                (m.quality, m.summary, Some(m.result))
            }
            None => (self.quality.clone(), self.quality_before, None),
        };
        surface.write_params(&mut grid);
        let wall_support_rel = self.wall_support(&geometry, &surface, &grid);
        let far_field_max_displacement = volume
            .phase
            .report
            .as_ref()
            .map_or(0.0, |r| r.far_field.max_displacement);
        let report = Report {
            far_field_max_displacement,
            design: self
                .prepared
                .registry()
                .names()
                .iter()
                .zip(x)
                .map(|(n, v)| (n.to_string(), *v))
                .collect(),
            param,
            model,
            surface: surface_phase,
            deform: volume.phase,
            seconds: t_all.elapsed().as_secs_f64(),
            quality_before: self.quality_before,
            quality_after,
            wall_support_rel,
        };
        // Kept for a linearisation at the same x (`Study::linearise`).
        *self.recent.lock().unwrap_or_else(PoisonError::into_inner) = Some(Arc::new(EvaluatedAt {
            x: x.to_vec(),
            geometry: geometry.clone(),
            surface: surface.clone(),
            record,
            deformed,
            coords: grid.coords.clone(),
        }));
        Ok(Evaluation {
            geometry,
            grid,
            surface,
            cell_quality,
            report,
        })
    }

    /// Stage 1 (§5): the control nodes moved by the design vector.
    fn move_control_nodes(&self, x: &[f64]) -> Result<(Vec<Point3>, ParamPhase)> {
        param_phase(&self.prepared, &self.db, x)
    }

    /// Stage 2 (§3.1–3.2): surfaces re-solved, curves and corners re-intersected.
    fn update_model(&self, points: &[Point3]) -> Result<(GeomDb, ModelPhase)> {
        let t = Instant::now();
        let (geometry, r) = self.model.update(points)?;
        let phase =
            ModelPhase::from_update(&r, self.db.reference_length(), t.elapsed().as_secs_f64());
        Ok((geometry, phase))
    }

    /// Stage 3 (§3.3): the wall nodes at their frozen parameters on the new geometry, and
    /// what the update's linearisation needs of it.
    fn update_surface(
        &self,
        geometry: &GeomDb,
    ) -> Result<(SurfaceGrid, SurfacePhase, surfgrid::UpdateRecord)> {
        let t = Instant::now();
        let (surface, r, record) = self.surface_updater.update_recorded(
            &self.surface,
            &self.db,
            geometry,
            &self.case.surface_grid.update_options(),
        )?;
        Ok((
            surface,
            SurfacePhase::from_update(&r, t.elapsed().as_secs_f64()),
            record,
        ))
    }

    /// Stages 2 and 3 without their reports, for the control nodes `points`: the updated
    /// geometry, the wall grid on it with its update record, and the prescribed positions of
    /// stage 4 ([`Study::prescribed`]).
    pub(super) fn wall_positions(
        &self,
        points: &[Point3],
    ) -> Result<(GeomDb, SurfaceGrid, surfgrid::UpdateRecord, Vec<[f64; 3]>)> {
        let (geometry, _) = self.model.update(points)?;
        let (surface, _, record) = self.surface_updater.update_recorded(
            &self.surface,
            &self.db,
            &geometry,
            &self.case.surface_grid.update_options(),
        )?;
        let (positions, _) = self.prescribed(&surface);
        Ok((geometry, surface, record, positions))
    }

    /// The prescribed positions of the volume deformation for the wall grid `surface`, in
    /// the order of the set-up's boundary conditions (`setup::deform_bc`): the wall nodes at
    /// their new place on the geometry, then the nodes of `fixed` markers where they are;
    /// and whether a wall node moved.
    pub(super) fn prescribed(&self, surface: &SurfaceGrid) -> (Vec<[f64; 3]>, bool) {
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
        (positions, any)
    }

    /// Stage 4 (§4): the volume grid deformed with the wall nodes prescribed at their new
    /// positions and the fixed nodes where they are; skipped when no wall node moved.
    fn deform_volume(&self, surface: &SurfaceGrid) -> Result<Volume> {
        let t = Instant::now();
        let (positions, any) = self.prescribed(surface);
        if !any {
            // The solution is Δx = 0: the next evaluation starts cold.
            *self.last.lock().unwrap_or_else(PoisonError::into_inner) = None;
            return Ok(Volume {
                deformed: None,
                phase: DeformPhase {
                    seconds: t.elapsed().as_secs_f64(),
                    skipped: true,
                    report: None,
                },
            });
        }
        let warm_start = self.case.deform.warm_start;
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
        let mut d = self.deformer.deform_to(&positions, warm.as_deref())?;
        let coords = std::mem::take(&mut d.coords);
        let quality = std::mem::take(&mut d.cell_quality);
        let summary = Quality::from(d.report.quality_after);
        let phase = DeformPhase {
            seconds: t.elapsed().as_secs_f64(),
            skipped: false,
            report: Some(d.report.clone()),
        };
        // Kept for its solver state only (coordinates and quality taken above): the warm
        // start of the next evaluation, and the linearisation at x.
        let d = Arc::new(d);
        if warm_start {
            *self.last.lock().unwrap_or_else(PoisonError::into_inner) = Some(d.clone());
        }
        Ok(Volume {
            deformed: Some(Moved {
                coords,
                quality,
                summary,
                result: d,
            }),
            phase,
        })
    }

    /// The largest distance of a wall node of `grid` from its support evaluated anew on
    /// `geometry`, relative to the reference length (in parallel; a maximum does not depend
    /// on the order).
    fn wall_support(&self, geometry: &GeomDb, surface: &SurfaceGrid, grid: &Mesh) -> f64 {
        let lref = self.db.reference_length();
        self.wall
            .par_iter()
            .enumerate()
            .with_min_len(256)
            .filter(|(_, w)| **w)
            .map(|(i, _)| {
                let e = surface.evaluate_node(geometry, i);
                let p = grid.coords[i];
                (Point3::new(p[0], p[1], p[2]) - e).norm() / lref
            })
            .reduce(|| 0.0, f64::max)
    }
}

/// `Ok` when `x` holds one value per design variable of `prepared`, otherwise the error
/// saying how many it needs.
pub(super) fn check_length(prepared: &param::Prepared, x: &[f64]) -> Result<()> {
    let n = prepared.registry().len();
    if x.len() != n {
        return Err(param::Error::VectorLength {
            expected: n,
            found: x.len(),
        }
        .into());
    }
    Ok(())
}

/// Stage 1 (§5): the control points of `db` moved by `prepared` at `x`, with the phase's
/// figures (nodes moved, largest move, seconds).
pub(super) fn param_phase(
    prepared: &param::Prepared,
    db: &GeomDb,
    x: &[f64],
) -> Result<(Vec<Point3>, ParamPhase)> {
    let t = Instant::now();
    let pts = prepared.apply(x)?;
    let base = db.control_points();
    let nodes_moved = pts.iter().zip(base).filter(|(p, q)| p != q).count();
    let max_move = pts
        .iter()
        .zip(base)
        .map(|(p, q)| (p - q).norm())
        .fold(0.0, f64::max);
    let phase = ParamPhase {
        seconds: t.elapsed().as_secs_f64(),
        nodes_moved,
        max_move,
    };
    Ok((pts, phase))
}
