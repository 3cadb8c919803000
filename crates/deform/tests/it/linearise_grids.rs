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

/// Reverse products converge for any seed (issue 44), in the order an optimiser or
/// OpenMDAO's `check_partials` asks for them, each adjoint solve started from the previous
/// one's solution: a dense seed, single-entry seeds on unknown nodes, one on a symmetry-plane
/// node's normal component (zero once projected: the answer is zero), a wall-only seed (no
/// unknown seeded: zero right-hand side, a non-zero start). A single-entry seed after a dense
/// one starts from a solution far worse than zero, and a zero right-hand side with a warm
/// start used to stall on the recurrence's round-off ("adjoint of Eq. 21: solver pcg-amg did
/// not converge in 30 iterations (relative residual 1.68e-2)" on the default case). Each
/// product passes the dot-product test against the forward one, and agrees with the cold
/// product.
#[test]
fn reverse_products_converge_for_any_seed_on_the_gmsh_onera_m6_grid() {
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
    let bc = BoundaryConditions {
        markers: vec![
            ("symmetry".into(), MarkerRole::SlidePlane),
            ("farfield".into(), MarkerRole::Fixed),
        ],
        displacements: nodes.iter().map(|&v| (v, [0.0; 3])).collect(),
    };
    let d = Deformer::new(&m, &bc, &DeformOptions::default()).unwrap();
    let w: Vec<[f64; 3]> = nodes
        .iter()
        .map(|&v| {
            let p = m.coords[v as usize];
            [0.002 * p[1] * p[2], 0.001 * p[1], 0.01 * p[1] * p[1]]
        })
        .collect();
    let base = d.deform(&w, None).unwrap();
    let lin = d.linearise(&base).unwrap().with_rel_tol(1e-12);
    let dw: Vec<[f64; 3]> = nodes
        .iter()
        .map(|&v| {
            let p = m.coords[v as usize];
            [(3.0 * p[0]).sin(), (p[1] + p[2]).cos(), p[0] * p[1]]
        })
        .collect();
    let jv = lin.jvp(&dw).unwrap().values;
    let dot = |a: &[[f64; 3]], b: &[[f64; 3]]| -> f64 {
        a.iter()
            .zip(b)
            .map(|(p, q)| p[0] * q[0] + p[1] * q[1] + p[2] * q[2])
            .sum()
    };
    let norm = |a: &[[f64; 3]]| dot(a, a).sqrt();
    let n = m.n_nodes();
    let wall: std::collections::HashSet<u32> = nodes.iter().copied().collect();
    let sym: Vec<u32> = m
        .marker("symmetry")
        .unwrap()
        .elements
        .node_set()
        .into_iter()
        .filter(|v| !wall.contains(v))
        .collect();
    let far: std::collections::HashSet<u32> = m
        .marker("farfield")
        .unwrap()
        .elements
        .node_set()
        .into_iter()
        .collect();
    let free: Vec<usize> = (0..n)
        .filter(|&i| {
            let v = i as u32;
            !wall.contains(&v) && !far.contains(&v) && m.coords[i][1].abs() > 1e-9
        })
        .collect();
    let single = |i: usize, c: usize| {
        let mut s = vec![[0.0; 3]; n];
        s[i][c] = 1.0;
        s
    };
    let mut seeds: Vec<(String, Vec<[f64; 3]>)> = vec![(
        "dense".into(),
        m.coords
            .iter()
            .map(|p| [(2.0 * p[0]).sin(), (p[1] - p[2]).cos(), p[2] * p[0]])
            .collect(),
    )];
    seeds.push((
        "wall only".into(),
        (0..n)
            .map(|i| {
                if wall.contains(&(i as u32)) {
                    [1.0, -0.5, 0.25]
                } else {
                    [0.0; 3]
                }
            })
            .collect(),
    ));
    for k in 0..6 {
        let i = free[(k * 997 + 13) % free.len()];
        seeds.push((
            format!("single {} at node {i}", ["x", "y", "z"][k % 3]),
            single(i, k % 3),
        ));
    }
    let s = sym[sym.len() / 2] as usize;
    seeds.push((format!("symmetry normal at node {s}"), single(s, 1)));
    seeds.push((
        "single after the symmetry normal".into(),
        single(free[7], 2),
    ));
    let mut start = deform::AdjointStart::default();
    for (name, yb) in &seeds {
        let warm = lin
            .vjp_from(yb, &mut start)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let cold = lin.vjp(yb).unwrap_or_else(|e| panic!("{name} (cold): {e}"));
        let (l, r) = (dot(&jv, yb), dot(&dw, &warm.values));
        let scale = norm(&jv) * norm(yb);
        eprintln!(
            "{name}: {} iterations (cold {}), <J dw, y> = {l:.6e}, dot-product error {:.2e}",
            warm.iterations,
            cold.iterations,
            (l - r).abs() / scale
        );
        assert!(
            (l - r).abs() <= 1e-10 * scale,
            "{name}: {l:e} against {r:e}"
        );
        let diff: f64 = warm
            .values
            .iter()
            .zip(&cold.values)
            .map(|(a, b)| (0..3).map(|c| (a[c] - b[c]).powi(2)).sum::<f64>())
            .sum::<f64>()
            .sqrt();
        assert!(
            diff <= 1e-9 * norm(&cold.values).max(1e-300) + 1e-300,
            "{name}: warm and cold products differ by {diff:e}"
        );
    }
}
