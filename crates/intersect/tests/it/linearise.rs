//! The linearised model update (`ModelBaseline::linearise`) on the wing–body fixture:
//! forward products against central differences of `ModelBaseline::update` (nodes,
//! junction control points, corners, component ranges), and the dot-product test.

use geom_db::GeomDb;
use geom_db::linearise::ModelTangent;
use geom_db::prelude::{Point3, Vector3};
use intersect::update::{ModelBaseline, UpdateOptions};
use proptest::prelude::*;

use crate::fixture::load;

/// A smooth field over space: every control node moves by it (shared nodes consistently),
/// so the fuselage and the wing both change and the junction moves.
fn field(p: &Point3, k: f64) -> Vector3 {
    Vector3::new(
        0.05 * (0.7 * p.x + k).sin() + 0.02 * p.y,
        0.04 * p.y * (0.3 * p.z + k).cos() + 0.01 * p.x,
        0.06 * p.z + 0.02 * (p.x * p.y * 0.2 + k).sin(),
    )
}

fn moved(db: &GeomDb, s: f64, k: f64) -> Vec<Point3> {
    db.control_points()
        .iter()
        .map(|p| p + field(p, k) * s)
        .collect()
}

/// The outputs compared: every control node, every corner, every range, and the control
/// points of the re-intersected curves, flattened.
fn flatten_model(db: &GeomDb, own: &[usize]) -> Vec<f64> {
    let mut v = Vec::new();
    for p in &db.control_nodes {
        v.extend_from_slice(&[p.x, p.y, p.z]);
    }
    for c in &db.corners {
        v.extend_from_slice(&[c.point.x, c.point.y, c.point.z]);
    }
    for cc in &db.curve_components {
        v.extend_from_slice(&[cc.t0, cc.t1]);
    }
    for &ci in own {
        for a in &db.curves[ci].arcs {
            for p in a.control_points() {
                v.extend_from_slice(&[p.x, p.y, p.z]);
            }
        }
    }
    v
}

