//! Which control nodes each design variable moves ([`variable_reach`]), and the check that
//! none moves nothing ([`check_live`]): a dead variable would leave the geometry unchanged
//! for every value while an optimiser sees a zero gradient column.

use std::path::Path;

use param::Prepared;
use serde::Serialize;

use crate::case::CaseError;

/// One design variable's reach: how many control nodes it moves.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct VariableReach {
    /// The variable.
    pub name: String,
    /// The modifier that owns it.
    pub modifier: String,
    /// Control nodes whose position depends on it.
    pub nodes_moved: usize,
}

/// The point at which the reach is measured: every variable moved from its initial value
/// towards the bound with more room, by a fraction in [0.25, 0.75) that differs from one
/// variable to the next (so that products of variables, Eq. 37, and cancellations between
/// variables do not hide a dependence, as they would at the initial point).
fn generic_point(prep: &Prepared) -> Vec<f64> {
    const GOLDEN: f64 = 0.618_033_988_749_894_8;
    prep.registry()
        .variables()
        .iter()
        .enumerate()
        .map(|(i, v)| {
            let f = 0.25 + 0.5 * ((i + 1) as f64 * GOLDEN).fract();
            let room = if v.upper - v.value >= v.value - v.lower {
                v.upper - v.value
            } else {
                v.lower - v.value
            };
            v.value + f * room
        })
        .collect()
}

/// For every design variable (registry order), the number of control nodes whose position
/// depends on it: the nonzero rows of its column of the exact Jacobian (`param`), taken at a
/// generic point inside the bounds (each variable moved towards a bound by a fraction that
/// differs from one variable to the next).
pub fn variable_reach(prep: &Prepared) -> Result<Vec<VariableReach>, param::Error> {
    let reg = prep.registry();
    let (_, jac) = prep.apply_with_jacobian(&generic_point(prep))?;
    let mut nodes: Vec<Vec<usize>> = vec![Vec::new(); reg.len()];
    for (_, (row, col)) in jac.iter() {
        nodes[col].push(row / 3);
    }
    for list in &mut nodes {
        list.sort_unstable();
        list.dedup();
    }
    Ok(reg
        .variables()
        .iter()
        .enumerate()
        .map(|(i, v)| VariableReach {
            name: v.name.clone(),
            modifier: reg.owner(i).to_string(),
            nodes_moved: nodes[i].len(),
        })
        .collect())
}

/// [`variable_reach`] of a study's parametrisation.
pub fn variable_reach_of(study: &crate::Study) -> Result<Vec<VariableReach>, param::Error> {
    variable_reach(study.prepared())
}

/// The first variable of `reach` that moves no control node, as the error that names it
/// (`case` names the case file).
///
/// ```
/// use aeroshape::reach::{VariableReach, check_live};
/// let r = vec![VariableReach { name: "waist".into(), modifier: "fus".into(), nodes_moved: 0 }];
/// let e = check_live(&r, "case.ron".as_ref()).unwrap_err();
/// assert_eq!(e.to_string(), "case.ron: design variable \"waist\" (modifier \"fus\") moves no control node");
/// ```
pub fn check_live(reach: &[VariableReach], case: &Path) -> Result<(), CaseError> {
    match reach.iter().find(|r| r.nodes_moved == 0) {
        Some(r) => Err(CaseError::DeadVariable {
            path: case.display().to_string(),
            variable: r.name.clone(),
            modifier: r.modifier.clone(),
        }),
        None => Ok(()),
    }
}
