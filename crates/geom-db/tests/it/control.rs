//! Control nodes (§3): the solve for A and its inverse, bit-for-bit restore, C0 across
//! shared borders after control-node moves.

use geom_db::prelude::{Point3, Vector3};
use geom_db::{Arc, CheckOptions, GeomDb, Patch, control};
use proptest::prelude::*;

use crate::fixture;

fn pt() -> impl Strategy<Value = Point3> {
    (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64).prop_map(|(x, y, z)| Point3::new(x, y, z))
}

/// Deterministic pseudo-random displacements (a hash of the index and a seed), |d| ≤ amp.
fn displacement(i: usize, seed: u64, amp: f64) -> Vector3 {
    let mut h = seed ^ (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    let mut next = || {
        h ^= h >> 33;
        h = h.wrapping_mul(0xff51_afd7_ed55_8ccd);
        h ^= h >> 33;
        (h >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    Vector3::new(next(), next(), next()) * (amp / 3f64.sqrt())
}

fn coeff_bits(db: &GeomDb) -> Vec<u64> {
    let mut out = Vec::new();
    for c in &db.curves {
        for a in &c.arcs {
            out.extend(
                a.coeffs
                    .iter()
                    .flat_map(|p| p.coords.iter().map(|x| x.to_bits())),
            );
        }
    }
    for s in &db.surfaces {
        for p in &s.patches {
            out.extend(
                p.coeffs
                    .iter()
                    .flat_map(|p| p.coords.iter().map(|x| x.to_bits())),
            );
        }
    }
    out
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn control_points_to_coefficients_and_back(pts in proptest::collection::vec(pt(), 2..13)) {
        let arc = Arc::from_control_points(&pts);
        let back = arc.control_points();
        // round-off bound: eps × (n + 1) × ‖V⁻¹‖ (points of size ≤ √3)
        let n = arc.degree;
        let tol = 4.0 * f64::EPSILON * (n + 1) as f64 * control::inverse_vandermonde_norm(n);
        for (a, b) in pts.iter().zip(&back) {
            prop_assert!((a - b).norm() < tol, "{a} vs {b}, tol {tol:e}");
        }
        // the arc passes through its control points at the frozen nodes
        for (x, p) in control::nodes(n).iter().zip(&pts) {
            prop_assert!((arc.point(*x) - p).norm() < tol);
        }
    }

    #[test]
    fn patch_control_points_to_coefficients_and_back(
        (n, m, pts) in (1usize..9, 1usize..9)
            .prop_flat_map(|(n, m)| (Just(n), Just(m), proptest::collection::vec(pt(), (n + 1) * (m + 1)))),
    ) {
        let p = Patch::from_control_points(n, m, &pts);
        let tol = 4.0 * f64::EPSILON * ((n + 1) * (m + 1)) as f64
            * control::inverse_vandermonde_norm(n) * control::inverse_vandermonde_norm(m);
        for (a, b) in pts.iter().zip(&p.control_points()) {
            prop_assert!((a - b).norm() < tol, "{a} vs {b}, tol {tol:e}");
        }
    }

    #[test]
    fn moved_then_restored_is_bit_for_bit(seed in any::<u64>(), every in 1usize..5) {
        let db = fixture("wing_body.ron");
        let orig = db.control_points().to_vec();
        let l = db.reference_length();
        let moved: Vec<Point3> = orig
            .iter()
            .enumerate()
            .map(|(i, p)| if i % every == 0 { p + displacement(i, seed, 0.01 * l) } else { *p })
            .collect();
        let mut work = db.clone();
        work.set_control_points(&moved).unwrap();
        prop_assert_ne!(coeff_bits(&work), coeff_bits(&db));
        work.set_control_points(&orig).unwrap();
        prop_assert_eq!(coeff_bits(&work), coeff_bits(&db));
        prop_assert_eq!(work.to_ron_string(), db.to_ron_string());
    }

    #[test]
    fn c0_at_every_border_after_random_moves(
        seed in any::<u64>(), which in 0usize..2, rough in any::<bool>(),
    ) {
        let name = ["sphere.ron", "cylinder.ron"][which];
        let db = fixture(name);
        let l = db.reference_length();
        // smooth moves (a random smooth displacement field, as parametrisations produce) or
        // rough ones (independent random moves of every node)
        let w = displacement(usize::MAX, seed, 3.0);
        let phase = displacement(usize::MAX - 1, seed, 3.0);
        let moved: Vec<Point3> = db
            .control_points()
            .iter()
            .enumerate()
            .map(|(i, p)| {
                if rough {
                    p + displacement(i, seed, 0.02 * l)
                } else {
                    let s = (w.dot(&p.coords) + phase.x).sin();
                    let c = (w.y * p.x - w.x * p.z + w.z * p.y + phase.y).cos();
                    p + Vector3::new(s, c, s * c) * (0.02 * l)
                }
            })
            .collect();
        let work = db.with_control_points(&moved).unwrap();
        // Borders are the same polynomial on both sides up to round-off, which in the power
        // basis is relative to the coefficients' size (large for rough moves of degree-8
        // patches): bound the gap by 16 eps Σ|a| of the largest patch.
        let coeff_size = work
            .surfaces
            .iter()
            .flat_map(|s| s.patches.iter())
            .map(|p| p.coeffs.iter().map(|c| c.coords.abs().sum()).sum::<f64>())
            .fold(0.0, f64::max);
        let tol = (16.0 * f64::EPSILON * coeff_size).max(1e-10 * l);
        // patch borders, arc joints, curve components against both surfaces: every border
        // polynomial is fixed by its shared control nodes
        let report = work.check(&CheckOptions { gap_rel: tol / l, samples: 9 });
        for g in &report.gaps {
            if g.what.contains(" ends and ") {
                continue; // corners are not control nodes: intersect re-computes them
            }
            prop_assert!(g.max <= tol, "{name}: {} = {:e} > {tol:e}", g.what, g.max);
        }
        if !rough {
            prop_assert!(tol <= 1e-8 * l, "smooth moves: coefficients {coeff_size:e}");
        }
        // and the control nodes moved by much more than the tolerance
        let moved_by = moved
            .iter()
            .zip(db.control_points())
            .map(|(a, b)| (a - b).norm())
            .fold(0.0, f64::max);
        prop_assert!(moved_by > 100.0 * tol, "{moved_by:e} vs {tol:e}");
    }
}

#[test]
fn zero_perturbation_is_bit_for_bit() {
    for name in ["sphere.ron", "cylinder.ron", "wing_body.ron"] {
        let db = fixture(name);
        let same = db.with_control_points(db.control_points()).unwrap();
        assert_eq!(coeff_bits(&same), coeff_bits(&db), "{name}");
    }
}

#[test]
fn without_baseline_the_solve_reproduces_the_coefficients() {
    // A database deserialised without validation has no baseline: set_control_points solves
    // every arc and patch. The fixtures' coefficients are themselves solutions of Eq. (9)
    // from their control nodes (assign_control_nodes re-solves), so the solve reproduces
    // them to round-off.
    let text = crate::fixture_text("wing_body.ron");
    let db = fixture("wing_body.ron");
    let mut raw: GeomDb = ron::from_str(&text).unwrap();
    raw.set_control_points(db.control_points()).unwrap();
    for (a, b) in raw.surfaces.iter().zip(&db.surfaces) {
        for (p, q) in a.patches.iter().zip(&b.patches) {
            for (x, y) in p.coeffs.iter().zip(&q.coeffs) {
                assert!((x - y).norm() < 1e-12 * db.reference_length());
            }
        }
    }
}

#[test]
fn control_point_errors() {
    let mut db = fixture("cylinder.ron");
    let mut pts = db.control_points().to_vec();
    pts.pop();
    assert!(matches!(
        db.set_control_points(&pts),
        Err(geom_db::Error::ControlPointCount { .. })
    ));
    let mut pts = db.control_points().to_vec();
    pts[3].y = f64::INFINITY;
    let e = db.set_control_points(&pts).unwrap_err();
    assert_eq!(e.to_string(), "control node 3: coordinate y is infinite");
}

#[test]
fn shared_nodes_are_shared() {
    // a cube-sphere edge's control nodes are shared by both faces and by its support curve
    let db = fixture("sphere.ron");
    let deg = db.surfaces[0].patches[0].deg_u;
    let per_face = (deg + 1) * (deg + 1);
    // 6 faces, 8 corners shared by 3 faces, 12 edges with deg - 1 interior nodes shared by 2
    let expected = 6 * per_face - 12 * (deg - 1) - 8 * 2;
    assert_eq!(db.control_nodes.len(), expected);
    for c in &db.curves {
        for ids in &c.control.nodes {
            for id in ids {
                let users = db
                    .surfaces
                    .iter()
                    .filter(|s| s.control.nodes[0].contains(id))
                    .count();
                assert!(users >= 2, "{id} is used by {users} faces");
            }
        }
    }
}
