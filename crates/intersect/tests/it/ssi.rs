//! Support-curve update by surface–surface intersection (Eq. 12) against analytic curves.

use crate::shapes::*;
use geom_db::eval::ParamSurface;
use geom_db::prelude::{Point3, Vector3};
use intersect::check::curve_surface_deviation;
use intersect::project::{ProjectOptions, SurfaceProjector};
use intersect::ssi::{IntersectionSeeds, Method, Param, SsiOptions, update_curve_points};
use testkit::assert_close;

fn seeds<S1: ParamSurface, S2: ParamSurface>(
    pts: &[Point3],
    s1: &S1,
    s2: &S2,
    scale: f64,
) -> IntersectionSeeds {
    let po = ProjectOptions::default().with_length_scale(scale);
    let p1 = SurfaceProjector::new("s1", s1, &po).unwrap();
    let p2 = SurfaceProjector::new("s2", s2, &po).unwrap();
    let o = SsiOptions::default().with_length_scale(scale);
    IntersectionSeeds::new("curve", pts, None, None, &p1, &p2, &o).unwrap()
}

#[test]
fn plane_sphere_circle_follows_the_plane() {
    let sphere = Sphere {
        c: Point3::origin(),
        r: 1.0,
    };
    let (h0, h1) = (0.2, -0.35);
    let plane0 = Plane::horizontal(h0, 1.5);
    let rho0 = (1.0f64 - h0 * h0).sqrt();
    let az: Vec<f64> = (0..13).map(|k| 0.3 + 5.5 * k as f64 / 12.0).collect();
    let pts: Vec<Point3> = az
        .iter()
        .map(|a| Point3::new(rho0 * a.cos(), rho0 * a.sin(), h0))
        .collect();
    let sd = seeds(&pts, &plane0, &sphere, 2.0);
    let plane1 = Plane::horizontal(h1, 1.5);
    let up = update_curve_points(&sd, &plane1, &sphere, &SsiOptions::default()).unwrap();
    let rho1 = (1.0f64 - h1 * h1).sqrt();
    assert_eq!(up.fallbacks, 0);
    for (a, p) in az.iter().zip(&up.points) {
        // sphere is surface 2, its azimuth u is frozen: the point keeps its azimuth
        assert_eq!(
            p.method,
            Method::Frozen {
                surface: 2,
                param: Param::U
            }
        );
        assert_close!(p.point, [rho1 * a.cos(), rho1 * a.sin(), h1], abs = 1e-13);
        assert!(p.residual <= 2e-12);
    }
}

#[test]
fn zero_change_returns_the_initial_points() {
    let sphere = Sphere {
        c: Point3::new(0.1, 0.2, 0.3),
        r: 1.3,
    };
    let plane = Plane {
        o: Point3::new(0.1, 0.2, 0.5),
        e1: Vector3::new(1.0, 0.0, 0.2).normalize(),
        e2: Vector3::y(),
        dom: ([-2.0, 2.0], [-2.0, 2.0]),
    };
    // circle: plane ∩ sphere; centre = projection of the sphere centre on the plane
    let n = plane.normal();
    let dc = (sphere.c - plane.o).dot(&n);
    let centre = sphere.c - n * dc;
    let rad = (sphere.r * sphere.r - dc * dc).sqrt();
    let pts: Vec<Point3> = (0..9)
        .map(|k| {
            let t = 0.4 + 0.6 * k as f64;
            centre + (plane.e1 * t.cos() + plane.e2 * t.sin()) * rad
        })
        .collect();
    let sd = seeds(&pts, &plane, &sphere, 3.0);
    let up = update_curve_points(&sd, &plane, &sphere, &SsiOptions::default()).unwrap();
    assert_eq!(up.iterations, 0);
    for (p, q) in pts.iter().zip(up.new_points()) {
        assert_close!([q.x, q.y, q.z], [p.x, p.y, p.z], abs = 4e-16 * 3.0);
    }
}

