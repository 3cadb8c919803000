//! Points, directions, placements and curves (ISO 10303-42 geometry schema).

use super::dec::Dec;
use crate::error::EntityProblem;
use crate::value::{Id, Instance, Value};

/// `CARTESIAN_POINT(name, coordinates)`: 1 to 3 coordinates (2 in parameter space).
#[derive(Debug, Clone, PartialEq)]
pub struct CartesianPoint {
    /// The coordinates.
    pub coordinates: Vec<f64>,
}

/// `DIRECTION(name, direction_ratios)`: not necessarily of unit length.
#[derive(Debug, Clone, PartialEq)]
pub struct Direction {
    /// The ratios (2 or 3).
    pub ratios: Vec<f64>,
}

/// `VECTOR(name, orientation, magnitude)`.
#[derive(Debug, Clone, PartialEq)]
pub struct Vector {
    /// A `DIRECTION`.
    pub orientation: Id,
    /// The length.
    pub magnitude: f64,
}

/// `AXIS1_PLACEMENT(name, location, axis)`.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis1Placement {
    /// A `CARTESIAN_POINT`.
    pub location: Id,
    /// A `DIRECTION` (default (0, 0, 1)).
    pub axis: Option<Id>,
}

/// `AXIS2_PLACEMENT_2D(name, location, ref_direction)` and `AXIS2_PLACEMENT_3D(name,
/// location, axis, ref_direction)`: a right-handed frame; `axis` defaults to (0, 0, 1) and
/// `ref_direction` to (1, 0, 0) (made orthogonal to the axis).
#[derive(Debug, Clone, PartialEq)]
pub struct Axis2Placement {
    /// A `CARTESIAN_POINT`.
    pub location: Id,
    /// The z direction (3D only).
    pub axis: Option<Id>,
    /// The x direction.
    pub ref_direction: Option<Id>,
    /// True for `AXIS2_PLACEMENT_2D`.
    pub planar: bool,
}

/// `LINE(name, pnt, dir)`: pnt + t dir, dir a `VECTOR` (so t scales with its magnitude).
#[derive(Debug, Clone, PartialEq)]
pub struct Line {
    /// A `CARTESIAN_POINT`.
    pub point: Id,
    /// A `VECTOR`.
    pub direction: Id,
}

/// The conics: `CIRCLE(name, position, radius)`, `ELLIPSE(name, position, semi_axis_1,
/// semi_axis_2)`, `HYPERBOLA(name, position, semi_axis, semi_imag_axis)` and
/// `PARABOLA(name, position, focal_dist)`, in the frame `position`.
#[derive(Debug, Clone, PartialEq)]
pub struct Conic {
    /// Which conic.
    pub kind: ConicKind,
    /// An `AXIS2_PLACEMENT_2D` or `_3D`.
    pub position: Id,
    /// Radius, first semi-axis, semi-axis or focal distance.
    pub a: f64,
    /// Second semi-axis (ellipse), imaginary semi-axis (hyperbola); equal to `a` for a
    /// circle, 0 for a parabola.
    pub b: f64,
}

/// The kind of a [`Conic`]; its parametrisation (ISO 10303-42 §4.3) is, in the frame
/// (C, x, y): circle C + r (cos t x + sin t y), ellipse C + a cos t x + b sin t y,
/// hyperbola C + a cosh t x + b sinh t y, parabola C + f (t² x + 2 t y).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ConicKind {
    /// `CIRCLE`.
    Circle,
    /// `ELLIPSE`.
    Ellipse,
    /// `HYPERBOLA`.
    Hyperbola,
    /// `PARABOLA`.
    Parabola,
}

/// `POLYLINE(name, points)`: straight segments, parameter k..k+1 on segment k.
#[derive(Debug, Clone, PartialEq)]
pub struct Polyline {
    /// `CARTESIAN_POINT`s.
    pub points: Vec<Id>,
}

/// `B_SPLINE_CURVE_WITH_KNOTS(name, degree, control_points_list, curve_form, closed_curve,
/// self_intersect, knot_multiplicities, knots, knot_spec)`, or the complex instance with
/// `RATIONAL_B_SPLINE_CURVE(weights_data)`.
#[derive(Debug, Clone, PartialEq)]
pub struct BSplineCurve {
    /// The degree (≥ 1).
    pub degree: usize,
    /// `CARTESIAN_POINT`s.
    pub control_points: Vec<Id>,
    /// `POLYLINE_FORM`, `CIRCULAR_ARC`, …, `UNSPECIFIED`.
    pub form: String,
    /// Closed (`.U.`: unknown).
    pub closed: Option<bool>,
    /// The distinct knots.
    pub knots: Vec<f64>,
    /// Their multiplicities (Σ = control points + degree + 1).
    pub multiplicities: Vec<usize>,
    /// `UNIFORM_KNOTS`, `QUASI_UNIFORM_KNOTS`, `PIECEWISE_BEZIER_KNOTS`, `UNSPECIFIED`.
    pub knot_spec: String,
    /// The weights of a rational curve.
    pub weights: Option<Vec<f64>>,
}

