//! The design-variable registry: names, initial values, bounds, scaling and groups.
//!
//! Values are in physical units (length units of the model, radians, …). The *initial*
//! value of a variable is the value at which its modifier reproduces the initial geometry
//! (0 for node, line and surface modifiers unless stated otherwise; the baseline planform
//! value for a master). Optimisers usually prefer scaled variables: `scaled = value / scale`.

use std::collections::{BTreeMap, HashMap};

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

fn one() -> f64 {
    1.0
}

/// One design variable.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DesignVariable {
    /// Unique name.
    pub name: String,
    /// Initial value: the modifier reproduces the initial geometry at this value (default 0).
    #[serde(default)]
    pub value: f64,
    /// Lower bound (physical units).
    pub lower: f64,
    /// Upper bound (physical units).
    pub upper: f64,
    /// Scale for the optimiser: `scaled = value / scale` (default 1, must be > 0).
    #[serde(default = "one")]
    pub scale: f64,
    /// A group label (e.g. "wing twist"), free text, for reports and selection.
    #[serde(default)]
    pub group: String,
}

impl DesignVariable {
    /// A variable with initial value 0, bounds `[lower, upper]`, scale 1 and no group.
    pub fn new(name: impl Into<String>, lower: f64, upper: f64) -> Self {
        Self {
            name: name.into(),
            value: 0.0,
            lower,
            upper,
            scale: 1.0,
            group: String::new(),
        }
    }

    /// Sets the group.
    pub fn with_group(mut self, group: impl Into<String>) -> Self {
        self.group = group.into();
        self
    }

    /// Sets the initial value.
    pub fn with_value(mut self, value: f64) -> Self {
        self.value = value;
        self
    }

    /// Sets the scale.
    pub fn with_scale(mut self, scale: f64) -> Self {
        self.scale = scale;
        self
    }

    /// Checks the definition: non-empty name, finite numbers, lower ≤ value ≤ upper,
    /// scale > 0.
    pub fn validate(&self) -> Result<()> {
        let bad = |reason: String| Error::BadVariable {
            name: self.name.clone(),
            reason,
        };
        if self.name.trim().is_empty() {
            return Err(bad("empty name".into()));
        }
        for (what, x) in [
            ("value", self.value),
            ("lower", self.lower),
            ("upper", self.upper),
            ("scale", self.scale),
        ] {
            if !x.is_finite() {
                return Err(bad(format!("{what} = {x} is not finite")));
            }
        }
        if self.lower > self.upper {
            return Err(bad(format!(
                "lower bound {} is above upper bound {}",
                self.lower, self.upper
            )));
        }
        if self.scale <= 0.0 {
            return Err(bad(format!("scale {} must be positive", self.scale)));
        }
        self.check(self.value)
    }

    /// `Ok` when `value` is finite and within the bounds.
    pub fn check(&self, value: f64) -> Result<()> {
        if value.is_finite() && value >= self.lower && value <= self.upper {
            Ok(())
        } else {
            Err(Error::OutOfBounds {
                name: self.name.clone(),
                value,
                lower: self.lower,
                upper: self.upper,
            })
        }
    }
}

/// A design vector as a map name → value (the `DV.ron` file, see `docs/formats/case-ron.md`).
pub type DesignValues = BTreeMap<String, f64>;

/// Parses design values from RON text (a map `{"name": value, …}`); `path` names the file.
///
/// ```
/// let dv = param::parse_design_values("{\"twist\": 0.1}", "dv.ron").unwrap();
/// assert_eq!(dv["twist"], 0.1);
/// assert!(param::parse_design_values("{\"twist\": }", "dv.ron").is_err());
/// ```
pub fn parse_design_values(text: &str, path: &str) -> Result<DesignValues> {
    crate::ron_from_str(text, path)
}

