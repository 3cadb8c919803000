//! The safeguarded, box-constrained Newton minimiser in a few parameters: the one Newton of
//! the workspace. It serves the foot of the normal (Eq. 11, [`crate::invert`]), the
//! support-curve update (Eq. 12, as least squares) and corners (Eq. 13) in `intersect`, the
//! sliding boundary nodes of `deform` and the fixtures of `xtask`.
//!
//! Each iteration: the active set (parameters at a bound whose gradient pushes outward) is
//! frozen; the reduced Newton system H_FF δ_F = −g_F is solved by Cholesky, with a
//! Levenberg–Marquardt shift μI added (μ = 1e-10 max diag H, growing ×100) while H_FF + μI is
//! not positive definite or δ is not a descent direction; the step is projected onto the
//! parameter box and halved until the Armijo condition f(x + αδ) ≤ f(x) + 1e-4 α g·δ holds
//! (or, at round-off level, where differences of f are noise, until the residual decreases
//! without f rising above its noise). Iterations are bounded; convergence is decided on a
//! problem-specific residual in length units against an absolute tolerance that the caller
//! derives from the model size. After convergence up to three polishing steps are taken
//! (kept while the residual halves), so residuals usually end at round-off.
//!
//! When no descent is possible any more (round-off, or bounds that clamp the step to nothing)
//! or the iterations are spent, a residual within 16× the tolerance is accepted as converged
//! and reported as it is ([`NewtonReport`]).
//!
//! [`pair`] holds the one problem that two crates solve with it: the intersection point of
//! two surfaces with one parameter frozen (Eq. 12);
//! [`line`](mod@line) holds the intersection of a straight line and a surface (thickness constraints).

use nalgebra::{SMatrix, SVector};

pub mod line;
pub mod pair;

/// Objective value, gradient and (approximate) Hessian at a point.
#[derive(Debug, Clone, Copy)]
pub struct Eval<const N: usize> {
    /// f(x).
    pub f: f64,
    /// ∇f(x).
    pub g: SVector<f64, N>,
    /// The Hessian of f, or an approximation (Gauss–Newton JᵀJ for least squares).
    pub h: SMatrix<f64, N, N>,
    /// Residual in length units (problem-specific), computed with the active set.
    pub res: f64,
    /// Round-off level of f (absolute): differences of f below it are noise.
    pub fnoise: f64,
}

/// A minimisation problem in N bounded parameters.
pub trait Problem<const N: usize> {
    /// f, ∇f, H and the residual at x; `active[i]` tells that parameter i is held at a bound
    /// (the residual should then ignore that parameter's stationarity condition).
    fn eval(&self, x: &[f64; N], active: &[bool; N]) -> Eval<N>;
}

/// Settings of [`minimise`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Settings {
    /// Absolute tolerance of the residual (length units; derive it from the model size).
    pub tol: f64,
    /// Largest number of Newton iterations.
    pub max_iters: usize,
}

/// How a Newton solve ended.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct NewtonReport {
    /// The residual is within the tolerance (or within 16× it where no descent is possible
    /// any more, see the module documentation).
    pub converged: bool,
    /// Newton iterations made.
    pub iterations: usize,
    /// Final residual (length units).
    pub residual: f64,
    /// The tolerance the residual was held to.
    pub tolerance: f64,
}

/// Outcome of [`minimise`].
#[derive(Debug, Clone, Copy)]
pub struct Outcome<const N: usize> {
    /// The final parameters (inside the box).
    pub x: [f64; N],
    /// The evaluation at `x`.
    pub eval: Eval<N>,
    /// Parameters held at a bound at the end.
    pub active: [bool; N],
    /// Convergence, iterations and residual.
    pub report: NewtonReport,
}

fn active_set<const N: usize>(
    x: &[f64; N],
    g: &SVector<f64, N>,
    lo: &[f64; N],
    hi: &[f64; N],
) -> [bool; N] {
    let mut a = [false; N];
    for i in 0..N {
        a[i] = (x[i] <= lo[i] && g[i] > 0.0) || (x[i] >= hi[i] && g[i] < 0.0);
    }
    a
}

