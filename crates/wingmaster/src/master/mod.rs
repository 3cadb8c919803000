//! The wing master (issue item 6; paper §5.4 and §6.2): the model generator that produces the
//! master discretisation of a wing-like component from its sections and planform, and
//! feeds `param`'s master modifier through [`param::MasterSource`].
//!
//! * [`WingMasterSpec`] (RON) names the sampled support surface, the span direction, the
//!   master size n_s × n_t, the key sections (spanwise position t_K on the surface) and the
//!   design variables at each key section (twist, chord, shift, any of the ten thickness
//!   parameters of Eq. 39, camber ordinates) and at planform level (sweep, dihedral, span).
//! * [`WingMasterSpec::bind`] samples the initial master from the surface (n_s points along
//!   each section, uniform in the section parameter; n_t stations, uniform in the spanwise
//!   parameter) and fits each key section once (`crate::fit`); the fitted section binds the
//!   key section's own sample points for Eq. (40), so a zero deviation returns the sampled
//!   points bit for bit.
//! * [`WingMaster`] implements [`param::MasterSource`]: `generate(x)` moves the sampled
//!   points by deviations only (§6.2, "deviations, not shapes"), linearly interpolated in the
//!   span coordinate between key sections; `jacobian(x)` is exact.
//!
//! Frames. Every section (station or key section) gets a frame from its samples: trailing
//! edge TE = midpoint of the first and last sample, leading edge LE = the sample farthest from
//! TE, chord c = |TE − LE|, chord direction x̂ = (TE − LE) with its span component removed,
//! ẑ = x̂ × ê (ê the unit span axis), reference point F = LE + f (TE − LE) with f the
//! `reference_chord_fraction`, span coordinate y = F · ê. The key section's fit has its own
//! (refined) frame; its Eq. (40) deviations are expressed per unit chord in the key's sample
//! frame (x̂_K, ẑ_K) and applied at a station in the station's frame (x̂_j, ẑ_j) times c_j.
//!
//! A master point p (station j, sample i) moves to
//!
//! p′ = F_j + (1 + Δc_j / c_j) R_ê(θ_j) (p + D_ij − F_j) + d_j + T_j
//!
//! with, all linearly interpolated in y between key sections (held constant outside):
//! D_ij = c_j Σ_K w_K (δˣ_K,i x̂_j + δᶻ_K,i ẑ_j) the Eq. (40) thickness and camber deviation,
//! θ_j the twist (right-handed about ê: nose up for ê = +y, x̂ = +x), Δc_j the chord change
//! (scaling about F_j, so the reference line keeps its sweep), d_j the key shifts; and the
//! planform terms
//!
//! T_j = (tan(Λ₀ + ΔΛ) − tan Λ₀) η_j â + (tan(Γ₀ + ΔΓ) − tan Γ₀) η_j n̂ + (Δb η_j / Y) r̂,
//!
//! η_j = y_j − y_root, where y_root and y_tip are the first and last key sections,
//! Y = y_tip − y_root, â the streamwise axis (orthogonal to ê), n̂ = â × ê, Λ₀ and Γ₀ the
//! initial sweep and dihedral of the reference line F_root → F_tip, and
//! r̂ = (F_tip − F_root) / Y, so a span change stretches the wing along its reference line
//! (sweep and dihedral kept).
//!
//! Files: the spec and the bound master's data here, [`WingMasterSpec::bind`] in `bind.rs`,
//! the master's evaluation and exact Jacobian ([`MasterSource`] of [`WingMaster`]) in
//! `evaluate.rs`.

use std::collections::BTreeMap;

use geom_db::eval::ParamSurface;
use geom_db::prelude::{Point3, Vector3};
use geom_db::{GeomDb, SurfaceId};
use param::{MasterGrid, MasterSource, Param};
use serde::{Deserialize, Serialize};

use crate::airfoil::{Airfoil, Frame};
use crate::error::{Error, Result};
use crate::fit::{FitOptions, SectionFit, fit_normalised};
use crate::modify::SectionModifier;
use crate::thickness::{NAMES, ThicknessParams};

mod bind;
mod evaluate;

pub use bind::master_sources;

fn y_axis() -> Vector3 {
    Vector3::y()
}

fn x_axis() -> Vector3 {
    Vector3::x()
}

fn default_camber_points() -> usize {
    8
}

