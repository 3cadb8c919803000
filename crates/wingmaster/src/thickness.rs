//! The thickness distribution of §6.1: two quartic B-splines with polygons P0..P4 and P4..P8,
//! built from the ten parameters of Eq. (39) by conditions 1–6, optionally refined by extra
//! free control points (beyond the paper).
//!
//! Both pieces are clamped B-splines of degree 4 (each a single quartic Bézier segment when
//! no extra points are used). They are stored as one B-spline on t ∈ [0, 1] whose knot 0.5
//! has multiplicity 4, so that the curve is C0 at P4 by construction and the basis functions
//! B_i(t) of Eq. (40) are those of one [`KnotVector`]. The derivation of each condition is in
//! `docs/crates/wingmaster.md`.

use geom_db::bspline::KnotVector;

use crate::error::{Error, Result};

/// Degree of both thickness pieces.
pub const THICKNESS_DEGREE: usize = 4;

/// Number of named thickness parameters (Eq. 39).
pub const N_NAMED: usize = 10;

/// The names of the ten parameters of Eq. (39), in vector order.
pub const NAMES: [&str; N_NAMED] = [
    "r0", "z1", "z2", "xtmax", "tmax", "crv4", "x6", "z6", "phi_te", "d78",
];

/// The ten thickness parameters of Eq. (39) plus optional extra control points.
///
/// Lengths are in chords, angles in radians. The thickness is the half-thickness z_t(x).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ThicknessParams {
    /// Leading-edge radius of curvature r0 (> 0).
    pub r0: f64,
    /// Ordinate of P1 (its abscissa is 0: vertical tangent at the leading edge).
    pub z1: f64,
    /// Ordinate of P2 (its abscissa follows from r0).
    pub z2: f64,
    /// Position of the maximum thickness, x of P4.
    pub xtmax: f64,
    /// Maximum thickness (full thickness: P4 = (xtmax, tmax/2)).
    pub tmax: f64,
    /// Curvature d²z_t/dx² of the half-thickness at P4 (negative at a maximum).
    pub crv4: f64,
    /// Abscissa of the free point P6.
    pub x6: f64,
    /// Ordinate of the free point P6.
    pub z6: f64,
    /// Trailing-edge angle: the full included angle between upper and lower surfaces of the
    /// symmetric section, so that P8 − P7 makes the angle phi_te/2 with the chord.
    pub phi_te: f64,
    /// Distance |P8 − P7|.
    pub d78: f64,
    /// Extra free control points (beyond the paper): the first ⌈n/2⌉ are inserted in the
    /// front piece between P2 and P3, the others in the rear piece between P6 and P7.
    #[serde(default)]
    pub extra: Vec<[f64; 2]>,
}

/// A built thickness polygon: P0..P8 (plus extra points) and its B-spline basis.
#[derive(Debug, Clone, PartialEq)]
pub struct ThicknessPolygon {
    knots: KnotVector,
    points: Vec<[f64; 2]>,
    p4: usize,
}

/// Derivative coefficients of a clamped degree-4 B-spline with `n` control points at its
/// ends: (a, b) at the start with C'(0) = a (P1 − P0) and C''(0)·e_z contribution b·z2
/// (Σ of the three coefficients is zero), and the same at the end.
#[derive(Debug, Clone, Copy)]
struct EndCoeffs {
    a_start: f64,
    b_start: f64,
    a_end: f64,
    b_end: f64,
}

fn end_coeffs(n: usize) -> Result<EndCoeffs> {
    let p = THICKNESS_DEGREE;
    let kv = KnotVector::clamped_uniform(p, n)?;
    let (_, d0) = kv.basis_ders(0.0, 2);
    let (_, d1) = kv.basis_ders(1.0, 2);
    Ok(EndCoeffs {
        a_start: d0[1][1],
        b_start: d0[2][2],
        a_end: d1[1][p],
        b_end: d1[2][p - 2],
    })
}

/// Splits a number of extra points into (front, rear).
pub fn split_extra(n: usize) -> (usize, usize) {
    let front = n.div_ceil(2);
    (front, n - front)
}

fn invalid(parameter: &str, value: f64, reason: &str) -> Error {
    Error::InvalidSection {
        parameter: parameter.to_string(),
        value,
        reason: reason.to_string(),
    }
}

