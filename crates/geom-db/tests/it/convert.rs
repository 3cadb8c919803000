//! Basis conversions: Bézier ↔ power round trips and B-spline extraction against the
//! B-spline evaluation of `bspline::KnotVector`.

use geom_db::bspline::{KnotVector, bernstein};
use geom_db::convert::{
    bezier_to_power, bezier_to_power_2d, bspline_surface_to_power, bspline_to_power,
    patch_to_bspline, power_to_bezier, power_to_bezier_2d, power_to_bspline,
};
use geom_db::eval::ParamSurface;
use geom_db::prelude::Point3;
use geom_db::{Arc, Patch};
use proptest::prelude::*;

fn pt() -> impl Strategy<Value = Point3> {
    (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64).prop_map(|(x, y, z)| Point3::new(x, y, z))
}

/// A random knot vector of degree p (clamped, domain [a, a + len]) with distinct interior
/// knots of multiplicity 1..=p, and its control points.
fn bspline() -> impl Strategy<Value = (KnotVector, Vec<Point3>)> {
    (
        1usize..6,
        proptest::collection::vec((-0.4..0.4f64, 1usize..6), 0..4),
    )
        .prop_flat_map(|(p, interior)| {
            let mults: Vec<usize> = interior.iter().map(|&(_, m)| 1 + (m - 1) % p).collect();
            let n = p + 1 + mults.iter().sum::<usize>();
            let d = interior.len();
            let values: Vec<f64> = interior
                .iter()
                .enumerate()
                .map(|(i, &(jit, _))| (i as f64 + 1.0 + jit) / (d as f64 + 1.0))
                .collect();
            (
                proptest::collection::vec(pt(), n),
                -2.0..2.0f64,
                0.1..3.0f64,
            )
                .prop_map(move |(ctrl, a, len)| {
                    let mut knots = vec![a; p + 1];
                    for (t, &m) in values.iter().zip(&mults) {
                        knots.extend(std::iter::repeat_n(a + len * t, m));
                    }
                    knots.extend(std::iter::repeat_n(a + len, p + 1));
                    (KnotVector::new(p, knots).unwrap(), ctrl)
                })
        })
}