/// The exact new point on the Steinmetz curve x² + y² = r1², y² + z² = r2² for the frozen
/// parameter of the x-axis cylinder (surface 2), on the branch of the old point.
fn steinmetz_expected(old: &Point3, uv2: [f64; 2], method: Method, r1: f64, r2: f64) -> Point3 {
    match method {
        Method::Frozen {
            surface: 2,
            param: Param::U,
        } => {
            let (y, z) = (r2 * uv2[0].cos(), r2 * uv2[0].sin());
            Point3::new(old.x.signum() * (r1 * r1 - y * y).sqrt(), y, z)
        }
        Method::Frozen {
            surface: 2,
            param: Param::V,
        } => {
            let x = uv2[1];
            let y = old.y.signum() * (r1 * r1 - x * x).sqrt();
            Point3::new(x, y, old.z.signum() * (r2 * r2 - y * y).sqrt())
        }
        m => panic!("unexpected method {m:?}"),
    }
}

fn steinmetz_case(r1: f64, r2_old: f64, r2_new: f64, phis: &[f64]) {
    let c1 = Cylinder::axis_z(r1, 3.0);
    let c2 = Cylinder::axis_x(r2_old, 3.0);
    let pts: Vec<Point3> = phis
        .iter()
        .map(|&f| {
            let (y, z) = (r2_old * f.cos(), r2_old * f.sin());
            Point3::new((r1 * r1 - y * y).sqrt(), y, z)
        })
        .collect();
    let sd = seeds(&pts, &c1, &c2, 5.0);
    let c2n = Cylinder::axis_x(r2_new, 3.0);
    let up = update_curve_points(&sd, &c1, &c2n, &SsiOptions::default()).unwrap();
    for ((old, s), p) in pts.iter().zip(&sd.points).zip(&up.points) {
        let q = Point3::from(p.point);
        // on both new cylinders
        assert_close!(q.x * q.x + q.y * q.y, r1 * r1, abs = 1e-12);
        assert_close!(q.y * q.y + q.z * q.z, r2_new * r2_new, abs = 1e-12);
        // where the frozen parameter says
        let e = steinmetz_expected(old, s.uv2, p.method, r1, r2_new);
        assert_close!(p.point, [e.x, e.y, e.z], abs = 1e-12);
    }
}

#[test]
fn steinmetz_unequal_radii() {
    let phis: Vec<f64> = (0..11).map(|k| -2.8 + 5.6 * k as f64 / 10.0).collect();
    steinmetz_case(1.0, 0.6, 0.75, &phis);
    steinmetz_case(1.0, 0.75, 0.5, &phis);
}

#[test]
fn steinmetz_towards_equal_radii() {
    // equal radii: the curve splits into two ellipses x = ±z crossing at (0, ±r, 0) where the
    // cylinders are tangent; points away from the crossings stay well posed
    let phis: Vec<f64> = (0..9).map(|k| 0.5 + 2.1 * k as f64 / 8.0).collect();
    steinmetz_case(1.0, 0.8, 1.0, &phis);
    steinmetz_case(1.0, 1.0, 0.9, &phis);
    let c = Cylinder::axis_x(1.0, 3.0);
    // on the ellipse x = z for equal radii
    let c1 = Cylinder::axis_z(1.0, 3.0);
    let pts: Vec<Point3> = phis
        .iter()
        .map(|&f| Point3::new(f.sin(), f.cos(), f.sin()))
        .collect();
    let sd = seeds(&pts, &c1, &c, 5.0);
    let up = update_curve_points(&sd, &c1, &c, &SsiOptions::default()).unwrap();
    for p in &up.points {
        assert_close!(p.point[0], p.point[2], abs = 1e-12);
    }
}

/// Initial points of h(x, y) = c on the bicubic graph along x = x_k (1-D Newton in y).
fn bicubic_level_points(b: &BicubicGraph, c: f64) -> Vec<Point3> {
    let mut out = Vec::new();
    for k in 0..9 {
        let x = 0.3 + 0.45 * k as f64 / 8.0;
        let mut y = 0.5;
        for _ in 0..60 {
            let h = b.h(x, y);
            y -= (h[0] - c) / h[2];
        }
        assert!((b.h(x, y)[0] - c).abs() < 1e-14 && (0.0..=1.0).contains(&y));
        out.push(Point3::new(x, y, c));
    }
    out
}