fn clamp<const N: usize>(x: &mut [f64; N], lo: &[f64; N], hi: &[f64; N]) {
    for i in 0..N {
        x[i] = x[i].clamp(lo[i], hi[i]);
    }
}

/// The reduced Newton step −H_FF⁻¹ g_F (zero on the active set), with a Levenberg–Marquardt
/// shift while H_FF is not positive definite or the step is not a descent direction.
fn newton_step<const N: usize>(e: &Eval<N>, active: &[bool; N]) -> Option<SVector<f64, N>> {
    let mut h = e.h;
    let mut g = e.g;
    for i in 0..N {
        if active[i] {
            g[i] = 0.0;
            for j in 0..N {
                h[(i, j)] = 0.0;
                h[(j, i)] = 0.0;
            }
            h[(i, i)] = 1.0;
        }
    }
    let scale = (0..N)
        .map(|i| h[(i, i)].abs())
        .fold(0.0, f64::max)
        .max(1e-300);
    let mut mu = 0.0;
    for _ in 0..12 {
        let mut hm = h;
        for i in 0..N {
            hm[(i, i)] += mu;
        }
        if let Some(ch) = hm.cholesky() {
            let d = -ch.solve(&g);
            if d.iter().all(|v| v.is_finite()) && d.dot(&g) <= 0.0 {
                return Some(d);
            }
        }
        mu = if mu == 0.0 { 1e-10 * scale } else { mu * 100.0 };
    }
    None
}