/// One end of a `TRIMMED_CURVE`: a parameter value, a point, or both.
#[derive(Debug, Clone, PartialEq)]
pub enum Trim {
    /// `PARAMETER_VALUE(t)` (or a bare real).
    Parameter(f64),
    /// A `CARTESIAN_POINT`.
    Point(Id),
}

/// `TRIMMED_CURVE(name, basis_curve, trim_1, trim_2, sense_agreement,
/// master_representation)`.
#[derive(Debug, Clone, PartialEq)]
pub struct TrimmedCurve {
    /// The curve trimmed.
    pub basis: Id,
    /// Start: parameter and/or point.
    pub trim1: Vec<Trim>,
    /// End: parameter and/or point.
    pub trim2: Vec<Trim>,
    /// True when the trimmed curve runs in the basis curve's direction.
    pub sense: bool,
    /// `PARAMETER`, `CARTESIAN` or `UNSPECIFIED`: which trim value to trust.
    pub master: String,
}

/// `PCURVE(name, basis_surface, reference_to_curve)`: a curve in the parameter space of
/// a surface, given by a `DEFINITIONAL_REPRESENTATION` holding one 2D curve.
#[derive(Debug, Clone, PartialEq)]
pub struct Pcurve {
    /// The surface.
    pub surface: Id,
    /// The `DEFINITIONAL_REPRESENTATION`.
    pub representation: Id,
}

/// `SURFACE_CURVE`, `SEAM_CURVE` or `INTERSECTION_CURVE(name, curve_3d,
/// associated_geometry, master_representation)`.
#[derive(Debug, Clone, PartialEq)]
pub struct SurfaceCurve {
    /// True for `SEAM_CURVE` (both pcurves on one periodic surface).
    pub seam: bool,
    /// The 3D curve.
    pub curve: Id,
    /// `PCURVE`s (or surfaces).
    pub associated: Vec<Id>,
    /// `CURVE_3D`, `PCURVE_S1`, `PCURVE_S2`.
    pub master: String,
}

/// `COMPOSITE_CURVE(name, segments, self_intersect)`.
#[derive(Debug, Clone, PartialEq)]
pub struct CompositeCurve {
    /// `COMPOSITE_CURVE_SEGMENT`s.
    pub segments: Vec<Id>,
}

/// `COMPOSITE_CURVE_SEGMENT(transition, same_sense, parent_curve)`.
#[derive(Debug, Clone, PartialEq)]
pub struct CompositeCurveSegment {
    /// Runs in the parent's direction.
    pub same_sense: bool,
    /// The curve.
    pub parent: Id,
}

/// `OFFSET_CURVE_3D(name, basis_curve, distance, self_intersect, ref_direction)`.
#[derive(Debug, Clone, PartialEq)]
pub struct OffsetCurve3d {
    /// The curve offset.
    pub basis: Id,
    /// The distance.
    pub distance: f64,
    /// A `DIRECTION`: the offset is along ref_direction × tangent.
    pub ref_direction: Id,
}

impl Axis2Placement {
    pub(crate) fn decode(inst: &Instance, planar: bool) -> Result<Self, EntityProblem> {
        let rec = &inst.records[0];
        let mut d = Dec::new(rec, if planar { 3 } else { 4 }, false)?;
        d.skip(1);
        let location = d.id("location")?;
        let axis = if planar { None } else { d.opt_id("axis")? };
        Ok(Axis2Placement {
            location,
            axis,
            ref_direction: d.opt_id("ref_direction")?,
            planar,
        })
    }
}

impl Conic {
    pub(crate) fn decode(inst: &Instance, kind: ConicKind) -> Result<Self, EntityProblem> {
        let rec = &inst.records[0];
        let n = match kind {
            ConicKind::Ellipse | ConicKind::Hyperbola => 4,
            _ => 3,
        };
        let mut d = Dec::new(rec, n, false)?;
        d.skip(1);
        let position = d.id("position")?;
        let (a, b) = match kind {
            ConicKind::Circle => {
                let r = d.real("radius")?;
                (r, r)
            }
            ConicKind::Ellipse => (d.real("semi_axis_1")?, d.real("semi_axis_2")?),
            ConicKind::Hyperbola => (d.real("semi_axis")?, d.real("semi_imag_axis")?),
            ConicKind::Parabola => (d.real("focal_dist")?, 0.0),
        };
        Ok(Conic {
            kind,
            position,
            a,
            b,
        })
    }
}

