//! Property tests: rigid motions of every boundary are reproduced by the deformation (with
//! R), and Eq. 34 preserves distances, for random motions.

use deform::{BoundaryConditions, DeformOptions, MarkerRole, RigidMotion, deform};
use proptest::prelude::*;

fn motion() -> impl Strategy<Value = RigidMotion> {
    (
        -60.0..60.0f64,
        prop::array::uniform3(-1.0..1.0f64),
        prop::array::uniform3(-1.0..1.0f64),
        prop::array::uniform3(-0.3..0.3f64),
    )
        .prop_filter("axis direction not too short", |(_, _, d, _)| {
            d.iter().map(|v| v * v).sum::<f64>() > 0.05
        })
        .prop_map(
            |(angle_deg, axis_point, axis_dir, translation)| RigidMotion {
                angle_deg,
                axis_point,
                axis_dir,
                translation,
            },
        )
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, ..ProptestConfig::default() })]

    #[test]
    fn eq34_preserves_distances(m in motion(), p in prop::array::uniform3(-2.0..2.0f64), q in prop::array::uniform3(-2.0..2.0f64)) {
        let d = |a: [f64; 3], b: [f64; 3]| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
        let (mp, mq) = (m.apply(p, 1.0), m.apply(q, 1.0));
        prop_assert!((d(mp, mq) - d(p, q)).abs() <= 1e-13 * (1.0 + d(p, q)));
    }

    #[test]
    fn rigid_boundaries_give_rigid_grid(m in motion()) {
        let grid = deform::generate::box_with_block([4, 4, 4], [0.0; 3], [1.0; 3], [1, 1, 1], [3, 2, 3]);
        let markers = grid
            .markers
            .iter()
            .map(|mk| (mk.name.clone(), MarkerRole::Rigid(m)))
            .collect();
        let bc = BoundaryConditions { markers, displacements: vec![] };
        let d = deform(&grid, &bc, &DeformOptions { rel_tol: 1e-13, ..Default::default() }).unwrap();
        prop_assert!(d.report.unknowns > 0);
        for (i, p) in grid.coords.iter().enumerate() {
            let e = m.apply(*p, 1.0);
            for k in 0..3 {
                prop_assert!((d.coords[i][k] - e[k]).abs() < 1e-11, "node {i}: {:?} vs {e:?}", d.coords[i]);
            }
        }
    }
}
