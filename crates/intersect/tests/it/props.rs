//! Property tests: exact feet on a sphere, identity and translation of the curve update.

use crate::shapes::*;
use geom_db::prelude::{Point3, Vector3};
use intersect::project::{ProjectOptions, SurfaceProjector};
use intersect::ssi::{IntersectionSeeds, SsiOptions, update_curve_points};
use proptest::prelude::*;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn sphere_distance_is_exact(
        az in 0.1f64..6.1, pol in 0.2f64..2.9, rho in 0.05f64..5.0, r in 0.5f64..3.0,
    ) {
        let s = Sphere { c: Point3::new(1.0, 2.0, -1.0), r };
        let proj = SurfaceProjector::new("sphere", &s, &ProjectOptions::default()).unwrap();
        let dir = Vector3::new(pol.sin() * az.cos(), pol.sin() * az.sin(), pol.cos());
        let f = proj.project(&(s.c + dir * rho)).unwrap();
        prop_assert!((f.distance - (rho - r).abs()).abs() <= 1e-11 * r.max(rho));
    }

    #[test]
    fn plane_translation_moves_circle_rigidly(
        h0 in -0.6f64..0.6, dh in -0.3f64..0.3, dx in -0.2f64..0.2,
    ) {
        // cylinder (axis z) ∩ horizontal plane: translating the plane by dh moves every
        // control point by dh in z; translating the cylinder sideways by dx (and the plane
        // unchanged) moves them by dx in x
        let cyl = Cylinder::axis_z(0.7, 3.0);
        let pts: Vec<Point3> = (0..7)
            .map(|k| {
                let a = -2.5 + 5.0 * k as f64 / 6.0;
                Point3::new(0.7 * a.cos(), 0.7 * a.sin(), h0)
            })
            .collect();
        let po = ProjectOptions::default().with_length_scale(4.0);
        let pl = Plane::horizontal(h0, 2.0);
        let p1 = SurfaceProjector::new("plane", &pl, &po).unwrap();
        let p2 = SurfaceProjector::new("cyl", &cyl, &po).unwrap();
        let o = SsiOptions::default().with_length_scale(4.0);
        let sd = IntersectionSeeds::new("c", &pts, None, None, &p1, &p2, &o).unwrap();
        let up = update_curve_points(&sd, &Plane::horizontal(h0 + dh, 2.0), &cyl, &o).unwrap();
        for (p, q) in pts.iter().zip(up.new_points()) {
            prop_assert!((q - (p + Vector3::z() * dh)).norm() < 1e-13);
        }
        let mut moved = cyl.clone();
        moved.o.x += dx;
        let up = update_curve_points(&sd, &pl, &moved, &o).unwrap();
        for (p, q) in pts.iter().zip(up.new_points()) {
            prop_assert!((q - (p + Vector3::x() * dx)).norm() < 1e-13);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]

    #[test]
    fn model_update_keeps_the_junction_on_both_surfaces(
        k in 0.95f64..1.05, dz in -0.03f64..0.03,
    ) {
        // test wing-body: fuselage radius × k and the whole wing up by dz; every control
        // point of the junction on both new surfaces, its corners on the leading and
        // trailing edges (x = 0 and x = 1)
        use intersect::project::{ProjectOptions, SurfaceProjector};
        use intersect::update::{UpdateOptions, update_model};
        let db = crate::model::wing_body();
        let scale = db.reference_length();
        let mut nodes = db.control_points().to_vec();
        for ids in &db.surfaces[0].control.nodes {
            for id in ids {
                let p = db.control_points()[id.index()];
                nodes[id.index()] = Point3::new(p.x, p.y * k, p.z * k);
            }
        }
        for ids in &db.surfaces[1].control.nodes {
            for id in ids {
                let p = db.control_points()[id.index()];
                nodes[id.index()] = Point3::new(p.x, p.y, p.z + dz);
            }
        }
        let (new, rep) = update_model(&db, &nodes, &UpdateOptions::default()).unwrap();
        prop_assert!(rep.max_curve_residual <= 1e-10 * scale);
        let po = ProjectOptions::default().with_length_scale(scale);
        let pf = SurfaceProjector::new("fuselage", &new.surfaces[0], &po).unwrap();
        let pw = SurfaceProjector::new("wing", &new.surfaces[1], &po).unwrap();
        for arc in &new.curves[0].arcs {
            for q in arc.control_points() {
                prop_assert!(pf.project(&q).unwrap().distance <= 1e-10 * scale);
                prop_assert!(pw.project(&q).unwrap().distance <= 1e-10 * scale);
            }
        }
        prop_assert!(new.corners[0].point.x.abs() <= 1e-12);
        prop_assert!((new.corners[1].point.x - 1.0).abs() <= 1e-12);
    }
}
