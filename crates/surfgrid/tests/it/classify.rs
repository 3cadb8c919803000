//! Classification of a generated grid written as SU2 (parameters dropped).

use surfgrid::{ClassifyOptions, GenerateOptions, NodeSupport, SizeField, classify, generate};

use crate::common::fixture;

fn su2_round_trip(m: &mesh::Mesh) -> mesh::Mesh {
    let mut buf = Vec::new();
    mesh::su2::write(m, &mut buf).unwrap();
    mesh::su2::read(&buf[..], std::path::Path::new("generated.su2")).unwrap()
}

#[test]
fn sphere_parameters_recovered_from_su2() {
    let db = fixture("sphere");
    let field = SizeField::uniform(0.2).unwrap();
    let g = generate(&db, &field, &GenerateOptions::default()).unwrap();
    let m = su2_round_trip(&g.to_mesh(&db));
    assert!(m.classes.is_none());
    let (c, rep) = classify(&m, &db, &ClassifyOptions::default()).unwrap();
    eprintln!("{rep:?}");
    assert_eq!(rep.corners, db.corners.len());
    assert!(rep.max_distance < 1e-12 * db.reference_length());
    for i in 0..g.n_nodes() {
        match (g.support[i], c.support[i]) {
            (NodeSupport::Corner(a), NodeSupport::Corner(b)) => assert_eq!(a, b),
            (NodeSupport::Curve { comp: a, t: s }, NodeSupport::Curve { comp: b, t }) => {
                assert_eq!(a, b, "node {i}");
                assert!((s - t).abs() <= 1e-9, "node {i}: t {s} vs {t}");
            }
            (NodeSupport::Surface { comp: a, uv: p }, NodeSupport::Surface { comp: b, uv: q }) => {
                assert_eq!(a, b, "node {i}");
                assert!(
                    (p[0] - q[0]).abs() <= 1e-9 && (p[1] - q[1]).abs() <= 1e-9,
                    "node {i}"
                );
            }
            (a, b) => panic!("node {i}: {a:?} classified as {b:?}"),
        }
    }
    // the classified grid updates like a generated one: zero change is bit for bit
    let (u, rep) = surfgrid::update(&c, &db, &db, &surfgrid::UpdateOptions::default()).unwrap();
    assert_eq!(rep.moved_nodes, 0);
    assert!(u.coords == c.coords);
}

#[test]
fn a_node_off_the_geometry_is_named() {
    let db = fixture("sphere");
    let field = SizeField::uniform(0.3).unwrap();
    let g = generate(&db, &field, &GenerateOptions::default()).unwrap();
    let mut m = g.to_mesh(&db);
    m.classes = None;
    let k = g.n_nodes() - 1;
    let orig = m.coords[k];
    m.coords[k] = orig.map(|x| x * 1.001); // radially off the unit sphere by 1e-3
    match classify(&m, &db, &ClassifyOptions::default()) {
        Err(surfgrid::Error::NodeOffGeometry { node, distance, .. }) => {
            assert_eq!(node, k);
            assert!((distance - 1e-3).abs() < 1e-5, "{distance}");
        }
        other => panic!("expected NodeOffGeometry, got {:?}", other.map(|x| x.1)),
    }
    m.coords[k] = orig;
    m.markers[0].name = "nacelle".into();
    assert!(matches!(
        classify(&m, &db, &ClassifyOptions::default()),
        Err(surfgrid::Error::UnknownMarker { .. })
    ));
}
