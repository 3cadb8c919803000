//! Quality measures against analytic values, and the generated box.

use mesh::quality::{self, tet_min_dihedral, tet_quality, triangle_quality};
use mesh::{ElementKind, generate};
use proptest::prelude::*;

const S: f64 = std::f64::consts::FRAC_1_SQRT_2;
const REGULAR: [[f64; 3]; 4] = [
    [1.0, 0.0, -S],
    [0.0, 1.0, S],
    [-1.0, 0.0, -S],
    [0.0, -1.0, S],
];

#[test]
fn regular_flat_and_inverted_tetrahedra() {
    testkit::assert_close!(tet_quality(REGULAR), 1.0, rel = 1e-14);
    let inverted = [REGULAR[1], REGULAR[0], REGULAR[2], REGULAR[3]];
    testkit::assert_close!(tet_quality(inverted), -1.0, rel = 1e-14);
    let flat = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.3, 0.3, 0.0],
    ];
    assert_eq!(tet_quality(flat), 0.0);
    assert_eq!(tet_quality([[1.0; 3]; 4]), 0.0);
    // The Kuhn tetrahedron of a unit cube: V = 1/6, Σl² = 10, q = 12 (1/2)^(2/3) / 10.
    let kuhn = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [1.0, 1.0, 1.0],
    ];
    testkit::assert_close!(tet_quality(kuhn), 1.2 * 0.5f64.powf(2.0 / 3.0), rel = 1e-14);
    // Dihedral angles: regular acos(1/3); Kuhn 45°, 60°, 90° (min 45°); flat 0.
    testkit::assert_close!(
        tet_min_dihedral(REGULAR),
        (1.0f64 / 3.0).acos().to_degrees(),
        rel = 1e-12
    );
    testkit::assert_close!(tet_min_dihedral(kuhn), 45.0, rel = 1e-12);
    testkit::assert_close!(tet_min_dihedral(flat), 0.0, abs = 1e-12);
}

#[test]
fn triangles_signed_in_two_dimensions() {
    let h = 3f64.sqrt() / 2.0;
    let eq = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, h, 0.0]];
    testkit::assert_close!(triangle_quality(eq, true), 1.0, rel = 1e-14);
    let cw = [eq[0], eq[2], eq[1]];
    testkit::assert_close!(triangle_quality(cw, true), -1.0, rel = 1e-14);
    testkit::assert_close!(triangle_quality(cw, false), 1.0, rel = 1e-14);
    testkit::assert_close!(quality::triangle_min_angle(eq), 60.0, rel = 1e-12);
    // Right isosceles: 4√3 (1/2) / (1 + 1 + 2) = √3/2.
    let right = [[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    testkit::assert_close!(
        triangle_quality(right, true),
        3f64.sqrt() / 2.0,
        rel = 1e-14
    );
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 64,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x5eed_0001),
        ..ProptestConfig::default()
    })]
    /// q is invariant under translation, rotation and uniform scaling.
    #[test]
    fn quality_is_similarity_invariant(
        pts in prop::array::uniform4(prop::array::uniform3(-1.0f64..1.0)),
        angle in 0.0f64..6.3, scale in 0.01f64..100.0, shift in prop::array::uniform3(-5.0f64..5.0),
    ) {
        let q0 = tet_quality(pts);
        let (c, s) = (angle.cos(), angle.sin());
        let moved = pts.map(|p| {
            let r = [c * p[0] - s * p[1], s * p[0] + c * p[1], p[2]];
            [scale * r[0] + shift[0], scale * r[1] + shift[1], scale * r[2] + shift[2]]
        });
        let q1 = tet_quality(moved);
        prop_assert!((q0 - q1).abs() <= 1e-9 * (1.0 + q0.abs()) , "{} vs {}", q0, q1);
        prop_assert!((-1.0 - 1e-12..=1.0 + 1e-12).contains(&q0));
    }
}