/// Checks that `mults` and `knots` agree with each other and with the number of control
/// points.
pub(crate) fn check_knots(
    what: &str,
    n_points: usize,
    degree: usize,
    knots: &[f64],
    mults: &[usize],
) -> Result<(), EntityProblem> {
    if knots.len() != mults.len() {
        return Err(EntityProblem::Invalid {
            reason: format!(
                "{what}: {} knots but {} multiplicities",
                knots.len(),
                mults.len()
            ),
        });
    }
    let total: usize = mults.iter().fold(0usize, |a, &m| a.saturating_add(m));
    if total != n_points + degree + 1 {
        return Err(EntityProblem::Invalid {
            reason: format!(
                "{what}: the multiplicities add up to {total}, but {n_points} control points of degree {degree} need {}",
                n_points + degree + 1
            ),
        });
    }
    Ok(())
}

impl BSplineCurve {
    /// Decodes the simple form, or the complex form when the instance has several records.
    pub(crate) fn decode(inst: &Instance) -> Result<Self, EntityProblem> {
        let complex = inst.is_complex();
        let (base, knots_rec) = if complex {
            let base = inst
                .record("B_SPLINE_CURVE")
                .ok_or(EntityProblem::Complex {
                    missing: "B_SPLINE_CURVE",
                })?;
            let k = inst
                .record("B_SPLINE_CURVE_WITH_KNOTS")
                .ok_or(EntityProblem::Complex {
                    missing: "B_SPLINE_CURVE_WITH_KNOTS",
                })?;
            (base, k)
        } else {
            (&inst.records[0], &inst.records[0])
        };
        let mut d = Dec::new(base, if complex { 5 } else { 9 }, complex)?;
        if !complex {
            d.skip(1);
        }
        let degree = d.count("degree", 1)?;
        let control_points = d.ids("control_points_list")?;
        let form = d.enumeration("curve_form")?;
        let closed = d.logical("closed_curve")?;
        d.logical("self_intersect")?;
        let mut k = if complex {
            Dec::new(knots_rec, 3, true)?
        } else {
            d
        };
        let multiplicities = k.counts("knot_multiplicities")?;
        let knots = k.reals("knots")?;
        let knot_spec = k.enumeration("knot_spec")?;
        check_knots(
            "knots",
            control_points.len(),
            degree,
            &knots,
            &multiplicities,
        )?;
        let weights = match inst.record("RATIONAL_B_SPLINE_CURVE") {
            Some(r) if complex => {
                let w = Dec::new(r, 1, true)?.reals("weights_data")?;
                if w.len() != control_points.len() {
                    return Err(EntityProblem::Invalid {
                        reason: format!(
                            "{} weights for {} control points",
                            w.len(),
                            control_points.len()
                        ),
                    });
                }
                Some(w)
            }
            _ => None,
        };
        Ok(BSplineCurve {
            degree,
            control_points,
            form,
            closed,
            knots,
            multiplicities,
            knot_spec,
            weights,
        })
    }
}

impl TrimmedCurve {
    pub(crate) fn decode(inst: &Instance) -> Result<Self, EntityProblem> {
        let rec = &inst.records[0];
        let mut d = Dec::new(rec, 6, false)?;
        d.skip(1);
        let basis = d.id("basis_curve")?;
        let mut trims = || -> Result<Vec<Trim>, EntityProblem> {
            let (i, v) = d.value();
            let items = match v {
                Value::List(items) => items.as_slice(),
                v => std::slice::from_ref(v),
            };
            items
                .iter()
                .map(|x| match x {
                    Value::Ref(id) => Ok(Trim::Point(*id)),
                    Value::Typed(_, inner) => match **inner {
                        Value::Real(t) => Ok(Trim::Parameter(t)),
                        Value::Int(t) => Ok(Trim::Parameter(t as f64)),
                        _ => Err(bad_trim(i, x)),
                    },
                    Value::Real(t) => Ok(Trim::Parameter(*t)),
                    Value::Int(t) => Ok(Trim::Parameter(*t as f64)),
                    _ => Err(bad_trim(i, x)),
                })
                .collect()
        };
        let trim1 = trims()?;
        let trim2 = trims()?;
        Ok(TrimmedCurve {
            basis,
            trim1,
            trim2,
            sense: d.boolean("sense_agreement")?,
            master: d.enumeration("master_representation")?,
        })
    }
}

fn bad_trim(index: usize, v: &Value) -> EntityProblem {
    EntityProblem::Param {
        index,
        name: "trim",
        path: String::new(),
        expected: "PARAMETER_VALUE(t) or a point reference".into(),
        found: v.describe(),
    }
}

impl SurfaceCurve {
    pub(crate) fn decode(inst: &Instance, seam: bool) -> Result<Self, EntityProblem> {
        let rec = &inst.records[0];
        let mut d = Dec::new(rec, 4, false)?;
        d.skip(1);
        Ok(SurfaceCurve {
            seam,
            curve: d.id("curve_3d")?,
            associated: d.ids("associated_geometry")?,
            master: d.enumeration("master_representation")?,
        })
    }
}
