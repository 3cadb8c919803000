//! Surfaces (ISO 10303-42): elementary, B-spline, swept and offset.

use super::dec::Dec;
use super::geometry::check_knots;
use crate::error::EntityProblem;
use crate::value::{Id, Instance};

/// The elementary surfaces, each in the frame `position` (C, x, y, z), with their
/// parametrisations (ISO 10303-42 §4.4):
///
/// * `PLANE(name, position)`: C + u x + v y;
/// * `CYLINDRICAL_SURFACE(name, position, radius)`: C + r (cos u x + sin u y) + v z;
/// * `CONICAL_SURFACE(name, position, radius, semi_angle)`:
///   C + (r + v tan α)(cos u x + sin u y) + v z;
/// * `SPHERICAL_SURFACE(name, position, radius)`: C + r cos v (cos u x + sin u y) + r sin v z;
/// * `TOROIDAL_SURFACE(name, position, major_radius, minor_radius)` (and
///   `DEGENERATE_TOROIDAL_SURFACE`): C + (R + r cos v)(cos u x + sin u y) + r sin v z.
///
/// Angles are in the file's plane angle unit.
#[derive(Debug, Clone, PartialEq)]
pub struct ElementarySurface {
    /// Which surface.
    pub kind: ElementaryKind,
    /// An `AXIS2_PLACEMENT_3D`.
    pub position: Id,
    /// Radius (major radius of a torus; 0 for a plane).
    pub radius: f64,
    /// Semi-angle of a cone, minor radius of a torus (0 otherwise).
    pub second: f64,
}

/// The kind of an [`ElementarySurface`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ElementaryKind {
    /// `PLANE`.
    Plane,
    /// `CYLINDRICAL_SURFACE`.
    Cylinder,
    /// `CONICAL_SURFACE`.
    Cone,
    /// `SPHERICAL_SURFACE`.
    Sphere,
    /// `TOROIDAL_SURFACE`.
    Torus,
}

/// `B_SPLINE_SURFACE_WITH_KNOTS(name, u_degree, v_degree, control_points_list,
/// surface_form, u_closed, v_closed, self_intersect, u_multiplicities, v_multiplicities,
/// u_knots, v_knots, knot_spec)`, or the complex instance with
/// `RATIONAL_B_SPLINE_SURFACE(weights_data)`. `control_points[i][j]` has u index i.
#[derive(Debug, Clone, PartialEq)]
pub struct BSplineSurface {
    /// Degree in u.
    pub u_degree: usize,
    /// Degree in v.
    pub v_degree: usize,
    /// `CARTESIAN_POINT`s, rows of constant u index.
    pub control_points: Vec<Vec<Id>>,
    /// `PLANE_SURF`, `CYLINDRICAL_SURF`, …, `UNSPECIFIED`.
    pub form: String,
    /// Closed in u.
    pub u_closed: Option<bool>,
    /// Closed in v.
    pub v_closed: Option<bool>,
    /// Distinct u knots.
    pub u_knots: Vec<f64>,
    /// Their multiplicities.
    pub u_multiplicities: Vec<usize>,
    /// Distinct v knots.
    pub v_knots: Vec<f64>,
    /// Their multiplicities.
    pub v_multiplicities: Vec<usize>,
    /// Weights of a rational surface, same layout as the points.
    pub weights: Option<Vec<Vec<f64>>>,
}

/// `SURFACE_OF_REVOLUTION(name, swept_curve, axis_position)`: the curve rotated about an
/// `AXIS1_PLACEMENT`; u is the angle, v the curve's parameter.
#[derive(Debug, Clone, PartialEq)]
pub struct SurfaceOfRevolution {
    /// The swept curve.
    pub curve: Id,
    /// An `AXIS1_PLACEMENT`.
    pub axis: Id,
}

/// `SURFACE_OF_LINEAR_EXTRUSION(name, swept_curve, extrusion_axis)`: C(u) + v V, V a
/// `VECTOR`.
#[derive(Debug, Clone, PartialEq)]
pub struct SurfaceOfLinearExtrusion {
    /// The swept curve.
    pub curve: Id,
    /// A `VECTOR`.
    pub direction: Id,
}

/// `OFFSET_SURFACE(name, basis_surface, distance, self_intersect)`: S + d N.
#[derive(Debug, Clone, PartialEq)]
pub struct OffsetSurface {
    /// The surface offset.
    pub surface: Id,
    /// The distance along the unit normal S_u × S_v / |S_u × S_v|.
    pub distance: f64,
}

