//! Linear inequality constraints A·x ≤ b on design variables (§6: the engineers'
//! semi-empirical knowledge), their feasibility check and export.

use std::collections::BTreeMap;
use std::io::Write;

use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::registry::Registry;

/// One named constraint Σ a_k x_k ≤ rhs (x in physical units).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinearConstraint {
    /// Name, for reports.
    pub name: String,
    /// a_k by variable name.
    pub coefficients: BTreeMap<String, f64>,
    /// The right-hand side.
    pub rhs: f64,
}

/// A violated constraint.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Violation {
    /// The constraint's name.
    pub name: String,
    /// a·x.
    pub lhs: f64,
    /// b.
    pub rhs: f64,
}

impl std::fmt::Display for Violation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "constraint '{}' violated: {} > {} (excess {:.3e})",
            self.name,
            self.lhs,
            self.rhs,
            self.lhs - self.rhs
        )
    }
}

/// Constraints resolved against a registry: dense A (one row per constraint) and b.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ConstraintMatrix {
    /// Constraint names (rows).
    pub names: Vec<String>,
    /// Variable names (columns).
    pub variables: Vec<String>,
    /// A, row-major.
    pub a: Vec<Vec<f64>>,
    /// b.
    pub b: Vec<f64>,
}

impl ConstraintMatrix {
    /// Resolves `constraints` (unknown variable names and non-finite numbers are errors
    /// naming the constraint).
    pub fn new(constraints: &[LinearConstraint], reg: &Registry) -> Result<Self> {
        let mut a = Vec::with_capacity(constraints.len());
        let mut b = Vec::with_capacity(constraints.len());
        for c in constraints {
            let ctx = format!("constraint '{}'", c.name);
            let mut row = vec![0.0; reg.len()];
            for (n, &v) in &c.coefficients {
                let i = reg.require(n, &ctx)?;
                if !v.is_finite() {
                    return Err(crate::Error::BadModifier {
                        modifier: ctx,
                        reason: format!("coefficient of '{n}' is {v}"),
                    });
                }
                row[i] += v;
            }
            if !c.rhs.is_finite() {
                return Err(crate::Error::BadModifier {
                    modifier: ctx,
                    reason: format!("right-hand side is {}", c.rhs),
                });
            }
            a.push(row);
            b.push(c.rhs);
        }
        Ok(Self {
            names: constraints.iter().map(|c| c.name.clone()).collect(),
            variables: reg.names().iter().map(|s| s.to_string()).collect(),
            a,
            b,
        })
    }

    /// The violated constraints at x (a·x > b + tol·(|a|·|x| + |b|), tol = 1e-12), in order.
    pub fn violations(&self, x: &[f64]) -> Vec<Violation> {
        let mut out = Vec::new();
        for ((row, &b), name) in self.a.iter().zip(&self.b).zip(&self.names) {
            let lhs: f64 = row.iter().zip(x).map(|(a, x)| a * x).sum();
            let mag: f64 = row.iter().zip(x).map(|(a, x)| (a * x).abs()).sum::<f64>() + b.abs();
            if lhs > b + 1e-12 * mag {
                out.push(Violation {
                    name: name.clone(),
                    lhs,
                    rhs: b,
                });
            }
        }
        out
    }

    /// Writes `{"names", "variables", "a", "b"}` as JSON.
    pub fn write_json(&self, mut w: impl Write) -> std::io::Result<()> {
        serde_json::to_writer(&mut w, self)?;
        writeln!(w)
    }
}
