//! Property tests (fixed seed, modest case counts): B-spline partition of unity on random
//! user knots, rotation by θ then −θ, and linearity of the tensor surface level.

use geom_db::SurfaceId;
use geom_db::prelude::{Point3, Vector3};
use param::*;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngAlgorithm, TestRng, TestRunner};

use crate::common::*;

fn runner(cases: u32) -> TestRunner {
    TestRunner::new_with_rng(
        Config {
            cases,
            failure_persistence: None,
            ..Config::default()
        },
        TestRng::from_seed(RngAlgorithm::ChaCha, &[7; 32]),
    )
}

#[test]
fn bspline_partition_of_unity_on_random_knots() {
    let strat = (
        1usize..5,
        prop::collection::vec(0.0f64..1.0, 0..6),
        0.0f64..=1.0,
    );
    runner(64)
        .run(&strat, |(p, mut inner, s)| {
            inner.sort_by(f64::total_cmp);
            let mut knots = vec![0.0; p + 1];
            knots.extend(inner);
            knots.extend(std::iter::repeat_n(1.0, p + 1));
            let b = Basis::BSpline {
                degree: p,
                n_basis: 0,
                knots: Some(knots),
            };
            let Ok(b) = b.prepare("t") else {
                return Ok(()); // too many repeated knots: rejected, fine
            };
            let h = b.eval(s);
            prop_assert!((h.iter().sum::<f64>() - 1.0).abs() < 1e-13);
            prop_assert!(h.iter().all(|&v| v >= 0.0));
            Ok(())
        })
        .unwrap();
}

#[test]
fn rotation_and_inverse_on_random_axes() {
    let db = fixture("cylinder");
    let strat = (
        prop::array::uniform3(-1.0f64..1.0),
        prop::array::uniform3(-2.0f64..2.0),
        -3.0f64..3.0,
    );
    runner(16)
        .run(&strat, |(d, x0, th)| {
            let dir = Vector3::from(d);
            if dir.norm() < 0.1 {
                return Ok(());
            }
            let p = Parametrisation {
                modifiers: vec![node_mod(
                    "n",
                    Links {
                        surfaces: vec![SurfaceId(0)],
                        ..Links::default()
                    },
                    Axis {
                        point: Point3::from(x0),
                        direction: dir,
                    },
                    true,
                    [false; 3],
                )],
                constraints: vec![],
            };
            let p1 = p
                .bind(&db, &MasterSources::new())
                .unwrap()
                .apply(&[th])
                .unwrap();
            let db1 = db.with_control_points(&p1).unwrap();
            let p2 = p
                .bind(&db1, &MasterSources::new())
                .unwrap()
                .apply(&[-th])
                .unwrap();
            for (a, b) in p2.iter().zip(db.control_points()) {
                prop_assert!((a - b).norm() < 1e-13 * 10.0);
            }
            Ok(())
        })
        .unwrap();
}

#[test]
fn tensor_surface_is_linear_in_its_coefficients() {
    let (db, all) = wing_body_all();
    let p = Parametrisation {
        modifiers: vec![all.modifiers[2].clone()],
        constraints: vec![],
    };
    let prep = p.bind(&db, &MasterSources::new()).unwrap();
    let n = prep.registry().len();
    let strat = (
        prop::collection::vec(-0.05f64..0.05, n),
        prop::collection::vec(-0.05f64..0.05, n),
    );
    let r0 = db.control_points().to_vec();
    runner(16)
        .run(&strat, |(a, b)| {
            let ab: Vec<f64> = a.iter().zip(&b).map(|(x, y)| x + y).collect();
            let (pa, pb, pab) = (
                prep.apply(&a).unwrap(),
                prep.apply(&b).unwrap(),
                prep.apply(&ab).unwrap(),
            );
            for k in 0..r0.len() {
                let lin = (pa[k] - r0[k]) + (pb[k] - r0[k]);
                prop_assert!(((pab[k] - r0[k]) - lin).norm() < 1e-13);
            }
            Ok(())
        })
        .unwrap();
}
