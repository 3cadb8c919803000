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
    /// Planform-level variables.
    #[serde(default)]
    pub planform: PlanformVariables,
    /// The key sections, t increasing.
    pub key_sections: Vec<KeySection>,
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

impl WingMasterSpec {
    /// Parses a spec from RON (with `param`'s RON options); `path` names the file.
    pub fn from_ron_str(text: &str, path: &str) -> Result<Self> {
        param::ron_from_str(text, path).map_err(|e| err(e.to_string()))
    }

    /// The spec as pretty RON.
    pub fn to_ron_string(&self) -> String {
        let cfg = ron::ser::PrettyConfig::new()
            .struct_names(false)
            .indentor("  ".to_string())
            .extensions(
                ron::extensions::Extensions::UNWRAP_VARIANT_NEWTYPES
                    | ron::extensions::Extensions::IMPLICIT_SOME,
            );
        ron::ser::to_string_pretty(self, cfg).unwrap_or_else(|e| format!("// {e}"))
    }

    /// Every variable name the spec uses, in first-use order (planform sweep, dihedral,
    /// span, then each key section: twist, chord, shift x/y/z, thickness, camber), each once.
    /// A master modifier may list its variables in any order.
    pub fn variable_names(&self) -> Vec<String> {
        let mut out: Vec<String> = Vec::new();
        let mut push = |n: &Option<String>| {
            if let Some(n) = n
                && !out.contains(n)
            {
                out.push(n.clone());
            }
        };
        let p = &self.planform;
        push(&p.sweep);
        push(&p.dihedral);
        push(&p.span);
        for k in &self.key_sections {
            push(&k.twist);
            push(&k.chord);
            for s in &k.shift {
                push(s);
            }
            for v in k.thickness.values() {
                push(&Some(v.clone()));
            }
            for v in k.camber.values() {
                push(&Some(v.clone()));
            }
        }
        out
    }

    /// Samples the surface at normalised (section s, span t).
    fn sample(&self, db: &GeomDb, s: f64, t: f64) -> Point3 {
        let surf = db.surface(self.surface);
        let ([u0, u1], [v0, v1]) = surf.domain();
        let (a, b) = match self.spanwise {
            Param::V => (s, t),
            Param::U => (t, s),
        };
        surf.point(u0 + a * (u1 - u0), v0 + b * (v1 - v0))
    }

    fn section_samples(&self, db: &GeomDb, t: f64) -> Vec<Point3> {
        (0..self.n_s)
            .map(|i| self.sample(db, i as f64 / (self.n_s - 1) as f64, t))
            .collect()
    }

