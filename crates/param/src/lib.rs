//! Shape parametrisation (paper §5): design variables with bounds and linear inequality
//! constraints; node (Eqs. 34–35), line (Eq. 36), surface (Eqs. 37–38) and master (§5.4)
//! modifiers acting on the control nodes of the geometric database; the exact Jacobian of
//! control node coordinates with respect to the design variables.
//!
//! Layer: depends on `geom-db` (control nodes, evaluation, B-spline bases) and `intersect`
//! (foot of the normal on a support curve). `param` produces control-node positions; it
//! never touches a grid. The model update after the nodes moved (curves and corners
//! re-intersected) is `intersect::update::update_model`.
//!
//! * [`registry`]: [`DesignVariable`] (name, initial value, bounds, scale, group) and the
//!   ordered [`Registry`] of a parametrisation; design vectors as name → value maps.
//! * [`modifier`]: the four levels as RON-serialisable definitions with their linked
//!   entities (surfaces, curves, control nodes, iso-parametric lines).
//! * [`basis`]: Hicks–Henne bumps, Bernstein polynomials, B-splines (any degree, clamped
//!   uniform or user knots) for Eqs. (36)–(38).
//! * [`master`]: the [`MasterSource`] trait of master generators, projection of control
//!   nodes onto the bilinear initial master, and the built-in station master.
//! * [`Prepared`]: a parametrisation bound to a geometry; positions and Jacobian for a
//!   design vector. Composition rules are in [`prepare`].
//! * [`constraints`]: A·x ≤ b with names, feasibility, dense/JSON export.
//! * [`jacobian`]: the sparse Jacobian, a [`sprs::CsMat`] (CSR).
//!
//! The equations, conventions and algorithms are in `docs/crates/param.md`.

pub mod basis;
pub mod constraints;
pub mod error;
pub mod jacobian;
pub mod master;
pub mod modifier;
pub mod prepare;
pub mod registry;

use serde::{Deserialize, Serialize};

pub use basis::{Basis, Bump};
pub use constraints::{ConstraintMatrix, LinearConstraint, Violation};
pub use error::{Error, Result};
pub use jacobian::Jacobian;
pub use master::{MasterError, MasterGrid, MasterSource, Station, StationsMaster};
pub use modifier::{
    Axis, Decay, Direction, IsoLine, LineModifier, LineSupport, Links, MasterModifier, MasterSpec,
    Modifier, NodeModifier, Param, SurfaceForm, SurfaceModifier,
};
pub use prepare::{MasterSources, Prepared};
pub use registry::{DesignValues, DesignVariable, Registry, parse_design_values};

/// A parametrisation: an ordered list of modifiers (each owning its design variables and
/// linked entities) and linear inequality constraints on the variables.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Parametrisation {
    /// The modifiers, applied in order (see [`prepare`] for the composition rule).
    #[serde(default)]
    pub modifiers: Vec<Modifier>,
    /// Linear inequality constraints A·x ≤ b.
    #[serde(default)]
    pub constraints: Vec<LinearConstraint>,
}

impl Parametrisation {
    /// The registry of all design variables (modifier order), validating each variable and
    /// rejecting duplicate variable or modifier names.
    pub fn registry(&self) -> Result<Registry> {
        let mut names = std::collections::BTreeSet::new();
        for m in &self.modifiers {
            if m.name().trim().is_empty() {
                return Err(Error::BadModifier {
                    modifier: format!("({} modifier)", m.level()),
                    reason: "empty name".into(),
                });
            }
            if !names.insert(m.name()) {
                return Err(Error::BadModifier {
                    modifier: m.name().to_string(),
                    reason: "two modifiers have this name".into(),
                });
            }
        }
        Registry::new(self.modifiers.iter().flat_map(|m| {
            m.variables()
                .into_iter()
                .map(|v| (m.name().to_string(), v.clone()))
        }))
    }

    /// The constraints resolved against the registry (A dense, b).
    pub fn constraint_matrix(&self) -> Result<ConstraintMatrix> {
        ConstraintMatrix::new(&self.constraints, &self.registry()?)
    }

    /// Binds the parametrisation to a geometry (checks every link, computes what depends on
    /// the initial shape); `masters` supplies external master generators by name.
    pub fn bind(&self, db: &geom_db::GeomDb, masters: &MasterSources) -> Result<Prepared> {
        Prepared::new(self, db, masters)
    }

    /// Parses a parametrisation from RON; `path` names the file in errors.
    pub fn from_ron_str(text: &str, path: &str) -> Result<Self> {
        ron_from_str(text, path)
    }

    /// The parametrisation as pretty RON.
    pub fn to_ron_string(&self) -> String {
        ron_to_string(self)
    }
}

/// The RON options every `param` file is read with: `unwrap_variant_newtypes` (write
/// `Node(name: …)` instead of `Node((name: …))`) and `implicit_some` (write `rotation: (…)`
/// instead of `rotation: Some((…))`).
pub fn ron_options() -> ron::Options {
    ron::Options::default()
        .with_default_extension(ron::extensions::Extensions::UNWRAP_VARIANT_NEWTYPES)
        .with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME)
}

/// Writes `value` as pretty RON in the form [`ron_options`] reads back: no struct names,
/// newtype variants unwrapped, `Some` implicit, two-space indent. Serialising plain data
/// cannot fail; a failure would come back as a RON comment naming it.
pub fn ron_to_string<T: serde::Serialize + ?Sized>(value: &T) -> String {
    let cfg = ron::ser::PrettyConfig::new()
        .struct_names(false)
        .indentor("  ".to_string())
        .extensions(
            ron::extensions::Extensions::UNWRAP_VARIANT_NEWTYPES
                | ron::extensions::Extensions::IMPLICIT_SOME,
        );
    ron::ser::to_string_pretty(value, cfg).unwrap_or_else(|e| format!("// {e}"))
}

/// Parses RON with [`ron_options`], reporting errors as `path:line:column: message`.
pub fn ron_from_str<T: serde::de::DeserializeOwned>(text: &str, path: &str) -> Result<T> {
    ron_options().from_str(text).map_err(|e| Error::Syntax {
        path: path.to_string(),
        line: e.span.start.line,
        column: e.span.start.col,
        message: e.code.to_string(),
    })
}
