//! Classification of a generated grid written as SU2 (parameters dropped).

use surfgrid::{ClassifyOptions, GenerateOptions, NodeSupport, SizeField, classify, generate};

use crate::common::{check_grid, fixture, wing_body_field};

fn su2_round_trip(m: &mesh::Mesh) -> mesh::Mesh {
    let mut buf = Vec::new();
    mesh::su2::write(m, &mut buf).unwrap();
    mesh::su2::read(&buf[..], std::path::Path::new("generated.su2")).unwrap()
}

/// Every node has the same support entity in `c` as in `g` and parameters within 1e-9.
fn same_supports(g: &surfgrid::SurfaceGrid, c: &surfgrid::SurfaceGrid) {
    assert_eq!(g.n_nodes(), c.n_nodes());
    for i in 0..g.n_nodes() {
        match (g.support[i], c.support[i]) {
            (NodeSupport::Corner(a), NodeSupport::Corner(b)) => assert_eq!(a, b, "node {i}"),
            (NodeSupport::Curve { comp: a, t: s }, NodeSupport::Curve { comp: b, t }) => {
                assert_eq!(a, b, "node {i}");
                assert!((s - t).abs() <= 1e-9, "node {i}: t {s} vs {t}");
            }
            (NodeSupport::Surface { comp: a, uv: p }, NodeSupport::Surface { comp: b, uv: q }) => {
                assert_eq!(a, b, "node {i}");
                assert!(
                    (p[0] - q[0]).abs() <= 1e-9 && (p[1] - q[1]).abs() <= 1e-9,
                    "node {i}: {p:?} vs {q:?}"
                );
            }
            (a, b) => panic!("node {i}: {a:?} classified as {b:?}"),
        }
    }
}

/// The whole wing-body (poles at the nose, tail and tip cap ends, the wing's trailing edge
/// a seam inside one marker) written as SU2 and classified back.
#[test]
fn wing_body_parameters_recovered_from_su2() {
    let db = fixture("wing_body");
    let field = wing_body_field(&db, 0.15);
    let g = generate(&db, &field, &GenerateOptions::default()).unwrap();
    let m = su2_round_trip(&g.to_mesh(&db));
    assert!(m.classes.is_none());
    let (c, rep) = classify(&m, &db, &ClassifyOptions::default()).unwrap();
    eprintln!("{rep:?}");
    assert!(rep.max_distance < 1e-12 * db.reference_length());
    same_supports(&g, &c);
    // the classified grid is a valid grid tied to the geometry (pole copies included)
    check_grid(&db, &c, false);
    let (u, rep) = surfgrid::update(&c, &db, &db, &surfgrid::UpdateOptions::default()).unwrap();
    assert_eq!(rep.moved_nodes, 0);
    assert!(u.coords == c.coords);
}

/// The cylinder: the caps' centres (poles) and radial seams lie inside one marker.
#[test]
fn cylinder_parameters_recovered_from_su2() {
    let db = fixture("cylinder");
    let field = SizeField::uniform(0.2).unwrap();
    let g = generate(&db, &field, &GenerateOptions::default()).unwrap();
    let m = su2_round_trip(&g.to_mesh(&db));
    let (c, _) = classify(&m, &db, &ClassifyOptions::default()).unwrap();
    same_supports(&g, &c);
    check_grid(&db, &c, true);
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
    same_supports(&g, &c);
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
