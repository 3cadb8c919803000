//! Geometric constraints on the CAD model (issue 46): functions of the design vector measured
//! on the updated geometric database — its support surfaces after the model update — not on
//! the grid, with exact derivatives through the chain (param → control nodes → model update,
//! junctions re-intersected). See docs/constraints.md.
//!
//! Measures ([`Measure`]):
//! - **thickness** at stations: the line p + t d through each station p along the direction
//!   d (unit; default +z, the wing's thickness direction in aeroshape's axes) meets the listed
//!   surfaces at points r(u, v) = p + t d ([`geom_db::newton::line`]); the thickness is
//!   t_max − t_min, the distance between the upper and the lower intersection. Its derivative
//!   holds the line: dt = n·δr / n·d (n = r_u × r_v), so d(thickness) = dt_upper − dt_lower
//!   = (δP_upper − δP_lower)·d with the intersection parameters' sensitivity included;
//! - **volume** enclosed by the listed surfaces, by the divergence theorem with the field
//!   F = (x·m) m (∇·F = 1, m the unit `axis`): V = Σ_s σ_s ∬ (r·m) (m·(r_u × r_v)) du dv over
//!   the surfaces' support patches, σ_s = ±1 so that σ_s r_u × r_v points out of the body
//!   (the topology's inward normal, which points into the flow region). Planes parallel to m carry no flux, so a part
//!   left open on such planes (a wing root on the symmetry plane y = 0 with m = z) counts as
//!   closed there. The integrand is a polynomial of degree 3p − 1 in u on a patch of degree
//!   p, which ⌈3p/2⌉ Gauss points integrate exactly; δV = Σ σ ∬ [(δr·m)(m·N) + (r·m)
//!   (m·(δr_u × r_v + r_u × δr_v))] du dv;
//! - **area** of the listed support surfaces, A = Σ ∬ |r_u × r_v| du dv, by Gauss rules on
//!   each patch split into 2^k × 2^k cells, k raised until two levels agree to 1e-12
//!   relative; δA = Σ ∬ N·δN / |N| du dv on the final level.
//!
//! The measures and their derivatives are `intersect::measure`'s (geometry only, below the
//! grid); this module holds the case's specifications and names the values. Each
//! [`ConstraintSpec`] names one measure, whether it is taken relative to its value on
//! the initial model, and optional bounds on what is reported (the ratio when relative).

use geom_db::{GeomDb, SurfaceId};
use intersect::measure::{self, LineFailure, Measured as Kernel};
use serde::{Deserialize, Serialize};

pub use intersect::measure::Thickness;

/// One constraint of the case's `constraints` section.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConstraintSpec {
    /// Name in tables and files (a thickness at several stations gives `name[k]`).
    pub name: String,
    /// What is measured.
    pub measure: Measure,
    /// Report the value divided by its value on the initial model (default false).
    #[serde(default)]
    pub relative: bool,
    /// Lower bound of the reported value (the ratio when `relative`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lower: Option<f64>,
    /// Upper bound of the reported value (the ratio when `relative`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub upper: Option<f64>,
}

/// A geometric measure of the model (module doc).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Measure {
    /// Thickness along `direction` at `stations`, between the outermost intersections of
    /// the line with `surfaces`.
    Thickness {
        /// Support surfaces of the part (e.g. the wing's).
        surfaces: Vec<SurfaceId>,
        /// Where.
        stations: Stations,
        /// The thickness direction (normalised; default (0, 0, 1)).
        #[serde(default = "default_axis")]
        direction: [f64; 3],
    },
    /// Volume enclosed by `surfaces` (closed, or open only on planes parallel to `axis`).
    Volume {
        /// Support surfaces of the part.
        surfaces: Vec<SurfaceId>,
        /// The direction m of the divergence field (x·m) m (normalised; default (0, 0, 1)).
        #[serde(default = "default_axis")]
        axis: [f64; 3],
    },
    /// Area of `surfaces` (their support surfaces, whole).
    Area {
        /// Support surfaces.
        surfaces: Vec<SurfaceId>,
    },
}

