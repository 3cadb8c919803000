//! Evaluation against analytic truths: the sphere's normal and curvatures, a plane's first
//! fundamental form, derivatives against central differences.

use geom_db::eval::{ParamCurve, ParamSurface, SurfaceDerivs};
use geom_db::prelude::{Point3, Vector3};
use geom_db::{Arc, Patch, SupportCurve, SupportSurface};
use proptest::prelude::*;
use testkit::assert_close;

use crate::fixture;

/// Gaussian and mean curvature from the two fundamental forms.
fn curvatures(d: &SurfaceDerivs) -> (f64, f64) {
    let n = d.du.cross(&d.dv).normalize();
    let (e, f, g) = (d.du.dot(&d.du), d.du.dot(&d.dv), d.dv.dot(&d.dv));
    let (l, m, nn) = (d.duu.dot(&n), d.duv.dot(&n), d.dvv.dot(&n));
    let det = e * g - f * f;
    (
        (l * nn - m * m) / det,
        (e * nn - 2.0 * f * m + g * l) / (2.0 * det),
    )
}

#[test]
fn sphere_points_normals_and_curvature() {
    let db = fixture("sphere.ron");
    let (mut pos, mut ang, mut kerr, mut herr) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for (s, sc) in db.surfaces.iter().zip(&db.surface_components) {
        for i in 0..=20 {
            for j in 0..=20 {
                let (u, v) = (i as f64 / 20.0, j as f64 / 20.0);
                let d = s.derivs(u, v);
                pos = pos.max((d.point.coords.norm() - 1.0).abs());
                // inward (into the fluid) normal of a sphere in flow: outward radial
                let n = d.unit_normal().unwrap() * sc.inward.sign();
                let exact = d.point.coords.normalize();
                ang = ang.max(n.cross(&exact).norm());
                assert!(n.dot(&exact) > 0.0);
                let (k, h) = curvatures(&d);
                kerr = kerr.max((k - 1.0).abs());
                herr = herr.max((h.abs() - 1.0).abs());
            }
        }
    }
    // the degree-8 interpolant is within 1e-6 of the sphere; its first derivatives within
    // ~3e-5 and second derivatives within ~3e-3 (each derivative costs an order of accuracy)
    assert!(pos < 1e-6, "position error {pos:e}");
    assert!(ang < 5e-5, "normal angle error {ang:e}");
    assert!(kerr < 4e-3, "Gaussian curvature error {kerr:e}");
    assert!(herr < 4e-3, "mean curvature error {herr:e}");
}

#[test]
fn plane_first_fundamental_form_is_exact() {
    let o = Point3::new(1.0, -2.0, 0.5);
    let a = Vector3::new(2.0, 0.5, -1.0);
    let b = Vector3::new(-0.25, 3.0, 1.5);
    // an affine map represented with higher degrees than needed: still exact
    let patch = Patch::interpolate(3, 2, |u, v| o + a * u + b * v);
    let s = SupportSurface::new("plane", 1, 1, vec![patch]);
    for &(u, v) in &[(0.0, 0.0), (0.3, 0.7), (1.0, 0.2), (0.5, 1.0)] {
        let d = s.derivs(u, v);
        let g = d.first_fundamental_form();
        assert_close!(g[(0, 0)], a.dot(&a), rel = 1e-13);
        assert_close!(g[(0, 1)], a.dot(&b), rel = 1e-13);
        assert_close!(g[(1, 0)], a.dot(&b), rel = 1e-13);
        assert_close!(g[(1, 1)], b.dot(&b), rel = 1e-13);
        let n = d.unit_normal().unwrap();
        let exact = a.cross(&b).normalize();
        assert_close!(n.dot(&exact), 1.0, rel = 1e-14);
        assert!(d.duu.norm() < 1e-12 && d.duv.norm() < 1e-12 && d.dvv.norm() < 1e-12);
        let p = o + a * u + b * v;
        assert!((d.point - p).norm() < 1e-14);
    }
}

fn coeff() -> impl Strategy<Value = Point3> {
    (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64).prop_map(|(x, y, z)| Point3::new(x, y, z))
}