impl ThicknessParams {
    /// A plausible symmetric starting point of thickness `t` (NACA-00xx-like proportions).
    pub fn naca_like(t: f64) -> Self {
        let h = t / 2.0;
        Self {
            r0: 1.1 * t * t,
            z1: 0.5 * h,
            z2: 0.9 * h,
            xtmax: 0.3,
            tmax: t,
            crv4: -3.75 * t,
            x6: 0.65,
            z6: 0.75 * h,
            phi_te: 2.0 * (1.2 * t).atan(),
            d78: 0.15,
            extra: Vec::new(),
        }
    }

    /// The parameters as a vector: the ten named ones in [`NAMES`] order, then the extra
    /// points' (x, z).
    pub fn to_vec(&self) -> Vec<f64> {
        let mut v = vec![
            self.r0,
            self.z1,
            self.z2,
            self.xtmax,
            self.tmax,
            self.crv4,
            self.x6,
            self.z6,
            self.phi_te,
            self.d78,
        ];
        for e in &self.extra {
            v.extend_from_slice(e);
        }
        v
    }

    /// Inverse of [`to_vec`](Self::to_vec); `v.len()` must be 10 + 2·(number of extras).
    pub fn from_vec(v: &[f64]) -> Self {
        debug_assert!(v.len() >= N_NAMED && (v.len() - N_NAMED).is_multiple_of(2));
        Self {
            r0: v[0],
            z1: v[1],
            z2: v[2],
            xtmax: v[3],
            tmax: v[4],
            crv4: v[5],
            x6: v[6],
            z6: v[7],
            phi_te: v[8],
            d78: v[9],
            extra: v[N_NAMED..].chunks(2).map(|c| [c[0], c[1]]).collect(),
        }
    }

    /// Builds the polygon by conditions 1–6 of §6.1.
    pub fn polygon(&self) -> Result<ThicknessPolygon> {
        Ok(self.polygon_with_jacobian(false)?.0)
    }