/// A wing master: the sampled surface, the frame directions, the master size, the key
/// sections and the planform variables (RON; see `docs/crates/wingmaster.md`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WingMasterSpec {
    /// The wing's support surface the master is sampled from.
    pub surface: SurfaceId,
    /// Which surface parameter runs along the span (the other runs round the section, from
    /// the trailing edge over one surface, round the leading edge and back).
    pub spanwise: Param,
    /// The span direction ê (any non-zero length; default +y).
    #[serde(default = "y_axis")]
    pub span_axis: Vector3,
    /// The streamwise direction â of sweep (its span component is removed; default +x).
    #[serde(default = "x_axis")]
    pub streamwise: Vector3,
    /// Points per section (≥ 20).
    pub n_s: usize,
    /// Stations along the span (≥ 2).
    pub n_t: usize,
    /// Chord fraction f of the reference point F (twist axis, chord-scaling centre, sweep
    /// and span reference line); 0 = leading edge (default), 0.25 = quarter chord.
    #[serde(default)]
    pub reference_chord_fraction: f64,
    /// Camber control points of the key-section fits (including the two fixed ends).
    #[serde(default = "default_camber_points")]
    pub camber_points: usize,
    /// Extra thickness control points of the key-section fits.
    #[serde(default)]
    pub thickness_extra: usize,
    /// The section parameter of `surface` runs the other way (the master samples it from
    /// 1 to 0, so that a section starts at the trailing edge).
    #[serde(default, skip_serializing_if = "is_false")]
    pub reverse_section: bool,
    /// The spanwise parameter of `surface` runs from the tip to the root (the master
    /// samples it from 1 to 0, so that t = 0 is the root).
    #[serde(default, skip_serializing_if = "is_false")]
    pub reverse_span: bool,
    /// A wing split at the leading edge over two support surfaces (upper and lower faces):
    /// `surface` holds the section from the trailing edge to the leading edge, `second`
    /// from the leading edge back to the trailing edge. Each section samples the first
    /// surface for s ∈ [0, ½] and the second for s ∈ (½, 1].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub second: Option<SectionFace>,
    /// Planform-level variables.
    #[serde(default)]
    pub planform: PlanformVariables,
    /// The key sections, t increasing.
    pub key_sections: Vec<KeySection>,
}

/// The second face of a wing split at the leading edge ([`WingMasterSpec::second`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SectionFace {
    /// Its support surface.
    pub surface: SurfaceId,
    /// Which of its parameters runs along the span.
    pub spanwise: Param,
    /// Its section parameter runs from the trailing edge to the leading edge (sampled
    /// from 1 to 0, so that the section continues from the leading edge).
    #[serde(default, skip_serializing_if = "is_false")]
    pub reverse_section: bool,
    /// Its spanwise parameter runs from the tip to the root.
    #[serde(default, skip_serializing_if = "is_false")]
    pub reverse_span: bool,
}

fn is_false(b: &bool) -> bool {
    !*b
}

/// Planform-level design variables of a [`WingMasterSpec`] (absent: held at zero).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlanformVariables {
    /// Sweep deviation ΔΛ of the reference line (radians, positive backwards along â).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sweep: Option<String>,
    /// Dihedral deviation ΔΓ of the reference line (radians, positive towards n̂ = â × ê).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dihedral: Option<String>,
    /// Span deviation Δb (length units): change of the distance y_tip − y_root.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub span: Option<String>,
}

/// A key section of a [`WingMasterSpec`]: its position and the variables that set its
/// deviations (absent: zero deviation).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KeySection {
    /// Position along the spanwise surface parameter, normalised to [0, 1].
    pub t: f64,
    /// Twist deviation θ (radians, right-handed about the span axis through F).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub twist: Option<String>,
    /// Chord deviation Δc (length units; the section is scaled about F).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub chord: Option<String>,
    /// Translation deviations x, y, z (length units).
    #[serde(default)]
    pub shift: [Option<String>; 3],
    /// Thickness parameters of Eq. (39) → variable name, e.g. `{"tmax": "tip_tmax"}`; the
    /// variable is the deviation of the parameter (chords, radians for `phi_te`).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub thickness: BTreeMap<String, String>,
    /// Interior camber control point j (1 ..= camber_points − 2) → variable: the deviation
    /// ΔQ_j of its ordinate (chords).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub camber: BTreeMap<usize, String>,
}

