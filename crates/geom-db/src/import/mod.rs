//! CAD import: IGES and STEP files → one neutral model of exact geometry → the geometric
//! database (power-basis arcs and patches, Eqs. 2–10; topology by sewing, §2.1).
//!
//! * Front ends: `from_iges` reads IGES 5.3 entities (curves 100, 102, 104, 106, 110,
//!   112, 126, 130, 142; surfaces 108, 114, 118, 120, 122, 128, 140, 190–198; faces 144, 143,
//!   bounded 108, 510 in 514 shells of 186 solids, independent surfaces), `from_step` the
//!   B-rep of AP203/AP214/AP242 (solids, shell-based surface models, advanced faces over edge
//!   loops, elementary, B-spline, swept and offset surfaces, lines, conics, B-spline, trimmed,
//!   composite, offset and surface curves) with its length and angle units.
//! * [`model`]: the neutral intermediate ([`CadModel`]): exact curves and surfaces
//!   (NURBS, analytic, revolution, extrusion, ruled, offset), faces with loops of edge uses,
//!   shells; each item names its source entity.
//! * [`stage`]: the conversion as named stages — faces with exact geometry (trimming box,
//!   support surfaces), edges, loops, corners, T-junctions, sewing, orientation, shells,
//!   database — each documented in its file.
//! * Units: the file's length unit is honoured and reported; [`ImportOptions::units`]
//!   converts to another, [`ImportOptions::file_units`] overrides the declared one; a
//!   model whose size does not fit its unit (an aircraft 36 "inches" long) gets a warning
//!   with the evidence ([`size_warning`]).
//! * Roles ([`recognise`], by shape): symmetry plane, far field, wing, wing tip, fuselage,
//!   fuselage caps or body, naming each surface component `<role>.<entity>` (e.g.
//!   `wing.D31`, `fuselage.#17`); [`ImportOptions::roles`] overrides them.
//! * The way back ([`to_iges`]): support surfaces as 114 or 128, surface components as 144
//!   trimmed surfaces with 142 boundaries over 112/126 model curves.

// `!(x > 0.0)` deliberately rejects NaN as well as non-positive values.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod approx;
mod export;
mod from_iges;
mod from_step;
pub mod model;
mod report;
mod roles;
pub mod stage;
#[cfg(test)]
mod tests;
mod units;

pub use export::to_iges;
pub use model::{CadModel, LengthUnit};
pub use report::{
    EdgeReport, EntityConversion, FaceReport, ImportReport, JunctionReport, ShellReport,
};
pub use roles::{FaceRole, recognise};
pub use units::{AIRCRAFT_LENGTH, ANY_LENGTH, size_warning};

use crate::db::GeomDb;