/// The ordered list of all design variables of a parametrisation (modifier order, then the
/// order within each modifier) — the order of the design vector x.
#[derive(Debug, Clone, Default)]
pub struct Registry {
    vars: Vec<DesignVariable>,
    owner: Vec<String>,
    index: HashMap<String, usize>,
}

impl Registry {
    /// Builds the registry from `(owner modifier, variable)` pairs, validating each variable
    /// and rejecting duplicate names.
    pub fn new(vars: impl IntoIterator<Item = (String, DesignVariable)>) -> Result<Self> {
        let mut r = Registry::default();
        for (owner, v) in vars {
            v.validate()?;
            if let Some(&i) = r.index.get(&v.name) {
                return Err(Error::DuplicateVariable {
                    name: v.name,
                    first: r.owner[i].clone(),
                    second: owner,
                });
            }
            r.index.insert(v.name.clone(), r.vars.len());
            r.vars.push(v);
            r.owner.push(owner);
        }
        Ok(r)
    }

    /// Number of design variables.
    pub fn len(&self) -> usize {
        self.vars.len()
    }

    /// True when there are no design variables.
    pub fn is_empty(&self) -> bool {
        self.vars.is_empty()
    }

    /// The variables in design-vector order.
    pub fn variables(&self) -> &[DesignVariable] {
        &self.vars
    }

    /// The modifier that owns variable `i`.
    pub fn owner(&self, i: usize) -> &str {
        &self.owner[i]
    }

    /// Index of the variable `name`.
    pub fn index_of(&self, name: &str) -> Option<usize> {
        self.index.get(name).copied()
    }

    /// Index of `name`, or [`Error::UnknownVariable`] with `context`.
    pub fn require(&self, name: &str, context: &str) -> Result<usize> {
        self.index_of(name).ok_or_else(|| Error::UnknownVariable {
            context: context.to_string(),
            name: name.to_string(),
        })
    }

    /// The initial design vector.
    pub fn initial(&self) -> Vec<f64> {
        self.vars.iter().map(|v| v.value).collect()
    }

    /// Names in design-vector order.
    pub fn names(&self) -> Vec<&str> {
        self.vars.iter().map(|v| v.name.as_str()).collect()
    }

    /// The design vector from named values: unnamed variables keep their initial value;
    /// unknown names and values outside the bounds are errors naming the variable.
    pub fn vector_from_values(&self, values: &DesignValues) -> Result<Vec<f64>> {
        let mut x = self.initial();
        for (name, &v) in values {
            let i = self.require(name, "design vector")?;
            self.vars[i].check(v)?;
            x[i] = v;
        }
        Ok(x)
    }

    /// The named values of a design vector.
    pub fn values_from_vector(&self, x: &[f64]) -> Result<DesignValues> {
        self.check_len(x)?;
        Ok(self
            .vars
            .iter()
            .zip(x)
            .map(|(v, &x)| (v.name.clone(), x))
            .collect())
    }

    /// Checks the length of `x` and every bound; the first violation names the variable.
    pub fn check_bounds(&self, x: &[f64]) -> Result<()> {
        self.check_len(x)?;
        for (v, &xi) in self.vars.iter().zip(x) {
            v.check(xi)?;
        }
        Ok(())
    }

    pub(crate) fn check_len(&self, x: &[f64]) -> Result<()> {
        if x.len() != self.vars.len() {
            return Err(Error::VectorLength {
                expected: self.vars.len(),
                found: x.len(),
            });
        }
        Ok(())
    }

    /// Scaled vector `x_i / scale_i` for the optimiser.
    pub fn to_scaled(&self, x: &[f64]) -> Vec<f64> {
        self.vars.iter().zip(x).map(|(v, &x)| x / v.scale).collect()
    }

    /// Physical vector from a scaled one, `s_i × scale_i`.
    pub fn from_scaled(&self, s: &[f64]) -> Vec<f64> {
        self.vars.iter().zip(s).map(|(v, &s)| s * v.scale).collect()
    }
}
