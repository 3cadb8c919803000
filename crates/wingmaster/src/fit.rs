//! Least-squares fit of the section parametrisation (Eq. 39 thickness, B-spline camber) to
//! airfoil coordinates, minimising the normal distances from the points to the curve.
//!
//! Unknowns θ = (the ten parameters of Eq. 39, the extra thickness points, the interior camber
//! ordinates). For each input point q_i the foot σ_i on the section curve is found by a
//! safeguarded Gauss–Newton projection; the residual is the signed normal distance
//! d_i = n_i · (q_i − p(σ_i; θ)). Because (q_i − p) ⟂ p′ at the foot, ∂d_i/∂θ = −n_i · ∂p/∂θ
//! at fixed σ_i, which gives the Jacobian; θ is updated by Levenberg–Marquardt (Marquardt's
//! diagonal scaling), the feet are re-projected after every trial step. The camber ordinates
//! enter linearly and are solved jointly with the nonlinear thickness parameters.
//!
//! Minimax rounds ([`FitOptions::minimax_rounds`]): the least-squares solution is then
//! refined towards the smallest maximum distance by Lawson's iteratively reweighted least
//! squares: the weighted cost Σ w_i d_i² is minimised by the same Levenberg–Marquardt steps
//! (rows of the residual and the Jacobian scaled by √w_i), and between rounds
//! w_i ← w_i |d_i| / mean_j(w_j |d_j|). The round with the smallest max |d_i| is kept.

use nalgebra::{DMatrix, DVector};

use crate::airfoil::{Airfoil, Frame, NormalisedAirfoil};
use crate::camber::{CamberLine, camber_knots, greville};
use crate::error::{Error, Result};
use crate::section::{Section, SectionParams};
use crate::thickness::{N_NAMED, ThicknessParams, split_extra};

/// The minimax rounds chosen by the UIUC survey (`docs/perf-log/2026-12-07-sections.md`); the
/// survey's default. [`FitOptions::default`] keeps 0 (least squares, as before).
pub const DEFAULT_MINIMAX_ROUNDS: usize = 5;

/// Options of [`fit`].
#[derive(Debug, Clone, PartialEq)]
pub struct FitOptions {
    /// Number of camber control points, including the two end points (0, 0) and (1, 0)
    /// that the local frame fixes; m − 2 camber ordinates are fitted. At least 2.
    pub camber_points: usize,
    /// Extra thickness control points beyond the paper's P0..P8 (each adds x and z).
    pub thickness_extra: usize,
    /// Levenberg–Marquardt iteration limit.
    pub max_iterations: usize,
    /// Convergence: stop after three consecutive accepted steps that each reduce the sum of
    /// squared normal distances by less than this fraction.
    pub tolerance: f64,
    /// Rounds of Lawson's reweighting towards the minimax fit after the least-squares fit
    /// (0, the default: least squares only; [`DEFAULT_MINIMAX_ROUNDS`] is the surveyed
    /// choice). Each round multiplies every point's weight by its distance
    /// (normalised by the weighted mean) and refits from the previous solution; the round
    /// with the smallest maximum distance is returned.
    pub minimax_rounds: usize,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            camber_points: 8,
            thickness_extra: 0,
            max_iterations: 200,
            tolerance: 1e-4,
            minimax_rounds: 0,
        }
    }
}

impl FitOptions {
    /// Sets the number of camber control points.
    pub fn with_camber_points(mut self, m: usize) -> Self {
        self.camber_points = m;
        self
    }

    /// Sets the convergence tolerance (relative decrease of the sum of squares).
    pub fn with_tolerance(mut self, tol: f64) -> Self {
        self.tolerance = tol;
        self
    }

    /// Sets the number of minimax (Lawson) reweighting rounds; 0 gives the least-squares fit.
    pub fn with_minimax_rounds(mut self, n: usize) -> Self {
        self.minimax_rounds = n;
        self
    }

    /// Sets the number of extra thickness control points.
    pub fn with_thickness_extra(mut self, n: usize) -> Self {
        self.thickness_extra = n;
        self
    }