fn default_axis() -> [f64; 3] {
    [0.0, 0.0, 1.0]
}

/// Points where a thickness is measured.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Stations {
    /// Explicit points (any point on the line through the part).
    Points(Vec<[f64; 3]>),
    /// A chordwise × spanwise grid on a wing's planform: the points
    /// (1 − η)[(1 − ξ) le_root + ξ te_root] + η[(1 − ξ) le_tip + ξ te_tip] for every ξ of
    /// `chordwise` and η of `spanwise` (fractions; spanwise outer, chordwise inner).
    Grid {
        /// Leading edge of the root section.
        le_root: [f64; 3],
        /// Trailing edge of the root section.
        te_root: [f64; 3],
        /// Leading edge of the tip section.
        le_tip: [f64; 3],
        /// Trailing edge of the tip section.
        te_tip: [f64; 3],
        /// Chordwise fractions ξ.
        chordwise: Vec<f64>,
        /// Spanwise fractions η.
        spanwise: Vec<f64>,
    },
}

impl Stations {
    /// The points, in order.
    pub fn points(&self) -> Vec<[f64; 3]> {
        match self {
            Stations::Points(p) => p.clone(),
            Stations::Grid {
                le_root,
                te_root,
                le_tip,
                te_tip,
                chordwise,
                spanwise,
            } => {
                let mut out = Vec::with_capacity(chordwise.len() * spanwise.len());
                for &eta in spanwise {
                    for &xi in chordwise {
                        out.push(std::array::from_fn(|c| {
                            (1.0 - eta) * ((1.0 - xi) * le_root[c] + xi * te_root[c])
                                + eta * ((1.0 - xi) * le_tip[c] + xi * te_tip[c])
                        }));
                    }
                }
                out
            }
        }
    }
}

/// Errors of the constraints; each names the constraint.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ConstraintError {
    /// The specification is bad (unknown surface, zero direction, empty list, no station).
    ///
    /// ```
    /// use aeroshape::constraints::{ConstraintSpec, Measure, measure};
    /// let db = geom_db::GeomDb::empty("empty");
    /// let spec = ConstraintSpec { name: "a".into(), relative: false, lower: None, upper: None,
    ///     measure: Measure::Area { surfaces: vec![geom_db::SurfaceId(3)] } };
    /// let e = measure(&db, &spec).unwrap_err();
    /// assert!(e.to_string().contains("surface 3"), "{e}");
    /// ```
    #[error("constraint {name:?}: {reason}")]
    BadSpec {
        /// The constraint.
        name: String,
        /// What is wrong.
        reason: String,
    },
    /// The line through a thickness station does not meet the part twice.
    ///
    /// ```
    /// use aeroshape::constraints::{ConstraintSpec, Measure, Stations, measure};
    /// let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/geom/sphere.ron");
    /// let db = geom_db::GeomDb::from_ron_str(&std::fs::read_to_string(path).unwrap(), path)
    ///     .unwrap();
    /// let spec = ConstraintSpec { name: "t".into(), relative: false, lower: None, upper: None,
    ///     measure: Measure::Thickness { surfaces: vec![geom_db::SurfaceId(0)],
    ///         stations: Stations::Points(vec![[50.0, 0.0, 0.0]]), direction: [0.0, 0.0, 1.0] } };
    /// let e = measure(&db, &spec).unwrap_err();
    /// assert!(matches!(e, aeroshape::constraints::ConstraintError::Line { .. }), "{e}");
    /// ```
    #[error(
        "constraint {name:?}, station {station} {line}: meets surfaces {surfaces} at {hits} point(s), 2 needed{failed}"
    )]
    Line {
        /// The constraint.
        name: String,
        /// Station index.
        station: usize,
        /// The line: its station and direction.
        line: String,
        /// The surfaces searched (names).
        surfaces: String,
        /// Intersections found.
        hits: usize,
        /// The Newton solves that did not converge (surface and residual), if any.
        failed: String,
    },
    /// The surface is tangent to the line (or singular) at a thickness intersection: no
    /// derivative.
    #[error(
        "constraint {name:?}, station {station}: the line is tangent to surface {surface} at the intersection"
    )]
    Tangent {
        /// The constraint.
        name: String,
        /// Station index.
        station: usize,
        /// The surface (name).
        surface: String,
    },
    /// A tangent of another model was given.
    #[error("constraint {name:?}: the model tangent does not match the model")]
    TangentLayout {
        /// The constraint.
        name: String,
    },
}

