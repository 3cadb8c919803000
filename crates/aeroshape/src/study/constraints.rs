//! The case's geometric constraints ([`crate::constraints`]) as functions of the design
//! vector: [`Study::constraints`] measures them on the updated model (param, then the model
//! update; no surface grid, no volume deformation), [`Study::constraints_jacobian`] adds
//! their exact derivatives through the same linearisation of the model update that the
//! chain's products use (`Prepared::apply_with_jacobian`, then `intersect`'s
//! `ModelLinearisation`: surfaces linear in their nodes, junctions by the implicit function
//! theorem), one forward product of the model update per design variable.

use geom_db::GeomDb;
use geom_db::prelude::Vector3;
use serde::Serialize;

use super::Study;
use super::error::Result;
use crate::constraints::{Measured, measure_all};

/// One row of the constraints at a design vector.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ConstraintRow {
    /// Name (`name[k]` for the k-th station of a thickness).
    pub name: String,
    /// The measured value at x (absolute).
    pub value: f64,
    /// The measured value on the initial model.
    pub initial: f64,
    /// value / initial.
    pub ratio: f64,
    /// The value the bounds apply to: `ratio` for a relative constraint, `value` otherwise.
    pub reported: f64,
    /// True for a constraint taken relative to the initial model.
    pub relative: bool,
    /// Lower bound of `reported`.
    pub lower: Option<f64>,
    /// Upper bound of `reported`.
    pub upper: Option<f64>,
}

impl ConstraintRow {
    /// True when `reported` is within its bounds.
    pub fn satisfied(&self) -> bool {
        self.lower.is_none_or(|l| self.reported >= l)
            && self.upper.is_none_or(|u| self.reported <= u)
    }
}

/// The constraints and their Jacobian at a design vector ([`Study::constraints_jacobian`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ConstraintJacobian {
    /// The rows at x.
    pub rows: Vec<ConstraintRow>,
    /// The design variables' names (the Jacobian's columns).
    pub variables: Vec<String>,
    /// d(reported)/dx: one row per constraint row, one column per design variable.
    pub jacobian: Vec<Vec<f64>>,
}

/// [`Study::constraints_linearised`]'s result.
struct Linearised {
    jp: param::Jacobian,
    db: GeomDb,
    lin: intersect::update::ModelLinearisation,
    at: Vec<Measured>,
    rows: Vec<ConstraintRow>,
}

impl Study {
    /// The case's constraints measured on the initial model (measured the first time it is
    /// asked for, then kept).
    pub fn initial_constraints(&self) -> Result<&[Measured]> {
        if let Some(m) = self.initial_constraints.get() {
            return Ok(m);
        }
        let m = measure_all(&self.db, &self.case.constraints)?;
        Ok(self.initial_constraints.get_or_init(|| m))
    }

    /// What both derivative products need at `x`: the param Jacobian, the updated model and
    /// its linearisation, the constraints measured on it and their rows.
    fn constraints_linearised(&self, x: &[f64]) -> Result<Linearised> {
        super::evaluate::check_length(&self.prepared, x)?;
        let initial = self.initial_constraints()?;
        let (points, jp) = self.prepared.apply_with_jacobian(x)?;
        let (db, _) = self.model.update(&points)?;
        let lin = self.model.linearise(&points, &db)?;
        let at = measure_all(&db, &self.case.constraints)?;
        let rows = self.rows(&at, initial);
        Ok(Linearised {
            jp,
            db,
            lin,
            at,
            rows,
        })
    }

    /// The model updated to `x` (param, then the model update; no grid), the model the
    /// constraints are measured on.
    pub fn updated_model(&self, x: &[f64]) -> Result<GeomDb> {
        super::evaluate::check_length(&self.prepared, x)?;
        let points = self.prepared.apply(x)?;
        Ok(self.model.update(&points)?.0)
    }

    fn rows(&self, at: &[Measured], initial: &[Measured]) -> Vec<ConstraintRow> {
        let mut specs = Vec::with_capacity(at.len());
        for s in &self.case.constraints {
            let n = match &s.measure {
                crate::constraints::Measure::Thickness { stations, .. } => stations.points().len(),
                _ => 1,
            };
            specs.extend(std::iter::repeat_n(s, n));
        }
        at.iter()
            .zip(initial)
            .zip(specs)
            .map(|((m, m0), s)| {
                let ratio = m.value / m0.value;
                ConstraintRow {
                    name: m.name.clone(),
                    value: m.value,
                    initial: m0.value,
                    ratio,
                    reported: if s.relative { ratio } else { m.value },
                    relative: s.relative,
                    lower: s.lower,
                    upper: s.upper,
                }
            })
            .collect()
    }

    /// The constraints at `x` as a table (value, initial, ratio, bounds).
    pub fn constraint_rows(&self, x: &[f64]) -> Result<Vec<ConstraintRow>> {
        let initial = self.initial_constraints()?;
        let db = self.updated_model(x)?;
        let at = measure_all(&db, &self.case.constraints)?;
        Ok(self.rows(&at, initial))
    }

    /// The constraints' values at `x`, in the case's order (a thickness gives one value per
    /// station): the ratio to the initial value for relative constraints, the value
    /// otherwise.
    pub fn constraints(&self, x: &[f64]) -> Result<Vec<f64>> {
        Ok(self
            .constraint_rows(x)?
            .into_iter()
            .map(|r| r.reported)
            .collect())
    }

    /// The constraints at `x` with their exact Jacobian d(reported)/dx (module doc).
    pub fn constraints_jacobian(&self, x: &[f64]) -> Result<ConstraintJacobian> {
        let Linearised {
            jp,
            db,
            lin,
            at,
            rows,
        } = self.constraints_linearised(x)?;
        let n = jp.cols();
        let mut jacobian = vec![vec![0.0; n]; at.len()];
        for l in 0..n {
            let c = param::jacobian::column(&jp, l);
            let dp: Vec<Vector3> = c
                .chunks_exact(3)
                .map(|v| Vector3::new(v[0], v[1], v[2]))
                .collect();
            let t = lin.jvp(&dp)?;
            for (k, (m, r)) in at.iter().zip(&rows).enumerate() {
                let d = m.tangent(&db, &t)?;
                jacobian[k][l] = if r.relative { d / r.initial } else { d };
            }
        }
        Ok(ConstraintJacobian {
            rows,
            variables: self
                .prepared
                .registry()
                .names()
                .iter()
                .map(|s| s.to_string())
                .collect(),
            jacobian,
        })
    }

    /// x̄ = Σ_k w_k d(reported_k)/dx at `x`: the reverse product of the constraints (one
    /// reverse product of the model update for any number of constraints).
    pub fn constraints_vjp(&self, x: &[f64], w: &[f64]) -> Result<Vec<f64>> {
        let Linearised {
            jp,
            db,
            lin,
            at,
            rows,
        } = self.constraints_linearised(x)?;
        super::linearise::check_len("constraint weights", at.len(), w.len())?;
        let mut bar = lin.zero_tangent();
        for ((m, r), wk) in at.iter().zip(&rows).zip(w) {
            let b = if r.relative { wk / r.initial } else { *wk };
            m.add_cotangent(&db, b, &mut bar)?;
        }
        let pb = lin.vjp(&bar)?;
        Ok(super::linearise::jac_t_times(&jp, &pb))
    }
}
