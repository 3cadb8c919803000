//! Validity and quality of every element kind: reference elements, single-corner
//! inversions, degenerate elements, similarity invariance and reflections.

use mesh::quality::{element_quality, quad_scaled_jacobian, scaled_jacobian};
use mesh::{ElementKind, Elements, Mesh};
use proptest::prelude::*;

type P = [f64; 3];

const HEXA: [P; 8] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [1.0, 1.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [1.0, 0.0, 1.0],
    [1.0, 1.0, 1.0],
    [0.0, 1.0, 1.0],
];

/// The prism in VTK's order: 0-1-2 clockwise seen from 3-4-5 (above).
fn prism() -> Vec<P> {
    let s = 3f64.sqrt() / 2.0;
    vec![
        [0.0, 0.0, 0.0],
        [0.5, s, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.5, s, 1.0],
        [1.0, 0.0, 1.0],
    ]
}

/// The pyramid with unit edges.
fn pyramid() -> Vec<P> {
    let h = std::f64::consts::FRAC_1_SQRT_2;
    vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.5, 0.5, h],
    ]
}

fn quality(kind: ElementKind, p: &[P]) -> f64 {
    let e: Vec<u32> = (0..p.len() as u32).collect();
    element_quality(kind, &e, p, false)
}

fn solids() -> Vec<(ElementKind, Vec<P>)> {
    vec![
        (ElementKind::Pyramid, pyramid()),
        (ElementKind::Prism, prism()),
        (ElementKind::Hexa, HEXA.to_vec()),
    ]
}

#[test]
fn ideal_elements_have_quality_one() {
    for (kind, p) in solids() {
        testkit::assert_close!(quality(kind, &p), 1.0, rel = 1e-14);
    }
    let sq = [HEXA[0], HEXA[1], HEXA[2], HEXA[3]];
    assert_eq!(quad_scaled_jacobian(sq, true), 1.0);
    // Stretched along one axis (a boundary-layer cell): the scaled Jacobian stays 1.
    let thin: Vec<P> = HEXA.iter().map(|p| [p[0], p[1], 1e-6 * p[2]]).collect();
    testkit::assert_close!(quality(ElementKind::Hexa, &thin), 1.0, rel = 1e-12);
    let thin: Vec<P> = prism().iter().map(|p| [p[0], p[1], 1e-6 * p[2]]).collect();
    testkit::assert_close!(quality(ElementKind::Prism, &thin), 1.0, rel = 1e-12);
}

#[test]
fn mirrored_elements_are_inverted() {
    for (kind, p) in solids() {
        let m: Vec<P> = p.iter().map(|q| [q[0], q[1], -q[2]]).collect();
        let q = quality(kind, &m);
        assert!(q <= -0.99, "{kind:?}: {q}");
    }
    // Gmsh's prism order read as VTK's: every corner negative.
    let g: Vec<P> = ElementKind::Prism
        .gmsh_order()
        .iter()
        .map(|&i| prism()[i as usize])
        .collect();
    assert!(quality(ElementKind::Prism, &g) < -0.99);
}

/// Moving any one node far through the opposite face makes the element invalid, and the
/// element stays valid for a small move of one node.
#[test]
fn every_corner_is_checked() {
    for (kind, p) in solids() {
        let c: P = {
            let n = p.len() as f64;
            let s = p
                .iter()
                .fold([0.0; 3], |a, q| [a[0] + q[0], a[1] + q[1], a[2] + q[2]]);
            [s[0] / n, s[1] / n, s[2] / n]
        };
        for i in 0..p.len() {
            let mut m = p.clone();
            // Through the centroid to the other side.
            m[i] = [
                c[0] + 1.5 * (c[0] - p[i][0]),
                c[1] + 1.5 * (c[1] - p[i][1]),
                c[2] + 1.5 * (c[2] - p[i][2]),
            ];
            let q = quality(kind, &m);
            assert!(q < 0.0, "{kind:?} node {i}: {q}");
            let mut m = p.clone();
            m[i] = [p[i][0] + 0.05, p[i][1] - 0.03, p[i][2] + 0.02];
            let q = quality(kind, &m);
            assert!(q > 0.5, "{kind:?} node {i} nudged: {q}");
        }
    }
}

/// A prism whose top triangle is pushed below its bottom at one corner only: the other
/// corners stay positive, the element is invalid.
#[test]
fn one_inverted_corner_of_a_boundary_layer_prism() {
    let mut p: Vec<P> = prism().iter().map(|q| [q[0], q[1], 1e-5 * q[2]]).collect();
    p[4][2] = -1e-6;
    assert!(quality(ElementKind::Prism, &p) < 0.0);
    let mut h: Vec<P> = HEXA.iter().map(|q| [q[0], q[1], 1e-5 * q[2]]).collect();
    h[6][2] = -1e-6;
    assert!(quality(ElementKind::Hexa, &h) < 0.0);
}

