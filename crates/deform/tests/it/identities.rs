//! Identities: zero motion, rigid motion of all boundaries, sliding planes, solver agreement,
//! thread-count independence, errors.

use deform::{
    BoundaryConditions, DeformOptions, MarkerRole, RigidMotion, SolverKind, Stiffness, deform,
};
use mesh::Mesh;

/// Whether each node lies on a marker.
fn on_marker(m: &Mesh) -> Vec<bool> {
    let mut on = vec![false; m.n_nodes()];
    for mk in &m.markers {
        for v in mk.elements.node_set() {
            on[v as usize] = true;
        }
    }
    on
}

/// A box with a block, interior nodes jittered (so the initial grid is not in spring
/// equilibrium and linear fields are not reproduced by the plain spring system).
fn box_grid() -> Mesh {
    let mut m = deform::generate::box_with_block(
        [8, 7, 9],
        [0.0; 3],
        [2.0, 1.5, 2.2],
        [3, 0, 3],
        [5, 3, 6],
    );
    let on_marker = on_marker(&m);
    let mut s = 7u64;
    for (i, p) in m.coords.iter_mut().enumerate() {
        if on_marker[i] {
            continue;
        }
        for c in p.iter_mut() {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            *c += 0.04 * (((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5);
        }
    }
    m
}

const BOX: [&str; 6] = ["x_m", "x_p", "y_m", "y_p", "z_m", "z_p"];

fn pitch(angle: f64) -> RigidMotion {
    RigidMotion {
        angle_deg: angle,
        axis_point: [0.8, 0.0, 1.1],
        axis_dir: [0.0, 1.0, 0.0],
        translation: [0.0; 3],
    }
}

#[test]
fn zero_motion_leaves_grid_bit_for_bit() {
    let m = box_grid();
    for solver in [
        SolverKind::PcgMultigrid,
        SolverKind::PcgJacobi,
        SolverKind::PointIteration,
    ] {
        let bc = BoundaryConditions {
            markers: vec![
                ("wing".into(), MarkerRole::Rigid(pitch(0.0))),
                ("y_m".into(), MarkerRole::SlidePlane),
            ],
            displacements: vec![(5, [0.0; 3])],
        };
        let opts = DeformOptions {
            solver,
            ..Default::default()
        };
        let d = deform(&m, &bc, &opts).unwrap();
        assert!(
            d.coords
                .iter()
                .zip(&m.coords)
                .all(|(a, b)| a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits()))
        );
        assert_eq!(d.report.iterations, 0);
    }
}

#[test]
fn rigid_motion_of_all_boundaries_moves_every_node_rigidly() {
    let m = box_grid();
    let motion = RigidMotion {
        angle_deg: 17.0,
        axis_point: [0.3, -0.2, 0.5],
        axis_dir: [0.3, 1.0, -0.4],
        translation: [0.1, -0.05, 0.2],
    };
    let mut markers: Vec<(String, MarkerRole)> = BOX
        .iter()
        .map(|s| (s.to_string(), MarkerRole::Rigid(motion)))
        .collect();
    markers.push(("wing".into(), MarkerRole::Rigid(motion)));
    let bc = BoundaryConditions {
        markers,
        displacements: vec![],
    };
    for stiffness in [
        Stiffness::InverseLength,
        Stiffness::InverseLengthSquared,
        Stiffness::Volume,
    ] {
        let opts = DeformOptions {
            rel_tol: 1e-13,
            stiffness,
            ..Default::default()
        };
        let d = deform(&m, &bc, &opts).unwrap();
        let mut err = 0.0f64;
        for (i, p) in m.coords.iter().enumerate() {
            let e = motion.apply(*p, 1.0);
            for k in 0..3 {
                err = err.max((d.coords[i][k] - e[k]).abs());
            }
        }
        // Grid size 3; round-off and the solver tolerance 1e-13.
        assert!(
            err < 1e-11,
            "{stiffness:?}: max deviation from the rigid motion {err:e}"
        );
        assert_eq!(d.report.quality_after.n_nonpositive, 0);
        testkit::assert_close!(
            d.report.quality_after.min,
            d.report.quality_before.min,
            rel = 1e-9
        );
    }
    // Without R the interior does not follow the rotation (the spring system alone cannot).
    let opts = DeformOptions {
        rel_tol: 1e-13,
        adapt_rotation: false,
        ..Default::default()
    };
    let d = deform(&m, &bc, &opts).unwrap();
    let err = m
        .coords
        .iter()
        .zip(&d.coords)
        .map(|(p, q)| {
            let e = motion.apply(*p, 1.0);
            (0..3).map(|k| (q[k] - e[k]).abs()).fold(0.0, f64::max)
        })
        .fold(0.0, f64::max);
    assert!(err > 1e-3, "without R: {err:e}");
}

#[test]
fn sliding_nodes_stay_on_their_plane() {
    let m = box_grid();
    let bc = BoundaryConditions {
        markers: vec![
            ("wing".into(), MarkerRole::Rigid(pitch(-8.0))),
            ("y_m".into(), MarkerRole::SlidePlane),
            ("x_p".into(), MarkerRole::SlidePlane),
        ],
        displacements: vec![],
    };
    let d = deform(&m, &bc, &DeformOptions::default()).unwrap();
    assert_eq!(d.report.quality_after.n_nonpositive, 0);
    assert!(d.report.sliding > 50, "{}", d.report.sliding);
    let scale = 3.0;
    let mut moved = 0.0f64;
    for name in ["y_m", "x_p"] {
        let nodes = m.marker(name).unwrap().elements.node_set();
        let (axis, value) = if name == "y_m" { (1, 0.0) } else { (0, 2.0) };
        for &v in &nodes {
            let p = d.coords[v as usize];
            assert!(
                (p[axis] - value).abs() <= 1e-12 * scale,
                "{name} node {v}: {p:?}"
            );
            let q = m.coords[v as usize];
            moved = moved.max(((p[0] - q[0]).powi(2) + (p[2] - q[2]).powi(2)).sqrt());
        }
    }
    // They did slide (tangential motion), and the box edges stayed on the box.
    assert!(moved > 1e-3, "{moved}");
    for &v in &m.marker("z_m").unwrap().elements.node_set() {
        assert_eq!(d.coords[v as usize][2], 0.0);
    }
}

#[test]
fn paper_iteration_and_pcg_agree() {
    let m = deform::generate::box_with_block([6, 5, 6], [0.0; 3], [1.0; 3], [2, 0, 2], [4, 2, 4]);
    let bc = BoundaryConditions {
        markers: vec![
            ("wing".into(), MarkerRole::Rigid(pitch(5.0))),
            ("y_m".into(), MarkerRole::SlidePlane),
        ],
        displacements: vec![],
    };
    let run = |solver| {
        let opts = DeformOptions {
            solver,
            rel_tol: 1e-11,
            max_iters: 200_000,
            step_rel_tol: 0.0,
            ..Default::default()
        };
        deform(&m, &bc, &opts).unwrap()
    };
    let a = run(SolverKind::PcgMultigrid);
    let b = run(SolverKind::PcgJacobi);
    let c = run(SolverKind::PointIteration);
    assert!(
        c.report.iterations > b.report.iterations,
        "{:?} {:?} {:?}",
        a.report.iterations,
        b.report.iterations,
        c.report.iterations
    );
    for i in 0..m.n_nodes() {
        testkit::assert_close!(a.coords[i], b.coords[i], rel = 0.0, abs = 1e-9);
        testkit::assert_close!(a.coords[i], c.coords[i], rel = 0.0, abs = 1e-8);
    }
}

#[test]
fn result_independent_of_thread_count_and_node_order() {
    let m = box_grid();
    let bc = BoundaryConditions {
        markers: vec![
            ("wing".into(), MarkerRole::Rigid(pitch(6.0))),
            ("y_m".into(), MarkerRole::SlidePlane),
        ],
        displacements: vec![],
    };
    // With the wall-distance stiffness the renumbered set-up computes the distance beside
    // the level order, in Morton numbering; without renumbering, in the springs.
    for stiffness in [Stiffness::InverseLengthSquared, Stiffness::WallDistance] {
        let run = |t: usize, renumber: bool| {
            testkit::with_threads(t, || {
                deform(
                    &m,
                    &bc,
                    &DeformOptions {
                        renumber,
                        stiffness,
                        ..Default::default()
                    },
                )
                .unwrap()
            })
        };
        let a = run(1, true);
        let b = run(3, true);
        assert!(
            a.coords
                .iter()
                .zip(&b.coords)
                .all(|(p, q)| p.iter().zip(q).all(|(x, y)| x.to_bits() == y.to_bits()))
        );
        // Without renumbering: same solution to the solver tolerance.
        let c = run(2, false);
        for (p, q) in a.coords.iter().zip(&c.coords) {
            testkit::assert_close!(*p, *q, abs = 1e-7);
        }
    }
}

#[test]
fn errors_name_the_entity() {
    let m = box_grid();
    let bad = BoundaryConditions {
        markers: vec![("nope".into(), MarkerRole::Fixed)],
        displacements: vec![],
    };
    let e = deform(&m, &bad, &DeformOptions::default()).unwrap_err();
    assert!(e.to_string().contains("nope"), "{e}");
    let bad = BoundaryConditions {
        markers: vec![("wing".into(), MarkerRole::SlidePlane)],
        displacements: vec![],
    };
    let e = deform(&m, &bad, &DeformOptions::default()).unwrap_err();
    assert!(
        matches!(e, deform::Error::NotPlanar { .. }) && e.to_string().contains("wing"),
        "{e}"
    );
    let bad = BoundaryConditions {
        markers: vec![],
        displacements: vec![(1_000_000, [0.0; 3])],
    };
    let e = deform(&m, &bad, &DeformOptions::default()).unwrap_err();
    assert!(e.to_string().contains("1000000"), "{e}");
}

#[test]
fn coincident_nodes_are_refused_naming_the_spring() {
    // An interior node moved onto a neighbour: a spring of zero length (infinite stiffness).
    let mut m = box_grid();
    let on_marker = on_marker(&m);
    let adj = mesh::Adjacency::build(&m);
    let i = (0..m.n_nodes()).rev().find(|&i| !on_marker[i]).unwrap();
    let j = adj.neighbours(i)[0] as usize;
    m.coords[i] = m.coords[j];
    let bc = BoundaryConditions {
        markers: vec![(
            "wing".into(),
            MarkerRole::Rigid(RigidMotion::translation([0.0, 0.0, 0.01])),
        )],
        displacements: vec![],
    };
    for renumber in [true, false] {
        let opts = DeformOptions {
            renumber,
            ..Default::default()
        };
        let e = deform(&m, &bc, &opts).unwrap_err();
        let deform::Error::Stiffness { nodes, .. } = e else {
            panic!("{e}");
        };
        // Input numbering, whatever the internal order; the first spring found is one of
        // the zero-length node's.
        assert!(nodes.contains(&(i as u32)), "{nodes:?}, expected {i}");
        let other = nodes[0] + nodes[1] - i as u32;
        assert_eq!(m.coords[other as usize], m.coords[i], "{nodes:?}");
    }
}

#[test]
fn inverting_motion_is_refused_unless_allowed() {
    // Push the wing through the far side of the box: impossible without inversion.
    let m = box_grid();
    let bc = BoundaryConditions {
        markers: vec![(
            "wing".into(),
            MarkerRole::Rigid(RigidMotion::translation([0.0, 0.0, 1.5])),
        )],
        displacements: vec![],
    };
    let opts = DeformOptions {
        max_increments: 2,
        ..Default::default()
    };
    let e = deform(&m, &bc, &opts).unwrap_err();
    assert!(matches!(e, deform::Error::Inverted { .. }), "{e}");
    assert!(e.to_string().contains("cell "), "{e}");
    let d = deform(
        &m,
        &bc,
        &DeformOptions {
            allow_inverted: true,
            ..opts
        },
    )
    .unwrap();
    assert!(d.report.quality_after.n_nonpositive > 0);
    assert_eq!(d.report.attempts, vec![1, 2]);
}

#[test]
fn randomly_numbered_input_gives_the_same_grid() {
    let m = box_grid();
    let mut s = m.clone();
    let perm = mesh::generate::shuffle_nodes(&mut s, 11);
    let bc = BoundaryConditions {
        markers: vec![
            ("wing".into(), MarkerRole::Rigid(pitch(6.0))),
            ("y_m".into(), MarkerRole::SlidePlane),
        ],
        displacements: vec![(3, [0.0, 0.0, 0.0])],
    };
    let a = deform(&m, &bc, &DeformOptions::default()).unwrap();
    let bc_s = BoundaryConditions {
        displacements: vec![(perm[3], [0.0; 3])],
        ..bc.clone()
    };
    let b = deform(&s, &bc_s, &DeformOptions::default()).unwrap();
    for i in 0..m.n_nodes() {
        testkit::assert_close!(a.coords[i], b.coords[perm[i] as usize], abs = 1e-9);
    }
}
