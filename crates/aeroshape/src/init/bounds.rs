//! The bounds of the default design space, checked by the study ([`check_bounds`]): each
//! variable alone at either bound must invert no cell of the grid (cells invalid in the
//! baseline grid are not counted, as in the deformation's guard); a bound that does not
//! (inverted cells, or an evaluation that fails, e.g. a junction that no longer intersects)
//! is halved until it does. A variable that still fails after the halvings is
//! returned as failed (`case init` leaves it out, with a note saying what failed).

use serde::Serialize;

use super::InitError;
use crate::study::Study;

/// The outcome of the check of every variable: those kept and those that failed.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Checked {
    /// The variables whose bounds were found, in registry order.
    pub kept: Vec<VariableCheck>,
    /// The variables that fail even at the smallest bound tried: name and what failed.
    pub failed: Vec<(String, String)>,
}

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

/// Checks each variable of `study` alone at either bound (halving the bound, at most
/// `max_halvings` times, until no cell is inverted and the evaluation succeeds) and returns
/// the checks in registry order. A variable still failing after the halvings is returned
/// in [`Checked::failed`] with the bound tried last and what failed there.
pub fn check_bounds(study: &Study, max_halvings: usize) -> Result<Checked, InitError> {
    let reach = crate::reach::variable_reach_of(study)?;
    let x0 = study.initial();
    let mut out = Checked::default();
    for (i, v) in study.registry().variables().iter().enumerate() {
        let mut bound = v.upper.min(-v.lower);
        let mut halvings = 0;
        loop {
            let mut q = [f64::NAN; 2];
            let mut failure = None;
            for (k, b) in [-bound, bound].into_iter().enumerate() {
                let mut x = x0.clone();
                x[i] = b;
                study.forget_warm_start();
                match study.evaluate(&x) {
                    Ok(ev) => {
                        q[k] = ev.report.quality_after.min;
                        // Cells invalid in the baseline grid do not count against the
                        // variable: only those it inverts (the guard's rule).
                        let (was, inverted) = (
                            ev.report.quality_before.inverted,
                            ev.report.quality_after.inverted,
                        );
                        if inverted > was {
                            failure =
                                Some(format!("{} inverted cells at {b:+.3e}", inverted - was));
                        }
                    }
                    Err(e) => failure = Some(format!("at {b:+.3e}: {e}")),
                }
                if failure.is_some() {
                    break;
                }
            }
            match failure {
                None => {
                    out.kept.push(VariableCheck {
                        name: v.name.clone(),
                        bound,
                        nodes_moved: reach[i].nodes_moved,
                        min_quality: q,
                        halvings,
                    });
                    break;
                }
                Some(why) if halvings == max_halvings => {
                    let e = InitError::Bounds {
                        variable: v.name.clone(),
                        bound,
                        why,
                    };
                    out.failed.push((v.name.clone(), e.to_string()));
                    break;
                }
                Some(_) => {
                    bound *= 0.5;
                    halvings += 1;
                }
            }
        }
    }
    Ok(out)
}
