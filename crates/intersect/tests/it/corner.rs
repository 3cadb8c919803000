//! Corners by curve–curve intersection (Eq. 13).

use crate::shapes::*;
use geom_db::prelude::{Point3, Vector3};
use intersect::corner::{CornerOptions, solve_corner};
use testkit::assert_close;

#[test]
fn two_great_circles_meet_at_the_known_point() {
    let eq = Circle {
        c: Point3::origin(),
        e1: Vector3::x(),
        e2: Vector3::y(),
        r: 1.0,
        dom: (0.0, 3.0),
    };
    let mer = Circle {
        c: Point3::origin(),
        e1: Vector3::y(),
        e2: Vector3::z(),
        r: 1.0,
        dom: (-1.0, 1.5),
    };
    // they meet at (0, 1, 0): t_eq = π/2, t_mer = 0
    for seed in [Some([1.4, 0.2]), None] {
        let c = solve_corner(
            "corner 1",
            ("equator", &eq),
            ("meridian", &mer),
            seed,
            &CornerOptions::default(),
        )
        .unwrap();
        assert_close!(c.t, [std::f64::consts::FRAC_PI_2, 0.0], abs = 1e-9);
        assert_close!(c.point, [0.0, 1.0, 0.0], abs = 1e-12);
        assert!(c.distance < 1e-14);
    }
}

#[test]
fn corner_at_curve_ends_after_a_move_needs_the_extension() {
    // a line ending at t = 1 on a circle; shift the circle so that they meet past the end
    let line = Line {
        o: Point3::new(0.0, 0.0, 0.0),
        d: Vector3::new(1.0, 0.0, 0.0),
        dom: (0.0, 1.0),
    };
    let circ = Circle {
        c: Point3::new(2.02, 0.0, 0.0),
        e1: Vector3::x(),
        e2: Vector3::y(),
        r: 1.0,
        dom: (2.0, 4.5),
    };
    let err = solve_corner(
        "corner 3",
        ("line", &line),
        ("circle", &circ),
        Some([1.0, std::f64::consts::PI]),
        &CornerOptions::default().with_length_scale(3.0),
    )
    .unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.contains("corner 3") && msg.contains("line") && msg.contains("circle"),
        "{msg}"
    );
    if let intersect::Error::CurvesDoNotMeet { distance, .. } = err {
        assert_close!(distance, 0.02, rel = 1e-9);
    } else {
        panic!("{err:?}");
    }
    let c = solve_corner(
        "corner 3",
        ("line", &line),
        ("circle", &circ),
        Some([1.0, std::f64::consts::PI]),
        &CornerOptions::default()
            .with_length_scale(3.0)
            .with_extension(0.1),
    )
    .unwrap();
    assert_close!(c.point, [1.02, 0.0, 0.0], abs = 1e-12);
    assert_close!(c.t[0], 1.02, abs = 1e-12);
}

#[test]
fn skew_lines_do_not_meet() {
    let a = Line {
        o: Point3::new(-1.0, 0.0, 0.0),
        d: Vector3::x(),
        dom: (0.0, 2.0),
    };
    let b = Line {
        o: Point3::new(0.0, -1.0, 0.25),
        d: Vector3::y(),
        dom: (0.0, 2.0),
    };
    let err = solve_corner(
        "corner 9",
        ("a", &a),
        ("b", &b),
        None,
        &CornerOptions::default(),
    )
    .unwrap_err();
    match err {
        intersect::Error::CurvesDoNotMeet {
            distance, t_a, t_b, ..
        } => {
            assert_close!(distance, 0.25, rel = 1e-12);
            assert_close!([t_a, t_b], [1.0, 1.0], abs = 1e-10);
        }
        e => panic!("{e:?}"),
    }
}