    /// Number of design variables of the fitted parametrisation:
    /// 10 + 2·extra + (camber points − 2).
    pub fn n_design_variables(&self) -> usize {
        N_NAMED + 2 * self.thickness_extra + self.camber_points.saturating_sub(2)
    }
}

/// The result of a fit: the parameters, the frame, the input points in local coordinates
/// with their feet on the fitted curve, and the error.
#[derive(Debug, Clone, PartialEq)]
pub struct SectionFit {
    /// The fitted parameters (local frame).
    pub params: SectionParams,
    /// The local frame of the input (file coordinates ↔ chords).
    pub frame: Frame,
    /// Input points in local coordinates, Selig order, upper surface first.
    pub points: Vec<[f64; 2]>,
    /// Foot parameter σ_i of each point on the fitted section.
    pub sigma: Vec<f64>,
    /// Signed normal distance of each point from the fitted section, in chords.
    pub distances: Vec<f64>,
    /// max |d_i|, chords.
    pub max_error: f64,
    /// RMS of d_i, chords.
    pub rms_error: f64,
    /// Levenberg–Marquardt iterations performed.
    pub iterations: usize,
    /// Number of design variables.
    pub n_design_variables: usize,
}

impl SectionFit {
    /// The fit's summary as JSON: the named thickness parameters, camber, extra thickness
    /// terms, trailing-edge thickness, errors, sizes and frame. This is the object that
    /// `aeroshape section fit --json` prints and Python's `SectionFit.as_dict()` returns.
    pub fn summary_json(&self) -> serde_json::Value {
        let t = &self.params.thickness;
        let frame = &self.frame;
        serde_json::json!({
            "name": self.params.name.trim(),
            "thickness": {
                "r0": t.r0, "z1": t.z1, "z2": t.z2, "xtmax": t.xtmax, "tmax": t.tmax,
                "crv4": t.crv4, "x6": t.x6, "z6": t.z6, "phi_te": t.phi_te, "d78": t.d78,
            },
            "camber": self.params.camber,
            "thickness_extra": t.extra,
            "te_thickness": self.params.te_thickness,
            "max_error": self.max_error,
            "rms_error": self.rms_error,
            "n_points": self.points.len(),
            "n_design_variables": self.n_design_variables,
            "iterations": self.iterations,
            "frame": {
                "le": frame.le, "chord": frame.chord, "angle_deg": frame.angle.to_degrees(),
            },
        })
    }
}

/// Fits the section parametrisation to an airfoil read from a file.
pub fn fit(airfoil: &Airfoil, opts: &FitOptions) -> Result<SectionFit> {
    let na = airfoil.normalise()?;
    fit_normalised(&na, &airfoil.name, opts)
}

struct Layout {
    n_thick: usize,
    camber_x: Vec<f64>,
}

impl Layout {
    fn params(&self, theta: &[f64], name: &str, te: f64) -> SectionParams {
        let m = self.camber_x.len();
        let mut camber = Vec::with_capacity(m);
        camber.push([self.camber_x[0], 0.0]);
        for l in 1..m - 1 {
            camber.push([self.camber_x[l], theta[self.n_thick + l - 1]]);
        }
        camber.push([self.camber_x[m - 1], 0.0]);
        SectionParams {
            name: name.to_string(),
            thickness: ThicknessParams::from_vec(&theta[..self.n_thick]),
            camber,
            te_thickness: te,
        }
    }
}

/// The section placed in the data frame: P = δ + M p with M = [[a, −b], [b, a]],
/// (a, b) = (1 − δx, −δz), so that the section's leading edge sits at δ and its trailing edge
/// stays at (1, 0). δ lets the fit place the leading edge between the data points.
struct Model {
    sec: Section,
    d: [f64; 2],
}

impl Model {
    fn ab(&self) -> (f64, f64) {
        (1.0 - self.d[0], -self.d[1])
    }

    fn map(&self, v: [f64; 2]) -> [f64; 2] {
        let (a, b) = self.ab();
        [a * v[0] - b * v[1], b * v[0] + a * v[1]]
    }

    fn eval(&self, sigma: f64) -> crate::section::SectionPoint {
        self.mapped(self.sec.eval(sigma))
    }

