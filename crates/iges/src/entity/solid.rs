//! The analytic surfaces of IGES 5.3 (the "solid" surfaces 190–198) and the 123 direction
//! they point to. Form 0 is unparametrised (no reference direction), form 1
//! parametrised (with `refdir`).

use super::{Dec, Enc};
use crate::directory::DeId;
use crate::error::EntityProblem;

/// Reads the reference direction that form 1 carries.
fn refdir(d: &mut Dec, form: i32) -> Result<Option<DeId>, EntityProblem> {
    if form == 1 {
        d.ptr("reference direction").map(Some)
    } else {
        Ok(None)
    }
}

/// 190 plane surface through `location` (a 116 point) with normal `normal` (a 123).
#[derive(Debug, Clone, PartialEq)]
pub struct PlaneSurface {
    /// LOCATION: a 116 point on the plane.
    pub location: DeId,
    /// NORMAL: a 123 direction.
    pub normal: DeId,
    /// REFDIR (form 1): a 123 direction, the u axis of the parametrisation.
    pub refdir: Option<DeId>,
}

impl PlaneSurface {
    pub(crate) fn decode(d: &mut Dec, form: i32) -> Result<Self, EntityProblem> {
        Ok(PlaneSurface {
            location: d.ptr("location point")?,
            normal: d.ptr("normal direction")?,
            refdir: refdir(d, form)?,
        })
    }
    pub(crate) fn encode(&self, e: &mut Enc) {
        e.ptr(self.location);
        e.ptr(self.normal);
        if let Some(r) = self.refdir {
            e.ptr(r);
        }
    }
}

/// 192 right circular cylindrical surface: axis through `location` along `axis`, radius
/// `radius`.
#[derive(Debug, Clone, PartialEq)]
pub struct CylindricalSurface {
    /// LOCATION: a 116 point on the axis.
    pub location: DeId,
    /// AXIS: a 123 direction.
    pub axis: DeId,
    /// RADIUS.
    pub radius: f64,
    /// REFDIR (form 1): a 123 direction, where the angle is 0.
    pub refdir: Option<DeId>,
}

impl CylindricalSurface {
    pub(crate) fn decode(d: &mut Dec, form: i32) -> Result<Self, EntityProblem> {
        Ok(CylindricalSurface {
            location: d.ptr("location point")?,
            axis: d.ptr("axis direction")?,
            radius: d.real("radius")?,
            refdir: refdir(d, form)?,
        })
    }
    pub(crate) fn encode(&self, e: &mut Enc) {
        e.ptr(self.location);
        e.ptr(self.axis);
        e.real(self.radius);
        if let Some(r) = self.refdir {
            e.ptr(r);
        }
    }
}

/// 194 right circular conical surface: axis through `location` along `axis`, radius
/// `radius` at `location`, semi-angle `semi_angle` (degrees).
#[derive(Debug, Clone, PartialEq)]
pub struct ConicalSurface {
    /// LOCATION: a 116 point on the axis.
    pub location: DeId,
    /// AXIS: a 123 direction.
    pub axis: DeId,
    /// RADIUS at `location`.
    pub radius: f64,
    /// SANG: semi-angle in degrees.
    pub semi_angle: f64,
    /// REFDIR (form 1): a 123 direction.
    pub refdir: Option<DeId>,
}

impl ConicalSurface {
    pub(crate) fn decode(d: &mut Dec, form: i32) -> Result<Self, EntityProblem> {
        Ok(ConicalSurface {
            location: d.ptr("location point")?,
            axis: d.ptr("axis direction")?,
            radius: d.real("radius")?,
            semi_angle: d.real("semi-angle")?,
            refdir: refdir(d, form)?,
        })
    }
    pub(crate) fn encode(&self, e: &mut Enc) {
        e.ptr(self.location);
        e.ptr(self.axis);
        e.real(self.radius);
        e.real(self.semi_angle);
        if let Some(r) = self.refdir {
            e.ptr(r);
        }
    }
}

/// 196 spherical surface of centre `center` and radius `radius`; `axis` is the polar axis.
#[derive(Debug, Clone, PartialEq)]
pub struct SphericalSurface {
    /// LOCATION: a 116 point, the centre.
    pub center: DeId,
    /// RADIUS.
    pub radius: f64,
    /// AXIS (form 1): a 123 direction, the polar axis.
    pub axis: Option<DeId>,
    /// REFDIR (form 1): a 123 direction.
    pub refdir: Option<DeId>,
}

impl SphericalSurface {
    pub(crate) fn decode(d: &mut Dec, form: i32) -> Result<Self, EntityProblem> {
        let center = d.ptr("centre point")?;
        let radius = d.real("radius")?;
        let axis = if form == 1 {
            Some(d.ptr("axis direction")?)
        } else {
            None
        };
        Ok(SphericalSurface {
            center,
            radius,
            axis,
            refdir: refdir(d, form)?,
        })
    }
    pub(crate) fn encode(&self, e: &mut Enc) {
        e.ptr(self.center);
        e.real(self.radius);
        if let Some(a) = self.axis {
            e.ptr(a);
        }
        if let Some(r) = self.refdir {
            e.ptr(r);
        }
    }
}

/// 198 toroidal surface of centre `center` and axis `axis`: the circle of radius `minor`
/// whose centre runs on the circle of radius `major`.
#[derive(Debug, Clone, PartialEq)]
pub struct ToroidalSurface {
    /// LOCATION: a 116 point, the centre.
    pub center: DeId,
    /// AXIS: a 123 direction.
    pub axis: DeId,
    /// MAJRAD.
    pub major: f64,
    /// MINRAD.
    pub minor: f64,
    /// REFDIR (form 1): a 123 direction.
    pub refdir: Option<DeId>,
}

impl ToroidalSurface {
    pub(crate) fn decode(d: &mut Dec, form: i32) -> Result<Self, EntityProblem> {
        Ok(ToroidalSurface {
            center: d.ptr("centre point")?,
            axis: d.ptr("axis direction")?,
            major: d.real("major radius")?,
            minor: d.real("minor radius")?,
            refdir: refdir(d, form)?,
        })
    }
    pub(crate) fn encode(&self, e: &mut Enc) {
        e.ptr(self.center);
        e.ptr(self.axis);
        e.real(self.major);
        e.real(self.minor);
        if let Some(r) = self.refdir {
            e.ptr(r);
        }
    }
}
