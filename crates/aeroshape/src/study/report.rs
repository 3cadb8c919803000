//! What a [`Study`](super::Study) reports: the timings and sizes of its set-up
//! ([`SetupReport`]) and, per evaluation, one record per phase ([`Report`]), serialised as
//! `report.json` by `aeroshape run`.

use serde::Serialize;

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
    /// The summary of a per-cell quality field.
    pub fn of(q: &[f64]) -> Self {
        mesh::quality::summary(q).into()
    }
}

impl From<mesh::quality::Summary> for Quality {
    fn from(s: mesh::quality::Summary) -> Self {
        Self {
            min: s.min,
            mean: s.mean,
            p1: s.p1,
            inverted: s.n_nonpositive,
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
    /// Largest sampled distance of a re-intersected junction from its defining surfaces
    /// (≥ 200 samples per arc, foot of the normal): the junction's real accuracy. None when
    /// no junction was re-intersected.
    pub curve_deviation: Option<f64>,
    /// The same relative to the model's reference length.
    pub curve_deviation_rel: Option<f64>,
    /// The tolerance of that distance (model units; 1e-8 of the model size by default).
    pub junction_tolerance: f64,
    /// Largest distance of an updated corner to a curve or surface defining it.
    pub corner_distance: Option<f64>,
    /// Per re-intersected junction: its sampled distance to each defining surface.
    pub junctions: Vec<JunctionFigures>,
}

impl ModelPhase {
    /// One line on the junctions' sampled accuracy, e.g. `junctions: 1 re-intersected,
    /// max distance 5.2e-8 (4.6e-9 of the model size) over 1601 samples, tolerance 1.1e-7;
    /// corners 3.1e-9; 0 re-fits`.
    pub fn junction_summary(&self) -> String {
        let samples: usize = self.junctions.iter().map(|j| j.samples).sum();
        let refits: usize = self.junctions.iter().map(|j| j.refits).sum();
        let corner = self
            .corner_distance
            .map_or("no corner updated".to_string(), |d| {
                format!("corners {d:.2e}")
            });
        match self.curve_deviation {
            Some(d) => format!(
                "junctions: {} re-intersected, max distance to their surfaces {d:.2e} ({:.2e} of the model size) over {samples} samples, tolerance {:.2e}; {corner}; {refits} re-fits",
                self.junctions.len(),
                self.curve_deviation_rel.unwrap_or(f64::NAN),
                self.junction_tolerance
            ),
            None => format!("junctions: none re-intersected; {corner}"),
        }
    }
}

/// The sampled accuracy of one re-intersected junction (`report.json`).
#[derive(Debug, Clone, Serialize)]
pub struct JunctionFigures {
    /// The curve's label (`curve N (name)`).
    pub curve: String,
    /// Samples measured.
    pub samples: usize,
    /// Largest distance to surface 1 and to surface 2.
    pub max: [f64; 2],
    /// Root mean square distance to surface 1 and to surface 2.
    pub rms: [f64; 2],
    /// Curve parameter where each maximum occurs.
    pub at_t: [f64; 2],
    /// The larger maximum before the adaptive re-fit.
    pub max_before_refit: f64,
    /// Re-fit rounds (arc degrees raised).
    pub refits: usize,
    /// Arc degrees after the update.
    pub degrees: Vec<usize>,
}

impl JunctionFigures {
    /// The figures of one curve of the update's report; None when it was not measured.
    fn of(c: &intersect::update::CurveReport) -> Option<Self> {
        let a = c.accuracy.as_ref()?;
        Some(Self {
            curve: c.label.clone(),
            samples: a.samples,
            max: [a.surfaces[0].max, a.surfaces[1].max],
            rms: [a.surfaces[0].rms, a.surfaces[1].rms],
            at_t: [a.surfaces[0].at_t, a.surfaces[1].at_t],
            max_before_refit: c.deviation_before_refit.unwrap_or(f64::NAN),
            refits: c.refits,
            degrees: c.degrees.clone(),
        })
    }
}

impl ModelPhase {
    /// The figures of a model update (`intersect`'s report) that took `seconds`; `lref` is the
    /// model's reference length. The one place that turns the update's report into the
    /// study's: a new figure of the update goes here.
    pub fn from_update(r: &intersect::update::UpdateReport, lref: f64, seconds: f64) -> Self {
        Self {
            seconds,
            surfaces_changed: r.surfaces_changed.len(),
            curves_reintersected: r.curves.iter().filter(|c| c.reintersected).count(),
            corners_updated: r.corners.iter().filter(|c| c.updated).count(),
            junction_residual: r.max_curve_residual,
            junction_residual_rel: r.max_curve_residual / lref,
            corner_residual: r.max_corner_residual,
            curve_deviation: r.max_deviation,
            curve_deviation_rel: r.max_deviation.map(|d| d / lref),
            junction_tolerance: r.junction_tolerance,
            corner_distance: r.max_corner_distance,
            junctions: r.curves.iter().filter_map(JunctionFigures::of).collect(),
        }
    }
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

impl SurfacePhase {
    /// The figures of a surface-grid update (`surfgrid`'s report) that took `seconds`.
    pub fn from_update(r: &surfgrid::UpdateReport, seconds: f64) -> Self {
        Self {
            seconds,
            moved_nodes: r.moved_nodes,
            max_displacement: r.max_displacement,
            remapped_components: r.components.iter().filter(|c| c.remapped).count(),
            worst_triangle: r
                .components
                .iter()
                .map(|c| c.worst_after)
                .fold(f64::INFINITY, f64::min),
        }
    }
}

/// Time of the volume deformation and `deform`'s own report.
#[derive(Debug, Clone, Serialize)]
pub struct DeformPhase {
    /// Seconds.
    pub seconds: f64,
    /// Skipped: no wall node moved, so the zero displacement is the solution and the
    /// baseline grid is returned.
    pub skipped: bool,
    /// What the deformation did (iterations, residual, increments, unknowns, sliding nodes,
    /// quality, solver notes: [`deform::DeformReport`]); `None` when skipped.
    pub report: Option<deform::DeformReport>,
}

impl DeformPhase {
    /// Linear-solver iterations (Eq. 21, all increments); 0 when skipped.
    pub fn iterations(&self) -> usize {
        self.report.as_ref().map_or(0, |r| r.iterations)
    }

    /// Rotation (R, Eq. 26) iterations; 0 when skipped.
    pub fn rotation_iterations(&self) -> usize {
        self.report.as_ref().map_or(0, |r| r.rotation_iterations)
    }
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
    /// Largest displacement of a far-field node: at least the wall's bounding-box diagonal
    /// from the wall along grid edges ([`deform::FarField`], in `deform.report.far_field`
    /// with its distance and node); 0 when the deformation was skipped.
    pub far_field_max_displacement: f64,
}

/// Timings and sizes of [`Study::new`](super::Study::new).
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
    /// Nodes of the grid.
    pub nodes: usize,
    /// Cells.
    pub cells: usize,
    /// Wall nodes.
    pub wall_nodes: usize,
    /// Seconds building the volume deformation set-up ([`deform::Deformer`]).
    pub deform: f64,
}