#[test]
fn degenerate_elements_give_zero_not_nan() {
    for (kind, p) in solids() {
        let same = vec![[0.3, 0.2, 0.1]; p.len()];
        assert_eq!(quality(kind, &same), 0.0, "{kind:?}");
        let flat: Vec<P> = p.iter().map(|q| [q[0], q[1], 0.0]).collect();
        let q = quality(kind, &flat);
        assert!(q.abs() < 1e-15, "{kind:?}: {q}");
    }
    // A prism with one collapsed vertical edge: zero, not NaN.
    let mut p = prism();
    p[3] = p[0];
    assert_eq!(quality(ElementKind::Prism, &p), 0.0);
    assert_eq!(quad_scaled_jacobian([[1.0; 3]; 4], false), 0.0);
    assert_eq!(quad_scaled_jacobian([[1.0; 3]; 4], true), 0.0);
    assert!(element_quality(ElementKind::Line, &[0, 1], &HEXA, false).is_nan());
}

#[test]
fn quads_in_two_and_three_dimensions() {
    let sq = [HEXA[0], HEXA[1], HEXA[2], HEXA[3]];
    // A rhombus with 60° corners: sin 60°.
    let s = 3f64.sqrt() / 2.0;
    let rh = [[0.0; 3], [1.0, 0.0, 0.0], [1.5, s, 0.0], [0.5, s, 0.0]];
    testkit::assert_close!(quad_scaled_jacobian(rh, true), s, rel = 1e-14);
    // The unit square sheared into the plane x + y + z = 0: corners of 60° and 120°.
    let tilted = sq.map(|p| [p[0], p[1], -p[0] - p[1]]);
    testkit::assert_close!(quad_scaled_jacobian(tilted, false), s, rel = 1e-12);
    // A bow tie (nodes 2 and 3 swapped) is invalid in both measures.
    let bow = [sq[0], sq[1], sq[3], sq[2]];
    assert!(quad_scaled_jacobian(bow, true) < 0.0);
    assert!(quad_scaled_jacobian(bow, false) <= 0.0);
}

/// Every cell kind of a grid is measured: no NaN in `cell_quality`, and the 2-D all-quad
/// grid has a real minimum.
#[test]
fn all_quad_and_hybrid_grids_have_no_unmeasured_cells() {
    let mut m = Mesh::new(2);
    m.coords = vec![
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [2.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 0.5, 0.0],
        [2.0, 1.0, 0.0],
    ];
    let mut cells = Elements::new();
    cells.push(ElementKind::Quad, &[0, 1, 4, 3], None);
    cells.push(ElementKind::Quad, &[1, 2, 5, 4], None);
    m.cells = cells;
    let q = mesh::quality::cell_quality(&m);
    assert!(q.iter().all(|x| x.is_finite() && *x > 0.0), "{q:?}");
    let s = mesh::quality::summary(&q);
    assert_eq!((s.measured, s.n_nonpositive), (2, 0));
    // Node 4 moved below the bottom edge: the two quads fold.
    m.coords[4] = [1.0, -0.5, 0.0];
    let s = mesh::quality::summary(&mesh::quality::cell_quality(&m));
    assert_eq!(s.n_nonpositive, 2);
}

fn rotate(p: P, a: f64, b: f64) -> P {
    let (ca, sa, cb, sb) = (a.cos(), a.sin(), b.cos(), b.sin());
    let r = [ca * p[0] - sa * p[1], sa * p[0] + ca * p[1], p[2]];
    [r[0], cb * r[1] - sb * r[2], sb * r[1] + cb * r[2]]
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 64,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x5eed_0043),
        ..ProptestConfig::default()
    })]
    /// The scaled Jacobian of a perturbed element is invariant under rotation, uniform
    /// scaling and translation, and a reflection flips the sign of every corner.
    #[test]
    fn scaled_jacobian_is_similarity_invariant(
        kind in prop::sample::select(vec![ElementKind::Pyramid, ElementKind::Prism, ElementKind::Hexa]),
        noise in prop::collection::vec(prop::array::uniform3(-0.1f64..0.1), 8),
        a in 0.0f64..6.3, b in 0.0f64..6.3, scale in 0.001f64..1000.0,
        shift in prop::array::uniform3(-5.0f64..5.0),
    ) {
        let base = solids().into_iter().find(|(k, _)| *k == kind).unwrap().1;
        let p: Vec<P> = base.iter().zip(&noise).map(|(q, d)| [q[0] + d[0], q[1] + d[1], q[2] + d[2]]).collect();
        let q0 = scaled_jacobian(kind, &p);
        let moved: Vec<P> = p.iter().map(|&q| {
            let r = rotate(q, a, b);
            [scale * r[0] + shift[0], scale * r[1] + shift[1], scale * r[2] + shift[2]]
        }).collect();
        let q1 = scaled_jacobian(kind, &moved);
        prop_assert!((q0 - q1).abs() <= 1e-9, "{} vs {}", q0, q1);
        prop_assert!(q0 > 0.0 && q0 <= 1.0, "{}", q0);
        let mirrored: Vec<P> = p.iter().map(|q| [-q[0], q[1], q[2]]).collect();
        prop_assert!(scaled_jacobian(kind, &mirrored) < 0.0);
    }
}
