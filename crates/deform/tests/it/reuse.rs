//! [`deform::Deformer`]: the reusable set-up gives the cold free function's answer, for any
//! sequence of calls and any thread count; a warm start agrees to the solver tolerance.

use deform::{
    BoundaryConditions, DeformOptions, Deformer, MarkerRole, SolverKind, Stiffness, deform,
};
use mesh::Mesh;

fn grid() -> Mesh {
    deform::generate::box_with_block([9, 6, 8], [0.0; 3], [2.0, 1.2, 1.6], [3, 0, 3], [6, 3, 5])
}

/// Wing nodes bent by `amp` × a smooth field (twist about y and heave), `y_m` sliding,
/// the other box faces fixed.
fn bc(m: &Mesh, amp: f64) -> BoundaryConditions {
    let mut nodes: Vec<u32> = m
        .marker("wing")
        .unwrap()
        .elements
        .node_set()
        .into_iter()
        .collect();
    nodes.sort_unstable();
    BoundaryConditions {
        markers: vec![("y_m".into(), MarkerRole::SlidePlane)],
        displacements: nodes
            .iter()
            .map(|&v| {
                let p = m.coords[v as usize];
                let s = p[1] / 1.2;
                (
                    v,
                    [
                        amp * 0.05 * s * (p[2] - 0.8),
                        amp * 0.02 * s,
                        amp * (0.06 * s * s - 0.05 * s * (p[0] - 1.0)),
                    ],
                )
            })
            .collect(),
    }
}

fn values(bc: &BoundaryConditions) -> Vec<[f64; 3]> {
    bc.displacements.iter().map(|e| e.1).collect()
}

#[test]
fn deformer_reuse_equals_cold_free_function_bit_for_bit() {
    let m = grid();
    for (solver, stiffness) in [
        (SolverKind::PcgMultigrid, Stiffness::InverseLength),
        (SolverKind::PcgJacobi, Stiffness::WallDistance),
        (SolverKind::PcgMultigrid, Stiffness::Volume),
    ] {
        let opts = DeformOptions {
            solver,
            stiffness,
            ..Default::default()
        };
        let d = Deformer::new(&m, &bc(&m, 0.0), &opts).unwrap();
        // Any call history: each answer is the cold one, bit for bit.
        for amp in [1.0, 0.0, -0.7, 1.0] {
            let b = bc(&m, amp);
            let cold = deform(&m, &b, &opts).unwrap();
            let warm = d.deform(&values(&b), None).unwrap();
            assert_eq!(
                warm.coords, cold.coords,
                "{solver:?} {stiffness:?} amp {amp}"
            );
            assert_eq!(warm.report.iterations, cold.report.iterations);
            if amp == 0.0 {
                assert_eq!(warm.coords, m.coords, "zero displacement is the baseline");
            } else {
                assert_ne!(warm.coords, m.coords);
                assert!(cold.report.iterations > 0);
            }
        }
    }
}