    /// Builds the polygon and, if asked, its Jacobian: `jac[k][j]` = ∂(x_k, z_k)/∂v_j with
    /// v = [`to_vec`](Self::to_vec).
    pub fn polygon_with_jacobian(
        &self,
        with_jac: bool,
    ) -> Result<(ThicknessPolygon, Vec<Vec<[f64; 2]>>)> {
        let v = self.to_vec();
        for (i, x) in v.iter().enumerate() {
            if !x.is_finite() {
                let name = NAMES.get(i).copied().unwrap_or("extra");
                return Err(invalid(name, *x, "not finite"));
            }
        }
        if self.r0 <= 0.0 {
            return Err(invalid(
                "r0",
                self.r0,
                "leading-edge radius must be positive",
            ));
        }
        if self.tmax <= 0.0 {
            return Err(invalid("tmax", self.tmax, "must be positive"));
        }
        if !(self.xtmax > 0.0 && self.xtmax < 1.0) {
            return Err(invalid("xtmax", self.xtmax, "must lie in (0, 1)"));
        }
        if self.crv4 >= 0.0 {
            return Err(invalid(
                "crv4",
                self.crv4,
                "curvature at the maximum thickness must be negative",
            ));
        }
        if self.z1 <= 0.0 {
            return Err(invalid("z1", self.z1, "must be positive"));
        }
        if !(self.phi_te > 0.0 && self.phi_te < std::f64::consts::PI) {
            return Err(invalid("phi_te", self.phi_te, "must lie in (0, pi)"));
        }
        if self.d78 <= 0.0 {
            return Err(invalid("d78", self.d78, "must be positive"));
        }
        let (nf, na) = split_extra(self.extra.len());
        let n_front = 5 + nf;
        let n_rear = 5 + na;
        let cf = end_coeffs(n_front)?;
        let cr = end_coeffs(n_rear)?;
        let nv = v.len();
        let h = self.tmax / 2.0;
        let zero = vec![[0.0; 2]; nv];
        let mut pts: Vec<[f64; 2]> = Vec::with_capacity(n_front + n_rear - 1);
        let mut jac: Vec<Vec<[f64; 2]>> = Vec::new();
        let mut push = |p: [f64; 2], d: Vec<[f64; 2]>, pts: &mut Vec<[f64; 2]>| {
            pts.push(p);
            if with_jac {
                jac.push(d);
            }
        };
        // Condition 1: P0 = (0, 0).
        push([0.0, 0.0], zero.clone(), &mut pts);
        // Condition 4: x1 = 0 (vertical tangent); x2 from r0. With C'(0) = a (0, z1) and
        // C''(0) = (b x2, ·): κ = b x2 / (a² z1²), so x2 = a² z1² / (b r0).
        let mut d = zero.clone();
        d[1][1] = 1.0;
        push([0.0, self.z1], d, &mut pts);
        let k2 = cf.a_start * cf.a_start / cf.b_start;
        let x2 = k2 * self.z1 * self.z1 / self.r0;
        let mut d = zero.clone();
        d[1][0] = 2.0 * k2 * self.z1 / self.r0;
        d[0][0] = -x2 / self.r0;
        d[2][1] = 1.0;
        push([x2, self.z2], d, &mut pts);
        for k in 0..nf {
            let mut d = zero.clone();
            d[N_NAMED + 2 * k][0] = 1.0;
            d[N_NAMED + 2 * k + 1][1] = 1.0;
            push(self.extra[k], d, &mut pts);
        }
        // Condition 3 (front): z3 = z4 (zero slope); curvature z'' = b (z_prev − z4) /
        // (a² (x4 − x3)²) = crv4.
        let (zprev, iprev) = if nf == 0 {
            (self.z2, 2)
        } else {
            (self.extra[nf - 1][1], N_NAMED + 2 * (nf - 1) + 1)
        };
        let cfe = cf.b_end / (cf.a_end * cf.a_end);
        let arg3 = cfe * (zprev - h) / self.crv4;
        if arg3 <= 0.0 {
            return Err(invalid(
                if nf == 0 { "z2" } else { "extra" },
                zprev,
                "the point before P3 must lie below tmax/2 for a maximum at P4",
            ));
        }
        let d3 = arg3.sqrt();
        let mut d = zero.clone();
        // ∂d3/∂v = ∂arg/∂v / (2 d3); x3 = xtmax − d3.
        let g = 1.0 / (2.0 * d3);
        d[iprev][0] = -g * cfe / self.crv4;
        d[4][0] = -g * (-0.5 * cfe / self.crv4);
        d[5][0] = -g * (-arg3 / self.crv4);
        d[3][0] = 1.0;
        d[4][1] = 0.5;
        push([self.xtmax - d3, h], d, &mut pts);
        // Condition 2: P4 = (xtmax, tmax/2).
        let mut d = zero.clone();
        d[3][0] = 1.0;
        d[4][1] = 0.5;
        push([self.xtmax, h], d, &mut pts);
        let p4 = pts.len() - 1;
        // Condition 3 (rear): z5 = z4; curvature from P6.
        let crs = cr.b_start / (cr.a_start * cr.a_start);
        let arg5 = crs * (self.z6 - h) / self.crv4;
        if arg5 <= 0.0 {
            return Err(invalid(
                "z6",
                self.z6,
                "P6 must lie below tmax/2 for a maximum at P4",
            ));
        }
        let d5 = arg5.sqrt();
        let g = 1.0 / (2.0 * d5);
        let mut d = zero.clone();
        d[7][0] = g * crs / self.crv4;
        d[4][0] = g * (-0.5 * crs / self.crv4);
        d[5][0] = g * (-arg5 / self.crv4);
        d[3][0] += 1.0;
        d[4][1] = 0.5;
        push([self.xtmax + d5, h], d, &mut pts);
        // Condition 6: P6 free.
        let mut d = zero.clone();
        d[6][0] = 1.0;
        d[7][1] = 1.0;
        push([self.x6, self.z6], d, &mut pts);
        for k in nf..nf + na {
            let mut d = zero.clone();
            d[N_NAMED + 2 * k][0] = 1.0;
            d[N_NAMED + 2 * k + 1][1] = 1.0;
            push(self.extra[k], d, &mut pts);
        }
        // Condition 5: P7 = P8 + d78 (−cos(phi/2), sin(phi/2)).
        let (s, c) = (self.phi_te / 2.0).sin_cos();
        let mut d = zero.clone();
        d[8][0] = 0.5 * self.d78 * s;
        d[8][1] = 0.5 * self.d78 * c;
        d[9][0] = -c;
        d[9][1] = s;
        push([1.0 - self.d78 * c, self.d78 * s], d, &mut pts);
        // Condition 1: P8 = (1, 0).
        push([1.0, 0.0], zero, &mut pts);

        // Abscissae must increase (x0 = x1 = 0 by condition 4) so that z_t is a function of x.
        for k in 2..pts.len() {
            if pts[k][0] <= pts[k - 1][0] {
                return Err(invalid(
                    &format!("x of control point {k}"),
                    pts[k][0],
                    &format!(
                        "control-point abscissae must increase (point {} is at x = {})",
                        k - 1,
                        pts[k - 1][0]
                    ),
                ));
            }
        }
        let knots = combined_knots(n_front, n_rear)?;
        Ok((
            ThicknessPolygon {
                knots,
                points: pts,
                p4,
            },
            jac,
        ))
    }
}

