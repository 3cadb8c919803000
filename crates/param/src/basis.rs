//! One-dimensional shape functions H_i(s), s ∈ [0, 1], of the line and surface modifiers
//! (Eqs. 36–38): Hicks–Henne bumps, Bernstein polynomials and B-splines.
//!
//! Every family evaluates to 0 outside [0, 1], so a node whose line parameter falls outside
//! the modifier's range is not moved.

use geom_db::bspline::{KnotVector, bernstein};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// One Hicks–Henne bump b(s) = sin^w(π s^m), m = ln ½ / ln p: zero at s = 0 and s = 1,
/// maximum 1 at s = p (the peak), narrower for larger w (the width exponent).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Bump {
    /// Peak position p ∈ (0, 1).
    pub peak: f64,
    /// Width exponent w > 0 (w = 1..4 typical; larger is narrower).
    pub width: f64,
}

impl Bump {
    /// b(s) (0 outside [0, 1]).
    pub fn eval(&self, s: f64) -> f64 {
        if !(0.0..=1.0).contains(&s) {
            return 0.0;
        }
        let m = 0.5f64.ln() / self.peak.ln();
        let x = (std::f64::consts::PI * s.powf(m)).sin().max(0.0);
        x.powf(self.width)
    }
}

/// A family of basis functions on [0, 1].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Basis {
    /// Hicks–Henne bumps, one function per bump.
    HicksHenne {
        /// The bumps.
        bumps: Vec<Bump>,
    },
    /// Bernstein polynomials B_{i,n}(s), i = 0..n: n + 1 functions.
    Bernstein {
        /// Degree n.
        degree: usize,
    },
    /// B-splines N_{i,p}(s): `n_basis` functions of degree p on clamped uniform knots over
    /// [0, 1], or on user knots (mapped linearly from their domain onto [0, 1]).
    BSpline {
        /// Degree p.
        degree: usize,
        /// Number of functions (ignored with user knots: knots − p − 1).
        #[serde(default)]
        n_basis: usize,
        /// User knot vector (non-decreasing; its domain [t_p, t_n] is mapped onto [0, 1]).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        knots: Option<Vec<f64>>,
    },
}

/// A [`Basis`] ready for evaluation (knot vector built and checked).
#[derive(Debug, Clone)]
pub enum Prepared {
    /// Hicks–Henne bumps.
    HicksHenne(Vec<Bump>),
    /// Bernstein polynomials of this degree.
    Bernstein(usize),
    /// B-splines on this knot vector.
    BSpline(KnotVector),
}

impl Basis {
    /// Checks the definition and builds the evaluator; `owner` names the modifier in errors.
    pub fn prepare(&self, owner: &str) -> Result<Prepared> {
        let bad = |reason: String| Error::BadModifier {
            modifier: owner.to_string(),
            reason,
        };
        match self {
            Basis::HicksHenne { bumps } => {
                for (i, b) in bumps.iter().enumerate() {
                    if !(b.peak > 0.0 && b.peak < 1.0) {
                        return Err(bad(format!(
                            "Hicks–Henne bump {i}: peak {} must be in (0, 1)",
                            b.peak
                        )));
                    }
                    if !(b.width > 0.0 && b.width.is_finite()) {
                        return Err(bad(format!(
                            "Hicks–Henne bump {i}: width {} must be positive",
                            b.width
                        )));
                    }
                }
                Ok(Prepared::HicksHenne(bumps.clone()))
            }
            Basis::Bernstein { degree } => {
                if *degree > 60 {
                    return Err(bad(format!("Bernstein degree {degree} above 60")));
                }
                Ok(Prepared::Bernstein(*degree))
            }
            Basis::BSpline {
                degree,
                n_basis,
                knots,
            } => {
                let kv = match knots {
                    Some(k) => KnotVector::new(*degree, k.clone()),
                    None => KnotVector::clamped_uniform(*degree, *n_basis),
                }
                .map_err(|e| bad(format!("B-spline basis: {e}")))?;
                Ok(Prepared::BSpline(kv))
            }
        }
    }
}

impl Prepared {
    /// Number of functions.
    pub fn len(&self) -> usize {
        match self {
            Prepared::HicksHenne(b) => b.len(),
            Prepared::Bernstein(n) => n + 1,
            Prepared::BSpline(kv) => kv.n_basis(),
        }
    }

    /// True when the family has no function.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// All functions at s (zeros outside [0, 1]).
    pub fn eval(&self, s: f64) -> Vec<f64> {
        let n = self.len();
        if !(0.0..=1.0).contains(&s) {
            return vec![0.0; n];
        }
        match self {
            Prepared::HicksHenne(b) => b.iter().map(|b| b.eval(s)).collect(),
            Prepared::Bernstein(d) => (0..=*d).map(|i| bernstein(*d, i, s)).collect(),
            Prepared::BSpline(kv) => {
                let (a, b) = kv.domain();
                kv.eval_all(a + s * (b - a))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hicks_henne_peak() {
        let b = Bump {
            peak: 0.3,
            width: 2.0,
        };
        assert!((b.eval(0.3) - 1.0).abs() < 1e-14);
        assert_eq!(b.eval(0.0), 0.0);
        assert!(b.eval(1.0).abs() < 1e-15);
        assert!(b.eval(0.29) < 1.0 && b.eval(0.31) < 1.0);
    }

    #[test]
    fn outside_is_zero() {
        let p = Basis::Bernstein { degree: 3 }.prepare("m").unwrap();
        assert_eq!(p.eval(-0.1), vec![0.0; 4]);
        assert_eq!(p.eval(1.5), vec![0.0; 4]);
    }
}
