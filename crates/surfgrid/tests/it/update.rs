//! Update at frozen parameters (§3.3): zero change, and the wing after a fuselage radius
//! change of ±5 % (the junction moves in the wing's parametric plane).

use geom_db::prelude::Point3;
use geom_db::{GeomDb, SurfCompId};
use intersect::update::{ModelBaseline, UpdateOptions as ModelOptions};
use surfgrid::{GenerateOptions, SizeField, UpdateOptions, generate, update};

use crate::common::fixture;

fn move_surface_nodes(db: &GeomDb, s: usize, f: impl Fn(&Point3) -> Point3) -> Vec<Point3> {
    let mut pts = db.control_points().to_vec();
    let mut done = vec![false; pts.len()];
    for ids in &db.surfaces[s].control.nodes {
        for id in ids {
            if !done[id.index()] {
                pts[id.index()] = f(&pts[id.index()]);
                done[id.index()] = true;
            }
        }
    }
    pts
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

#[test]
fn wing_after_fuselage_radius_change() {
    let db = fixture("wing_body");
    let wing = SurfCompId(
        db.surface_components
            .iter()
            .position(|c| c.name == "wing")
            .unwrap() as u32,
    );
    let fus = db
        .surfaces
        .iter()
        .position(|s| s.name == "fuselage")
        .unwrap();
    // the leading-edge radius (about 1.6 % of the chord) must be resolved by the spacing: a
    // line source along the leading edge
    let le_tip = Point3::new(3.0 + 5.0 * 25f64.to_radians().tan(), 5.0, 0.15);
    let field = SizeField::uniform(0.15)
        .unwrap()
        .with_line(surfgrid::spacing::LineSource {
            a: Point3::new(3.0, 0.0, -0.1),
            b: le_tip,
            h0: 0.02,
            r0: 0.02,
            growth: surfgrid::spacing::Growth::Smoothstep { radius: 0.4 },
        })
        .unwrap();
    let g = generate(
        &db,
        &field,
        &GenerateOptions::default().with_components(vec![wing]),
    )
    .unwrap();
    let base = ModelBaseline::new(&db, &ModelOptions::default()).unwrap();
    // zero change through the model update: bit for bit
    let (same, _) = base.update(db.control_points()).unwrap();
    let (g0, rep0) = update(&g, &db, &same, &UpdateOptions::default()).unwrap();
    assert_eq!(rep0.moved_nodes, 0);
    assert!(g0 == g);
    let st = surfgrid::grid_stats(&g, &field);
    eprintln!("wing: {st:?}");
    for k in [1.05, 0.95] {
        let nodes = move_surface_nodes(&db, fus, |p| Point3::new(p.x, p.y * k, p.z * k));
        let (new, _) = base.update(&nodes).unwrap();
        let (g2, rep) = update(&g, &db, &new, &UpdateOptions::default()).unwrap();
        let c = &rep.components[0];
        eprintln!("fuselage ×{k}: {rep:?}");
        assert!(c.remapped && c.max_boundary_shift > 1e-3);
        assert!(c.worst_after > 0.0);
        assert!(c.worst_after >= 0.9 * c.worst_initial, "{c:?}");
        // every node on its support in the new model
        let l = new.reference_length();
        for i in 0..g2.n_nodes() {
            let p = g2.evaluate_node(&new, i);
            assert!((p - g2.coords[i]).norm() <= 1e-12 * l, "node {i}");
        }
        // orientation w.r.t. the inward normal kept
        use geom_db::eval::ParamSurface;
        let cg = &g2.components[0];
        let sc = new.surface_component(cg.comp);
        let s = new.surface(sc.surface);
        for (j, t) in cg.global_triangles().enumerate() {
            let [a, b, cc] = t.map(|v| g2.coords[v as usize]);
            let lt = cg.triangles[j].map(|v| cg.uv[v as usize]);
            let uv = [
                (lt[0][0] + lt[1][0] + lt[2][0]) / 3.0,
                (lt[0][1] + lt[1][1] + lt[2][1]) / 3.0,
            ];
            let n = s.normal(uv[0], uv[1]).unwrap() * sc.inward.sign();
            assert!((b - a).cross(&(cc - a)).dot(&n) > 0.0, "triangle {j}");
        }
    }
}
