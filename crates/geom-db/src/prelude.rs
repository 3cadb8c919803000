//! f64 nalgebra aliases used across the workspace.

/// A point in 3D space.
pub type Point3 = nalgebra::Point3<f64>;
/// A vector in 3D space.
pub type Vector3 = nalgebra::Vector3<f64>;
/// A 3×3 matrix.
pub type Matrix3 = nalgebra::Matrix3<f64>;
/// A 2×2 matrix (first fundamental form, parametric Jacobians).
pub type Matrix2 = nalgebra::Matrix2<f64>;
/// A point in a parametric plane.
pub type Point2 = nalgebra::Point2<f64>;
/// A vector in a parametric plane.
pub type Vector2 = nalgebra::Vector2<f64>;
