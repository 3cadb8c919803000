//! The OpenCASCADE-written files of `tests/data/` (made by `make_step.py`): every instance
//! is typed or kept, the topology counts agree with what OpenCASCADE reads back, the units
//! are the ones written.

use step::{ConicKind, ElementaryKind, Entity, Id};

fn read(name: &str) -> step::StepFile {
    let bytes = std::fs::read(crate::data(name)).unwrap();
    step::parse(&bytes, name).unwrap_or_else(|e| panic!("{e}"))
}

fn expected() -> serde_json::Value {
    let text = std::fs::read_to_string(crate::data("expected.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

fn count(f: &step::StepFile, pred: impl Fn(&Entity) -> bool) -> usize {
    f.entities.iter().filter(|e| pred(e)).count()
}

/// The context of the shape representation that holds the solid or surface model.
fn shape_context(f: &step::StepFile) -> Id {
    f.entities
        .iter()
        .find_map(|e| match e {
            Entity::Representation(r) if r.kind.contains("SHAPE_REPRESENTATION") => Some(r.context),
            _ => None,
        })
        .unwrap()
}

#[test]
fn topology_counts_and_units_agree_with_opencascade() {
    let exp = expected();
    for name in ["box_ap214.stp", "cylinder_ap203.stp", "nurbs_ap242.stp"] {
        let f = read(name);
        let e = &exp[name];
        let faces = count(&f, |e| matches!(e, Entity::Face(_)));
        let edges = count(&f, |e| matches!(e, Entity::EdgeCurve(_)));
        let vertices = count(&f, |e| matches!(e, Entity::VertexPoint(_)));
        assert_eq!(faces as u64, e["faces"].as_u64().unwrap(), "{name} faces");
        assert_eq!(edges as u64, e["edges"].as_u64().unwrap(), "{name} edges");
        assert_eq!(
            vertices as u64,
            e["vertices"].as_u64().unwrap(),
            "{name} vertices"
        );
        let units = f.units(shape_context(&f)).unwrap();
        let want = e["unit"].as_str().unwrap();
        assert_eq!(units.length_name.as_deref(), Some(want), "{name}");
        let m = match want {
            "mm" => 1e-3,
            _ => 1.0,
        };
        assert_eq!(units.length, Some(m));
        assert_eq!(units.plane_angle, Some(1.0));
        // OpenCASCADE writes a distance uncertainty of 1e-7 of its unit.
        assert!(units.uncertainty.is_some_and(|u| u > 0.0));
    }
}

#[test]
fn schemas_are_read_from_the_header() {
    assert!(read("box_ap214.stp").schemas[0].starts_with("AUTOMOTIVE_DESIGN"));
    assert!(read("cylinder_ap203.stp").schemas[0].starts_with("CONFIG_CONTROL_DESIGN"));
    assert!(read("nurbs_ap242.stp").schemas[0].starts_with("AP242"));
}

#[test]
fn cylinder_entities_hold_the_file_values() {
    let f = read("cylinder_ap203.stp");
    // The cylinder of radius 5 mm about (1, 2, 3) mm + t z, written in metres.
    let (id, cyl) = f
        .iter()
        .find_map(|(i, e)| match e {
            Entity::Elementary(s) if s.kind == ElementaryKind::Cylinder => Some((i.id, s)),
            _ => None,
        })
        .unwrap();
    assert_eq!(cyl.radius, 0.005);
    let Some(Entity::Axis2Placement(p)) = f.entity(cyl.position) else {
        panic!()
    };
    assert_eq!(
        f.point(id, p.location, "location").unwrap(),
        [0.001, 0.002, 0.003]
    );
    assert_eq!(
        f.direction(id, p.axis.unwrap(), "axis").unwrap(),
        [0.0, 0.0, 1.0]
    );
    // Two circles of radius 5 mm, a seam curve with two pcurves on the cylinder.
    let circles = count(
        &f,
        |e| matches!(e, Entity::Conic(c) if c.kind == ConicKind::Circle && c.a == 0.005),
    );
    assert!(circles >= 2, "{circles}");
    let seams: Vec<_> = f
        .entities
        .iter()
        .filter_map(|e| match e {
            Entity::SurfaceCurve(s) if s.seam => Some(s),
            _ => None,
        })
        .collect();
    assert_eq!(seams.len(), 1);
    assert_eq!(seams[0].associated.len(), 2);
    for &pc in &seams[0].associated {
        let Some(Entity::Pcurve(p)) = f.entity(pc) else {
            panic!()
        };
        assert_eq!(p.surface, id);
    }
}

#[test]
fn rational_surface_is_decoded_from_its_complex_instance() {
    let f = read("nurbs_ap242.stp");
    let s = f
        .entities
        .iter()
        .find_map(|e| match e {
            Entity::BSplineSurface(s) => Some(s),
            _ => None,
        })
        .unwrap();
    let w = s.weights.as_ref().expect("rational");
    assert_eq!(w.len(), s.control_points.len());
    assert!(w.iter().flatten().any(|&x| (x - 1.0).abs() > 0.1));
    let nu = s.control_points.len();
    let nv = s.control_points[0].len();
    assert_eq!(
        s.u_multiplicities.iter().sum::<usize>(),
        nu + s.u_degree + 1
    );
    assert_eq!(
        s.v_multiplicities.iter().sum::<usize>(),
        nv + s.v_degree + 1
    );
    let rational_curves = count(
        &f,
        |e| matches!(e, Entity::BSplineCurve(c) if c.weights.is_some()),
    );
    assert!(rational_curves >= 2, "{rational_curves}");
}

#[test]
fn every_reference_of_a_typed_entity_names_an_instance() {
    for name in ["box_ap214.stp", "cylinder_ap203.stp", "nurbs_ap242.stp"] {
        let f = read(name);
        for (inst, e) in f.iter() {
            for r in e.references() {
                assert!(f.instance(r).is_some(), "{name}: {} -> {r}", inst.id);
            }
        }
    }
}