    /// Binds the spec to `db` and to the master modifier's variables `names` with their
    /// initial values `x0` (the master is the sampled surface at `x0`; deviations are
    /// x − x0). Samples the initial master and fits every key section; errors name the
    /// key section or the variable.
    pub fn bind(&self, db: &GeomDb, names: &[String], x0: &[f64]) -> Result<WingMaster> {
        if self.surface.index() >= db.surfaces.len() {
            return Err(err(format!(
                "{} does not exist (the model has {} surfaces)",
                self.surface,
                db.surfaces.len()
            )));
        }
        if self.n_s < 20 || self.n_t < 2 {
            return Err(err(format!(
                "{} × {} master: at least 20 points per section and 2 stations",
                self.n_s, self.n_t
            )));
        }
        if names.len() != x0.len() {
            return Err(err(format!(
                "{} variable names but {} initial values",
                names.len(),
                x0.len()
            )));
        }
        let f = self.reference_chord_fraction;
        if !(0.0..=1.0).contains(&f) {
            return Err(err(format!(
                "reference_chord_fraction = {f} must be in [0, 1]"
            )));
        }
        let e = unit(self.span_axis, "span_axis")?;
        let a = unit(
            self.streamwise - e * self.streamwise.dot(&e),
            "streamwise (with its span component removed)",
        )?;
        let n = a.cross(&e);
        if self.key_sections.is_empty() {
            return Err(err("no key sections"));
        }
        let mut used = vec![false; names.len()];
        let mut find = |v: &Option<String>, what: &str| -> Result<Option<usize>> {
            match v {
                None => Ok(None),
                Some(v) => {
                    let k = names.iter().position(|m| m == v).ok_or_else(|| {
                        err(format!(
                            "{what}: variable '{v}' is not one of the modifier's variables"
                        ))
                    })?;
                    used[k] = true;
                    Ok(Some(k))
                }
            }
        };
        let planform = [
            find(&self.planform.sweep, "planform sweep")?,
            find(&self.planform.dihedral, "planform dihedral")?,
            find(&self.planform.span, "planform span")?,
        ];
        let opts = FitOptions::default()
            .with_camber_points(self.camber_points)
            .with_thickness_extra(self.thickness_extra);
        let mut keys = Vec::with_capacity(self.key_sections.len());
        let mut prev_t = f64::NEG_INFINITY;
        for (k, ks) in self.key_sections.iter().enumerate() {
            let what = format!("key section {k} (t = {})", ks.t);
            if !(ks.t >= 0.0 && ks.t <= 1.0) || ks.t <= prev_t {
                return Err(err(format!("{what}: t must increase within [0, 1]")));
            }
            prev_t = ks.t;
            let samples = self.section_samples(db, ks.t);
            let frame = section_frame(&samples, e, f).map_err(|e| err(format!("{what}: {e}")))?;
            let pts2: Vec<[f64; 2]> = samples
                .iter()
                .map(|p| {
                    let d = p - frame.leading_edge;
                    [d.dot(&frame.x), d.dot(&frame.z)]
                })
                .collect();
            let airfoil = Airfoil {
                name: what.clone(),
                points: pts2.clone(),
                warnings: Vec::new(),
            };
            let na = airfoil.normalise().map_err(|e| {
                err(format!(
                    "{what}: {e} (the section parameter must run from the trailing edge round \
                     the leading edge back to the trailing edge)"
                ))
            })?;
            let fit = fit_normalised(&na, &what, &opts).map_err(|e| err(format!("{what}: {e}")))?;
            if fit.points.len() != self.n_s {
                return Err(err(format!(
                    "{what}: the fit kept {} of {} samples (repeated points?)",
                    fit.points.len(),
                    self.n_s
                )));
            }
            // The fit orders points upper surface first: find which way round they are.
            let mismatch = |rev: bool| -> f64 {
                fit.points
                    .iter()
                    .enumerate()
                    .map(|(i, q)| {
                        let g = fit.frame.to_global(*q);
                        let p = pts2[if rev { self.n_s - 1 - i } else { i }];
                        (g[0] - p[0]).powi(2) + (g[1] - p[1]).powi(2)
                    })
                    .sum()
            };
            let rev = mismatch(true) < mismatch(false);
            let order = (0..self.n_s)
                .map(|i| if rev { self.n_s - 1 - i } else { i })
                .collect();
            let modifier = SectionModifier::from_fit(&fit)?;
            let twist = find(&ks.twist, &what)?;
            let chord = find(&ks.chord, &what)?;
            let shift = [
                find(&ks.shift[0], &what)?,
                find(&ks.shift[1], &what)?,
                find(&ks.shift[2], &what)?,
            ];
            let mut thickness = Vec::new();
            for (p, v) in &ks.thickness {
                let pi = NAMES.iter().position(|m| m == p).ok_or_else(|| {
                    err(format!(
                        "{what}: '{p}' is not a thickness parameter of Eq. (39) ({})",
                        NAMES.join(", ")
                    ))
                })?;
                thickness.push((pi, find(&Some(v.clone()), &what)?.expect("named")));
            }
            let mut camber = Vec::new();
            for (&j, v) in &ks.camber {
                if j == 0 || j + 1 >= self.camber_points {
                    return Err(err(format!(
                        "{what}: camber point {j} is not interior (1 ..= {})",
                        self.camber_points.saturating_sub(2)
                    )));
                }
                camber.push((j, find(&Some(v.clone()), &what)?.expect("named")));
            }
            keys.push(BoundKey {
                frame,
                fit,
                modifier,
                order,
                twist,
                chord,
                shift,
                thickness,
                camber,
            });
        }
        if let Some(k) = used.iter().position(|u| !u) {
            return Err(err(format!(
                "variable '{}' is not used by the wing master",
                names[k]
            )));
        }
        let ys: Vec<f64> = keys.iter().map(|k| k.frame.y).collect();
        if let Some(w) = ys.windows(2).position(|w| w[1] <= w[0]) {
            return Err(err(format!(
                "key sections {w} and {} are not in increasing span coordinate ({} then {})",
                w + 1,
                ys[w],
                ys[w + 1]
            )));
        }
        let (root, tip) = (
            keys[0].frame.reference,
            keys[keys.len() - 1].frame.reference,
        );
        let span_length = tip.coords.dot(&e) - root.coords.dot(&e);
        let uses_planform = planform.iter().any(|p| p.is_some());
        if uses_planform && span_length.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
            return Err(err(
                "planform variables need at least two key sections apart along the span",
            ));
        }
        let (r, tan_sweep0, tan_dihedral0) = if span_length > 0.0 {
            let d = tip - root;
            (
                d / span_length,
                d.dot(&a) / span_length,
                d.dot(&n) / span_length,
            )
        } else {
            (e, 0.0, 0.0)
        };
        let mut points = Vec::with_capacity(self.n_s * self.n_t);
        let mut stations = Vec::with_capacity(self.n_t);
        for j in 0..self.n_t {
            let t = j as f64 / (self.n_t - 1) as f64;
            let samples = self.section_samples(db, t);
            let frame = section_frame(&samples, e, f)
                .map_err(|e| err(format!("station {j} (t = {t}): {e}")))?;
            stations.push(Station {
                frame,
                weights: weights(&ys, frame.y),
                eta: frame.y - ys[0],
            });
            points.extend(samples);
        }
        Ok(WingMaster {
            names: names.to_vec(),
            x0: x0.to_vec(),
            base: MasterGrid {
                n_s: self.n_s,
                n_t: self.n_t,
                points,
            },
            e,
            a,
            n,
            r,
            span_length,
            tan_sweep0,
            tan_dihedral0,
            planform,
            keys,
            stations,
        })
    }
}