/// Errors of the import. Every message is one line naming the file and, where there is
/// one, the entity (IGES directory line, STEP instance).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The IGES file could not be read.
    #[error(transparent)]
    Iges(#[from] iges::Error),
    /// The STEP file could not be read, or one of its instances is wrong.
    #[error(transparent)]
    Step(#[from] step::Error),
    /// An entity cannot be converted.
    ///
    /// ```
    /// use iges::{Entity, Global, IgesFile, Line};
    /// let mut f = IgesFile::new(Global::default());
    /// f.name = "x.igs".into();
    /// let l = f.push(Entity::Line(Line { start: [0.0; 3], end: [1.0, 0.0, 0.0] }));
    /// let p = f.push(Entity::Plane(iges::Plane {
    ///     coefficients: [0.0, 0.0, 1.0, 0.0],
    ///     boundary: Some(l),
    ///     symbol_location: [0.0; 3],
    ///     symbol_size: 0.0,
    /// }));
    /// f.entities[p.index()].de.form = 1;
    /// let err = geom_db::import::import(&f, &Default::default()).unwrap_err();
    /// assert!(matches!(err, geom_db::import::Error::Entity { .. }), "{err}");
    /// assert!(err.to_string().starts_with("x.igs: entity at D line 3 (type 108)"), "{err}");
    /// ```
    #[error("{file}: {entity}: {reason}")]
    Entity {
        /// The CAD file.
        file: String,
        /// The entity: `entity at D line 37 (type 144)` or `#37 (ADVANCED_FACE)`.
        entity: String,
        /// What is wrong.
        reason: String,
    },
    /// The model as a whole cannot be imported (no faces, no unit to convert from, ...).
    ///
    /// ```
    /// let f = iges::IgesFile::new(iges::Global::default());
    /// let err = geom_db::import::import(&f, &Default::default()).unwrap_err();
    /// assert!(matches!(err, geom_db::import::Error::Model { .. }), "{err}");
    /// ```
    #[error("{file}: {reason}")]
    Model {
        /// The CAD file.
        file: String,
        /// What is wrong.
        reason: String,
    },
    /// The database built from the file does not validate.
    #[error(
        "{file}: the imported model does not validate: {source}{}",
        from.as_ref().map_or(String::new(), |f| format!(", made from {f}"))
    )]
    Invalid {
        /// The CAD file.
        file: String,
        /// The validation error.
        source: Box<crate::Error>,
        /// The file's entity the item at fault was made from (`entity D37 (126)`, `the
        /// domain boundary of entity #12 (B_SPLINE_SURFACE_WITH_KNOTS)`), when known: a
        /// support curve's or surface's source.
        from: Option<String>,
    },
}

/// Options of the import.
#[derive(Debug, Clone, PartialEq)]
pub struct ImportOptions {
    /// Approximation tolerance in output units; `None`: `rel_tolerance` × model size.
    pub tolerance: Option<f64>,
    /// Approximation tolerance relative to the model size (bounding-box diagonal), default
    /// 1e-7.
    pub rel_tolerance: f64,
    /// Sewing tolerance (corners and coincident edges) in output units; `None`:
    /// `rel_sew_tolerance` × model size, but at least 10 × the approximation tolerance.
    pub sew_tolerance: Option<f64>,
    /// Sewing tolerance relative to the model size, default 1e-6 (the gap tolerance of
    /// [`GeomDb::check`](crate::GeomDb::check)).
    pub rel_sew_tolerance: f64,
    /// Reverse every surface component's orientation after the automatic choice.
    pub flip: bool,
    /// Convert lengths to this unit (`None`: keep the file's). A file that declares no
    /// unit cannot be converted.
    pub units: Option<LengthUnit>,
    /// The unit the file's numbers are in, overriding the one it declares (a header that
    /// says inches over numbers in metres); `None`: the file's own.
    pub file_units: Option<LengthUnit>,
    /// Roles given by hand, overriding the recognition by shape ([`recognise`]): face
    /// entity (`D31`, `#17`, as in [`FaceReport::entity`]) → role name (`wing`,
    /// `fuselage`, `farfield`, …). The surface component is named `<role>.<entity>`; the
    /// role `farfield` makes its shell enclose the fluid.
    pub roles: std::collections::BTreeMap<String, String>,
    /// Assign control nodes (Eq. 9, [`GeomDb::assign_control_nodes`]) at the end of the
    /// import, so that the model can be parametrised at once; default true.
    pub control_nodes: bool,
}

impl Default for ImportOptions {
    fn default() -> Self {
        Self {
            tolerance: None,
            rel_tolerance: 1e-7,
            sew_tolerance: None,
            rel_sew_tolerance: 1e-6,
            flip: false,
            units: None,
            file_units: None,
            roles: Default::default(),
            control_nodes: true,
        }
    }
}

impl ImportOptions {
    /// Sets an absolute approximation tolerance.
    pub fn with_tolerance(mut self, tol: f64) -> Self {
        self.tolerance = Some(tol);
        self
    }

    /// Sets [`flip`](Self::flip).
    pub fn with_flip(mut self, flip: bool) -> Self {
        self.flip = flip;
        self
    }

