//! The CAD of `case init` ([`read_cad`]): a geometric database (`.ron`) as it is, or an IGES
//! or STEP file imported (`geom_db::import`, as `aeroshape geom import` does), with the
//! tolerance figures the file carries: its own resolution (IGES global parameter 19, STEP
//! `UNCERTAINTY_MEASURE_WITH_UNIT`), the largest conversion error and the largest sewing gap
//! the import measured. An imported file gets its control nodes (Eq. 9) as `geom import`
//! gives them: one per interpolation point of every arc and patch, shared where they
//! coincide; a `.ron` is taken as it is (without control nodes, `case init` refuses it).

use std::path::Path;

use geom_db::GeomDb;
use geom_db::import::{ImportOptions, ImportReport};

use super::{InitError, Tolerance};

/// The kind of a CAD file, by its extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CadKind {
    /// A geometric database (`.ron`).
    Database,
    /// IGES (`.igs`, `.iges`) or STEP (`.stp`, `.step`), imported; the content decides
    /// which (a STEP file starts with `ISO-10303-21`).
    Exchange,
}

impl CadKind {
    /// The kind of `path` by its extension (any case), `None` for another extension.
    ///
    /// ```
    /// use aeroshape::init::cad::CadKind;
    /// assert_eq!(CadKind::of("m6.IGS".as_ref()), Some(CadKind::Exchange));
    /// assert_eq!(CadKind::of("wing.step".as_ref()), Some(CadKind::Exchange));
    /// assert_eq!(CadKind::of("geom.ron".as_ref()), Some(CadKind::Database));
    /// assert_eq!(CadKind::of("wing.stl".as_ref()), None);
    /// ```
    pub fn of(path: &Path) -> Option<Self> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "ron" => Some(Self::Database),
            "igs" | "iges" | "stp" | "step" => Some(Self::Exchange),
            _ => None,
        }
    }
}

/// A CAD file read for `case init`.
#[derive(Debug, Clone)]
pub struct Cad {
    /// The geometric database.
    pub db: GeomDb,
    /// The tolerance figures of the file (empty for a `.ron`).
    pub tolerances: Vec<Tolerance>,
    /// The import's report (`None` for a `.ron`).
    pub import: Option<ImportReport>,
    /// Control nodes made here for an imported file whose import gave none (0 otherwise).
    pub control_nodes_made: usize,
}

/// Reads `path`: a `.ron` database, or an IGES or STEP file imported with the default
/// options (the file's own length unit). Errors name the file.
pub fn read_cad(path: &Path) -> Result<Cad, InitError> {
    let shown = path.display().to_string();
    let kind = CadKind::of(path).ok_or_else(|| InitError::CadFormat {
        path: path.to_path_buf(),
    })?;
    let read_err = |source| InitError::Read {
        path: path.to_path_buf(),
        source,
    };
    if kind == CadKind::Database {
        let text = std::fs::read_to_string(path).map_err(read_err)?;
        let db = GeomDb::from_ron_str(&text, &shown)?;
        return Ok(Cad {
            db,
            tolerances: Vec::new(),
            import: None,
            control_nodes_made: 0,
        });
    }
    let bytes = std::fs::read(path).map_err(read_err)?;
    let opts = ImportOptions::default();
    let cad_err = |source| InitError::Import {
        source: Box::new(source),
    };
    let (mut db, report, resolution) = if geom_db::import::is_step(&bytes) {
        let file = step::parse(&bytes, &shown).map_err(|e| cad_err(e.into()))?;
        let resolution = step_uncertainty(&file);
        let (db, report) = geom_db::import::import_step(&file, &opts).map_err(cad_err)?;
        (db, report, resolution.map(|r| (r, "STEP uncertainty")))
    } else {
        let file = iges::parse(&bytes, &shown).map_err(|e| cad_err(e.into()))?;
        let r = file.global.resolution;
        let (db, report) = geom_db::import::import(&file, &opts).map_err(cad_err)?;
        (
            db,
            report,
            (r > 0.0).then_some((r, "IGES minimum resolution (global parameter 19)")),
        )
    };
    let mut control_nodes_made = 0;
    if db.control_nodes.is_empty() {
        db.assign_control_nodes()?;
        control_nodes_made = db.control_nodes.len();
    }
    let mut tolerances = Vec::new();
    if let Some((r, what)) = resolution {
        tolerances.push(Tolerance {
            source: format!("{shown}: the file's own resolution, {what}"),
            value: r,
        });
    }
    tolerances.push(Tolerance {
        source: format!("{shown}: largest conversion error measured at import"),
        value: report.max_error,
    });
    tolerances.push(Tolerance {
        source: format!("{shown}: largest sewing gap measured at import, × 2"),
        value: 2.0 * report.max_sew_gap,
    });
    Ok(Cad {
        db,
        tolerances,
        import: Some(report),
        control_nodes_made,
    })
}

/// The largest distance uncertainty of the STEP file's representation contexts, in its
/// length unit (`None` when no context gives one).
fn step_uncertainty(file: &step::StepFile) -> Option<f64> {
    file.iter()
        .filter(|(_, e)| matches!(e, step::Entity::Context(c) if !c.uncertainty.is_empty()))
        .filter_map(|(i, _)| file.units(i.id).ok()?.uncertainty)
        .filter(|u| u.is_finite() && *u > 0.0)
        .reduce(f64::max)
}