impl WingMasterSpec {
    /// [`bind`](Self::bind) with the names and initial values of the master modifier `m`'s
    /// variables.
    pub fn bind_modifier(&self, db: &GeomDb, m: &param::MasterModifier) -> Result<WingMaster> {
        let names: Vec<String> = m.variables.iter().map(|v| v.name.clone()).collect();
        let x0: Vec<f64> = m.variables.iter().map(|v| v.value).collect();
        self.bind(db, &names, &x0)
            .map_err(|e| err(format!("modifier '{}': {e}", m.name)))
    }
}

/// The master sources of a parametrisation: every master modifier whose source is
/// `External(name)` with `name` a key of `specs` gets its wing master bound
/// ([`WingMasterSpec::bind_modifier`]); pass the result to `Parametrisation::bind`. External
/// names not in `specs` are left out (param then reports them as missing). A spec used by
/// two modifiers is an error (the sources are keyed by name and each binding is specific to
/// its modifier's variables).
pub fn master_sources(
    db: &GeomDb,
    p: &param::Parametrisation,
    specs: &BTreeMap<String, WingMasterSpec>,
) -> Result<param::MasterSources> {
    let mut out = param::MasterSources::new();
    for m in &p.modifiers {
        if let param::Modifier::Master(mm) = m
            && let param::MasterSpec::External(name) = &mm.source
            && let Some(spec) = specs.get(name)
        {
            if out.contains_key(name) {
                return Err(err(format!(
                    "wing master '{name}' is used by two master modifiers; give each its own"
                )));
            }
            let wm = spec.bind_modifier(db, mm)?;
            out.insert(
                name.clone(),
                std::sync::Arc::new(wm) as std::sync::Arc<dyn MasterSource>,
            );
        }
    }
    Ok(out)
}

