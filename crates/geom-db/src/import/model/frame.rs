//! Frames and affine maps of the neutral model.
//!
//! A [`Frame`] keeps its axis vectors as given, not normalised: a frame mapped by an affine
//! map is the image of the canonical one, so analytic curves and surfaces stay exact (a
//! circle under a non-uniform scaling becomes the right ellipse) and their parametrisation
//! (hence the files' parameter-space curves) is unchanged.

use crate::prelude::{Matrix3, Point3, Vector3};

/// x' = L x + t.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Affine {
    /// The linear part L.
    pub linear: Matrix3,
    /// The translation t.
    pub translation: Vector3,
}

impl Affine {
    /// The identity.
    pub fn identity() -> Self {
        Affine {
            linear: Matrix3::identity(),
            translation: Vector3::zeros(),
        }
    }

    /// A uniform scaling about the origin (a change of length unit).
    pub fn scaling(s: f64) -> Self {
        Affine {
            linear: Matrix3::identity() * s,
            translation: Vector3::zeros(),
        }
    }

    /// L p + t.
    pub fn point(&self, p: &Point3) -> Point3 {
        Point3::from(self.linear * p.coords + self.translation)
    }

    /// L v.
    pub fn vector(&self, v: &Vector3) -> Vector3 {
        self.linear * v
    }

    /// `self` applied first, then `outer`.
    pub fn then(&self, outer: &Affine) -> Affine {
        Affine {
            linear: outer.linear * self.linear,
            translation: outer.linear * self.translation + outer.translation,
        }
    }

    /// The factor s when L = s Q with Q orthogonal (a similarity), `None` otherwise
    /// (relative tolerance 1e-9).
    pub fn similarity_factor(&self) -> Option<f64> {
        let g = self.linear.transpose() * self.linear;
        let s2 = g.trace() / 3.0;
        if !(s2 > 0.0) || !s2.is_finite() {
            return None;
        }
        let off = (g - Matrix3::identity() * s2).abs().max();
        (off <= 1e-9 * s2).then(|| s2.sqrt() * self.linear.determinant().signum())
    }
}

/// An origin and three axis vectors (see the module doc: not necessarily orthonormal).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// The origin.
    pub origin: Point3,
    /// The first axis.
    pub x: Vector3,
    /// The second axis.
    pub y: Vector3,
    /// The third axis (the normal of a plane, the axis of a cylinder).
    pub z: Vector3,
}

impl Frame {
    /// The right-handed orthonormal frame with axis `z` and first axis the part of `x_hint`
    /// orthogonal to `z` (ISO 10303-42 `build_axes`): without a hint, (1, 0, 0), or
    /// (0, 0, 1) when the axis is along x. `None` when `z` is null or `x_hint` parallel to it.
    pub fn orthonormal(origin: Point3, z: Vector3, x_hint: Option<Vector3>) -> Option<Frame> {
        let zn = z.norm();
        if !(zn > 0.0) || !zn.is_finite() {
            return None;
        }
        let z = z / zn;
        let hint = x_hint.unwrap_or_else(|| {
            if (z - Vector3::x()).norm() > 1e-12 {
                Vector3::x()
            } else {
                Vector3::z()
            }
        });
        let x = hint - z * z.dot(&hint);
        let xn = x.norm();
        if !(xn > 1e-12 * hint.norm()) || !xn.is_finite() {
            return None;
        }
        let x = x / xn;
        Some(Frame {
            origin,
            x,
            y: z.cross(&x),
            z,
        })
    }

    /// An orthonormal frame with normal `z` and a first axis chosen from the coordinate axis
    /// least aligned with it (deterministic; for planes given by a normal only).
    pub fn from_normal(origin: Point3, z: Vector3) -> Option<Frame> {
        let a = z.abs();
        let hint = if a.x <= a.y && a.x <= a.z {
            Vector3::x()
        } else if a.y <= a.z {
            Vector3::y()
        } else {
            Vector3::z()
        };
        Frame::orthonormal(origin, z, Some(hint))
    }

    /// origin + a x + b y + c z.
    pub fn at(&self, a: f64, b: f64, c: f64) -> Point3 {
        self.origin + self.x * a + self.y * b + self.z * c
    }

    /// The frame's coordinates (a, b, c) of `p` (solving with the axis matrix); `None` when
    /// the axes are degenerate.
    pub fn local(&self, p: &Point3) -> Option<Vector3> {
        let m = Matrix3::from_columns(&[self.x, self.y, self.z]);
        m.try_inverse().map(|inv| inv * (p - self.origin))
    }

    /// The image of the frame under `m`.
    pub fn transformed(&self, m: &Affine) -> Frame {
        Frame {
            origin: m.point(&self.origin),
            x: m.vector(&self.x),
            y: m.vector(&self.y),
            z: m.vector(&self.z),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn build_axes_follows_the_step_rule() {
        let f = Frame::orthonormal(Point3::origin(), Vector3::new(0.0, 0.0, 2.0), None).unwrap();
        assert_eq!((f.x, f.y, f.z), (Vector3::x(), Vector3::y(), Vector3::z()));
        let f = Frame::orthonormal(Point3::origin(), Vector3::x(), None).unwrap();
        assert_eq!((f.x, f.y), (Vector3::z(), -Vector3::y()));
        let f = Frame::orthonormal(
            Point3::origin(),
            Vector3::z(),
            Some(Vector3::new(1.0, 1.0, 5.0)),
        )
        .unwrap();
        assert!((f.x - Vector3::new(1.0, 1.0, 0.0) / 2f64.sqrt()).norm() < 1e-15);
        assert!(Frame::orthonormal(Point3::origin(), Vector3::z(), Some(Vector3::z())).is_none());
    }

    #[test]
    fn local_coordinates_invert_at() {
        let m = Affine {
            linear: Matrix3::new(2.0, 0.5, 0.0, 0.0, 1.0, 0.3, 0.1, 0.0, 3.0),
            translation: Vector3::new(1.0, -2.0, 0.5),
        };
        let f = Frame::from_normal(Point3::new(0.5, 0.0, 1.0), Vector3::new(1.0, 2.0, 3.0))
            .unwrap()
            .transformed(&m);
        let p = f.at(0.3, -1.2, 2.5);
        let q = f.local(&p).unwrap();
        assert!((q - Vector3::new(0.3, -1.2, 2.5)).norm() < 1e-13);
        assert_eq!(m.similarity_factor(), None);
        let r = Affine {
            linear: Matrix3::new(0.0, -2.0, 0.0, 2.0, 0.0, 0.0, 0.0, 0.0, 2.0),
            translation: Vector3::zeros(),
        };
        assert!((r.similarity_factor().unwrap() - 2.0).abs() < 1e-15);
    }
}
