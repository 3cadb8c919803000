//! Conditions 1–6 of §6.1 on built polygons, checked on the evaluated B-spline curve.

use testkit::assert_close;
use wingmaster::ThicknessParams;

fn params(extra: Vec<[f64; 2]>) -> ThicknessParams {
    ThicknessParams {
        r0: 0.0158,
        z1: 0.028,
        z2: 0.052,
        xtmax: 0.31,
        tmax: 0.12,
        crv4: -0.45,
        x6: 0.62,
        z6: 0.042,
        phi_te: 0.28,
        d78: 0.16,
        extra,
    }
}

/// dz/dx and d²z/dx² of the curve at t.
fn slope_curv(poly: &wingmaster::ThicknessPolygon, t: f64) -> (f64, f64) {
    let d = poly.ders(t, 2);
    let (x1, z1, x2, z2) = (d[1][0], d[1][1], d[2][0], d[2][1]);
    (z1 / x1, (x1 * z2 - z1 * x2) / x1.powi(3))
}

fn check(p: &ThicknessParams) {
    let poly = p.polygon().unwrap();
    let pts = poly.points();
    let n = pts.len();
    // 1: end points.
    assert_eq!(pts[0], [0.0, 0.0]);
    assert_eq!(pts[n - 1], [1.0, 0.0]);
    assert_close!(poly.point(0.0).to_vec(), vec![0.0, 0.0], abs = 1e-15);
    assert_close!(poly.point(1.0).to_vec(), vec![1.0, 0.0], abs = 1e-15);
    // 2: P4 and the curve passes through it at the join t = 0.5.
    let i4 = poly.p4_index();
    assert_eq!(pts[i4], [p.xtmax, p.tmax / 2.0]);
    assert_close!(
        poly.point(0.5).to_vec(),
        vec![p.xtmax, p.tmax / 2.0],
        abs = 1e-15
    );
    let left = poly.point(0.5 - 1e-9);
    let right = poly.point(0.5 + 1e-9);
    assert_close!(left.to_vec(), right.to_vec(), abs = 1e-8);
    // 3: zero slope and curvature crv4 on both sides of P4.
    for t in [0.5 - 1e-7, 0.5 + 1e-7] {
        let (s, k) = slope_curv(&poly, t);
        assert!(s.abs() < 1e-6, "slope {s} at {t}");
        assert_close!(k, p.crv4, rel = 1e-5);
    }
    // 4: vertical tangent and radius r0 at the leading edge.
    let d = poly.ders(0.0, 2);
    assert_eq!(d[1][0], 0.0);
    assert!(d[1][1] > 0.0);
    let kappa = (d[1][0] * d[2][1] - d[1][1] * d[2][0]).abs() / d[1][1].abs().powi(3);
    assert_close!(1.0 / kappa, p.r0, rel = 1e-12);
    // The osculating circle: points near the nose satisfy x ≈ z² / (2 r0).
    let q = poly.point(1e-4);
    assert_close!(q[0], q[1] * q[1] / (2.0 * p.r0), rel = 1e-3);
    // 5: trailing-edge angle and |P8 − P7|.
    let (s, _) = slope_curv(&poly, 1.0);
    assert_close!(-s.atan() * 2.0, p.phi_te, rel = 1e-12);
    let p7 = pts[n - 2];
    assert_close!((1.0 - p7[0]).hypot(p7[1]), p.d78, rel = 1e-12);
    // 6: P6 free (placed as given).
    let (nf, _) = wingmaster::thickness::split_extra(p.extra.len());
    assert_eq!(pts[i4 + 2], [p.x6, p.z6]);
    assert_eq!(pts[1], [0.0, p.z1]);
    assert_eq!(pts[2][1], p.z2);
    for (k, e) in p.extra.iter().enumerate() {
        let idx = if k < nf { 3 + k } else { i4 + 3 + (k - nf) };
        assert_eq!(pts[idx], *e);
    }
}

#[test]
fn conditions_hold_on_the_paper_polygon() {
    check(&params(vec![]));
}

#[test]
fn conditions_hold_with_extra_points() {
    check(&params(vec![[0.17, 0.056]]));
    check(&params(vec![[0.17, 0.056], [0.8, 0.025]]));
    check(&params(vec![[0.19, 0.054], [0.21, 0.058], [0.8, 0.025]]));
}

#[test]
fn invalid_parameters_are_reported() {
    let mut p = params(vec![]);
    p.z6 = 0.07; // above tmax/2: no maximum at P4
    let e = p.polygon().unwrap_err().to_string();
    assert!(e.contains("z6"), "{e}");
    let mut p = params(vec![]);
    p.crv4 = 0.3;
    assert!(p.polygon().unwrap_err().to_string().contains("crv4"));
    let mut p = params(vec![]);
    p.d78 = 0.5; // P7 left of P6
    assert!(p.polygon().is_err());
}