/// Per key section: the Eq. (40) deviation of every sample per unit chord in the key's
/// sample frame (x̂_K, ẑ_K), indexed by sample; `None` when zero.
type KeyDeviation = Option<Vec<[f64; 2]>>;

impl WingMaster {
    /// The initial master (the sampled surface).
    pub fn initial(&self) -> &MasterGrid {
        &self.base
    }

    /// The frame of station j (t = j / (n_t − 1)).
    pub fn station_frame(&self, j: usize) -> &SectionFrame {
        &self.stations[j].frame
    }

    /// The frame of key section k (from its samples).
    pub fn key_frame(&self, k: usize) -> &SectionFrame {
        &self.keys[k].frame
    }

    /// The fit of key section k (its frame, parameters and errors).
    pub fn key_fit(&self, k: usize) -> &SectionFit {
        &self.keys[k].fit
    }

    /// The initial sweep Λ₀ and dihedral Γ₀ of the reference line (radians).
    pub fn initial_sweep_dihedral(&self) -> (f64, f64) {
        (self.tan_sweep0.atan(), self.tan_dihedral0.atan())
    }

    /// Maps local Eq. (40) deviations of the fit points (chords, fit frame) to the key's
    /// sample frame per unit chord, indexed by sample.
    fn to_key_frame(&self, k: usize, dev: &[[f64; 2]]) -> Vec<[f64; 2]> {
        let key = &self.keys[k];
        let fr: &Frame = &key.fit.frame;
        let (s, c) = fr.angle.sin_cos();
        let scale = fr.chord / key.frame.chord;
        let mut out = vec![[0.0, 0.0]; dev.len()];
        for (i, d) in dev.iter().enumerate() {
            out[key.order[i]] = [scale * (c * d[0] - s * d[1]), scale * (s * d[0] + c * d[1])];
        }
        out
    }

    /// The thickness parameters of key k at deviations `dx`.
    fn key_thickness(&self, k: usize, dx: &[f64]) -> ThicknessParams {
        let key = &self.keys[k];
        let mut v = key.fit.params.thickness.to_vec();
        for &(pi, var) in &key.thickness {
            v[pi] += dx[var];
        }
        ThicknessParams::from_vec(&v)
    }

    fn key_deviation(&self, k: usize, dx: &[f64]) -> Result<KeyDeviation> {
        let key = &self.keys[k];
        let moved = key
            .thickness
            .iter()
            .chain(&key.camber)
            .any(|&(_, v)| dx[v] != 0.0);
        if !moved {
            return Ok(None);
        }
        let th = self.key_thickness(k, dx);
        let poly = th.polygon().map_err(|e| Error::KeySection {
            key: k,
            source: Box::new(e),
        })?;
        let dp: Vec<[f64; 2]> = poly
            .points()
            .iter()
            .zip(key.modifier.base_polygon().points())
            .map(|(p, q)| [p[0] - q[0], p[1] - q[1]])
            .collect();
        let mut dq = vec![[0.0, 0.0]; key.fit.params.camber.len()];
        for &(j, v) in &key.camber {
            dq[j][1] += dx[v];
        }
        Ok(Some(
            self.to_key_frame(k, &key.modifier.deviation(&dp, &dq)),
        ))
    }