#[test]
fn deformer_warm_start_agrees_to_tolerance_and_saves_iterations() {
    let m = grid();
    let opts = DeformOptions::default();
    let d = Deformer::new(&m, &bc(&m, 0.0), &opts).unwrap();
    let first = d.deform(&values(&bc(&m, 1.0)), None).unwrap();
    let b2 = bc(&m, 1.05);
    let cold = deform(&m, &b2, &opts).unwrap();
    let warm = d.deform(&values(&b2), Some(&first)).unwrap();
    let dmax = b2
        .displacements
        .iter()
        .map(|e| e.1.iter().map(|c| c * c).sum::<f64>().sqrt())
        .fold(0.0, f64::max);
    let err = warm
        .coords
        .iter()
        .zip(&cold.coords)
        .map(|(p, q)| (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt())
        .fold(0.0, f64::max);
    assert!(
        err <= 1e-6 * dmax,
        "warm vs cold: {err:.3e} (max displacement {dmax:.3e})"
    );
    assert!(
        warm.report.iterations < cold.report.iterations,
        "warm {} vs cold {} iterations",
        warm.report.iterations,
        cold.report.iterations
    );
}

#[test]
fn deformer_warm_start_from_the_same_motion_takes_no_iteration() {
    let m = grid();
    let b = bc(&m, 1.0);
    let d = Deformer::new(&m, &b, &DeformOptions::default()).unwrap();
    let first = d.deform(&values(&b), None).unwrap();
    assert!(first.report.iterations > 0 && first.report.rotation_iterations > 0);
    let again = d.deform(&values(&b), Some(&first)).unwrap();
    assert_eq!(again.report.iterations, 0);
    assert_eq!(again.report.rotation_iterations, 0);
    // The same answer up to the round-off of re-applying the plane constraints.
    let err = testkit::max_coordinate_difference(&again.coords, &first.coords);
    assert!(err <= 1e-15, "{err:.3e}");
}

#[test]
fn deformer_independent_of_thread_count() {
    let m = grid();
    let b = bc(&m, 1.0);
    let run = |t: usize| {
        testkit::with_threads(t, || {
            let d = Deformer::new(&m, &b, &DeformOptions::default()).unwrap();
            d.deform(&values(&b), None).unwrap().coords
        })
    };
    assert_eq!(run(1), run(3));
}

#[test]
fn deformer_refuses_wrong_input() {
    let m = grid();
    let b = bc(&m, 1.0);
    let d = Deformer::new(&m, &b, &DeformOptions::default()).unwrap();
    let e = d.deform(&values(&b)[1..], None).unwrap_err().to_string();
    assert!(e.contains("prescribed nodes"), "{e}");
    let mut v = values(&b);
    v[3][1] = f64::NAN;
    let e = d.deform(&v, None).unwrap_err().to_string();
    assert!(e.contains("not finite"), "{e}");
    // A result of another set-up (other grid) is no warm start for this one.
    let small = deform::generate::box_with_block(
        [6, 5, 6],
        [0.0; 3],
        [2.0, 1.2, 1.6],
        [2, 0, 2],
        [4, 3, 4],
    );
    let other = Deformer::new(&small, &bc(&small, 1.0), &DeformOptions::default())
        .unwrap()
        .deform(&values(&bc(&small, 1.0)), None)
        .unwrap();
    let e = d.deform(&values(&b), Some(&other)).unwrap_err().to_string();
    assert!(e.contains("warm start"), "{e}");
}

#[test]
fn deformer_to_positions_puts_the_prescribed_nodes_exactly_there() {
    // The wing's leading column of nodes at x ≈ 0.005, the wing moved by −0.005 in x plus a
    // small shear: positions computed apart from the displacements, as a caller's geometry
    // would give them. Where p is much smaller than x⁰ (the leading column, now near x = 0),
    // x⁰ + (p − x⁰) loses p's low bits and misses p.
    let m = deform::generate::box_with_block(
        [9, 6, 8],
        [-0.9925, 0.0, 0.0],
        [2.0, 1.2, 1.6],
        [3, 0, 3],
        [6, 3, 5],
    );
    let b = bc(&m, 0.0);
    let d = Deformer::new(&m, &b, &DeformOptions::default()).unwrap();
    let positions: Vec<[f64; 3]> = b
        .displacements
        .iter()
        .map(|&(v, _)| {
            let p = m.coords[v as usize];
            [p[0] - 5e-3 + 1e-4 * (p[1] + 0.1), p[1], p[2] + 1e-3 * p[0]]
        })
        .collect();
    let disp: Vec<[f64; 3]> = b
        .displacements
        .iter()
        .zip(&positions)
        .map(|(&(v, _), p)| {
            let x0 = m.coords[v as usize];
            [p[0] - x0[0], p[1] - x0[1], p[2] - x0[2]]
        })
        .collect();
    let by_disp = d.deform(&disp, None).unwrap();
    let to = d.deform_to(&positions, None).unwrap();
    let mut inexact = 0;
    for (&(v, _), p) in b.displacements.iter().zip(&positions) {
        assert_eq!(to.coords[v as usize], *p, "node {v}");
        inexact += usize::from(by_disp.coords[v as usize] != *p);
    }
    assert!(inexact > 0, "the test needs positions that x⁰ + d misses");
    // The same solve (right-hand sides from p − x⁰ or (x⁰ + d) − x⁰, equal up to round-off),
    // and the quality is that of the grid returned.
    let err = testkit::max_coordinate_difference(&to.coords, &by_disp.coords);
    assert!(err <= 1e-15, "{err:.3e}");
    assert_eq!(to.cell_quality, deform::cell_quality(&m, &to.coords));
    let e = d.deform_to(&positions[1..], None).unwrap_err().to_string();
    assert!(e.contains("positions given"), "{e}");
}

#[test]
fn exported_stiffness_matrix_is_the_same_in_any_internal_numbering() {
    // The spring matrix with the renumbering on and off: the same springs between the same
    // input nodes (`nodes`), a symmetric M-matrix whose unknowns are the free and sliding
    // nodes; only the diagonal's sums may differ in their last bits (another order).
    let m = grid();
    let b = bc(&m, 1.0);
    let export = |renumber: bool| {
        let opts = DeformOptions {
            renumber,
            stiffness: Stiffness::WallDistance,
            ..Default::default()
        };
        Deformer::new(&m, &b, &opts)
            .unwrap()
            .stiffness_matrix()
            .unwrap()
    };
    let (a, c) = (export(true), export(false));
    let n = a.nodes.len();
    assert!(n > 100 && a.matrix.shape() == (n, n) && a.matrix.is_csr());
    let mut prescribed = vec![false; m.n_nodes()];
    for &(v, _) in &b.displacements {
        prescribed[v as usize] = true;
    }
    assert!(a.nodes.iter().all(|&v| !prescribed[v as usize]));
    // Row of each input node in the unrenumbered export.
    let mut row_of = vec![usize::MAX; m.n_nodes()];
    for (k, &v) in c.nodes.iter().enumerate() {
        row_of[v as usize] = k;
    }
    assert_eq!(c.matrix.nnz(), a.matrix.nnz());
    for (k, row) in a.matrix.outer_iterator().enumerate() {
        let mut off = 0.0;
        for (l, &v) in row.iter() {
            let w = *c
                .matrix
                .get(row_of[a.nodes[k] as usize], row_of[a.nodes[l] as usize])
                .expect("same pattern");
            assert_eq!(a.matrix.get(l, k), Some(&v), "symmetric");
            if l == k {
                assert!(v > 0.0);
                testkit::assert_close!(v, w, rel = 1e-12);
            } else {
                assert!(v < 0.0);
                assert_eq!(v.to_bits(), w.to_bits(), "spring ({k}, {l})");
                off -= v;
            }
        }
        // a_kk = Σ K over all neighbours ≥ Σ over the unknown ones.
        assert!(a.matrix.get(k, k).unwrap() >= &(off * (1.0 - 1e-12)));
    }
}