/// Minimises f over the box [lo, hi] from x0 (clamped into the box first).
///
/// ```
/// use geom_db::newton::{Eval, Problem, Settings, minimise};
/// use nalgebra::{SMatrix, SVector};
/// // f(x) = ½ (x − 2)², x ∈ [0, 1]: the minimum is on the bound x = 1
/// struct P;
/// impl Problem<1> for P {
///     fn eval(&self, x: &[f64; 1], active: &[bool; 1]) -> Eval<1> {
///         let g = x[0] - 2.0;
///         Eval { f: 0.5 * g * g, g: SVector::<f64, 1>::new(g), h: SMatrix::<f64, 1, 1>::new(1.0),
///                res: if active[0] { 0.0 } else { g.abs() }, fnoise: 0.0 }
///     }
/// }
/// let o = minimise(&P, [0.0], &[0.0], &[1.0], Settings { tol: 1e-12, max_iters: 20 });
/// assert!(o.report.converged && o.x[0] == 1.0 && o.active[0]);
/// ```
pub fn minimise<const N: usize, P: Problem<N> + ?Sized>(
    prob: &P,
    x0: [f64; N],
    lo: &[f64; N],
    hi: &[f64; N],
    s: Settings,
) -> Outcome<N> {
    let mut x = x0;
    clamp(&mut x, lo, hi);
    let mut active = [false; N];
    let mut e = prob.eval(&x, &active);
    active = active_set(&x, &e.g, lo, hi);
    e = prob.eval(&x, &active);
    let mut iters = 0;
    let mut stalled = false;
    let report = |e: &Eval<N>, iters: usize, converged: bool| NewtonReport {
        converged,
        iterations: iters,
        residual: e.res,
        tolerance: s.tol,
    };
    while iters < s.max_iters {
        if e.res <= s.tol {
            // one polishing step: Newton converges quadratically, so a last full step takes
            // the residual from the tolerance down to round-off; kept only if it helps
            // (up to three steps while the residual at least halves)
            for _ in 0..3 {
                let Some(d) = newton_step(&e, &active) else {
                    break;
                };
                let mut xt = [0.0; N];
                for i in 0..N {
                    xt[i] = x[i] + d[i];
                }
                clamp(&mut xt, lo, hi);
                let et = prob.eval(&xt, &active);
                let at = active_set(&xt, &et.g, lo, hi);
                if at == active && et.res < e.res && et.f <= e.f + e.fnoise.max(et.fnoise) {
                    let halved = et.res <= 0.5 * e.res;
                    x = xt;
                    e = et;
                    if halved {
                        continue;
                    }
                }
                break;
            }
            return Outcome {
                x,
                eval: e,
                active,
                report: report(&e, iters, true),
            };
        }
        iters += 1;
        let step = newton_step(&e, &active);
        let Some(d) = step else {
            stalled = true;
            break;
        };
        // projected backtracking line search
        let mut alpha = 1.0;
        let mut accepted = None;
        for _ in 0..40 {
            let mut xt = [0.0; N];
            for i in 0..N {
                xt[i] = x[i] + alpha * d[i];
            }
            clamp(&mut xt, lo, hi);
            if xt == x {
                break;
            }
            let dx = SVector::<f64, N>::from_fn(|i, _| xt[i] - x[i]);
            let et0 = prob.eval(&xt, &active);
            let at = active_set(&xt, &et0.g, lo, hi);
            let et = if at == active {
                et0
            } else {
                prob.eval(&xt, &at)
            };
            let armijo = et.f <= e.f + 1e-4 * e.g.dot(&dx);
            let roundoff = et.f <= e.f + e.fnoise.max(et.fnoise) && et.res < e.res;
            if armijo || roundoff {
                accepted = Some((xt, et, at));
                break;
            }
            alpha *= 0.5;
        }
        let Some((xt, et, at)) = accepted else {
            stalled = true;
            break;
        };
        x = xt;
        e = et;
        active = at;
    }
    // No descent possible any more (round-off, or a step that the bounds clamp to nothing) or
    // the iterations spent while still improving at round-off level (e.g. at a corner of the
    // domain): a residual within 16× the tolerance is accepted as converged and reported as
    // it is.
    let converged = e.res <= s.tol || ((stalled || iters >= s.max_iters) && e.res <= 16.0 * s.tol);
    Outcome {
        x,
        eval: e,
        active,
        report: report(&e, iters, converged),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rosenbrock-like valley with a bound that is active at the optimum.
    struct Quad;
    impl Problem<2> for Quad {
        fn eval(&self, x: &[f64; 2], active: &[bool; 2]) -> Eval<2> {
            // f = (x-3)^2 + 10 (y - x^2/4)^2
            let r = x[1] - 0.25 * x[0] * x[0];
            let f = (x[0] - 3.0).powi(2) + 10.0 * r * r;
            let g = SVector::<f64, 2>::new(2.0 * (x[0] - 3.0) - 10.0 * r * x[0], 20.0 * r);
            let h = SMatrix::<f64, 2, 2>::new(
                2.0 + 10.0 * (0.25 * x[0] * x[0]) * 2.0 * 0.5 * 2.0 - 10.0 * r,
                -10.0 * x[0],
                -10.0 * x[0],
                20.0,
            );
            let res = (0..2)
                .filter(|&i| !active[i])
                .map(|i| g[i].abs())
                .fold(0.0, f64::max);
            Eval {
                f,
                g,
                h,
                res,
                fnoise: 0.0,
            }
        }
    }

    #[test]
    fn unconstrained_and_bounded_minimum() {
        let s = Settings {
            tol: 1e-12,
            max_iters: 100,
        };
        let o = minimise(&Quad, [0.0, 0.0], &[-10.0, -10.0], &[10.0, 10.0], s);
        assert!(o.report.converged);
        assert!((o.x[0] - 3.0).abs() < 1e-10 && (o.x[1] - 2.25).abs() < 1e-10);
        // with x ≤ 2 the optimum is at x = 2, y = 1, bound active
        let o = minimise(&Quad, [0.0, 0.0], &[-10.0, -10.0], &[2.0, 10.0], s);
        assert!(o.report.converged, "{o:?}");
        assert_eq!(o.x[0], 2.0);
        assert!((o.x[1] - 1.0).abs() < 1e-10);
        assert!(o.active[0] && !o.active[1]);
    }

    #[test]
    fn bounded_iterations_report_failure() {
        let s = Settings {
            tol: 1e-14,
            max_iters: 2,
        };
        let o = minimise(&Quad, [-8.0, 9.0], &[-10.0, -10.0], &[10.0, 10.0], s);
        assert!(!o.report.converged);
        assert_eq!(o.report.iterations, 2);
        assert!(o.report.residual > 16.0 * s.tol);
        assert_eq!(o.report.tolerance, 1e-14);
    }
}