    /// Per station: (θ, Δc, shift + planform terms).
    fn station_state(&self, j: usize, dx: &[f64]) -> (f64, f64, Vector3) {
        let st = &self.stations[j];
        let (mut theta, mut dc, mut d) = (0.0, 0.0, Vector3::zeros());
        for &(k, w) in &st.weights {
            let key = &self.keys[k];
            if let Some(v) = key.twist {
                theta += w * dx[v];
            }
            if let Some(v) = key.chord {
                dc += w * dx[v];
            }
            for (c, s) in key.shift.iter().enumerate() {
                if let Some(v) = s {
                    d[c] += w * dx[*v];
                }
            }
        }
        let [sw, dh, sp] = self.planform;
        if let Some(v) = sw
            && dx[v] != 0.0
        {
            let dt = (self.tan_sweep0.atan() + dx[v]).tan() - self.tan_sweep0;
            d += self.a * (dt * st.eta);
        }
        if let Some(v) = dh
            && dx[v] != 0.0
        {
            let dt = (self.tan_dihedral0.atan() + dx[v]).tan() - self.tan_dihedral0;
            d += self.n * (dt * st.eta);
        }
        if let Some(v) = sp
            && dx[v] != 0.0
        {
            d += self.r * (dx[v] * st.eta / self.span_length);
        }
        (theta, dc, d)
    }

    fn deviations(&self, x: &[f64]) -> Result<Vec<f64>> {
        if x.len() != self.names.len() {
            return Err(err(format!(
                "{} values for {} variables",
                x.len(),
                self.names.len()
            )));
        }
        if let Some(i) = x.iter().position(|v| !v.is_finite()) {
            return Err(err(format!(
                "variable '{}' = {} is not finite",
                self.names[i], x[i]
            )));
        }
        Ok(x.iter().zip(&self.x0).map(|(a, b)| a - b).collect())
    }
}

/// `a + d` per component, leaving components with d = 0 untouched (bit for bit).
fn add(p: Point3, d: Vector3) -> Point3 {
    let mut q = p;
    for c in 0..3 {
        if d[c] != 0.0 {
            q[c] += d[c];
        }
    }
    q
}

impl MasterSource for WingMaster {
    fn variable_names(&self) -> Vec<String> {
        self.names.clone()
    }

    fn generate(&self, x: &[f64]) -> std::result::Result<MasterGrid, param::MasterError> {
        let dx = self.deviations(x)?;
        let devs: Vec<KeyDeviation> = (0..self.keys.len())
            .map(|k| self.key_deviation(k, &dx))
            .collect::<Result<_>>()?;
        let n_s = self.base.n_s;
        let mut points = self.base.points.clone();
        for (j, st) in self.stations.iter().enumerate() {
            let (theta, dc, shift) = self.station_state(j, &dx);
            let fr = &st.frame;
            let scale = 1.0 + dc / fr.chord;
            for i in 0..n_s {
                let p = self.base.points[j * n_s + i];
                let mut dsec = Vector3::zeros();
                for &(k, w) in &st.weights {
                    if let Some(d) = &devs[k] {
                        dsec += (fr.x * d[i][0] + fr.z * d[i][1]) * (w * fr.chord);
                    }
                }
                let mut disp = dsec + shift;
                if theta != 0.0 || dc != 0.0 {
                    let v = p - fr.reference + dsec;
                    disp += rotate(v, self.e, theta).0 * scale - v;
                }
                points[j * n_s + i] = add(p, disp);
            }
        }
        Ok(MasterGrid {
            n_s,
            n_t: self.base.n_t,
            points,
        })
    }

    fn jacobian(
        &self,
        x: &[f64],
    ) -> Option<std::result::Result<Vec<Vec<Vector3>>, param::MasterError>> {
        Some(self.exact_jacobian(x).map_err(Into::into))
    }
}

