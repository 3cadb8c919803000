//! Wing planform (§6.2): area S, aspect ratio AR, span b, root and mean chord, taper ratios at
//! spanwise stations, sweep at a chosen chord fraction, dihedral, and per key section twist and
//! maximum thickness, with their dependencies resolved explicitly.
//!
//! The chord is piecewise linear in the spanwise fraction η = 2y/b ∈ [0, 1]:
//! c(η) = c_root τ(η), τ given by the taper ratios τ_k = c_k / c_root at stations η_k
//! (τ(0) = 1). With I = ∫₀¹ τ dη the mean chord is c̄ = c_root I, the (two-sided) area
//! S = b c̄ and AR = b² / S. Once the taper ratios are fixed, the planform size has two degrees
//! of freedom: exactly two of {S, AR, b, c_root, c̄} must be given, and not the pair
//! (c_root, c̄), which are tied by I. Anything else is reported as over- or
//! under-determined.

use crate::error::{Error, Result};

/// The planform data as the engineer gives them; `None` = not given (to be derived).
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PlanformSpec {
    /// Reference area S (both halves).
    pub area: Option<f64>,
    /// Aspect ratio b²/S.
    pub aspect_ratio: Option<f64>,
    /// Span b (tip to tip).
    pub span: Option<f64>,
    /// Root chord.
    pub root_chord: Option<f64>,
    /// Mean (geometric) chord S/b.
    pub mean_chord: Option<f64>,
    /// Key stations: spanwise fraction η ∈ (0, 1], increasing; the last must be 1 (tip).
    #[serde(default)]
    pub stations: Vec<f64>,
    /// Taper ratio c(η_k)/c_root at each station.
    #[serde(default)]
    pub taper: Vec<f64>,
    /// Chord fraction at which sweep is given (0 = leading edge, 0.25 = quarter chord).
    #[serde(default)]
    pub sweep_chord_fraction: f64,
    /// Sweep angle of each panel (root→station 0, station 0→1, …), radians.
    #[serde(default)]
    pub sweep: Vec<f64>,
    /// Dihedral angle of each panel, radians.
    #[serde(default)]
    pub dihedral: Vec<f64>,
}

/// A resolved planform.
#[derive(Debug, Clone, PartialEq)]
pub struct Planform {
    /// Span b.
    pub span: f64,
    /// Root chord.
    pub root_chord: f64,
    /// Area S.
    pub area: f64,
    /// Aspect ratio.
    pub aspect_ratio: f64,
    /// Mean chord S/b.
    pub mean_chord: f64,
    /// Station fractions including the root: [0, η_1, …, 1].
    pub eta: Vec<f64>,
    /// Chords at `eta`.
    pub chords: Vec<f64>,
    /// Leading-edge x at `eta`.
    pub x_le: Vec<f64>,
    /// Spanwise y at `eta` (semi-span side).
    pub y: Vec<f64>,
    /// Vertical z at `eta` (dihedral).
    pub z: Vec<f64>,
}

fn err(reason: String) -> Error {
    Error::Planform { reason }
}