#[test]
fn plane_bicubic_patch() {
    let b = BicubicGraph::sample();
    let c0 = b.h(0.5, 0.5)[0];
    let pts = bicubic_level_points(&b, c0);
    let plane0 = Plane::horizontal(c0, 2.0);
    let sd = seeds(&pts, &b, &plane0, 2.0);
    // move the plane
    let c1 = c0 + 0.01;
    let up =
        update_curve_points(&sd, &b, &Plane::horizontal(c1, 2.0), &SsiOptions::default()).unwrap();
    for p in &up.points {
        assert_close!(p.point[2], c1, abs = 1e-13);
        assert_close!(b.h(p.point[0], p.point[1])[0], c1, abs = 1e-13);
    }
    // change the patch (raise one coefficient) with the plane fixed
    let mut b2 = b.clone();
    b2.c[1][2] += 0.02;
    let up = update_curve_points(&sd, &b2, &plane0, &SsiOptions::default()).unwrap();
    for p in &up.points {
        assert_close!(p.point[2], c0, abs = 1e-13);
        assert_close!(b2.h(p.point[0], p.point[1])[0], c0, abs = 1e-13);
        assert!(p.moved > 0.0);
    }
}

#[test]
fn translating_a_surface_along_the_junction_normal_moves_the_curve_by_the_known_amount() {
    // vertical cylinder (fuselage-like) cut by a tilted plane (wing-like): an ellipse.
    // Translating the plane by δ along its normal n moves each point, with the cylinder's
    // angle frozen, by δ / n_z along the generator z.
    let cyl = Cylinder::axis_z(1.0, 4.0);
    let alpha: f64 = 0.4;
    let n = Vector3::new(alpha.sin(), 0.0, alpha.cos());
    let e1 = Vector3::new(alpha.cos(), 0.0, -alpha.sin());
    let plane = Plane {
        o: Point3::new(0.0, 0.0, 0.3),
        e1,
        e2: Vector3::y(),
        dom: ([-3.0, 3.0], [-3.0, 3.0]),
    };
    // ellipse points: angle a on the cylinder, z from the plane equation (p − o)·n = 0
    let pts: Vec<Point3> = (0..10)
        .map(|k| {
            let a = -2.9 + 5.8 * k as f64 / 9.0;
            let (x, y) = (a.cos(), a.sin());
            let z = 0.3 - x * n.x / n.z;
            Point3::new(x, y, z)
        })
        .collect();
    let sd = seeds(&pts, &plane, &cyl, 8.0);
    for delta in [1e-6, 0.01, -0.2] {
        let moved = plane.translated(n * delta);
        let up = update_curve_points(&sd, &moved, &cyl, &SsiOptions::default()).unwrap();
        for (old, p) in pts.iter().zip(&up.points) {
            assert_eq!(
                p.method,
                Method::Frozen {
                    surface: 2,
                    param: Param::U
                }
            );
            let want = old + Vector3::z() * (delta / n.z);
            assert_close!(p.point, [want.x, want.y, want.z], abs = 1e-13);
            assert_close!(p.moved, delta.abs() / n.z, rel = 1e-9);
        }
    }
}

#[test]
fn frozen_parameter_without_solution_falls_back_to_the_normal_plane() {
    // sphere (surface 1) ∩ plane z = h (surface 2, parameters x, y): at 45° both plane
    // parameters are frozen candidates, and moving the plane to z = 0.8 leaves the iso-lines
    // x = 0.707 and y = 0.707 without intersection (0.5 + 0.64 > 1). The fallback puts the
    // point on the new circle in the old normal plane x = y.
    let sphere = Sphere {
        c: Point3::origin(),
        r: 1.0,
    };
    let s45 = std::f64::consts::FRAC_1_SQRT_2;
    let pts = vec![Point3::new(s45, s45, 0.0), Point3::new(-0.6, 0.8, 0.0)];
    let sd = seeds(&pts, &sphere, &Plane::horizontal(0.0, 1.5), 2.0);
    let up = update_curve_points(
        &sd,
        &sphere,
        &Plane::horizontal(0.8, 1.5),
        &SsiOptions::default(),
    )
    .unwrap();
    let p = &up.points[0];
    assert_eq!(p.method, Method::NormalPlane);
    assert!(matches!(p.frozen, Method::Frozen { surface: 2, .. }));
    assert_close!(p.point, [0.6 * s45, 0.6 * s45, 0.8], abs = 1e-12);
    assert!(up.fallbacks >= 1);
    // the other point is on the new circle too, whatever the method
    let q = Point3::from(up.points[1].point);
    assert_close!(q.coords.norm(), 1.0, abs = 1e-12);
    assert_close!(q.z, 0.8, abs = 1e-12);
}