    /// A point of the section (local frame) placed in the data frame.
    fn mapped(&self, mut e: crate::section::SectionPoint) -> crate::section::SectionPoint {
        let p = self.map(e.p);
        e.p = [p[0] + self.d[0], p[1] + self.d[1]];
        e.dp = self.map(e.dp);
        e
    }
}

/// [`project`] that also returns the section point (local frame) at the returned foot, so
/// that the caller does not evaluate it again. The foot is the last σ at which the section
/// was evaluated: the final Newton step, below 1e-11, is not applied.
fn project_eval(sec: &Model, q: [f64; 2], sigma0: f64) -> (f64, crate::section::SectionPoint) {
    let mut s = sigma0;
    for _ in 0..30 {
        let eu = sec.sec.eval(s);
        let e = sec.mapped(eu);
        let r = [e.p[0] - q[0], e.p[1] - q[1]];
        let g = r[0] * e.dp[0] + r[1] * e.dp[1];
        let h = e.dp[0] * e.dp[0] + e.dp[1] * e.dp[1];
        if h <= 0.0 || !h.is_finite() {
            return (s, eu);
        }
        let step = (-g / h).clamp(-0.1, 0.1);
        let sn = (s + step).clamp(-1.0, 1.0);
        if (sn - s).abs() < 1e-11 {
            return (s, eu);
        }
        s = sn;
    }
    (s, sec.sec.eval(s))
}

/// The signed normal distance of q from the section point e (data frame) and the normal.
fn distance_from(e: &crate::section::SectionPoint, q: [f64; 2]) -> (f64, [f64; 2]) {
    let len = (e.dp[0] * e.dp[0] + e.dp[1] * e.dp[1]).sqrt();
    let n = if len > 0.0 {
        [-e.dp[1] / len, e.dp[0] / len]
    } else {
        [0.0, 1.0]
    };
    let d = n[0] * (q[0] - e.p[0]) + n[1] * (q[1] - e.p[1]);
    (d, n)
}

/// |d_i| of every point from its foot `e` (local frame) on the placed section.
fn abs_distances(sec: &Model, pts: &[[f64; 2]], evs: &[crate::section::SectionPoint]) -> Vec<f64> {
    pts.iter()
        .zip(evs)
        .map(|(&q, e)| distance_from(&sec.mapped(*e), q).0.abs())
        .collect()
}

/// Lawson's update of the minimax weights: w_i ← w_i |d_i| / mean_j(w_j |d_j|), floored
/// at 1e-6 so that no point drops out of the fit.
fn lawson_update(wts: &mut [f64], d: &[f64]) {
    let mean = wts.iter().zip(d).map(|(w, d)| w * d).sum::<f64>() / wts.len() as f64;
    if !(mean > 0.0 && mean.is_finite()) {
        return;
    }
    for (w, d) in wts.iter_mut().zip(d) {
        *w = (*w * d / mean).max(1e-6);
    }
}

/// Projects q onto the section starting from σ0 (Gauss–Newton on (p − q)·p′ = 0, clamped
/// to [−1, 1]).
fn project(sec: &Model, q: [f64; 2], sigma0: f64) -> f64 {
    let mut s = sigma0;
    for _ in 0..30 {
        let e = sec.eval(s);
        let r = [e.p[0] - q[0], e.p[1] - q[1]];
        let g = r[0] * e.dp[0] + r[1] * e.dp[1];
        let h = e.dp[0] * e.dp[0] + e.dp[1] * e.dp[1];
        if h <= 0.0 || !h.is_finite() {
            break;
        }
        let mut step = -g / h;
        // Limit the step so the linear model stays meaningful.
        step = step.clamp(-0.1, 0.1);
        let sn = (s + step).clamp(-1.0, 1.0);
        let done = (sn - s).abs() < 1e-11;
        s = sn;
        if done {
            break;
        }
    }
    s
}

fn normal_distance(sec: &Model, q: [f64; 2], s: f64) -> (f64, [f64; 2]) {
    distance_from(&sec.eval(s), q)
}