/// `Result` of the constraints.
pub type Result<T, E = ConstraintError> = std::result::Result<T, E>;

/// One measured value of a constraint, with what its derivative needs.
#[derive(Debug, Clone)]
pub struct Measured {
    /// Name (`name` or `name[k]` for the k-th station).
    pub name: String,
    /// The measured value (absolute: length, area or volume units).
    pub value: f64,
    kernel: Kernel,
}

impl Measured {
    /// The value's derivative for the perturbation `t` of the model `db` that was measured
    /// (a tangent of the model update's linearisation, `ModelLinearisation::jvp`).
    pub fn tangent(&self, db: &GeomDb, t: &geom_db::linearise::ModelTangent) -> Result<f64> {
        if !Kernel::fits(db, t) {
            return Err(ConstraintError::TangentLayout {
                name: self.name.clone(),
            });
        }
        Ok(self.kernel.tangent(db, t))
    }

    /// The transpose of [`tangent`](Self::tangent): adds `bar` times the value's gradient
    /// with respect to the model to the cotangent `w` (of `ModelLinearisation::zero_tangent`
    /// layout, then its `vjp`).
    pub fn add_cotangent(
        &self,
        db: &GeomDb,
        bar: f64,
        w: &mut geom_db::linearise::ModelTangent,
    ) -> Result<()> {
        if !Kernel::fits(db, w) {
            return Err(ConstraintError::TangentLayout {
                name: self.name.clone(),
            });
        }
        self.kernel.add_cotangent(db, bar, w);
        Ok(())
    }

    /// The thickness measured, for a thickness constraint.
    pub fn thickness(&self) -> Option<&Thickness> {
        match &self.kernel {
            Kernel::Thickness(th) => Some(th),
            _ => None,
        }
    }
}

fn surface_label(db: &GeomDb, s: SurfaceId) -> String {
    let name = &db.surface(s).name;
    if name.is_empty() {
        format!("{}", s.0)
    } else {
        format!("{} ({name})", s.0)
    }
}

fn line_error(
    f: LineFailure,
    name: &str,
    station: usize,
    p: &[f64; 3],
    d: &[f64; 3],
    db: &GeomDb,
    surfaces: &[SurfaceId],
) -> ConstraintError {
    let failed = if f.failed.is_empty() {
        String::new()
    } else {
        let list: Vec<String> = f
            .failed
            .iter()
            .take(3)
            .map(|(s, r)| format!("surface {} residual {r:.3e}", surface_label(db, *s)))
            .collect();
        format!(
            " ({} Newton solve(s) did not converge: {})",
            f.failed.len(),
            list.join(", ")
        )
    };
    ConstraintError::Line {
        name: name.to_string(),
        station,
        line: format!(
            "at ({:.6}, {:.6}, {:.6}), the line along ({:.3}, {:.3}, {:.3})",
            p[0], p[1], p[2], d[0], d[1], d[2]
        ),
        surfaces: surfaces
            .iter()
            .map(|s| surface_label(db, *s))
            .collect::<Vec<_>>()
            .join(", "),
        hits: f.hits,
        failed,
    }
}

