//! The case file (`CASE.ron`, see `docs/formats/case-ron.md`): the geometry, its
//! parametrisation and, as the chain grows, the grid and the other inputs of a study.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

/// The case-file format version this build reads and writes.
pub const CASE_FORMAT_VERSION: u32 = 1;

/// Errors of loading a case file or its design vector; each names the file.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CaseError {
    /// The file cannot be read.
    #[error("{path}: {source}")]
    Read {
        /// The file.
        path: String,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The text is not a valid case (RON syntax, unknown field, wrong type).
    #[error("{path}:{line}:{column}: {message}")]
    Syntax {
        /// The file.
        path: String,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What the parser says.
        message: String,
    },
    /// The case declares a format version this build does not read.
    #[error("{path}: format_version {found} is not supported (this build reads {supported})")]
    Version {
        /// The file.
        path: String,
        /// The version in the file.
        found: u32,
        /// The version this build reads.
        supported: u32,
    },
    /// A design variable moves no control node (see [`crate::reach`]).
    #[error("{path}: design variable {variable:?} (modifier {modifier:?}) moves no control node")]
    DeadVariable {
        /// The case file.
        path: String,
        /// The variable.
        variable: String,
        /// Its modifier.
        modifier: String,
    },
}

/// A case: what the chain works on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Case {
    /// File format version ([`CASE_FORMAT_VERSION`]).
    pub format_version: u32,
    /// The geometric database (RON), relative to the case file's folder.
    pub geometry: String,
    /// The parametrisation of the geometry (paper §5).
    #[serde(default)]
    pub parametrisation: param::Parametrisation,
    /// The baseline grid (.su2, .msh, .vtu), relative to the case file's folder. A `.msh`
    /// with parametric nodes or an `.su2` grid: the wall markers are tied to the geometry by
    /// projection (`surfgrid::classify`) either way.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub grid: Option<String>,
    /// The grid's markers that lie on the geometry and follow it (their triangles are given
    /// their surface components by geometry alone, `surfgrid::classify::wall_surface`).
    #[serde(default)]
    pub wall: Vec<String>,
    /// Planar markers whose nodes slide on their plane (e.g. `symmetry`).
    #[serde(default)]
    pub slide: Vec<String>,
    /// Markers that do not move (e.g. `farfield`); markers named nowhere are fixed too. A
    /// node of a fixed marker never moves, even on a `slide` marker
    /// ([`crate::precedence`]).
    #[serde(default)]
    pub fixed: Vec<String>,
    /// Options of the volume deformation (paper §4).
    #[serde(default)]
    pub deform: DeformSettings,
    /// Options of the surface-grid classification and update (paper §3.3).
    #[serde(default)]
    pub surface_grid: SurfaceGridSettings,
    /// Wing masters (§6, `wingmaster::WingMasterSpec`) by name: a master modifier whose
    /// source is `External("name")` is driven by the wing master of that name.
    #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub wing_masters: std::collections::BTreeMap<String, wingmaster::WingMasterSpec>,
    /// Geometric constraints measured on the updated model ([`crate::constraints`]);
    /// optional, empty by default.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub constraints: Vec<crate::constraints::ConstraintSpec>,
}

/// Spring stiffness choice of the case file (see `deform::Stiffness`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum StiffnessChoice {
    /// K = 1 / l.
    InverseLength,
    /// K = 1 / l² (default).
    #[default]
    InverseLengthSquared,
    /// K = (1 / l²)(V̄ / V_ij).
    Volume,
    /// K = (1 / l²)(1 + (ℓ / d)²), d the edge's distance to the moving boundary
    /// (`deform::Stiffness::WallDistance`: stiffens the cells near the wall).
    WallDistance,
}

/// Linear solver choice of the case file (see `deform::SolverKind`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum SolverChoice {
    /// Conjugate gradients with smoothed-aggregation multigrid (default).
    #[default]
    PcgMultigrid,
    /// Conjugate gradients with Jacobi.
    PcgJacobi,
    /// The paper's point iteration (Eq. 22).
    PointIteration,
}

/// Deformation options of a case; every field has the default of `deform::DeformOptions`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DeformSettings {
    /// Spring stiffness.
    pub stiffness: StiffnessChoice,
    /// Use the adaptation matrices R (Eqs. 18–26).
    pub adapt_rotation: bool,
    /// How far R reaches from the wall (`deform::DeformOptions::rotation_reach`): `None`
    /// (default), everywhere; `Some(L)`, blended to the identity with the distance from the
    /// wall along grid edges, fully at L (grid units; `Some(0.0)`: no R at all). A case
    /// without it loads with `None`:
    ///
    /// ```
    /// use aeroshape::case::Case;
    /// let old = Case::from_ron_str("(format_version: 1, geometry: \"g.ron\", deform: (adapt_rotation: true))", "c.ron").unwrap();
    /// assert_eq!(old.deform.options().rotation_reach, None);
    /// let new = Case::from_ron_str("(format_version: 1, geometry: \"g.ron\", deform: (rotation_reach: Some(2.5)))", "c.ron").unwrap();
    /// assert_eq!(new.deform.options().rotation_reach, Some(2.5));
    /// ```
    pub rotation_reach: Option<f64>,
    /// Linear solver.
    pub solver: SolverChoice,
    /// Relative residual at which a solve stops.
    pub rel_tol: f64,
    /// Iteration limit of one solve.
    pub max_iters: usize,
    /// Quality guard: split into increments below this fraction of the initial minimum.
    pub min_quality_ratio: f64,
    /// Largest number of increments.
    pub max_increments: usize,
    /// Start each evaluation's solves from the previous evaluation's solution, and each
    /// reverse product's adjoint solves from the previous one's (see `aeroshape::study`);
    /// `false`: from the baseline and from zero, bit for bit history independent.
    pub warm_start: bool,
}