fn flatten_tangent(t: &ModelTangent, own: &[usize]) -> Vec<f64> {
    let mut v = Vec::new();
    for p in &t.nodes {
        v.extend_from_slice(&[p.x, p.y, p.z]);
    }
    for c in &t.corners {
        v.extend_from_slice(&[c.x, c.y, c.z]);
    }
    for r in &t.ranges {
        v.extend_from_slice(r);
    }
    for &ci in own {
        for a in t.curves[ci].as_ref().expect("own curve") {
            for p in a {
                v.extend_from_slice(&[p.x, p.y, p.z]);
            }
        }
    }
    v
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Checks the forward product at the moved nodes `s` with `opts`; returns the update's
/// number of re-fits there.
fn check_forward(s: f64, opts: &UpdateOptions) -> usize {
    let db = load("wing_body.ron");
    let base = ModelBaseline::new(&db, opts).unwrap();
    let x = moved(&db, s, 0.3);
    let (updated, report) = base.update(&x).unwrap();
    let lin = base.linearise(&x, &updated).unwrap();
    let own: Vec<usize> = lin
        .intersection_curves()
        .iter()
        .map(|c| c.index())
        .collect();
    assert!(!own.is_empty());
    let dp: Vec<Vector3> = db.control_points().iter().map(|p| field(p, 1.1)).collect();
    let t = lin.jvp(&dp).unwrap();
    let jv = flatten_tangent(&t, &own);
    // step study (docs/crates/intersect.md): the error is noise ∝ 7e-11 / h from h = 1e-6
    // (5e-5) to h = 1e-3 (6e-8), truncation below 3e-8 at h = 3e-3
    let h = 2e-3;
    let plus: Vec<Point3> = x.iter().zip(&dp).map(|(p, d)| p + d * h).collect();
    let minus: Vec<Point3> = x.iter().zip(&dp).map(|(p, d)| p - d * h).collect();
    let (up, rp) = base.update(&plus).unwrap();
    let (um, rm) = base.update(&minus).unwrap();
    assert_eq!((rp.refits, rm.refits), (report.refits, report.refits));
    let (fp, fm) = (flatten_model(&up, &own), flatten_model(&um, &own));
    let fd: Vec<f64> = fp
        .iter()
        .zip(&fm)
        .map(|(a, b)| (a - b) / (2.0 * h))
        .collect();
    assert_eq!(fd.len(), jv.len());
    let err: Vec<f64> = fd.iter().zip(&jv).map(|(a, b)| a - b).collect();
    let rel = norm(&err) / norm(&fd);
    eprintln!(
        "model update at s = {s}: |FD| = {:.4e}, relative error {rel:.3e}",
        norm(&fd)
    );
    assert!(rel < 1e-6, "relative error {rel:.3e}");
    // the junction's control points are not the nodes' own motion: they are re-intersected
    let n = db.control_nodes.len();
    let junction: Vec<usize> = (0..n)
        .filter(|&i| {
            !db.surfaces
                .iter()
                .any(|s| s.control.nodes.iter().flatten().any(|id| id.index() == i))
        })
        .collect();
    assert!(!junction.is_empty());
    let mut jn = 0.0f64;
    let mut moved_by_field = 0.0f64;
    for &i in &junction {
        let d = Vector3::new(fd[3 * i], fd[3 * i + 1], fd[3 * i + 2]);
        jn = jn.max(d.norm());
        moved_by_field = moved_by_field.max((d - dp[i]).norm());
        let j = Vector3::new(jv[3 * i], jv[3 * i + 1], jv[3 * i + 2]);
        assert!(
            (d - j).norm() <= 1e-6 * norm(&fd),
            "junction node {i}: {d} vs {j}"
        );
    }
    assert!(jn > 1e-2, "junction rows near zero: {jn}");
    assert!(
        moved_by_field > 1e-3,
        "junction rows equal the field: {moved_by_field}"
    );
    report.refits
}

#[test]
fn forward_product_matches_central_differences_off_the_baseline() {
    assert_eq!(check_forward(1.0, &UpdateOptions::default()), 0);
}

/// A junction tolerance the moved junction misses: the update re-fits it (degrees raised,
/// new control nodes), and the product differentiates the re-fit (foot seeds, Eq. 12 at the
/// new nodes) as it ran.
fn refit_options() -> UpdateOptions {
    UpdateOptions::default().with_junction_rel_tol(REFIT_TOL)
}

const REFIT_TOL: f64 = 5e-10;

#[test]
fn forward_product_through_a_refit_matches_central_differences() {
    assert!(check_forward(1.0, &refit_options()) > 0);
}

#[test]
fn forward_product_matches_central_differences_at_the_baseline() {
    // nothing changed at the baseline: curves and corners are differentiated as re-solved
    assert_eq!(check_forward(0.0, &UpdateOptions::default()), 0);
}

fn random_cotangent(lin: &intersect::update::ModelLinearisation, seed: u64) -> ModelTangent {
    let mut s = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    let mut r = move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    };
    let mut t = lin.zero_tangent();
    for v in &mut t.nodes {
        *v = Vector3::new(r(), r(), r());
    }
    for c in t.curves.iter_mut().flatten() {
        for a in c.iter_mut() {
            for v in a.iter_mut() {
                *v = Vector3::new(r(), r(), r());
            }
        }
    }
    for v in &mut t.corners {
        *v = Vector3::new(r(), r(), r());
    }
    for v in &mut t.ranges {
        *v = [r(), r()];
    }
    t
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 6, ..ProptestConfig::default() })]
    /// ⟨J dP, ȳ⟩ = ⟨dP, Jᵀ ȳ⟩ to 1e-10 relative, without and with a re-fit.
    #[test]
    fn dot_product_test(seed in 0u64..1_000_000, k in 0.0f64..3.0) {
        let db = load("wing_body.ron");
        // without and with a re-fit of the junction
        for opts in [UpdateOptions::default(), refit_options()] {
            let base = ModelBaseline::new(&db, &opts).unwrap();
            let x = moved(&db, 1.0, 0.3);
            let (updated, _) = base.update(&x).unwrap();
            let lin = base.linearise(&x, &updated).unwrap();
            let dp: Vec<Vector3> = db.control_points().iter().map(|p| field(p, k)).collect();
            let ybar = random_cotangent(&lin, seed);
            let jdp = lin.jvp(&dp).unwrap();
            let jty = lin.vjp(&ybar).unwrap();
            let a = jdp.dot(&ybar);
            let b: f64 = dp.iter().zip(&jty).map(|(p, q)| p.dot(q)).sum();
            let scale = jdp.dot(&jdp).sqrt() * ybar.dot(&ybar).sqrt();
            prop_assert!((a - b).abs() <= 1e-10 * scale, "{a} vs {b} (scale {scale})");
        }
    }
}