impl Planform {
    /// Resolves the planform: checks the stations, derives the missing size quantities from
    /// the two given, then places the leading edge by sweep and the stations by dihedral.
    pub fn resolve(spec: &PlanformSpec) -> Result<Self> {
        let n = spec.stations.len();
        if n == 0 {
            return Err(err(
                "no stations: give at least the tip (eta = 1) and its taper".into(),
            ));
        }
        if spec.taper.len() != n {
            return Err(err(format!(
                "{} stations but {} taper ratios",
                n,
                spec.taper.len()
            )));
        }
        for (k, &e) in spec.stations.iter().enumerate() {
            let prev = if k == 0 { 0.0 } else { spec.stations[k - 1] };
            if !(e > prev && e <= 1.0) {
                return Err(err(format!(
                    "station {k}: eta = {e} must increase in (0, 1]"
                )));
            }
            if !(spec.taper[k] > 0.0 && spec.taper[k].is_finite()) {
                return Err(err(format!(
                    "station {k}: taper = {} must be > 0",
                    spec.taper[k]
                )));
            }
        }
        if spec.stations[n - 1] != 1.0 {
            return Err(err(format!(
                "the last station must be the tip (eta = 1), not {}",
                spec.stations[n - 1]
            )));
        }
        for (what, v) in [("sweep", &spec.sweep), ("dihedral", &spec.dihedral)] {
            if !v.is_empty() && v.len() != n {
                return Err(err(format!("{} {what} angles for {n} panels", v.len())));
            }
        }
        let mut eta = vec![0.0];
        eta.extend_from_slice(&spec.stations);
        let mut tau = vec![1.0];
        tau.extend_from_slice(&spec.taper);
        let integral: f64 = (0..n)
            .map(|k| 0.5 * (tau[k] + tau[k + 1]) * (eta[k + 1] - eta[k]))
            .sum();
        // Size: exactly two independent of {S, AR, b, c_root, c̄}.
        let given: Vec<(&str, f64)> = [
            ("area", spec.area),
            ("aspect_ratio", spec.aspect_ratio),
            ("span", spec.span),
            ("root_chord", spec.root_chord),
            ("mean_chord", spec.mean_chord),
        ]
        .into_iter()
        .filter_map(|(k, v)| v.map(|v| (k, v)))
        .collect();
        for (k, v) in &given {
            if !(v.is_finite() && *v > 0.0) {
                return Err(err(format!("{k} = {v} must be positive")));
            }
        }
        let names: Vec<&str> = given.iter().map(|g| g.0).collect();
        if given.len() != 2 {
            return Err(err(format!(
                "{} of area, aspect_ratio, span, root_chord, mean_chord given ({}): the size \
                 has two degrees of freedom once the taper ratios are fixed, give exactly two",
                given.len(),
                if names.is_empty() {
                    "none".to_string()
                } else {
                    names.join(", ")
                }
            )));
        }
        let get = |k: &str| given.iter().find(|g| g.0 == k).map(|g| g.1);
        let cbar_from_root = |c: f64| c * integral;
        let (b, cbar) = match (
            get("area"),
            get("aspect_ratio"),
            get("span"),
            get("root_chord").map(cbar_from_root),
            get("mean_chord"),
        ) {
            (Some(s), Some(ar), None, None, None) => {
                let b = (s * ar).sqrt();
                (b, s / b)
            }
            (Some(s), None, Some(b), None, None) => (b, s / b),
            (Some(s), None, None, Some(c), None) | (Some(s), None, None, None, Some(c)) => {
                (s / c, c)
            }
            (None, Some(ar), Some(b), None, None) => (b, b / ar),
            (None, Some(ar), None, Some(c), None) | (None, Some(ar), None, None, Some(c)) => {
                (ar * c, c)
            }
            (None, None, Some(b), Some(c), None) | (None, None, Some(b), None, Some(c)) => (b, c),
            _ => {
                return Err(err(
                    "root_chord and mean_chord are not independent (mean = root x the taper \
                     integral): give one of them with area, aspect_ratio or span"
                        .into(),
                ));
            }
        };
        let root_chord = cbar / integral;
        let area = b * cbar;
        let chords: Vec<f64> = tau.iter().map(|t| root_chord * t).collect();
        let y: Vec<f64> = eta.iter().map(|e| 0.5 * b * e).collect();
        // Sweep at chord fraction f: x_f(y) advances by tan(Λ) dy per panel.
        let f = spec.sweep_chord_fraction;
        let mut x_le = vec![0.0];
        let mut z = vec![0.0];
        let mut xf = f * root_chord;
        for k in 0..n {
            let dy = y[k + 1] - y[k];
            let sw = spec.sweep.get(k).copied().unwrap_or(0.0);
            let dh = spec.dihedral.get(k).copied().unwrap_or(0.0);
            xf += sw.tan() * dy;
            x_le.push(xf - f * chords[k + 1]);
            z.push(z[k] + dh.tan() * dy);
        }
        Ok(Self {
            span: b,
            root_chord,
            area,
            aspect_ratio: b * b / area,
            mean_chord: cbar,
            eta,
            chords,
            x_le,
            y,
            z,
        })
    }