fn arr(p: &Point3) -> [f64; 3] {
    [p.x, p.y, p.z]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    #[test]
    fn power_bezier_round_trip(b in proptest::collection::vec(pt(), 2..12), t in 0.0..1.0f64) {
        let a = bezier_to_power(&b);
        let back = power_to_bezier(&a);
        // round-off relative to the size of the power coefficients
        let size: f64 = a.iter().map(|p| p.coords.abs().sum()).sum();
        let tol = 16.0 * f64::EPSILON * size.max(1.0);
        for (x, y) in b.iter().zip(&back) {
            prop_assert!((x - y).norm() < tol, "{x} vs {y}");
        }
        // the power form evaluates as the Bernstein form
        let n = b.len() - 1;
        let bez = b.iter().enumerate().fold(Point3::origin().coords, |s, (i, p)| {
            s + p.coords * bernstein(n, i, t)
        });
        prop_assert!((Arc::new(a).point(t).coords - bez).norm() < tol);
    }

    #[test]
    fn power_bezier_round_trip_2d(
        (n, m, b) in (1usize..7, 1usize..7)
            .prop_flat_map(|(n, m)| (Just(n), Just(m), proptest::collection::vec(pt(), (n + 1) * (m + 1)))),
        u in 0.0..1.0f64, v in 0.0..1.0f64,
    ) {
        let a = bezier_to_power_2d(n, m, &b);
        let back = power_to_bezier_2d(n, m, &a);
        let size: f64 = a.iter().map(|p| p.coords.abs().sum()).sum();
        let tol = 16.0 * f64::EPSILON * size.max(1.0);
        for (x, y) in b.iter().zip(&back) {
            prop_assert!((x - y).norm() < tol);
        }
        let mut bez = Point3::origin().coords;
        for i in 0..=n {
            for j in 0..=m {
                bez += b[i * (m + 1) + j].coords * bernstein(n, i, u) * bernstein(m, j, v);
            }
        }
        let patch = Patch { deg_u: n, deg_v: m, coeffs: a };
        prop_assert!((patch.point(u, v).coords - bez).norm() < tol);
    }

    #[test]
    fn bspline_extraction_matches_curve_point((kv, ctrl) in bspline(), f in 0.0..1.0f64) {
        let arcs = bspline_to_power(&kv, &ctrl).unwrap();
        let (a, b) = kv.domain();
        prop_assert_eq!(arcs.len(), kv.breakpoints().len() - 1);
        prop_assert_eq!(arcs[0].t0, a);
        prop_assert_eq!(arcs.last().unwrap().t1, b);
        let raw: Vec<[f64; 3]> = ctrl.iter().map(arr).collect();
        for t in [a + f * (b - a), a, b] {
            let arc = arcs.iter().find(|x| x.t0 <= t && t <= x.t1).unwrap();
            let local = (t - arc.t0) / (arc.t1 - arc.t0);
            let want = Point3::from(kv.curve_point(&raw, t));
            let got = arc.arc.point(local);
            prop_assert!((got - want).norm() < 1e-11, "t = {t}: {got} vs {want}");
        }
        // consecutive arcs meet (the B-spline is at least C0)
        for w in arcs.windows(2) {
            prop_assert!((w[0].arc.point(1.0) - w[1].arc.point(0.0)).norm() < 1e-11);
        }
    }

    #[test]
    fn bspline_surface_extraction_matches_tensor_evaluation(
        (ku, cu) in bspline(), (kv, cv) in bspline(), fu in 0.0..1.0f64, fv in 0.0..1.0f64,
    ) {
        // control net: tensor product of the two random polygons, made non-separable
        let (nu, nv) = (cu.len(), cv.len());
        let mut ctrl = Vec::with_capacity(nu * nv);
        for i in 0..nu {
            for j in 0..nv {
                let (p, q) = (cu[i], cv[j]);
                ctrl.push(Point3::new(p.x + q.x, p.y * q.y, p.z - q.z * p.x));
            }
        }
        let ps = bspline_surface_to_power(&ku, &kv, &ctrl).unwrap();
        let (ua, ub) = ku.domain();
        let (va, vb) = kv.domain();
        let (u, v) = (ua + fu * (ub - ua), va + fv * (vb - va));
        let bu = ku.eval_all(u);
        let bv = kv.eval_all(v);
        let mut want = Point3::origin().coords;
        for i in 0..nu {
            for j in 0..nv {
                want += ctrl[i * nv + j].coords * bu[i] * bv[j];
            }
        }
        let i = ps.u_breaks.windows(2).position(|w| w[0] <= u && u <= w[1]).unwrap();
        let j = ps.v_breaks.windows(2).position(|w| w[0] <= v && v <= w[1]).unwrap();
        let lu = (u - ps.u_breaks[i]) / (ps.u_breaks[i + 1] - ps.u_breaks[i]);
        let lv = (v - ps.v_breaks[j]) / (ps.v_breaks[j + 1] - ps.v_breaks[j]);
        let got = ps.surface.point(i as f64 + lu, j as f64 + lv);
        prop_assert!((got.coords - want).norm() < 1e-10, "{got} vs {want}");
    }

    #[test]
    fn power_to_single_span_bspline_and_back(c in proptest::collection::vec(pt(), 2..10), t in 0.0..1.0f64) {
        let arc = Arc::new(c);
        let (kv, ctrl) = power_to_bspline(&arc);
        let raw: Vec<[f64; 3]> = ctrl.iter().map(arr).collect();
        prop_assert!((Point3::from(kv.curve_point(&raw, t)) - arc.point(t)).norm() < 1e-12);
        let again = bspline_to_power(&kv, &ctrl).unwrap();
        prop_assert_eq!(again.len(), 1);
        for (x, y) in again[0].arc.coeffs.iter().zip(&arc.coeffs) {
            prop_assert!((x - y).norm() < 1e-10);
        }
    }
}

#[test]
fn patch_to_bspline_evaluates_the_same() {
    let p = Patch::interpolate(3, 2, |u, v| {
        Point3::new(u * u - v, u * v * v, (u + v).sin())
    });
    let (ku, kv, ctrl) = patch_to_bspline(&p);
    let (bu, bv) = (ku.eval_all(0.3), kv.eval_all(0.8));
    let mut want = Point3::origin().coords;
    for i in 0..=3 {
        for j in 0..=2 {
            want += ctrl[i * 3 + j].coords * bu[i] * bv[j];
        }
    }
    assert!((p.point(0.3, 0.8).coords - want).norm() < 1e-14);
}

#[test]
fn conversion_errors() {
    let kv = KnotVector::clamped_uniform(2, 5).unwrap();
    assert!(bspline_to_power(&kv, &[Point3::origin(); 4]).is_err());
    assert!(bspline_surface_to_power(&kv, &kv, &[Point3::origin(); 24]).is_err());
}
