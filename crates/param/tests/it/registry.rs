//! Registry: names, bounds, duplicates, unknown names, links to missing entities, RON.

use geom_db::prelude::{Point3, Vector3};
use geom_db::{ControlNodeId, CurveId, SurfaceId};
use param::*;

use crate::common::*;

#[test]
fn bounds_are_checked_and_named() {
    let (_, all) = wing_body_all();
    let reg = all.registry().unwrap();
    let mut dv = DesignValues::new();
    dv.insert("tip_theta".into(), 5.0);
    let e = reg.vector_from_values(&dv).unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, Error::OutOfBounds { .. }));
    assert!(
        msg.contains("tip_theta") && msg.contains("[-3, 3]"),
        "{msg}"
    );
    dv.insert("tip_theta".into(), 0.5);
    let x = reg.vector_from_values(&dv).unwrap();
    assert_eq!(x[reg.index_of("tip_theta").unwrap()], 0.5);
    assert!(reg.check_bounds(&x).is_ok());
    dv.insert("unknown".into(), 0.0);
    let e = reg.vector_from_values(&dv).unwrap_err();
    assert!(e.to_string().contains("'unknown'"), "{e}");
    // reversed bounds and an initial value outside
    let bad = DesignVariable::new("b", 1.0, -1.0);
    assert!(bad.validate().unwrap_err().to_string().contains("'b'"));
    let bad = DesignVariable::new("c", 0.5, 1.0);
    assert!(matches!(bad.validate(), Err(Error::OutOfBounds { .. })));
    // scaling round trip
    let s = reg.to_scaled(&x);
    assert_eq!(reg.from_scaled(&s), x);
}

#[test]
fn duplicate_names_are_rejected() {
    let (_, mut all) = wing_body_all();
    let dup = all.modifiers[0].clone();
    if let Modifier::Line(mut l) = dup {
        l.name = "bump2".into();
        all.modifiers.push(Modifier::Line(l));
    }
    let e = all.registry().unwrap_err();
    assert!(matches!(e, Error::DuplicateVariable { .. }), "{e}");
    assert!(
        e.to_string().contains("'hh0'") && e.to_string().contains("'bump2'"),
        "{e}"
    );
}

#[test]
fn links_to_missing_entities_are_errors() {
    let db = fixture("wing_body");
    let cases = [
        Links {
            surfaces: vec![SurfaceId(9)],
            ..Links::default()
        },
        Links {
            curves: vec![CurveId(42)],
            ..Links::default()
        },
        Links {
            nodes: vec![ControlNodeId(1_000_000)],
            ..Links::default()
        },
    ];
    for (links, what) in cases
        .into_iter()
        .zip(["surface 9", "curve 42", "control node 1000000"])
    {
        let p = Parametrisation {
            modifiers: vec![node_mod(
                "n",
                links,
                Axis {
                    point: Point3::origin(),
                    direction: Vector3::z(),
                },
                true,
                [false; 3],
            )],
            constraints: vec![],
        };
        let e = p.bind(&db, &MasterSources::new()).err().unwrap();
        assert!(matches!(e, Error::MissingEntity { .. }));
        assert!(
            e.to_string().contains(what) && e.to_string().contains("'n'"),
            "{e}"
        );
    }
}

#[test]
fn variable_count_must_match_basis() {
    let (db, mut all) = wing_body_all();
    if let Modifier::Line(l) = &mut all.modifiers[0] {
        l.variables.pop();
    }
    let e = all.bind(&db, &MasterSources::new()).err().unwrap();
    assert!(
        e.to_string().contains("'bump'") && e.to_string().contains("1 variables"),
        "{e}"
    );
}

#[test]
fn ron_round_trip_and_errors_with_position() {
    let (_, all) = wing_body_all();
    let text = all.to_ron_string();
    let back = Parametrisation::from_ron_str(&text, "p.ron").unwrap();
    assert_eq!(back, all);
    let e = Parametrisation::from_ron_str("(modifiers: [Node(name: 3)])", "p.ron").unwrap_err();
    let msg = e.to_string();
    assert!(msg.starts_with("p.ron:1:"), "{msg}");
}