#[test]
fn generated_box_is_valid_positive_and_closed() {
    let (lo, hi) = ([-1.0, 0.0, 2.0], [1.0, 0.5, 3.5]);
    let m = generate::box_tets(3, 4, 5, lo, hi);
    m.validate().unwrap();
    let mut vol = 0.0;
    for t in m.tets() {
        let p = t.map(|v| m.coords[v as usize]);
        let v = quality::tet_volume(p);
        assert!(v > 0.0);
        vol += v;
    }
    testkit::assert_close!(vol, 2.0 * 0.5 * 1.5, rel = 1e-12);
    // Each marker: area-weighted normal sum equals the outward normal times the face area.
    let size = [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]];
    for (a, axis) in ["x", "y", "z"].iter().enumerate() {
        for (side, sign) in [("_m", -1.0), ("_p", 1.0)] {
            let mk = m.marker(&format!("{axis}{side}")).unwrap();
            let mut n = [0.0; 3];
            for (_, t) in mk.elements.iter() {
                let p: Vec<[f64; 3]> = t.iter().map(|&v| m.coords[v as usize]).collect();
                let u = [p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]];
                let w = [p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]];
                n[0] += 0.5 * (u[1] * w[2] - u[2] * w[1]);
                n[1] += 0.5 * (u[2] * w[0] - u[0] * w[2]);
                n[2] += 0.5 * (u[0] * w[1] - u[1] * w[0]);
            }
            let mut want = [0.0; 3];
            want[a] = sign * size[(a + 1) % 3] * size[(a + 2) % 3];
            testkit::assert_close!(n, want, rel = 1e-12, abs = 1e-12);
        }
    }
    // Every boundary triangle is a face of exactly one tetrahedron (conforming split).
    let mut faces = std::collections::HashMap::new();
    for t in m.tets() {
        for f in [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]] {
            let mut k = [t[f[0]], t[f[1]], t[f[2]]];
            k.sort_unstable();
            *faces.entry(k).or_insert(0) += 1;
        }
    }
    let boundary: Vec<[u32; 3]> = faces
        .iter()
        .filter(|(_, c)| **c == 1)
        .map(|(k, _)| *k)
        .collect();
    assert!(faces.values().all(|&c| c <= 2));
    let n_marked: usize = m
        .markers
        .iter()
        .map(|k| k.elements.count(ElementKind::Triangle))
        .sum();
    assert_eq!(boundary.len(), n_marked);
    for mk in &m.markers {
        for (_, t) in mk.elements.iter() {
            let mut k = [t[0], t[1], t[2]];
            k.sort_unstable();
            assert_eq!(faces.get(&k), Some(&1));
        }
    }
}

#[test]
fn shuffled_box_keeps_quality_per_element() {
    let a = generate::box_tets(3, 3, 3, [0.0; 3], [1.0; 3]);
    let mut b = a.clone();
    let perm = generate::shuffle_nodes(&mut b, 42);
    assert_ne!(a.tets(), b.tets());
    for (i, p) in a.coords.iter().enumerate() {
        assert_eq!(*p, b.coords[perm[i] as usize]);
    }
    assert_eq!(quality::cell_quality(&a), quality::cell_quality(&b));
}

#[test]
fn summary_and_comparison() {
    let a = generate::box_tets(4, 4, 4, [0.0; 3], [1.0; 3]);
    let s = quality::summary(&quality::cell_quality(&a));
    // All tets are Kuhn tetrahedra of equal cubes.
    testkit::assert_close!(s.min, 1.2 * 0.5f64.powf(2.0 / 3.0), rel = 1e-12);
    testkit::assert_close!(s.max, s.min, rel = 1e-12);
    assert_eq!((s.count, s.measured, s.n_nonpositive), (384, 384, 0));
    // Zero perturbation: every ratio is exactly 1.
    let c = quality::compare(&a, &a, 3).unwrap();
    assert!(c.ratio.iter().all(|&r| r == 1.0));
    // Push one interior node onto a neighbour's plane: the elements around it degrade, the
    // worst one is reported with its centroid inside the box.
    let mut b = a.clone();
    let centre = (2 + 5 * (2 + 5 * 2)) as usize;
    b.coords[centre][0] += 0.24;
    let c = quality::compare(&a, &b, 5).unwrap();
    assert_eq!(c.worst.len(), 5);
    let w = c.worst[0];
    assert!(w.after < w.before && w.ratio < 1.0);
    assert!(a.tets()[w.id].contains(&(centre as u32)));
    assert!(c.worst.windows(2).all(|p| p[0].after <= p[1].after));
    assert!(w.centroid.iter().all(|&x| (0.0..=1.0).contains(&x)));
    assert_eq!(c.after.min, w.after);
    // Invert one element.
    b.coords[centre][0] += 0.5;
    let c = quality::compare(&a, &b, 1).unwrap();
    assert!(c.after.n_nonpositive > 0 && c.worst[0].after < 0.0);
}

#[test]
fn quality_is_independent_of_thread_count() {
    let mut m = generate::box_tets(8, 6, 5, [0.0; 3], [1.0; 3]);
    for (i, p) in m.coords.iter_mut().enumerate() {
        p[0] += 0.01 * ((i * 7919) % 13) as f64 / 13.0;
    }
    let q1 = testkit::with_threads(1, || quality::cell_quality(&m));
    let q3 = testkit::with_threads(3, || quality::cell_quality(&m));
    assert!(q1.iter().zip(&q3).all(|(a, b)| a.to_bits() == b.to_bits()));
}