fn unit(name: &str, what: &str, d: &[f64; 3]) -> Result<[f64; 3]> {
    let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    if n.is_finite() && n > 0.0 {
        Ok([d[0] / n, d[1] / n, d[2] / n])
    } else {
        Err(ConstraintError::BadSpec {
            name: name.to_string(),
            reason: format!(
                "the {what} ({}, {}, {}) is not a direction",
                d[0], d[1], d[2]
            ),
        })
    }
}

fn check_surfaces(db: &GeomDb, name: &str, surfaces: &[SurfaceId]) -> Result<()> {
    if surfaces.is_empty() {
        return Err(ConstraintError::BadSpec {
            name: name.to_string(),
            reason: "no surface listed".into(),
        });
    }
    for s in surfaces {
        if s.index() >= db.surfaces.len() {
            return Err(ConstraintError::BadSpec {
                name: name.to_string(),
                reason: format!(
                    "surface {} is not in the model ({} surfaces)",
                    s.0,
                    db.surfaces.len()
                ),
            });
        }
    }
    Ok(())
}

/// The sign σ of surface `s` that makes σ r_u × r_v point out of the body: the surface
/// components' inward normal points into the flow region (§2.1), i.e. out of the body, so
/// σ = +1 when it is +r_u × r_v, −1 otherwise (and +1 for a surface without components).
fn outward_sign(db: &GeomDb, s: SurfaceId) -> f64 {
    db.surface_components
        .iter()
        .find(|c| c.surface == s)
        .map_or(1.0, |c| c.inward.sign())
}

/// Measures the constraint `spec` on the model `db`: one value per station for a
/// thickness, one value otherwise.
pub fn measure(db: &GeomDb, spec: &ConstraintSpec) -> Result<Vec<Measured>> {
    let name = &spec.name;
    match &spec.measure {
        Measure::Thickness {
            surfaces,
            stations,
            direction,
        } => {
            check_surfaces(db, name, surfaces)?;
            let d = unit(name, "direction", direction)?;
            let points = stations.points();
            if points.is_empty() {
                return Err(ConstraintError::BadSpec {
                    name: name.clone(),
                    reason: "no station".into(),
                });
            }
            let single = points.len() == 1;
            points
                .iter()
                .enumerate()
                .map(|(k, p)| {
                    let th = measure::thickness(db, surfaces, p, &d)
                        .map_err(|e| line_error(e, name, k, p, &d, db, surfaces))?;
                    th.check_derivable(db)
                        .map_err(|s| ConstraintError::Tangent {
                            name: name.clone(),
                            station: k,
                            surface: surface_label(db, s),
                        })?;
                    Ok(Measured {
                        name: if single {
                            name.clone()
                        } else {
                            format!("{name}[{k}]")
                        },
                        value: th.value(),
                        kernel: Kernel::Thickness(th),
                    })
                })
                .collect()
        }
        Measure::Volume { surfaces, axis } => {
            check_surfaces(db, name, surfaces)?;
            let m = unit(name, "axis", axis)?;
            let signed: Vec<(SurfaceId, f64)> =
                surfaces.iter().map(|&s| (s, outward_sign(db, s))).collect();
            let kernel = Kernel::volume(db, signed, m);
            Ok(vec![Measured {
                name: name.clone(),
                value: kernel.value(),
                kernel,
            }])
        }
        Measure::Area { surfaces } => {
            check_surfaces(db, name, surfaces)?;
            let kernel = Kernel::area(db, surfaces);
            Ok(vec![Measured {
                name: name.clone(),
                value: kernel.value(),
                kernel,
            }])
        }
    }
}

/// Measures every constraint of `specs` on `db`, in order.
pub fn measure_all(db: &GeomDb, specs: &[ConstraintSpec]) -> Result<Vec<Measured>> {
    let mut out = Vec::new();
    for s in specs {
        out.extend(measure(db, s)?);
    }
    Ok(out)
}