/// Initial feet: nearest of a sampling of the curve on the point's own surface.
fn initial_sigma(sec: &Model, pts: &[[f64; 2]], le_index: usize) -> Vec<f64> {
    let ns = 400;
    let samples: Vec<(f64, [f64; 2])> = (-ns..=ns)
        .map(|k| {
            let s = k as f64 / ns as f64;
            (s, sec.eval(s).p)
        })
        .collect();
    pts.iter()
        .enumerate()
        .map(|(i, &q)| {
            let side = if i < le_index {
                1.0
            } else if i > le_index {
                -1.0
            } else {
                0.0
            };
            let mut best = (0.0, f64::INFINITY);
            for &(s, p) in &samples {
                if side * s < 0.0 {
                    continue;
                }
                let d = (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2);
                if d < best.1 {
                    best = (s, d);
                }
            }
            project(sec, q, best.0)
        })
        .collect()
}

fn interp(xs: &[f64], zs: &[f64], x: f64) -> f64 {
    let n = xs.len();
    if x <= xs[0] {
        return zs[0];
    }
    if x >= xs[n - 1] {
        return zs[n - 1];
    }
    let k = xs.partition_point(|&v| v <= x).clamp(1, n - 1);
    let (x0, x1) = (xs[k - 1], xs[k]);
    if x1 <= x0 {
        return zs[k];
    }
    zs[k - 1] + (zs[k] - zs[k - 1]) * (x - x0) / (x1 - x0)
}

fn surface(points: &[[f64; 2]]) -> (Vec<f64>, Vec<f64>) {
    let mut p: Vec<[f64; 2]> = points.to_vec();
    p.sort_by(|a, b| a[0].total_cmp(&b[0]));
    (
        p.iter().map(|q| q[0]).collect(),
        p.iter().map(|q| q[1]).collect(),
    )
}

/// Places `n` extra points on the legs P2–P3 (front) and P6–P7 (rear) of the polygon of
/// `p` (without extras); true if the result is a valid polygon.
fn place_extras(p: &mut ThicknessParams, n: usize) -> bool {
    let (nf, na) = split_extra(n);
    p.extra.clear();
    let Ok(base) = p.polygon() else {
        return false;
    };
    let b = base.points();
    let leg = |i: usize, k: usize, m: usize| {
        let f = (k + 1) as f64 / (m + 1) as f64;
        [
            b[i][0] + f * (b[i + 1][0] - b[i][0]),
            b[i][1] + f * (b[i + 1][1] - b[i][1]),
        ]
    };
    let mut extra: Vec<[f64; 2]> = (0..nf).map(|k| leg(2, k, nf)).collect();
    extra.extend((0..na).map(|k| leg(6, k, na)));
    p.extra = extra;
    p.polygon().is_ok()
}

