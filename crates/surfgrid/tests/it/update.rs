//! Update at frozen parameters (§3.3): zero change, and the whole wing-body after a fuselage
//! radius change of ±5 % (the junction moves in the fuselage's and the wing's parametric
//! planes).

use geom_db::GeomDb;
use geom_db::prelude::Point3;
use intersect::update::{ModelBaseline, UpdateOptions as ModelOptions};
use surfgrid::{GenerateOptions, SizeField, UpdateOptions, generate, update};

use crate::common::{check_grid, fixture, wing_body_field};

/// Control nodes of support surface `s` moved by `f`.
fn move_surface_nodes(db: &GeomDb, s: usize, f: impl Fn(&Point3) -> Point3) -> Vec<Point3> {
    db.control_points_with_surface_moved(geom_db::SurfaceId::from_index(s), f)
}

#[test]
fn zero_change_is_bit_for_bit() {
    let db = fixture("sphere");
    let field = SizeField::uniform(0.2).unwrap();
    let g = generate(&db, &field, &GenerateOptions::default()).unwrap();
    let (g2, rep) = update(&g, &db, &db.clone(), &UpdateOptions::default()).unwrap();
    assert_eq!(rep.moved_nodes, 0);
    assert!(g2 == g);
    let x = surfgrid::evaluate_frozen(&g, &db);
    assert!(x == g.coords);
}

/// The test: the whole wing-body (fuselage with its poles, wing, tip cap) after a
/// fuselage radius change of ±5 %: the junction moves in the fuselage's and the wing's
/// parametric planes, so both are re-mapped and smoothed; every triangle stays valid and
/// each component's worst quality within 10 % of the initial.
#[test]
fn wing_body_after_fuselage_radius_change() {
    let db = fixture("wing_body");
    let fus = db
        .surfaces
        .iter()
        .position(|s| s.name == "fuselage")
        .expect("the wing-body fixture has a surface named \"fuselage\"");
    let field = wing_body_field(&db, 0.15);
    let g = generate(&db, &field, &GenerateOptions::default()).unwrap();
    let base = ModelBaseline::new(&db, &ModelOptions::default()).unwrap();
    // zero change through the model update: bit for bit
    let (same, _) = base.update(db.control_points()).unwrap();
    let (g0, rep0) = update(&g, &db, &same, &UpdateOptions::default()).unwrap();
    assert_eq!(rep0.moved_nodes, 0);
    assert!(g0 == g);
    let st0 = surfgrid::grid_stats(&g, &field);
    // One updater for all the changes below: its factorised re-maps are reused.
    let updater = surfgrid::Updater::new(&g);
    for k in [1.05, 0.95] {
        // scale the fuselage about its axis (the x axis: the nose and tail poles stay)
        let nodes = move_surface_nodes(&db, fus, |p| Point3::new(p.x, p.y * k, p.z * k));
        let (new, _) = base.update(&nodes).unwrap();
        let (g2, rep) = update(&g, &db, &new, &UpdateOptions::default()).unwrap();
        eprintln!("fuselage ×{k}: {rep:?}");
        let (g3, rep3) = updater
            .update(&g, &db, &new, &UpdateOptions::default())
            .unwrap();
        assert!(g3 == g2 && rep3 == rep, "reuse changes nothing");
        // The updater on a grid of the same topology at other positions (g2, back to the
        // initial model): still the free function's answer.
        let back = update(&g2, &new, &same, &UpdateOptions::default()).unwrap();
        let back_reused = updater
            .update(&g2, &new, &same, &UpdateOptions::default())
            .unwrap();
        assert!(back.0 == back_reused.0 && back.1 == back_reused.1);
        assert!(rep.moved_nodes > 0);
        let remapped = rep.components.iter().filter(|c| c.remapped).count();
        assert!(
            remapped >= 2,
            "the junction moved on the fuselage and the wing"
        );
        for c in &rep.components {
            assert!(c.worst_after > 0.0, "{c:?}");
            assert!(c.worst_after >= 0.9 * c.worst_initial, "{c:?}");
        }
        // valid grid on the new model: orientation, support, conformity, fans at the poles
        check_grid(&new, &g2, false);
        // an updater refuses another grid
        let other = generate(&db, &wing_body_field(&db, 0.3), &GenerateOptions::default()).unwrap();
        assert!(
            updater
                .update(&other, &db, &new, &UpdateOptions::default())
                .is_err()
        );
        let st = surfgrid::grid_stats(&g2, &field);
        assert!(
            st.worst_quality >= 0.9 * st0.worst_quality,
            "{st:?} vs {st0:?}"
        );
        assert!(st.frac_min_angle_ge_20 >= 0.99, "{st:?}");
    }
}