/// One knot vector on [0, 1] for the two pieces: the front piece on [0, 0.5] and the rear
/// piece on [0.5, 1], with the knot 0.5 repeated 4 times (C0 join at P4).
fn combined_knots(n_front: usize, n_rear: usize) -> Result<KnotVector> {
    let p = THICKNESS_DEGREE;
    let f = KnotVector::clamped_uniform(p, n_front)?;
    let r = KnotVector::clamped_uniform(p, n_rear)?;
    let mut k: Vec<f64> = f.knots()[..f.knots().len() - 1]
        .iter()
        .map(|u| 0.5 * u)
        .collect();
    k.extend(r.knots()[p + 1..].iter().map(|u| 0.5 + 0.5 * u));
    // The join: p copies of 0.5 (front's p+1 end knots minus one, rear start knots dropped).
    Ok(KnotVector::new(p, k)?)
}

impl ThicknessPolygon {
    /// The control points P0..P8 (with the extra points in place).
    pub fn points(&self) -> &[[f64; 2]] {
        &self.points
    }

    /// Index of P4 in [`points`](Self::points).
    pub fn p4_index(&self) -> usize {
        self.p4
    }

    /// The B-spline basis B_i(t) of Eq. (40), t ∈ [0, 1].
    pub fn knots(&self) -> &KnotVector {
        &self.knots
    }

    /// The point (x, z_t) at t.
    pub fn point(&self, t: f64) -> [f64; 2] {
        self.knots.curve_point(&self.points, t)
    }

    /// The point and derivatives up to order `n` at t.
    pub fn ders(&self, t: f64, n: usize) -> Vec<[f64; 2]> {
        self.knots.curve_ders(&self.points, t, n)
    }

    /// The curve parameter t with x(t) = x (x(t) is monotone), by safeguarded Newton.
    pub fn t_at_x(&self, x: f64) -> f64 {
        let (mut lo, mut hi) = (0.0, 1.0);
        if x <= 0.0 {
            return 0.0;
        }
        if x >= 1.0 {
            return 1.0;
        }
        // Start from the control polygon: piecewise-linear guess.
        let mut t = 0.5;
        for _ in 0..60 {
            let d = self.ders(t, 1);
            let f = d[0][0] - x;
            if f > 0.0 {
                hi = t;
            } else {
                lo = t;
            }
            if f.abs() <= 1e-15 {
                break;
            }
            let mut tn = t - f / d[1][0];
            if !(tn > lo && tn < hi && tn.is_finite()) {
                tn = 0.5 * (lo + hi);
            }
            if (tn - t).abs() < 1e-16 {
                t = tn;
                break;
            }
            t = tn;
        }
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jacobian_matches_finite_differences() {
        let mut p = ThicknessParams::naca_like(0.12);
        p.extra = vec![[0.19, 0.054], [0.22, 0.058], [0.8, 0.03]];
        let (poly, jac) = p.polygon_with_jacobian(true).unwrap();
        let v = p.to_vec();
        for j in 0..v.len() {
            let h = 1e-7 * v[j].abs().max(1e-3);
            let mut vp = v.clone();
            vp[j] += h;
            let mut vm = v.clone();
            vm[j] -= h;
            let pp = ThicknessParams::from_vec(&vp).polygon().unwrap();
            let pm = ThicknessParams::from_vec(&vm).polygon().unwrap();
            for k in 0..poly.points().len() {
                for c in 0..2 {
                    let fd = (pp.points()[k][c] - pm.points()[k][c]) / (2.0 * h);
                    assert!(
                        (fd - jac[k][j][c]).abs() < 1e-6 * (1.0 + fd.abs()),
                        "d P{k}[{c}] / d v{j}: fd {fd} vs {}",
                        jac[k][j][c]
                    );
                }
            }
        }
    }

    #[test]
    fn combined_knots_have_join_of_multiplicity_four() {
        let k = combined_knots(5, 6).unwrap();
        assert_eq!(k.n_basis(), 10);
        assert_eq!(k.knots().iter().filter(|&&u| u == 0.5).count(), 4);
    }
}