impl WingMaster {
    /// d(master point)/dx, exact: twist, chord, shift and planform terms by differentiation
    /// of the formula in the module doc; thickness through the analytic polygon Jacobian of
    /// conditions 1–6 and the linear Eq. (40); camber (linear) directly.
    fn exact_jacobian(&self, x: &[f64]) -> Result<Vec<Vec<Vector3>>> {
        let dx = self.deviations(x)?;
        let nv = x.len();
        let devs: Vec<KeyDeviation> = (0..self.keys.len())
            .map(|k| self.key_deviation(k, &dx))
            .collect::<Result<_>>()?;
        // Per key: (variable, d(deviation)/d(variable) per sample, key frame per unit chord).
        let mut ddev: Vec<Vec<(usize, Vec<[f64; 2]>)>> = Vec::with_capacity(self.keys.len());
        for (k, key) in self.keys.iter().enumerate() {
            let mut cols = Vec::new();
            if !key.thickness.is_empty() {
                let th = self.key_thickness(k, &dx);
                let (_, jac) = th
                    .polygon_with_jacobian(true)
                    .map_err(|e| Error::KeySection {
                        key: k,
                        source: Box::new(e),
                    })?;
                let dq0 = vec![[0.0, 0.0]; key.fit.params.camber.len()];
                for &(pi, v) in &key.thickness {
                    let dp: Vec<[f64; 2]> = jac.iter().map(|row| row[pi]).collect();
                    let d = key.modifier.deviation(&dp, &dq0);
                    cols.push((v, self.to_key_frame(k, &d)));
                }
            }
            let np = key.modifier.base_polygon().points().len();
            for &(j, v) in &key.camber {
                let mut dq = vec![[0.0, 0.0]; key.fit.params.camber.len()];
                dq[j][1] = 1.0;
                let d = key.modifier.deviation(&vec![[0.0, 0.0]; np], &dq);
                cols.push((v, self.to_key_frame(k, &d)));
            }
            ddev.push(cols);
        }
        let n_s = self.base.n_s;
        let mut out = vec![vec![Vector3::zeros(); nv]; self.base.points.len()];
        for (j, st) in self.stations.iter().enumerate() {
            let (theta, dc, _) = self.station_state(j, &dx);
            let fr = &st.frame;
            let scale = 1.0 + dc / fr.chord;
            // planform columns (the same for every point of the station)
            let mut pcol: Vec<(usize, Vector3)> = Vec::new();
            let [sw, dh, sp] = self.planform;
            if let Some(v) = sw {
                let c = (self.tan_sweep0.atan() + dx[v]).cos();
                pcol.push((v, self.a * (st.eta / (c * c))));
            }
            if let Some(v) = dh {
                let c = (self.tan_dihedral0.atan() + dx[v]).cos();
                pcol.push((v, self.n * (st.eta / (c * c))));
            }
            if let Some(v) = sp {
                pcol.push((v, self.r * (st.eta / self.span_length)));
            }
            for i in 0..n_s {
                let row = &mut out[j * n_s + i];
                let p = self.base.points[j * n_s + i];
                let mut dsec = Vector3::zeros();
                for &(k, w) in &st.weights {
                    if let Some(d) = &devs[k] {
                        dsec += (fr.x * d[i][0] + fr.z * d[i][1]) * (w * fr.chord);
                    }
                }
                let v = p - fr.reference + dsec;
                let (rv, drv) = rotate(v, self.e, theta);
                for &(k, w) in &st.weights {
                    let key = &self.keys[k];
                    if let Some(l) = key.twist {
                        row[l] += drv * (scale * w);
                    }
                    if let Some(l) = key.chord {
                        row[l] += rv * (w / fr.chord);
                    }
                    for (c, s) in key.shift.iter().enumerate() {
                        if let Some(l) = s {
                            row[*l][c] += w;
                        }
                    }
                    for (l, col) in &ddev[k] {
                        let dd = (fr.x * col[i][0] + fr.z * col[i][1]) * (w * fr.chord);
                        row[*l] += rotate(dd, self.e, theta).0 * scale;
                    }
                }
                for (l, c) in &pcol {
                    row[*l] += c;
                }
            }
        }
        Ok(out)
    }
}