    /// Sets the output unit ([`units`](Self::units)).
    pub fn with_units(mut self, units: LengthUnit) -> Self {
        self.units = Some(units);
        self
    }
}

/// Converts an IGES file into a validated geometric database.
///
/// Every face (144, 143, 510, bounded 108, or an independent untrimmed surface) becomes a
/// surface component over a support surface; boundary curves become curve components,
/// shared between faces where they coincide within the sewing tolerance. See [`stage`].
pub fn import(
    file: &iges::IgesFile,
    opts: &ImportOptions,
) -> Result<(GeomDb, ImportReport), Error> {
    import_model(from_iges::model(file)?, opts)
}

/// Converts a STEP file into a validated geometric database (see [`import`]).
pub fn import_step(
    file: &step::StepFile,
    opts: &ImportOptions,
) -> Result<(GeomDb, ImportReport), Error> {
    import_model(from_step::model(file)?, opts)
}

/// Reads and converts a CAD file held in memory: STEP when it starts with
/// `ISO-10303-21`, IGES otherwise. `name` is used in messages.
pub fn import_bytes(
    bytes: &[u8],
    name: &str,
    opts: &ImportOptions,
) -> Result<(GeomDb, ImportReport), Error> {
    if is_step(bytes) {
        import_step(&step::parse(bytes, name)?, opts)
    } else {
        import(&iges::parse(bytes, name)?, opts)
    }
}

/// True when the bytes start (after blanks or a byte-order mark) with `ISO-10303-21`.
pub fn is_step(bytes: &[u8]) -> bool {
    let b = bytes.strip_prefix(&[0xEF, 0xBB, 0xBF][..]).unwrap_or(bytes);
    let start = b
        .iter()
        .position(|c| !c.is_ascii_whitespace())
        .unwrap_or(b.len());
    b[start..].len() >= 12 && b[start..start + 12].eq_ignore_ascii_case(b"ISO-10303-21")
}

/// Converts a neutral model into a validated geometric database: the unit conversion, then
/// the stages of [`stage`].
pub fn import_model(
    mut model: CadModel,
    opts: &ImportOptions,
) -> Result<(GeomDb, ImportReport), Error> {
    if let Some(u) = &opts.file_units {
        if model.unit.as_ref().is_some_and(|d| d.name != u.name) {
            model.warnings.push(format!(
                "the file declares {}; its numbers are read as {} (file units given)",
                model.unit.as_ref().map_or("", |d| d.name.as_str()),
                u.name
            ));
        }
        model.unit = Some(u.clone());
    }
    let (scale, units) = match (&opts.units, &model.unit) {
        (Some(t), Some(f)) => (f.metres / t.metres, Some(t.clone())),
        (Some(t), None) => {
            return Err(Error::Model {
                file: model.file.clone(),
                reason: format!(
                    "the file declares no length unit, so its lengths cannot be converted to {}",
                    t.name
                ),
            });
        }
        (None, u) => (1.0, u.clone()),
    };
    if scale != 1.0 {
        model.scale(scale);
    }
    let report = ImportReport {
        file: model.file.clone(),
        format: model.format,
        file_units: model.unit.as_ref().map(|u| u.name.clone()),
        units: units.map(|u| u.name),
        scale,
        reference_length: 0.0,
        tolerance: 0.0,
        sew_tolerance: 0.0,
        entities: Vec::new(),
        max_error: 0.0,
        faces: Vec::new(),
        shells: Vec::new(),
        curve_components: 0,
        sewn_edges: 0,
        max_sew_gap: 0.0,
        free_edges: Vec::new(),
        non_manifold_edges: Vec::new(),
        orientation_conflicts: 0,
        junctions: Vec::new(),
        warnings: model.warnings.clone(),
    };
    let (db, mut report) = stage::run(&model, opts, report)?;
    units::check(&db, model.unit.as_ref(), &mut report);
    Ok((db, report))
}