fn patch() -> impl Strategy<Value = Patch> {
    (1usize..6, 1usize..6).prop_flat_map(|(n, m)| {
        proptest::collection::vec(coeff(), (n + 1) * (m + 1)).prop_map(move |coeffs| Patch {
            deg_u: n,
            deg_v: m,
            coeffs,
        })
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn surface_derivatives_match_central_differences(
        p in patch(), u in 0.05..0.95f64, v in 0.05..0.95f64,
    ) {
        let s = SupportSurface::new("p", 1, 1, vec![p]);
        let h = 1e-5;
        let d = s.derivs(u, v);
        let f = |a: f64, b: f64| s.point(a, b).coords;
        let du = (f(u + h, v) - f(u - h, v)) / (2.0 * h);
        let dv = (f(u, v + h) - f(u, v - h)) / (2.0 * h);
        let duu = (f(u + h, v) - 2.0 * f(u, v) + f(u - h, v)) / (h * h);
        let dvv = (f(u, v + h) - 2.0 * f(u, v) + f(u, v - h)) / (h * h);
        let duv = (f(u + h, v + h) - f(u + h, v - h) - f(u - h, v + h) + f(u - h, v - h))
            / (4.0 * h * h);
        prop_assert!((d.point.coords - f(u, v)).norm() < 1e-14);
        prop_assert!((d.du - du).norm() < 1e-7 * (1.0 + du.norm()), "{} {}", d.du, du);
        prop_assert!((d.dv - dv).norm() < 1e-7 * (1.0 + dv.norm()));
        prop_assert!((d.duv - duv).norm() < 1e-4 * (1.0 + duv.norm()));
        prop_assert!((d.duu - duu).norm() < 1e-3 * (1.0 + duu.norm()));
        prop_assert!((d.dvv - dvv).norm() < 1e-3 * (1.0 + dvv.norm()));
    }

    #[test]
    fn curve_derivatives_match_central_differences(
        c in proptest::collection::vec(coeff(), 2..10), t in 0.05..0.95f64,
    ) {
        let curve = SupportCurve::new("c", vec![Arc::new(c)]);
        let h = 1e-5;
        let d = curve.derivs(t);
        let f = |a: f64| curve.point(a).coords;
        let d1 = (f(t + h) - f(t - h)) / (2.0 * h);
        let d2 = (f(t + h) - 2.0 * f(t) + f(t - h)) / (h * h);
        prop_assert!((d.d1 - d1).norm() < 1e-7 * (1.0 + d1.norm()));
        prop_assert!((d.d2 - d2).norm() < 1e-3 * (1.0 + d2.norm()));
    }

    #[test]
    fn batch_points_equal_single_points(p in patch(), n in 1usize..3) {
        // a 2×n grid of copies; batch evaluation (parallel above 4096 points) must give the
        // same bits as point-by-point evaluation
        let s = SupportSurface::new("g", 2, n, vec![p; 2 * n]);
        let uv: Vec<(f64, f64)> = (0..5000)
            .map(|k| ((k % 97) as f64 / 48.5, (k % 89) as f64 / 89.0 * n as f64))
            .collect();
        let batch = s.points(&uv);
        for (q, &(u, v)) in batch.iter().zip(&uv) {
            prop_assert_eq!(*q, s.point(u, v));
        }
    }
}

#[test]
fn global_parameters_select_arcs_and_patches() {
    let a0 = Arc::line(Point3::new(0.0, 0.0, 0.0), Point3::new(1.0, 0.0, 0.0));
    let a1 = Arc::line(Point3::new(1.0, 0.0, 0.0), Point3::new(1.0, 2.0, 0.0));
    let c = SupportCurve::new("l", vec![a0, a1]);
    assert_eq!(c.domain(), (0.0, 2.0));
    assert_eq!(c.point(1.5), Point3::new(1.0, 1.0, 0.0));
    assert_eq!(c.point(2.0), Point3::new(1.0, 2.0, 0.0));
    assert_eq!(c.derivs(1.5).d1, Vector3::new(0.0, 2.0, 0.0));
    assert_eq!(c.breaks(), vec![1.0]);
    // a 2×1 grid of unit squares shifted in x: global u = 1.25 is patch 1 at local 0.25
    let sq = |x0: f64| Patch::interpolate(1, 1, move |u, v| Point3::new(x0 + u, v, 0.0));
    let s = SupportSurface::new("s", 2, 1, vec![sq(0.0), sq(1.0)]);
    assert_eq!(s.point(1.25, 0.5), Point3::new(1.25, 0.5, 0.0));
    assert_eq!(s.point(2.0, 1.0), Point3::new(2.0, 1.0, 0.0));
    assert_eq!(s.domain(), ([0.0, 2.0], [0.0, 1.0]));
}
