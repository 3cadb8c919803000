//! The default design space of `case init` ([`candidate_space`]) and its bounds, checked by
//! the study ([`check_bounds`]): each variable alone at either bound must leave every cell
//! of the grid valid; a bound that does not is halved until it does.
//!
//! The space is what can be built on any imported wall without knowing which surface is a
//! wing and which a fuselage: per wall surface, one smooth bump along the surface normal
//! (surface level, Eq. 38, the middle Bernstein function of degree 2 in u and in v: zero on
//! the border of the surface's parameter domain, largest at its centre), named after the
//! surface (`wing.D123.bump`). The planform and section variables of §6 (`wing.twist.tip`,
//! `fuselage.waist`, …) need the roles and control nodes of the import (wing, fuselage,
//! junctions) and are not made here yet.

use geom_db::GeomDb;
use param::{
    Basis, DesignVariable, Direction, Modifier, Parametrisation, SurfaceForm, SurfaceModifier,
};
use serde::Serialize;

use super::InitError;
use crate::study::Study;

/// One design variable of the default space with its checked bounds.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct VariableCheck {
    /// The variable.
    pub name: String,
    /// Its bounds after the check (symmetric about 0).
    pub bound: f64,
    /// Control nodes it moves.
    pub nodes_moved: usize,
    /// Smallest cell quality with the variable alone at its lower and at its upper bound.
    pub min_quality: [f64; 2],
    /// Halvings of the first bound the check needed.
    pub halvings: usize,
}

/// A readable name of a surface component for variable names: its name (the import's
/// `role.entity`), else `component k`.
fn component_name(db: &GeomDb, k: usize) -> String {
    let n = db.surface_components[k].name.replace(' ', "_");
    if n.is_empty() {
        format!("component{k}")
    } else {
        n
    }
}

/// One bump on the support surface of each surface component of `walls` (indices; the
/// first component of a surface names it), with the bound `bound`.
pub fn candidate_space(db: &GeomDb, walls: &[usize], bound: f64) -> Parametrisation {
    let mut seen = Vec::new();
    let mut modifiers = Vec::new();
    for &k in walls {
        let surface = db.surface_components[k].surface;
        if seen.contains(&surface) {
            continue;
        }
        seen.push(surface);
        let name = component_name(db, k);
        modifiers.push(Modifier::Surface(SurfaceModifier {
            name: format!("{name}.bump"),
            surfaces: vec![surface],
            range_u: None,
            range_v: None,
            basis_u: Basis::Bernstein { degree: 2 },
            basis_v: Basis::Bernstein { degree: 2 },
            active_u: Some(vec![1]),
            active_v: Some(vec![1]),
            direction: Direction::Normal,
            form: SurfaceForm::Tensor {
                variables: vec![
                    DesignVariable::new(format!("{name}.bump"), -bound, bound)
                        .with_group(name)
                        .with_scale(bound / 10.0),
                ],
            },
        }));
    }
    Parametrisation {
        modifiers,
        constraints: Vec::new(),
    }
}

/// Checks each variable of `study` alone at either bound (halving the bound, at most
/// `max_halvings` times, until no cell is inverted) and returns the checks in registry
/// order. A variable still inverting cells after the halvings is an error naming it.
pub fn check_bounds(study: &Study, max_halvings: usize) -> Result<Vec<VariableCheck>, InitError> {
    let reach = crate::reach::variable_reach_of(study)?;
    let x0 = study.initial();
    let mut out = Vec::new();
    for (i, v) in study.registry().variables().iter().enumerate() {
        let mut bound = v.upper.min(-v.lower);
        let mut halvings = 0;
        loop {
            let mut q = [0.0; 2];
            let mut ok = true;
            for (k, b) in [-bound, bound].into_iter().enumerate() {
                let mut x = x0.clone();
                x[i] = b;
                study.forget_warm_start();
                match study.evaluate(&x) {
                    Ok(ev) => {
                        q[k] = ev.report.quality_after.min;
                        ok &= ev.report.quality_after.inverted == 0;
                    }
                    Err(_) => {
                        q[k] = f64::NAN;
                        ok = false;
                    }
                }
            }
            if ok {
                out.push(VariableCheck {
                    name: v.name.clone(),
                    bound,
                    nodes_moved: reach[i].nodes_moved,
                    min_quality: q,
                    halvings,
                });
                break;
            }
            if halvings == max_halvings {
                return Err(InitError::Bounds {
                    variable: v.name.clone(),
                    bound,
                });
            }
            bound *= 0.5;
            halvings += 1;
        }
    }
    Ok(out)
}