/// Initial parameters estimated from the data's thickness and camber distributions.
fn initial_guess(na: &NormalisedAirfoil, opts: &FitOptions, name: &str) -> Result<Vec<f64>> {
    let le = na.le_index;
    let (xu, zu) = surface(&na.points[..=le]);
    let (xl, zl) = surface(&na.points[le..]);
    let zt = |x: f64| 0.5 * (interp(&xu, &zu, x) - interp(&xl, &zl, x));
    let zc = |x: f64| 0.5 * (interp(&xu, &zu, x) + interp(&xl, &zl, x));
    let ng = 200;
    let xg: Vec<f64> = (0..=ng)
        .map(|k| 0.5 * (1.0 - (std::f64::consts::PI * k as f64 / ng as f64).cos()))
        .collect();
    let tg: Vec<f64> = xg.iter().map(|&x| zt(x)).collect();
    let imax = (1..ng)
        .max_by(|&a, &b| tg[a].total_cmp(&tg[b]))
        .unwrap_or(ng / 2);
    let h = tg[imax];
    if h <= 0.0 {
        return Err(Error::FitFailed {
            name: name.into(),
            iterations: 0,
            reason: "the upper surface does not lie above the lower one".into(),
        });
    }
    let xtmax = xg[imax].clamp(0.05, 0.9);
    // Curvature at the maximum: least-squares parabola over |x − xtmax| < 0.1.
    let (mut s0, mut s1, mut s2, mut s3, mut s4, mut b0, mut b1, mut b2) =
        (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for (k, &x) in xg.iter().enumerate() {
        let d = x - xtmax;
        if d.abs() < 0.1 {
            let z = tg[k];
            s0 += 1.0;
            s1 += d;
            s2 += d * d;
            s3 += d * d * d;
            s4 += d * d * d * d;
            b0 += z;
            b1 += d * z;
            b2 += d * d * z;
        }
    }
    let m = nalgebra::Matrix3::new(s0, s1, s2, s1, s2, s3, s2, s3, s4);
    let mut crv4 = m
        .lu()
        .solve(&nalgebra::Vector3::new(b0, b1, b2))
        .map(|c| 2.0 * c[2])
        .unwrap_or(f64::NAN);
    if crv4.is_nan() || crv4 >= -1e-3 * h || !crv4.is_finite() {
        crv4 = -3.75 * 2.0 * h;
    }
    // Leading-edge radius from points near the nose: r = (z² + x²) / (2x).
    let mut rs: Vec<f64> = na
        .points
        .iter()
        .filter(|p| p[0] > 1e-4 && p[0] < 0.01)
        .map(|p| {
            let z = p[1] - zc(p[0]);
            (z * z + p[0] * p[0]) / (2.0 * p[0])
        })
        .filter(|r| r.is_finite() && *r > 0.0)
        .collect();
    rs.sort_by(|a, b| a.total_cmp(b));
    let r0 = if rs.is_empty() {
        1.1 * 4.0 * h * h
    } else {
        rs[rs.len() / 2]
    };
    let x6 = xtmax + 0.55 * (1.0 - xtmax);
    let te = na.te_thickness;
    let rampv = |x: f64| crate::section::ramp(te, xtmax, x)[0];
    let z6 = (1.15 * (zt(x6) - rampv(x6))).clamp(0.05 * h, 0.95 * h);
    let (xa, xb) = (0.92, 0.99);
    let slope = ((zt(xb) - rampv(xb)) - (zt(xa) - rampv(xa))) / (xb - xa);
    let phi_te = 2.0 * (-slope).clamp(0.01, 1.0).atan();
    let d78 = 0.4 * (1.0 - x6);
    let mut p = ThicknessParams {
        r0,
        z1: 0.5 * h,
        z2: 0.9 * h,
        xtmax,
        tmax: 2.0 * h,
        crv4,
        x6,
        z6,
        phi_te,
        d78,
        extra: Vec::new(),
    };
    let mut ok = false;
    for _ in 0..40 {
        if place_extras(&mut p, opts.thickness_extra) {
            ok = true;
            break;
        }
        p.crv4 *= 1.5;
        p.z1 *= 0.85;
        p.r0 *= 1.2;
    }
    if !ok {
        return Err(Error::FitFailed {
            name: name.into(),
            iterations: 0,
            reason: format!(
                "no valid initial thickness polygon ({})",
                p.polygon().unwrap_err()
            ),
        });
    }
    let mut theta = p.to_vec();
    // Camber ordinates: linear least squares on the data camber line.
    let kv = camber_knots(opts.camber_points)?;
    let mc = opts.camber_points;
    if mc > 2 {
        let nfree = mc - 2;
        let mut a = DMatrix::<f64>::zeros(xg.len(), nfree);
        let mut bvec = DVector::<f64>::zeros(xg.len());
        for (k, &x) in xg.iter().enumerate() {
            let nb = kv.eval_all(x);
            for l in 0..nfree {
                a[(k, l)] = nb[l + 1];
            }
            bvec[k] = zc(x);
        }
        let ata = a.tr_mul(&a) + DMatrix::<f64>::identity(nfree, nfree) * 1e-10;
        let atb = a.tr_mul(&bvec);
        let sol = ata.cholesky().map(|c| c.solve(&atb));
        match sol {
            Some(s) => theta.extend(s.iter()),
            None => theta.extend(std::iter::repeat_n(0.0, nfree)),
        }
    }
    Ok(theta)
}

/// Fits the section parametrisation to an already normalised airfoil.
///
/// With extra thickness points two starts are tried: the data estimate, and the paper's
/// parametrisation fitted first with the extra points then placed on its polygon legs P2–P3
/// and P6–P7 (continuation); the better fit is returned.
pub fn fit_normalised(na: &NormalisedAirfoil, name: &str, opts: &FitOptions) -> Result<SectionFit> {
    if opts.thickness_extra == 0 {
        return Ok(fit_from(na, name, opts, None)?.0);
    }
    // Two starts: the data estimate, and the paper's fit continued with the extra points on
    // its polygon legs; the one with the smaller sum of squares is kept.
    let direct = fit_from(na, name, opts, None).map(|f| f.0);
    let base_opts = opts.clone().with_thickness_extra(0);
    let continued = fit_from(na, name, &base_opts, None).and_then(|(base, btheta)| {
        let mut p = base.params.thickness.clone();
        if !place_extras(&mut p, opts.thickness_extra) {
            return Err(Error::FitFailed {
                name: name.into(),
                iterations: base.iterations,
                reason: "extra points cannot be placed on the fitted polygon".into(),
            });
        }
        let mut start = p.to_vec();
        start.extend_from_slice(&btheta[N_NAMED..]);
        Ok(fit_from(na, name, opts, Some(start))?.0)
    });
    match (direct, continued) {
        (Ok(a), Ok(b)) => {
            // The measure that the fit minimises: the maximum distance after minimax rounds.
            let m = |f: &SectionFit| {
                if opts.minimax_rounds > 0 {
                    f.max_error
                } else {
                    f.rms_error
                }
            };
            Ok(if m(&b) < m(&a) { b } else { a })
        }
        (Ok(a), Err(_)) => Ok(a),
        (Err(_), Ok(b)) => Ok(b),
        (Err(e), Err(_)) => Err(e),
    }
}

/// The fit from a given start θ (thickness, camber ordinates, δ) or from the data estimate;
/// returns the fit and its raw θ in the data frame.
fn fit_from(
    na: &NormalisedAirfoil,
    name: &str,
    opts: &FitOptions,
    start: Option<Vec<f64>>,
) -> Result<(SectionFit, Vec<f64>)> {
    if opts.camber_points < 2 {
        return Err(Error::InvalidSection {
            parameter: "camber_points".into(),
            value: opts.camber_points as f64,
            reason: "at least 2 are needed".into(),
        });
    }
    let kv = camber_knots(opts.camber_points)?;
    let layout = Layout {
        n_thick: N_NAMED + 2 * opts.thickness_extra,
        camber_x: greville(&kv),
    };
    let te = na.te_thickness;
    let pts = &na.points;
    let npts = pts.len();
    let mut theta = match start {
        Some(t) => t,
        None => {
            let mut t = initial_guess(na, opts, name)?;
            t.extend([0.0, 0.0]);
            t
        }
    };
    let np = theta.len();
    let nd = theta.len() - 2;
    let build = |theta: &[f64]| -> Result<Model> {
        let d = [theta[nd], theta[nd + 1]];
        if d[0].hypot(d[1]) > 0.05 {
            return Err(Error::InvalidSection {
                parameter: "leading-edge offset".into(),
                value: d[0].hypot(d[1]),
                reason: "more than 0.05 chord from the data's leading-edge point".into(),
            });
        }
        Ok(Model {
            sec: layout.params(&theta[..nd], name, te).build()?,
            d,
        })
    };
    let mut sec = build(&theta)?;
    let mut sigma = initial_sigma(&sec, pts, na.le_index);
    // The section points at the feet (local frame), kept with σ so that the Jacobian and the
    // cost need no further evaluation.
    let mut evs: Vec<crate::section::SectionPoint> =
        sigma.iter().map(|&s| sec.sec.eval(s)).collect();
    let mut wts = vec![1.0f64; npts];
    let eval_cost = |sec: &Model, evs: &[crate::section::SectionPoint], wts: &[f64]| -> f64 {
        pts.iter()
            .zip(evs)
            .zip(wts)
            .map(|((&q, e), w)| w * distance_from(&sec.mapped(*e), q).0.powi(2))
            .sum()
    };
    let mut cost = eval_cost(&sec, &evs, &wts);
    // The best state over the reweighting rounds: (max |d_i|, θ, σ, feet).
    type Snapshot = (f64, Vec<f64>, Vec<f64>, Vec<crate::section::SectionPoint>);
    let mut best: Option<Snapshot> = None;
    let mut lambda = 1e-3;
    let mut nu = 2.0;
    let mut iterations = 0;
    let mut slow = 0;
    let mut jac = DMatrix::<f64>::zeros(npts, np);
    let mut res = DVector::<f64>::zeros(npts);
    let nt = layout.n_thick;
    let camber_kv = kv;
    for round in 0..=opts.minimax_rounds {
        if round > 0 {
            let ds = abs_distances(&sec, pts, &evs);
            lawson_update(&mut wts, &ds);
            cost = eval_cost(&sec, &evs, &wts);
            (lambda, nu, slow) = (1e-3, 2.0, 0);
        }
        for _ in 0..opts.max_iterations {
            iterations += 1;
            // Jacobian at the current feet.
            let (poly, pjac) =
                ThicknessParams::from_vec(&theta[..nt]).polygon_with_jacobian(true)?;
            let tk = poly.knots();
            let p = tk.degree();
            let mut local = vec![0.0; p + 1];
            let mut cb = vec![0.0; camber_kv.degree() + 1];
            for (i, (&q, &e)) in pts.iter().zip(&evs).enumerate() {
                let (d, n) = distance_from(&sec.mapped(e), q);
                let sw = wts[i].sqrt();
                res[i] = sw * d;
                let x = e.p[0];
                let (ma, mb) = sec.ab();
                // Frame columns: ∂P/∂δx = (1 − px, −pz), ∂P/∂δz = (pz, 1 − px).
                jac[(i, nd)] = -(n[0] * (1.0 - e.p[0]) - n[1] * e.p[1]);
                jac[(i, nd + 1)] = -(n[0] * e.p[1] + n[1] * (1.0 - e.p[0]));
                let n = [ma * n[0] + mb * n[1], -mb * n[0] + ma * n[1]];
                let span = tk.basis_into(e.t, &mut local);
                let c = sec.sec.camber_z(x);
                let r = sec.sec.ramp(x);
                for j in 0..nt {
                    let (mut dx, mut dz) = (0.0, 0.0);
                    for (a, b) in local.iter().enumerate() {
                        let dp = pjac[span - p + a][j];
                        dx += b * dp[0];
                        dz += b * dp[1];
                    }
                    let mut dzs = dz + r[1] * dx;
                    if j == 3 {
                        dzs += r[2];
                    }
                    let pz = c[1] * dx + e.sign * dzs;
                    jac[(i, j)] = -(n[0] * dx + n[1] * pz);
                }
                if nd > nt {
                    let cspan = camber_kv.basis_into(x.clamp(0.0, 1.0), &mut cb);
                    let cp = camber_kv.degree();
                    for j in nt..nd {
                        jac[(i, j)] = 0.0;
                    }
                    for (a, b) in cb.iter().enumerate() {
                        let l = cspan - cp + a;
                        if l >= 1 && l + 1 < opts.camber_points {
                            jac[(i, nt + l - 1)] = -n[1] * b;
                        }
                    }
                }
                if sw != 1.0 {
                    for j in 0..np {
                        jac[(i, j)] *= sw;
                    }
                }
            }
            // JᵀJ from the column dot products, upper triangle mirrored (half the work).
            let mut a = DMatrix::<f64>::zeros(np, np);
            for k in 0..np {
                let ck = jac.column(k);
                for l in k..np {
                    let v = ck.dot(&jac.column(l));
                    a[(k, l)] = v;
                    a[(l, k)] = v;
                }
            }
            let g = jac.tr_mul(&res);
            let dmax = (0..np).map(|k| a[(k, k)]).fold(0.0f64, f64::max);
            let mut accepted = false;
            while lambda < 1e12 {
                let mut m = a.clone();
                let mut dg = vec![0.0; np];
                for k in 0..np {
                    dg[k] = a[(k, k)].max(1e-12 * dmax);
                    m[(k, k)] += lambda * dg[k];
                }
                let Some(ch) = m.cholesky() else {
                    lambda *= 10.0;
                    continue;
                };
                let delta = ch.solve(&(-&g));
                let trial: Vec<f64> = theta.iter().zip(delta.iter()).map(|(t, d)| t + d).collect();
                let Ok(tsec) = build(&trial) else {
                    lambda *= 10.0;
                    continue;
                };
                let (tsig, tevs): (Vec<f64>, Vec<crate::section::SectionPoint>) = pts
                    .iter()
                    .zip(&sigma)
                    .map(|(&q, &s)| project_eval(&tsec, q, s))
                    .unzip();
                let tcost = eval_cost(&tsec, &tevs, &wts);
                if tcost < cost {
                    let rel = (cost - tcost) / cost.max(1e-300);
                    // Gain ratio: actual decrease over the decrease of the linear model,
                    // L(0) − L(δ) = δᵀAδ + 2λ δᵀDδ (from (A + λD)δ = −g).
                    let ad = &a * &delta;
                    let pred = delta.dot(&ad)
                        + 2.0 * lambda * (0..np).map(|k| dg[k] * delta[k] * delta[k]).sum::<f64>();
                    let rho = if pred > 0.0 {
                        (cost - tcost) / pred
                    } else {
                        0.0
                    };
                    theta = trial;
                    sec = tsec;
                    sigma = tsig;
                    evs = tevs;
                    cost = tcost;
                    // Nielsen's update of the damping.
                    lambda =
                        (lambda * (1.0 / 3.0f64).max(1.0 - (2.0 * rho - 1.0).powi(3))).max(1e-9);
                    nu = 2.0;
                    accepted = true;
                    slow = if rel < opts.tolerance { slow + 1 } else { 0 };
                    if slow >= 3 {
                        lambda = 1e12; // converged
                    }
                    break;
                }
                lambda *= nu;
                nu *= 2.0;
            }
            if !accepted || lambda >= 1e12 {
                break;
            }
        }
        let mx = abs_distances(&sec, pts, &evs)
            .into_iter()
            .fold(0.0, f64::max);
        if best.as_ref().is_none_or(|b| mx < b.0) {
            best = Some((mx, theta.clone(), sigma.clone(), evs.clone()));
        }
    }
    // Keep the round with the smallest maximum distance.
    if let Some((mx, t, sg, _)) = best {
        let now = abs_distances(&sec, pts, &evs)
            .into_iter()
            .fold(0.0, f64::max);
        if mx < now {
            sec = build(&t)?;
            (theta, sigma) = (t, sg);
        }
    }
    // The final frame: leading edge at δ, chord scaled by |(a, b)|, rotated by arg(a, b).
    let (ma, mb) = sec.ab();
    let old = na.frame;
    let frame = Frame {
        le: old.to_global(sec.d),
        chord: old.chord * ma.hypot(mb),
        angle: old.angle + mb.atan2(ma),
    };
    let local: Vec<[f64; 2]> = pts
        .iter()
        .map(|&q| frame.to_local(old.to_global(q)))
        .collect();
    let unit = Model {
        sec: sec.sec,
        d: [0.0, 0.0],
    };
    let mut distances = Vec::with_capacity(npts);
    for (&q, &s) in local.iter().zip(&sigma) {
        distances.push(normal_distance(&unit, q, s).0);
    }
    let max_error = distances.iter().fold(0.0f64, |m, d| m.max(d.abs()));
    let rms_error = (distances.iter().map(|d| d * d).sum::<f64>() / npts as f64).sqrt();
    let params = layout.params(&theta[..nd], name, te);
    let fit = SectionFit {
        params,
        frame,
        points: local,
        sigma,
        distances,
        max_error,
        rms_error,
        iterations,
        n_design_variables: opts.n_design_variables(),
    };
    Ok((fit, theta))
}

impl SectionFit {
    /// The fitted section.
    pub fn section(&self) -> Result<Section> {
        self.params.build()
    }

    /// The camber line of the fit.
    pub fn camber(&self) -> Result<CamberLine> {
        CamberLine::new(self.params.camber.clone())
    }
}
