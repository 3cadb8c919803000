//! A wing section built from its parameters (§6.1): thickness B-splines plus camber line,
//! evaluated on one curve parameter σ ∈ [−1, 1] that runs from the trailing edge over the
//! lower surface (σ < 0) through the leading edge (σ = 0) to the upper surface (σ > 0).
//!
//! Upper and lower surfaces are z = z_c(x) ± (z_t + z_te(x)) with the half-thickness added
//! vertically (perpendicular to the chord), where (x, z_t)(|σ|) is the thickness B-spline and
//! z_te(x) = (te/2) w³, w = max(0, (x − xtmax)/(1 − xtmax)) carries a blunt trailing edge of
//! thickness te without touching conditions 1–6 (value, slope and curvature at P4 and the
//! leading edge are unchanged).

use std::io::{self, Write};

use crate::camber::CamberLine;
use crate::error::Result;
use crate::piecewise::Piecewise;
use crate::thickness::{ThicknessParams, ThicknessPolygon};

/// The parameters of a section: the PARAMS.ron format of `aeroshape section build`
/// (documented in `docs/formats/section-ron.md`).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SectionParams {
    /// A name written on the first line of Selig output.
    #[serde(default)]
    pub name: String,
    /// The thickness parameters of Eq. (39).
    pub thickness: ThicknessParams,
    /// The camber polygon Q_j as (x, z), abscissae increasing; at least 2 points.
    pub camber: Vec<[f64; 2]>,
    /// Trailing-edge thickness in chords (0 for a sharp trailing edge).
    #[serde(default)]
    pub te_thickness: f64,
}

/// A built section, ready for evaluation.
#[derive(Debug, Clone, PartialEq)]
pub struct Section {
    thickness: ThicknessPolygon,
    camber: CamberLine,
    te_thickness: f64,
    xtmax: f64,
    thickness_pw: Piecewise,
    camber_pw: Piecewise,
}

/// A point of the section and its derivative with respect to σ.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SectionPoint {
    /// Position (x, z) in chords.
    pub p: [f64; 2],
    /// dp/dσ.
    pub dp: [f64; 2],
    /// Thickness-curve parameter t = |σ|.
    pub t: f64,
    /// +1 on the upper surface, −1 on the lower.
    pub sign: f64,
}

impl SectionParams {
    /// Builds the section (conditions 1–6, camber line).
    pub fn build(&self) -> Result<Section> {
        Section::new(
            self.thickness.polygon()?,
            CamberLine::new(self.camber.clone())?,
            self.te_thickness,
            self.thickness.xtmax,
        )
    }
}

impl Section {
    /// A section from its parts.
    pub fn new(
        thickness: ThicknessPolygon,
        camber: CamberLine,
        te_thickness: f64,
        xtmax: f64,
    ) -> Result<Self> {
        if !(te_thickness.is_finite() && te_thickness >= 0.0) {
            return Err(crate::Error::InvalidSection {
                parameter: "te_thickness".into(),
                value: te_thickness,
                reason: "must be finite and non-negative".into(),
            });
        }
        let thickness_pw = Piecewise::new(thickness.knots(), thickness.points())?;
        let camber_pw = Piecewise::new(camber.knots(), camber.points())?;
        Ok(Self {
            thickness,
            camber,
            te_thickness,
            xtmax,
            thickness_pw,
            camber_pw,
        })
    }

    /// The thickness polygon.
    pub fn thickness(&self) -> &ThicknessPolygon {
        &self.thickness
    }

    /// The camber line.
    pub fn camber(&self) -> &CamberLine {
        &self.camber
    }

    /// Trailing-edge thickness.
    pub fn te_thickness(&self) -> f64 {
        self.te_thickness
    }

    /// The blunt-trailing-edge ramp z_te(x) and its derivatives with respect to x and xtmax.
    pub(crate) fn ramp(&self, x: f64) -> [f64; 3] {
        ramp(self.te_thickness, self.xtmax, x)
    }

    /// The point at σ and dp/dσ.
    pub fn eval(&self, sigma: f64) -> SectionPoint {
        let sign = if sigma >= 0.0 { 1.0 } else { -1.0 };
        let t = sigma.abs().min(1.0);
        let d = self.thickness_pw.d2(t);
        let (x, zt) = (d[0][0], d[0][1]);
        let (xs, zts) = (d[1][0], d[1][1]);
        let c = self.camber_z(x);
        let r = self.ramp(x);
        let p = [x, c[0] + sign * (zt + r[0])];
        let dps = [xs, c[1] * xs + sign * (zts + r[1] * xs)];
        SectionPoint {
            p,
            dp: [sign * dps[0], sign * dps[1]],
            t,
            sign,
        }
    }

    /// z_c(x) and its first two x-derivatives (fast path of [`CamberLine::z_ders`]).
    pub fn camber_z(&self, x: f64) -> [f64; 3] {
        let u = self.camber.u_at_x(x);
        let d = self.camber_pw.d2(u);
        let (xu, zu) = (d[1][0], d[1][1]);
        let (xuu, zuu) = (d[2][0], d[2][1]);
        [d[0][1], zu / xu, (zuu * xu - zu * xuu) / (xu * xu * xu)]
    }

    /// The surface heights (upper, lower) at abscissa x ∈ [0, 1].
    pub fn heights_at(&self, x: f64) -> (f64, f64) {
        let t = self.thickness.t_at_x(x);
        let zt = self.thickness.point(t)[1];
        let c = self.camber.z_ders(x)[0];
        let r = self.ramp(x)[0];
        (c + zt + r, c - zt - r)
    }

    /// `n_per_surface` + 1 points per surface at cosine-spaced abscissae, in Selig order
    /// (trailing edge, upper surface, leading edge, lower surface, trailing edge); 2n + 1
    /// points in all.
    pub fn sample(&self, n_per_surface: usize) -> Vec<[f64; 2]> {
        let n = n_per_surface.max(2);
        let sig: Vec<f64> = (0..=n)
            .map(|k| {
                let x = 0.5 * (1.0 - (std::f64::consts::PI * k as f64 / n as f64).cos());
                self.thickness.t_at_x(x)
            })
            .collect();
        let mut out = Vec::with_capacity(2 * n + 1);
        for k in (0..=n).rev() {
            out.push(self.eval(sig[k]).p);
        }
        for &t in &sig[1..] {
            out.push(self.eval(-t).p);
        }
        out
    }
}

pub(crate) fn ramp(te: f64, xtmax: f64, x: f64) -> [f64; 3] {
    if te == 0.0 || x <= xtmax {
        return [0.0, 0.0, 0.0];
    }
    let l = 1.0 - xtmax;
    let w = (x - xtmax) / l;
    let h = 0.5 * te;
    // d/dx and d/dxtmax of h w³: dw/dx = 1/l, dw/dxtmax = (x − 1)/l².
    [
        h * w * w * w,
        3.0 * h * w * w / l,
        3.0 * h * w * w * (x - 1.0) / (l * l),
    ]
}

/// Writes points in Selig format: the name line, then one `x z` pair per line.
pub fn write_selig(w: &mut dyn Write, name: &str, points: &[[f64; 2]]) -> io::Result<()> {
    writeln!(w, "{}", name.trim())?;
    for p in points {
        writeln!(w, "{:>12.8} {:>12.8}", p[0], p[1])?;
    }
    Ok(())
}
