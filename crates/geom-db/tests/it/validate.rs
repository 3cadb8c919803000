//! Validation: each rule reports the first problem and names the entity.

use geom_db::prelude::Point3;
use geom_db::{Arc, Error, GeomDb, OrientedCurve, Patch};

use crate::fixture;

fn msg(db: &GeomDb) -> String {
    db.validate().unwrap_err().to_string()
}

#[test]
fn degree_and_coefficient_count() {
    let mut db = fixture("wing_body.ron");
    db.surfaces[2].patches[1].coeffs.pop();
    assert_eq!(
        msg(&db),
        "surface 2 patch 1: degree 8 × 1 needs 18 coefficients, 17 given"
    );
    let mut db = fixture("wing_body.ron");
    db.curves[0].arcs[3].degree = 0;
    assert_eq!(msg(&db), "curve 0 arc 3: degree 0 is outside 1..=24");
    let mut db = fixture("wing_body.ron");
    db.surfaces[0].patches[0].deg_u = 99;
    assert!(msg(&db).starts_with("surface 0 patch 0: degree 99 × 8 is outside"));
    let mut db = fixture("wing_body.ron");
    db.surfaces[1].n_u = 3;
    assert_eq!(msg(&db), "surface 1: n_u × n_v = 3 × 1 but 4 patches given");
}

#[test]
fn non_finite_numbers() {
    let mut db = fixture("wing_body.ron");
    db.surfaces[0].patches[2].coeffs[1].z = f64::NEG_INFINITY;
    assert_eq!(
        msg(&db),
        "surface 0 patch 2: coefficient a[0,1] z is infinite"
    );
    let mut db = fixture("wing_body.ron");
    db.curve_components[4].t0 = f64::NAN;
    assert!(msg(&db).starts_with("curve component 4: t0 = NaN is outside"));
    let mut db = fixture("wing_body.ron");
    db.control_nodes[17].x = f64::NAN;
    assert_eq!(msg(&db), "control node 17: coordinate x is NaN");
}

#[test]
fn dangling_ids() {
    let mut db = fixture("wing_body.ron");
    db.curve_components[2].curve = geom_db::CurveId(40);
    assert_eq!(
        msg(&db),
        "curve component 2: curve 40 does not exist (the model has 5 curves)"
    );
    let mut db = fixture("wing_body.ron");
    db.curve_components[0].end = geom_db::CornerId(6);
    assert_eq!(
        msg(&db),
        "curve component 0: end corner 6 does not exist (the model has 6 corners)"
    );
    let mut db = fixture("wing_body.ron");
    db.surface_components[1].loops[0][2] = OrientedCurve {
        comp: geom_db::CurveCompId(7),
        reversed: false,
    };
    assert!(msg(&db).starts_with("surface component 1 loop 0: curve component 7 does not exist"));
    let mut db = fixture("wing_body.ron");
    db.surfaces[1].control.nodes[0][0] = geom_db::ControlNodeId(100_000);
    assert!(msg(&db).starts_with("surface 1 patch 0: control node 100000 does not exist"));
    let mut db = fixture("wing_body.ron");
    db.curves[0].defining_surfaces.push(geom_db::SurfaceId(3));
    assert!(msg(&db).starts_with("curve 0: 3 defining surfaces, at most 2"));
}

#[test]
fn open_loop() {
    let mut db = fixture("wing_body.ron");
    db.surface_components[1].loops[0].remove(2);
    assert_eq!(
        msg(&db),
        "surface component 1 loop 0: not closed: curve component 1 ends at corner 2 but curve component 6 starts at corner 4"
    );
}

#[test]
fn zero_length_arc_and_degenerate_patch() {
    let mut db = fixture("wing_body.ron");
    let p = Point3::new(1.0, 2.0, 3.0);
    db.curves[3].arcs[0] = Arc::new(vec![p, Point3::origin()]);
    db.curves[3].control = Default::default();
    assert!(msg(&db).starts_with("curve 3 arc 0: zero length"));
    let mut db = fixture("wing_body.ron");
    // a patch collapsed onto a line
    db.surfaces[2].patches[0] =
        Patch::interpolate(8, 1, |u, v| Point3::new(u + v, 2.0 * (u + v), 0.0));
    db.surfaces[2].control = Default::default();
    assert!(
        msg(&db).starts_with("surface 2 patch 0: degenerate"),
        "{}",
        msg(&db)
    );
}

#[test]
fn control_nodes_off_their_patch() {
    let mut db = fixture("cylinder.ron");
    let id = db.surfaces[0].control.nodes[1][4];
    db.control_nodes[id.index()].z += 1e-3;
    let m = msg(&db);
    assert!(
        m.contains(&format!("{id} (control point")) && m.contains("away from the"),
        "{m}"
    );
}

#[test]
fn component_ranges() {
    let mut db = fixture("wing_body.ron");
    db.curve_components[0].t1 = 4.5;
    assert_eq!(
        msg(&db),
        "curve component 0: t1 = 4.5 is outside the domain [0, 4] of curve 0"
    );
    let mut db = fixture("wing_body.ron");
    db.curve_components[0].t1 = 0.0;
    assert_eq!(
        msg(&db),
        "curve component 0: empty parameter range t0 = t1 = 0"
    );
}

#[test]
fn version_and_unknown_fields() {
    let mut db = fixture("sphere.ron");
    db.format_version = 2;
    assert!(matches!(
        db.validate(),
        Err(Error::UnsupportedVersion { found: 2, .. })
    ));
    let text = crate::fixture_text("sphere.ron").replacen("name:", "nmae:", 1);
    let e = GeomDb::from_ron_str(&text, "s.ron").unwrap_err();
    assert!(matches!(e, Error::Syntax { line: 3, .. }), "{e}");
}

#[test]
fn assign_control_nodes_on_a_fresh_model() {
    // a model built from coefficients only gets shared control nodes
    let mut db = fixture("cylinder.ron");
    let count = db.control_nodes.len();
    for c in &mut db.curves {
        c.control = Default::default();
    }
    for s in &mut db.surfaces {
        s.control = Default::default();
    }
    db.control_nodes.clear();
    db.validate().unwrap();
    db.assign_control_nodes().unwrap();
    db.validate().unwrap();
    assert_eq!(db.control_nodes.len(), count);
}

#[test]
fn check_and_solve_never_panic_on_invalid_models() {
    let mut db = fixture("wing_body.ron");
    db.surfaces[1].control.nodes[2][3] = geom_db::ControlNodeId(1_000_000);
    db.curve_components[1].curve = geom_db::CurveId(99);
    let r = db.check(&geom_db::CheckOptions::default());
    assert!(!r.is_ok());
    assert_eq!(r.problems.len(), 1);
    assert!(r.problems[0].starts_with("surface 1 patch 2: control node 1000000 does not exist"));
    let pts = db.control_points().to_vec();
    let e = db.set_control_points(&pts).unwrap_err();
    assert!(
        e.to_string()
            .starts_with("surface 1: control node lists do not match"),
        "{e}"
    );
}
