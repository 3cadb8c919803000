//! The error type of `intersect`: every variant names the entity at fault and carries numbers.

/// Everything that can go wrong in `intersect`. Entity labels are supplied by the caller
/// (e.g. `"surface 3"`, `"curve 7"`), so a message can be read without the code.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A point to project (or a control point) has a non-finite coordinate.
    ///
    /// ```
    /// # use intersect::project::{ProjectOptions, SurfaceProjector};
    /// # use geom_db::eval::{ParamSurface, SurfaceDerivs};
    /// # use geom_db::prelude::{Point3, Vector3};
    /// struct Plane;
    /// impl ParamSurface for Plane {
    ///     fn domain(&self) -> ([f64; 2], [f64; 2]) { ([0.0, 1.0], [0.0, 1.0]) }
    ///     fn derivs(&self, u: f64, v: f64) -> SurfaceDerivs {
    ///         let z = Vector3::zeros();
    ///         SurfaceDerivs { point: Point3::new(u, v, 0.0), du: Vector3::x(), dv: Vector3::y(),
    ///                         duu: z, duv: z, dvv: z }
    ///     }
    /// }
    /// let proj = SurfaceProjector::new("plane", &Plane, &ProjectOptions::default()).unwrap();
    /// let err = proj.project(&Point3::new(f64::NAN, 0.0, 0.0)).unwrap_err();
    /// assert!(matches!(err, intersect::Error::NonFinitePoint { .. }));
    /// ```
    #[error("{entity}: point {index} has a non-finite coordinate")]
    NonFinitePoint {
        /// The entity the point was to be projected on / belongs to.
        entity: String,
        /// Index of the point in the caller's list.
        index: usize,
    },

    /// An entity cannot be used: empty or non-finite parameter domain, non-finite evaluation.
    ///
    /// ```
    /// # use intersect::project::{ProjectOptions, SurfaceProjector};
    /// # use geom_db::eval::{ParamSurface, SurfaceDerivs};
    /// # use geom_db::prelude::{Point3, Vector3};
    /// struct Empty;
    /// impl ParamSurface for Empty {
    ///     fn domain(&self) -> ([f64; 2], [f64; 2]) { ([1.0, 1.0], [0.0, 1.0]) }
    ///     fn derivs(&self, u: f64, v: f64) -> SurfaceDerivs {
    ///         let z = Vector3::zeros();
    ///         SurfaceDerivs { point: Point3::new(u, v, 0.0), du: Vector3::x(), dv: Vector3::y(),
    ///                         duu: z, duv: z, dvv: z }
    ///     }
    /// }
    /// let res = SurfaceProjector::new("empty", &Empty, &ProjectOptions::default());
    /// assert!(matches!(res, Err(intersect::Error::BadEntity { .. })));
    /// ```
    #[error("{entity}: {reason}")]
    BadEntity {
        /// The entity.
        entity: String,
        /// What is wrong with it.
        reason: String,
    },

    /// Point inversion (foot of the normal, Eq. 11) did not converge.
    #[error(
        "{entity}: foot of the normal from point {index} did not converge after {iters} \
         iterations (residual {residual:e}, tolerance {tol:e})"
    )]
    ProjectionFailed {
        /// The curve or surface projected on.
        entity: String,
        /// Index of the point in the caller's list (0 for a single point).
        index: usize,
        /// Newton iterations spent.
        iters: usize,
        /// Final residual: the length of the tangential part of r − p.
        residual: f64,
        /// Tolerance that was asked for.
        tol: f64,
    },

    /// A control point of a support curve is not on one of its defining surfaces in the
    /// initial model (Eq. 11 leaves a gap larger than the allowed one).
    #[error(
        "{curve}: control point {point} is {gap:e} away from defining surface {surface} \
         ({surface_label}) in the initial model (allowed {tol:e})"
    )]
    InitialGap {
        /// The support curve.
        curve: String,
        /// Control-point index.
        point: usize,
        /// 1 or 2: which defining surface.
        surface: usize,
        /// The surface's label.
        surface_label: String,
        /// Distance from the control point to the surface.
        gap: f64,
        /// Allowed gap.
        tol: f64,
    },

    /// The two defining surfaces are tangent at a control point: the intersection is not
    /// transversal and its tangent is undefined.
    #[error(
        "{curve}: defining surfaces are tangent at control point {point} \
         (sine of the angle between normals {sine:e})"
    )]
    TangentSurfaces {
        /// The support curve.
        curve: String,
        /// Control-point index.
        point: usize,
        /// |n1 × n2|.
        sine: f64,
    },

    /// Eq. (12) with a frozen parameter and the normal-plane fallback both failed for a
    /// control point of a support curve.
    #[error(
        "{curve}: control point {point} could not be re-intersected: Eq. 12 (frozen parameter) \
         left residual {frozen_residual:e} after {frozen_iters} iterations, the normal-plane \
         fallback left {fallback_residual:e} after {fallback_iters} (tolerance {tol:e})"
    )]
    CurveUpdateFailed {
        /// The support curve.
        curve: String,
        /// Control-point index.
        point: usize,
        /// Iterations of the frozen-parameter Newton.
        frozen_iters: usize,
        /// Its final |r1 − r2|.
        frozen_residual: f64,
        /// Iterations of the fallback.
        fallback_iters: usize,
        /// Its final residual.
        fallback_residual: f64,
        /// Tolerance.
        tol: f64,
    },

    /// Two curves that should meet at a corner (Eq. 13) no longer do.
    #[error(
        "corner {corner}: curves {curve_a} and {curve_b} no longer meet: minimal distance \
         {distance:e} > tolerance {tol:e} (after {iters} iterations, at t_a = {t_a}, t_b = {t_b})"
    )]
    CurvesDoNotMeet {
        /// The corner.
        corner: String,
        /// First curve.
        curve_a: String,
        /// Second curve.
        curve_b: String,
        /// Minimal distance found.
        distance: f64,
        /// Tolerance.
        tol: f64,
        /// Newton iterations.
        iters: usize,
        /// Parameter on the first curve.
        t_a: f64,
        /// Parameter on the second curve.
        t_b: f64,
    },

    /// The geometric database refused the updated model or the new control points.
    #[error(transparent)]
    GeomDb(#[from] geom_db::Error),

    /// A corner's curves were updated but the corner cannot be placed on one of them.
    #[error("{corner}: the new corner is {distance:e} away from {curve} (tolerance {tol:e})")]
    CornerOffCurve {
        /// The corner.
        corner: String,
        /// The curve it should lie on.
        curve: String,
        /// Distance from the corner to the curve.
        distance: f64,
        /// Tolerance.
        tol: f64,
    },

    /// A re-intersected junction is farther from one of its defining surfaces than the
    /// junction tolerance at one of its samples, after the adaptive re-fit.
    #[error(
        "{curve}: the junction is {distance:e} away from {surface} at t = {at_t} \
         (tolerance {tol:e}, {samples} samples, after {refits} re-fits)"
    )]
    JunctionOffSurface {
        /// The junction (support curve).
        curve: String,
        /// The defining surface it is off.
        surface: String,
        /// Largest sampled distance to that surface.
        distance: f64,
        /// Curve parameter of that sample.
        at_t: f64,
        /// Tolerance.
        tol: f64,
        /// Samples measured.
        samples: usize,
        /// Re-fit rounds done.
        refits: usize,
    },

    /// An updated corner is farther than the junction tolerance from a curve or surface that
    /// defines it (a curve ending there, or a defining or bounded surface of such a curve).
    #[error("{corner}: the corner is {distance:e} away from {entity} (tolerance {tol:e})")]
    CornerOffEntity {
        /// The corner.
        corner: String,
        /// The curve or surface.
        entity: String,
        /// Distance (foot of the normal).
        distance: f64,
        /// Tolerance.
        tol: f64,
    },
}

/// `Result` with [`Error`] as the default error type.
pub type Result<T, E = Error> = std::result::Result<T, E>;
