//! The committed fixtures: valid, checked, and stable through a RON round trip.

use geom_db::eval::ParamSurface;
use geom_db::{CheckOptions, GeomDb, Orientation};

use crate::{fixture, fixture_text};

#[test]
fn fixtures_load_check_and_round_trip() {
    for name in ["sphere.ron", "cylinder.ron", "wing_body.ron"] {
        let db = fixture(name);
        let report = db.check(&CheckOptions::default());
        assert!(report.is_ok(), "{name}: {:?}", report.problems);
        let text = db.to_ron_string();
        let again = GeomDb::from_ron_str(&text, name).unwrap();
        assert_eq!(again.to_ron_string(), text, "{name}");
        assert_eq!(text.trim_end(), fixture_text(name).trim_end(), "{name}");
        assert!(text.len() < 1 << 20, "{name} is {} bytes", text.len());
    }
}

#[test]
fn closed_and_open_models() {
    let sphere = fixture("sphere.ron").check(&CheckOptions::default());
    assert!(sphere.topology.closed);
    assert!(sphere.topology.free_edges.is_empty());
    let wb = fixture("wing_body.ron");
    let r = wb.check(&CheckOptions::default());
    assert!(!r.topology.closed);
    // the free edges are the two symmetry-plane lines of the fuselage
    let names: Vec<&str> = r
        .topology
        .free_edges
        .iter()
        .map(|c| wb.curve_component(*c).name.as_str())
        .collect();
    assert_eq!(names, ["fuselage bottom", "fuselage top"]);
    for c in &r.topology.free_edges {
        let cc = wb.curve_component(*c);
        for k in 0..=10 {
            let p = wb.curve_component_point(*c, k as f64 / 10.0);
            assert!(p.y.abs() < 1e-10, "{} leaves y = 0: {p}", cc.name);
        }
    }
}

#[test]
fn non_manifold_and_flipped_edges_are_problems() {
    let mut db = fixture("sphere.ron");
    // use one edge a third time in a one-edge loop? Loops must close: reuse a whole loop.
    let extra = db.surface_components[0].clone();
    db.surface_components.push(extra);
    db.validate().unwrap();
    let r = db.check(&CheckOptions::default());
    assert_eq!(r.topology.non_manifold.len(), 4);
    assert!(!r.is_ok());

    let mut db = fixture("sphere.ron");
    // traverse the first face backwards and flip its inward normal: loops stay consistent
    // with the normal, but every edge of the face is now used twice in the same direction
    let sc = &mut db.surface_components[0];
    sc.loops[0].reverse();
    for oc in &mut sc.loops[0] {
        oc.reversed = !oc.reversed;
    }
    sc.inward = match sc.inward {
        Orientation::Positive => Orientation::Negative,
        Orientation::Negative => Orientation::Positive,
    };
    let r = db.check(&CheckOptions::default());
    assert_eq!(r.topology.same_direction.len(), 4);
    assert!(r.topology.misoriented_loops.is_empty());
    assert!(!r.is_ok());
}

#[test]
fn wing_body_junction_lies_on_both_surfaces() {
    let db = fixture("wing_body.ron");
    let j = db.curves.iter().position(|c| c.name == "junction").unwrap();
    let curve = &db.curves[j];
    assert_eq!(curve.defining_surfaces.len(), 2);
    let r = db.check(&CheckOptions::default());
    let l = db.reference_length();
    for g in r.gaps.iter().filter(|g| {
        g.what.starts_with("curve component 0 ") || g.what.starts_with("curve component 1 ")
    }) {
        assert!(g.max < 1e-7 * l, "{}: {:e}", g.what, g.max);
    }
    // the junction corners are on the fuselage cylinder (radius 0.8)
    for c in &db.corners {
        if c.name.starts_with("junction") {
            let r = (c.point.y * c.point.y + c.point.z * c.point.z).sqrt();
            assert!((r - 0.8).abs() < 1e-9, "{}: radius {r}", c.name);
        }
    }
    // the wing surface is continuous across its chordwise patches (leading edge included)
    let wing = &db.surfaces[curve.defining_surfaces[0].index()];
    for i in 1..wing.n_u {
        for k in 0..=4 {
            let v = k as f64 / 4.0;
            let a = wing.patches[i - 1].point(1.0, v);
            let b = wing.patches[i].point(0.0, v);
            assert!((a - b).norm() < 1e-10 * l, "{:e}", (a - b).norm());
        }
    }
    let _ = wing.point(0.0, 0.0);
}

#[test]
fn format_doc_example_is_valid() {
    let doc = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/formats/geom-ron.md"),
    )
    .unwrap();
    let start = doc.find("```ron\n").unwrap() + "```ron\n".len();
    let end = start + doc[start..].find("```").unwrap();
    let mut db = GeomDb::from_ron_str(&doc[start..end], "geom-ron.md").unwrap();
    let r = db.check(&CheckOptions::default());
    assert!(r.is_ok(), "{:?}", r.problems);
    assert_eq!(r.topology.free_edges.len(), 4);
    assert_eq!(r.max_gap, 0.0);
    db.assign_control_nodes().unwrap();
    assert_eq!(db.control_nodes.len(), 4);
    // inward = Negative contradicts the counter-clockwise loop
    db.surface_components[0].inward = Orientation::Negative;
    assert_eq!(
        db.check(&CheckOptions::default())
            .topology
            .misoriented_loops
            .len(),
        1
    );
}