/// `RECTANGULAR_TRIMMED_SURFACE(name, basis_surface, u1, u2, v1, v2, usense, vsense)`.
#[derive(Debug, Clone, PartialEq)]
pub struct RectangularTrimmedSurface {
    /// The surface.
    pub surface: Id,
    /// u1, u2, v1, v2.
    pub bounds: [f64; 4],
    /// usense, vsense.
    pub senses: [bool; 2],
}

impl ElementarySurface {
    pub(crate) fn decode(inst: &Instance, kind: ElementaryKind) -> Result<Self, EntityProblem> {
        let rec = &inst.records[0];
        let n = match kind {
            ElementaryKind::Plane => 2,
            ElementaryKind::Cylinder | ElementaryKind::Sphere => 3,
            ElementaryKind::Cone | ElementaryKind::Torus => 4,
        };
        let mut d = Dec::new(rec, n, false)?;
        d.skip(1);
        let position = d.id("position")?;
        let (radius, second) = match kind {
            ElementaryKind::Plane => (0.0, 0.0),
            ElementaryKind::Cylinder | ElementaryKind::Sphere => (d.real("radius")?, 0.0),
            ElementaryKind::Cone => (d.real("radius")?, d.real("semi_angle")?),
            ElementaryKind::Torus => (d.real("major_radius")?, d.real("minor_radius")?),
        };
        Ok(ElementarySurface {
            kind,
            position,
            radius,
            second,
        })
    }
}

impl BSplineSurface {
    /// Decodes the simple form, or the complex form when the instance has several records.
    pub(crate) fn decode(inst: &Instance) -> Result<Self, EntityProblem> {
        let complex = inst.is_complex();
        let (base, knots_rec) = if complex {
            let base = inst
                .record("B_SPLINE_SURFACE")
                .ok_or(EntityProblem::Complex {
                    missing: "B_SPLINE_SURFACE",
                })?;
            let k = inst
                .record("B_SPLINE_SURFACE_WITH_KNOTS")
                .ok_or(EntityProblem::Complex {
                    missing: "B_SPLINE_SURFACE_WITH_KNOTS",
                })?;
            (base, k)
        } else {
            (&inst.records[0], &inst.records[0])
        };
        let mut d = Dec::new(base, if complex { 7 } else { 13 }, complex)?;
        if !complex {
            d.skip(1);
        }
        let u_degree = d.count("u_degree", 1)?;
        let v_degree = d.count("v_degree", 1)?;
        let control_points = d.ids2("control_points_list")?;
        let form = d.enumeration("surface_form")?;
        let u_closed = d.logical("u_closed")?;
        let v_closed = d.logical("v_closed")?;
        d.logical("self_intersect")?;
        let nu = control_points.len();
        let nv = control_points.first().map_or(0, Vec::len);
        if control_points.iter().any(|r| r.len() != nv) {
            return Err(EntityProblem::Invalid {
                reason: "the rows of control points have different lengths".into(),
            });
        }
        let mut k = if complex {
            Dec::new(knots_rec, 5, true)?
        } else {
            d
        };
        let u_multiplicities = k.counts("u_multiplicities")?;
        let v_multiplicities = k.counts("v_multiplicities")?;
        let u_knots = k.reals("u_knots")?;
        let v_knots = k.reals("v_knots")?;
        k.enumeration("knot_spec")?;
        check_knots("u knots", nu, u_degree, &u_knots, &u_multiplicities)?;
        check_knots("v knots", nv, v_degree, &v_knots, &v_multiplicities)?;
        let weights = match inst.record("RATIONAL_B_SPLINE_SURFACE") {
            Some(r) if complex => {
                let w = Dec::new(r, 1, true)?.reals2("weights_data")?;
                if w.len() != nu || w.iter().any(|row| row.len() != nv) {
                    return Err(EntityProblem::Invalid {
                        reason: format!("the weights are not {nu} × {nv} like the control points"),
                    });
                }
                Some(w)
            }
            _ => None,
        };
        Ok(BSplineSurface {
            u_degree,
            v_degree,
            control_points,
            form,
            u_closed,
            v_closed,
            u_knots,
            u_multiplicities,
            v_knots,
            v_multiplicities,
            weights,
        })
    }
}
