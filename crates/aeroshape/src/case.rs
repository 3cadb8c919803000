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
    /// The baseline grid (.su2, .msh, .vtu), relative to the case file's folder.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub grid: Option<String>,
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

    /// The case as pretty RON.
    pub fn to_ron_string(&self) -> String {
        let cfg = ron::ser::PrettyConfig::new()
            .struct_names(false)
            .indentor("  ".to_string())
            .extensions(
                ron::extensions::Extensions::UNWRAP_VARIANT_NEWTYPES
                    | ron::extensions::Extensions::IMPLICIT_SOME,
            );
        ron::ser::to_string_pretty(self, cfg).unwrap_or_else(|e| format!("// {e}"))
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