#[test]
fn surfaces_that_no_longer_meet_are_an_error_naming_the_curve() {
    let sphere = Sphere {
        c: Point3::origin(),
        r: 1.0,
    };
    let pts = vec![Point3::new(0.6, 0.8, 0.0)];
    let sd = seeds(&pts, &Plane::horizontal(0.0, 1.5), &sphere, 2.0);
    let err = update_curve_points(
        &sd,
        &Plane::horizontal(1.2, 1.5),
        &sphere,
        &SsiOptions::default(),
    )
    .unwrap_err();
    assert!(matches!(
        err,
        intersect::Error::CurveUpdateFailed { point: 0, .. }
    ));
    assert!(
        err.to_string().starts_with("curve: control point 0"),
        "{err}"
    );
}

#[test]
fn initial_gap_is_checked() {
    let sphere = Sphere {
        c: Point3::origin(),
        r: 1.0,
    };
    let po = ProjectOptions::default();
    let plane = Plane::horizontal(0.0, 1.5);
    let p1 = SurfaceProjector::new("wing", &plane, &po).unwrap();
    let p2 = SurfaceProjector::new("body", &sphere, &po).unwrap();
    let err = IntersectionSeeds::new(
        "junction",
        &[Point3::new(0.6, 0.8, 1e-3)],
        None,
        None,
        &p1,
        &p2,
        &SsiOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("junction") && err.contains("wing"), "{err}");
}

#[test]
fn between_control_points_accuracy_of_interpolated_arcs() {
    // the new control points of the plane ∩ sphere circle are interpolated by degree-n arcs;
    // the distance to both surfaces between control points is the interpolation error, which
    // must fall with more arcs / higher degree. Measured at 200 samples per arc.
    let sphere = Sphere {
        c: Point3::origin(),
        r: 1.0,
    };
    let h1 = 0.1;
    let plane1 = Plane::horizontal(h1, 1.5);
    let rho0 = (1.0f64 - 0.04f64).sqrt();
    let po = ProjectOptions::default().with_length_scale(2.0);
    let sp = SurfaceProjector::new("sphere", &sphere, &po).unwrap();
    let pp = SurfaceProjector::new("plane", &plane1, &po).unwrap();
    let mut devs = Vec::new();
    for (degree, arcs) in [(3usize, 8usize), (5, 8), (7, 16)] {
        let n = degree * arcs;
        let pts: Vec<Point3> = (0..=n)
            .map(|k| {
                let a = 0.3 + 5.6 * k as f64 / n as f64;
                Point3::new(rho0 * a.cos(), rho0 * a.sin(), 0.2)
            })
            .collect();
        let sd = seeds(&pts, &Plane::horizontal(0.2, 1.5), &sphere, 2.0);
        let up = update_curve_points(&sd, &plane1, &sphere, &SsiOptions::default()).unwrap();
        let curve = LagrangeCurve {
            degree,
            points: up.new_points(),
        };
        let dev = curve_surface_deviation("circle", &curve, &pp, &sp, 200).unwrap();
        assert_eq!(dev.samples, 200 * arcs + 1);
        // on the plane exactly (control points are, interpolation keeps z)
        assert!(dev.max_distance[0] < 1e-13, "{dev:?}");
        devs.push(dev.max_distance[1]);
    }
    assert!(devs[0] > 1e-6 && devs[0] < 1e-3, "{devs:?}");
    assert!(devs[1] < devs[0] / 20.0, "{devs:?}");
    assert!(devs[2] < 1e-10, "degree 7, 16 arcs: {devs:?}");
    eprintln!("between-control-point deviation (deg 3×8, 5×8, 7×16 arcs): {devs:?}");
}