    /// The chord at spanwise fraction η (linear between stations).
    pub fn chord_at(&self, eta: f64) -> f64 {
        interpolate(&self.eta, &self.chords, eta)
    }

    /// The leading-edge position (x, y, z) at η.
    pub fn leading_edge_at(&self, eta: f64) -> [f64; 3] {
        [
            interpolate(&self.eta, &self.x_le, eta),
            interpolate(&self.eta, &self.y, eta),
            interpolate(&self.eta, &self.z, eta),
        ]
    }

    /// The sweep angle of panel k measured at chord fraction f.
    pub fn sweep_at(&self, k: usize, f: f64) -> f64 {
        let xa = self.x_le[k] + f * self.chords[k];
        let xb = self.x_le[k + 1] + f * self.chords[k + 1];
        ((xb - xa) / (self.y[k + 1] - self.y[k])).atan()
    }
}

/// Linear interpolation of `values` given at increasing `at`, clamped at the ends.
pub fn interpolate(at: &[f64], values: &[f64], x: f64) -> f64 {
    let n = at.len();
    if x <= at[0] {
        return values[0];
    }
    if x >= at[n - 1] {
        return values[n - 1];
    }
    let k = at.partition_point(|&a| a <= x).clamp(1, n - 1);
    let w = (x - at[k - 1]) / (at[k] - at[k - 1]);
    values[k - 1] + w * (values[k] - values[k - 1])
}

/// Deviations (e.g. twist, Tmax or any section-parameter change) given at key sections,
/// interpolated linearly in η for the sections between them, as §6.2 recommends: the
/// interpolation acts on deviations from the initial wing, never on the shapes themselves.
/// `key_eta` increasing; each deviation vector has the same length.
pub fn interpolate_deviations(
    key_eta: &[f64],
    deviations: &[Vec<f64>],
    eta: f64,
) -> Result<Vec<f64>> {
    if key_eta.is_empty() || key_eta.len() != deviations.len() {
        return Err(err(format!(
            "{} key sections but {} deviation vectors",
            key_eta.len(),
            deviations.len()
        )));
    }
    if key_eta.windows(2).any(|w| w[1] <= w[0]) {
        return Err(err("key-section stations must increase".into()));
    }
    let m = deviations[0].len();
    if let Some(k) = deviations.iter().position(|d| d.len() != m) {
        return Err(err(format!(
            "key section {k} has {} deviations, section 0 has {m}",
            deviations[k].len()
        )));
    }
    Ok((0..m)
        .map(|i| {
            let col: Vec<f64> = deviations.iter().map(|d| d[i]).collect();
            interpolate(key_eta, &col, eta)
        })
        .collect())
}

/// A master discretisation (§6.2) of a wing-like component: for each spanwise station η_j
/// (with its twist θ_j, radians, nose up, about the leading edge) the section points q_ij in
/// the local frame (chords; the same count at every station) are placed at
/// LE(η_j) + c(η_j) R_y(θ_j) (x, 0, z). Returns the nodes station by station, so the node count
/// is fixed by the inputs and the deviation between two masters is a plain difference.
pub fn master_nodes(
    planform: &Planform,
    stations: &[(f64, f64)],
    sections: &[Vec<[f64; 2]>],
) -> Result<Vec<[f64; 3]>> {
    if stations.len() != sections.len() || stations.is_empty() {
        return Err(err(format!(
            "{} stations but {} sections",
            stations.len(),
            sections.len()
        )));
    }
    let n = sections[0].len();
    if let Some(j) = sections.iter().position(|s| s.len() != n) {
        return Err(err(format!(
            "section {j} has {} points, section 0 has {n}: a master needs a fixed count",
            sections[j].len()
        )));
    }
    let mut out = Vec::with_capacity(n * stations.len());
    for (&(eta, twist), sec) in stations.iter().zip(sections) {
        let le = planform.leading_edge_at(eta);
        let c = planform.chord_at(eta);
        let (s, co) = twist.sin_cos();
        for q in sec {
            // Nose-up twist: the trailing edge moves down.
            let x = co * q[0] + s * q[1];
            let z = -s * q[0] + co * q[1];
            out.push([le[0] + c * x, le[1], le[2] + c * z]);
        }
    }
    Ok(out)
}
