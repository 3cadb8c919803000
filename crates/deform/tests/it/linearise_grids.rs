//! [`deform::Linearisation`] on a grid the project did not make: the ONERA M6 half model
//! meshed by Gmsh from the SU2 test cases' IGES (`fixtures/grids/oneram6.su2`), wing twisted
//! and bent by node displacements, symmetry plane sliding, far field fixed.

use std::path::Path;

use deform::{BoundaryConditions, DeformOptions, Deformer, MarkerRole};

use crate::linearise::forward_vs_differences;

#[test]
fn forward_and_reverse_products_on_the_gmsh_onera_m6_grid() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/grids/oneram6.su2");
    let m = mesh::io::read_path(&path).unwrap();
    let mut nodes: Vec<u32> = m
        .marker("wing")
        .unwrap()
        .elements
        .node_set()
        .into_iter()
        .collect();
    nodes.sort_unstable();
    // The wing's extent: chord along x, span along y.
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for &v in &nodes {
        let p = m.coords[v as usize];
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let (chord, span) = (hi[0] - lo[0], hi[1] - lo[1]);
    // Twist 2° at the tip about the quarter chord, and a bend of 2 % of the span.
    let field = |amp: f64, phase: f64| -> Vec<[f64; 3]> {
        nodes
            .iter()
            .map(|&v| {
                let p = m.coords[v as usize];
                let s = (p[1] - lo[1]) / span;
                let th = amp * 2f64.to_radians() * s;
                let (x, z) = (p[0] - lo[0] - 0.25 * chord, p[2]);
                [
                    -th * z + phase * 0.01 * chord * (3.0 * s).sin(),
                    phase * 0.005 * span * s * s,
                    th * x + amp * 0.02 * span * s * s,
                ]
            })
            .collect()
    };
    let bc = BoundaryConditions {
        markers: vec![
            ("symmetry".into(), MarkerRole::SlidePlane),
            ("farfield".into(), MarkerRole::Fixed),
        ],
        displacements: nodes.iter().map(|&v| (v, [0.0; 3])).collect(),
    };
    let opts = DeformOptions {
        rel_tol: 1e-13,
        ..Default::default()
    };
    let d = Deformer::new(&m, &bc, &opts).unwrap();
    let w = field(1.0, 0.0);
    let dw = field(0.5, 1.0);
    let (err, size, inc) = forward_vs_differences(&d, &nodes, &w, &dw, 1e-4);
    eprintln!(
        "ONERA M6: relative error {err:.2e}, |FD off the inputs| / |dw| = {size:.3}, {inc} increment(s)"
    );
    assert_eq!(inc, 1);
    assert!(size > 0.1, "the product is too small to test ({size})");
    assert!(err < 1e-6, "relative error {err:e}");
    // Dot-product test.
    let base = d.deform(&w, None).unwrap();
    let lin = d.linearise(&base).unwrap().with_rel_tol(1e-14);
    let yb: Vec<[f64; 3]> = m
        .coords
        .iter()
        .map(|p| [(3.0 * p[0]).sin(), (2.0 * p[1] + p[2]).cos(), p[2] * p[0]])
        .collect();
    let jv = lin.jvp(&dw).unwrap().values;
    let jt = lin.vjp(&yb).unwrap().values;
    let dot = |a: &[[f64; 3]], b: &[[f64; 3]]| -> f64 {
        a.iter()
            .zip(b)
            .map(|(p, q)| p[0] * q[0] + p[1] * q[1] + p[2] * q[2])
            .sum()
    };
    let (l, r) = (dot(&jv, &yb), dot(&dw, &jt));
    let norm = |a: &[[f64; 3]]| dot(a, a).sqrt();
    eprintln!("ONERA M6: <J dw, y> = {l:.15e}, <dw, J^T y> = {r:.15e}");
    assert!((l - r).abs() <= 1e-10 * norm(&jv) * norm(&yb));
}