impl Default for DeformSettings {
    fn default() -> Self {
        let d = deform::DeformOptions::default();
        Self {
            stiffness: StiffnessChoice::default(),
            adapt_rotation: d.adapt_rotation,
            rotation_reach: d.rotation_reach,
            solver: SolverChoice::default(),
            rel_tol: d.rel_tol,
            max_iters: d.max_iters,
            min_quality_ratio: d.min_quality_ratio,
            max_increments: d.max_increments,
            warm_start: true,
        }
    }
}

impl DeformSettings {
    /// The `deform` options these settings give.
    pub fn options(&self) -> deform::DeformOptions {
        deform::DeformOptions {
            stiffness: match self.stiffness {
                StiffnessChoice::InverseLength => deform::Stiffness::InverseLength,
                StiffnessChoice::InverseLengthSquared => deform::Stiffness::InverseLengthSquared,
                StiffnessChoice::Volume => deform::Stiffness::Volume,
                StiffnessChoice::WallDistance => deform::Stiffness::WallDistance,
            },
            adapt_rotation: self.adapt_rotation,
            rotation_reach: self.rotation_reach,
            solver: match self.solver {
                SolverChoice::PcgMultigrid => deform::SolverKind::PcgMultigrid,
                SolverChoice::PcgJacobi => deform::SolverKind::PcgJacobi,
                SolverChoice::PointIteration => deform::SolverKind::PointIteration,
            },
            rel_tol: self.rel_tol,
            max_iters: self.max_iters,
            min_quality_ratio: self.min_quality_ratio,
            max_increments: self.max_increments,
            ..deform::DeformOptions::default()
        }
    }
}

/// Surface-grid options of a case; every field has the default of `surfgrid`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SurfaceGridSettings {
    /// Largest wall-node distance from the geometry accepted when the grid is classified,
    /// relative to the model's reference length.
    pub classify_rel_tol: f64,
    /// Largest number of parametric smoothing passes per component in the update.
    pub max_passes: usize,
    /// Smoothing stops at this fraction of the initial worst triangle quality.
    pub quality_fraction: f64,
    /// Largest distance of a re-projected boundary node, relative.
    pub boundary_rel_tol: f64,
}

impl Default for SurfaceGridSettings {
    fn default() -> Self {
        let u = surfgrid::UpdateOptions::default();
        Self {
            classify_rel_tol: surfgrid::ClassifyOptions::default().rel_tol,
            max_passes: u.max_passes,
            quality_fraction: u.quality_fraction,
            boundary_rel_tol: u.boundary_rel_tol,
        }
    }
}

impl SurfaceGridSettings {
    /// The `surfgrid::update` options.
    pub fn update_options(&self) -> surfgrid::UpdateOptions {
        surfgrid::UpdateOptions {
            max_passes: self.max_passes,
            quality_fraction: self.quality_fraction,
            boundary_rel_tol: self.boundary_rel_tol,
        }
    }
}

fn syntax(path: &str, e: ron::error::SpannedError) -> CaseError {
    CaseError::Syntax {
        path: path.to_string(),
        line: e.span.start.line,
        column: e.span.start.col,
        message: e.code.to_string(),
    }
}

impl Case {
    /// Parses a case from RON text (with the extensions of [`param::ron_options`]); `path`
    /// names the file in errors.
    ///
    /// ```
    /// let c = aeroshape::case::Case::from_ron_str(
    ///     "(format_version: 1, geometry: \"g.ron\")", "case.ron").unwrap();
    /// assert!(c.parametrisation.modifiers.is_empty());
    /// let e = aeroshape::case::Case::from_ron_str("(format_version: 1,\n geometry: 3)", "case.ron")
    ///     .unwrap_err();
    /// assert!(e.to_string().starts_with("case.ron:2:"));
    /// ```
    pub fn from_ron_str(text: &str, path: &str) -> Result<Self, CaseError> {
        let c: Case = param::ron_options()
            .from_str(text)
            .map_err(|e| syntax(path, e))?;
        if c.format_version != CASE_FORMAT_VERSION {
            return Err(CaseError::Version {
                path: path.to_string(),
                found: c.format_version,
                supported: CASE_FORMAT_VERSION,
            });
        }
        Ok(c)
    }

    /// Reads a case file.
    pub fn load(path: &Path) -> Result<Self, CaseError> {
        let p = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| CaseError::Read {
            path: p.clone(),
            source,
        })?;
        Self::from_ron_str(&text, &p)
    }

    /// A path of the case (geometry, grid) resolved against the case file's folder.
    pub fn resolve(case_path: &Path, rel: &str) -> PathBuf {
        let r = Path::new(rel);
        if r.is_absolute() {
            r.to_path_buf()
        } else {
            case_path.parent().unwrap_or_else(|| Path::new("")).join(r)
        }
    }

    /// The geometry file's path.
    pub fn geometry_path(&self, case_path: &Path) -> PathBuf {
        Self::resolve(case_path, &self.geometry)
    }

    /// The grid file's path, if the case names one.
    pub fn grid_path(&self, case_path: &Path) -> Option<PathBuf> {
        self.grid.as_ref().map(|g| Self::resolve(case_path, g))
    }

    /// The case as pretty RON.
    pub fn to_ron_string(&self) -> String {
        param::ron_to_string(self)
    }
}

/// Reads a design vector file (`DV.ron`: a map `{"name": value, …}`).
pub fn load_design_values(path: &Path) -> Result<param::DesignValues, CaseError> {
    let p = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|source| CaseError::Read {
        path: p.clone(),
        source,
    })?;
    param::ron_options()
        .from_str(&text)
        .map_err(|e| syntax(&p, e))
}