/// The frame of one section of the master (see the module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SectionFrame {
    /// Leading edge (the sample farthest from the trailing-edge midpoint).
    pub leading_edge: Point3,
    /// Trailing-edge midpoint.
    pub trailing_edge: Point3,
    /// Chord |TE − LE|.
    pub chord: f64,
    /// Unit chord direction with its span component removed.
    pub x: Vector3,
    /// Unit normal of the chord in the section plane, x̂ × ê.
    pub z: Vector3,
    /// The reference point F = LE + f (TE − LE).
    pub reference: Point3,
    /// Span coordinate y = F · ê.
    pub y: f64,
}

/// A key section bound to the geometry.
#[derive(Debug, Clone)]
struct BoundKey {
    frame: SectionFrame,
    fit: SectionFit,
    modifier: SectionModifier,
    /// Sample index of each fit point.
    order: Vec<usize>,
    twist: Option<usize>,
    chord: Option<usize>,
    shift: [Option<usize>; 3],
    /// (Eq. 39 parameter index, variable).
    thickness: Vec<(usize, usize)>,
    /// (camber control point, variable).
    camber: Vec<(usize, usize)>,
}

/// A station of the master.
#[derive(Debug, Clone)]
struct Station {
    frame: SectionFrame,
    /// (key, weight) of the linear interpolation in y.
    weights: Vec<(usize, f64)>,
    /// η = y − y_root.
    eta: f64,
}

/// A [`WingMasterSpec`] bound to a geometry and to the modifier's variables: the
/// [`MasterSource`] of a wing.
#[derive(Debug, Clone)]
pub struct WingMaster {
    names: Vec<String>,
    x0: Vec<f64>,
    base: MasterGrid,
    e: Vector3,
    a: Vector3,
    n: Vector3,
    r: Vector3,
    span_length: f64,
    tan_sweep0: f64,
    tan_dihedral0: f64,
    planform: [Option<usize>; 3],
    keys: Vec<BoundKey>,
    stations: Vec<Station>,
}

fn err(reason: impl Into<String>) -> Error {
    Error::Master {
        reason: reason.into(),
    }
}

fn unit(v: Vector3, what: &str) -> Result<Vector3> {
    let l = v.norm();
    if l > 0.0 && l.is_finite() {
        Ok(v / l)
    } else {
        Err(err(format!("{what} must be a non-zero finite vector")))
    }
}

/// The frame of a section from its samples (first and last at the trailing edge).
pub fn section_frame(samples: &[Point3], e: Vector3, f: f64) -> Result<SectionFrame> {
    let n = samples.len();
    if n < 3 {
        return Err(err(format!("{n} samples in a section")));
    }
    let te = Point3::from((samples[0].coords + samples[n - 1].coords) * 0.5);
    let mut best = (0, -1.0);
    for (i, p) in samples.iter().enumerate() {
        let d = (p - te).norm_squared();
        if d > best.1 {
            best = (i, d);
        }
    }
    let le = samples[best.0];
    let chord_vec = te - le;
    let chord = chord_vec.norm();
    let x = unit(
        chord_vec - e * chord_vec.dot(&e),
        "the chord (with its span component removed)",
    )?;
    let reference = le + chord_vec * f;
    Ok(SectionFrame {
        leading_edge: le,
        trailing_edge: te,
        chord,
        x,
        z: x.cross(&e),
        reference,
        y: reference.coords.dot(&e),
    })
}

/// Rodrigues: (R_b(θ) v, d/dθ R_b(θ) v), right-handed about the unit vector b.
fn rotate(v: Vector3, b: Vector3, theta: f64) -> (Vector3, Vector3) {
    let (s, c) = theta.sin_cos();
    let bxv = b.cross(&v);
    let bb = b * b.dot(&v);
    (v * c + bxv * s + bb * (1.0 - c), -v * s + bxv * c + bb * s)
}

/// Linear interpolation weights at y between keys at increasing `ys` (constant outside).
fn weights(ys: &[f64], y: f64) -> Vec<(usize, f64)> {
    let n = ys.len();
    if n == 1 || y <= ys[0] {
        return vec![(0, 1.0)];
    }
    if y >= ys[n - 1] {
        return vec![(n - 1, 1.0)];
    }
    let k = ys.partition_point(|&a| a <= y).clamp(1, n - 1);
    let w = (y - ys[k - 1]) / (ys[k] - ys[k - 1]);
    vec![(k - 1, 1.0 - w), (k, w)]
}
