//! The real SolidWorks export of the ONERA M6 wing with its far-field hemisphere.

use iges::{Entity, IgesFile};

fn m6() -> IgesFile {
    let path = crate::fixture("geom_oneram6.igs");
    let f = std::fs::File::open(&path).unwrap();
    iges::read(std::io::BufReader::new(f), "geom_oneram6.igs").unwrap()
}

#[test]
fn entity_counts_match_an_independent_count() {
    // Counted with awk over the odd directory lines (columns 1-8):
    // awk 'substr($0,73,1)=="D" { if ((substr($0,74)+0)%2==1) n[substr($0,1,8)+0]++ } ...'
    let f = m6();
    assert_eq!(
        f.type_counts(),
        vec![
            (100, 10),
            (102, 16),
            (110, 6),
            (120, 2),
            (124, 8),
            (126, 35),
            (128, 5),
            (142, 8),
            (144, 7),
            (314, 1),
        ]
    );
    assert!(f.warnings.is_empty(), "{:?}", f.warnings);
    assert!(
        f.iter()
            .all(|(_, r)| !matches!(r.entity, Entity::Unknown(_)))
    );
}

#[test]
fn global_section() {
    let f = m6();
    let g = &f.global;
    assert_eq!(g.sender_product_id, "geom_oneram6.SLDPRT");
    assert!(g.file_name.ends_with("geom_oneram6.IGS"), "{}", g.file_name);
    assert_eq!(g.file_name.len(), 95);
    assert_eq!(g.native_system_id, "SolidWorks 2013");
    // Units flag 6 with name "M": metres (the M6 semi-span is 1.1963 m).
    assert_eq!(g.units_flag, 6);
    assert_eq!(g.units_name, "M");
    assert_eq!(g.unit_in_mm(), Some(1000.0));
    assert_eq!(g.resolution, 1e-8);
    assert_eq!(g.max_coordinate, 499.99);
    assert_eq!(g.version, 11);
    assert!(f.start.starts_with("SolidWorks IGES file"));
}

#[test]
fn typed_entities_hold_the_file_values() {
    let f = m6();
    let at = |line: u32| {
        let id = iges::DeId::from_pointer(line as i64, f.entities.len()).unwrap();
        (id, &f.get(id).unwrap().entity)
    };
    // D7: "100,0.,0.201475,0.,11.201475,0.,-10.798525,0.;" with matrix D5.
    let (id, e) = at(7);
    let Entity::CircularArc(a) = e else {
        panic!("{e:?}")
    };
    assert_eq!(a.center, [0.201475, 0.0]);
    assert_eq!(a.start, [11.201475, 0.0]);
    assert_eq!(a.end, [-10.798525, 0.0]);
    assert_eq!(f.get(id).unwrap().de.transform.map(|t| t.line()), Some(5));
    // D9: "120,3,7,0.,6.28318530717959;"
    let (_, e) = at(9);
    let Entity::SurfaceOfRevolution(s) = e else {
        panic!("{e:?}")
    };
    assert_eq!((s.axis.line(), s.generatrix.line()), (3, 7));
    assert_eq!(s.end_angle, 6.28318530717959);
    // D103: "144,69,1,1,87,101;": one outer and one inner boundary.
    let (_, e) = at(103);
    let Entity::TrimmedSurface(t) = e else {
        panic!("{e:?}")
    };
    assert_eq!(t.surface.line(), 69);
    assert_eq!(t.outer.map(|o| o.line()), Some(87));
    assert_eq!(
        t.inner.iter().map(|i| i.line()).collect::<Vec<_>>(),
        vec![101]
    );
    // D105: the wing's 128, degree 3 x 3, K1 = 58 (59 control points in u).
    let (_, e) = at(105);
    let Entity::BSplineSurface(b) = e else {
        panic!("{e:?}")
    };
    assert_eq!((b.degree_u, b.degree_v, b.n_u), (3, 3, 59));
    assert_eq!(b.knots_u.len(), 59 + 3 + 1);
    assert_eq!(b.weights.len(), b.n_u * b.n_v);
    assert_eq!(b.control_points[0], [0.690684127, 1.1963, 0.0]);
    // D29: "142,1,9,25,27,1;"
    let (_, e) = at(29);
    let Entity::CurveOnSurface(c) = e else {
        panic!("{e:?}")
    };
    assert_eq!(c.surface.line(), 9);
    assert_eq!(c.param_curve.map(|p| p.line()), Some(25));
    assert_eq!(c.model_curve.map(|p| p.line()), Some(27));
}

#[test]
fn transformation_of_an_arc() {
    let f = m6();
    let id = iges::DeId::from_pointer(7, f.entities.len()).unwrap();
    let t = f.transform(id).unwrap().expect("D7 has a matrix");
    // D5 row 1: 1.40285071361946E-014, 1., -6.98296267768627E-015, 0.201474999999997.
    assert_eq!(t.rotation[0][1], 1.0);
    assert_eq!(t.translation[0], 0.201474999999997);
    // Rotation part is orthonormal.
    for i in 0..3 {
        for j in 0..3 {
            let dot: f64 = (0..3).map(|k| t.rotation[i][k] * t.rotation[j][k]).sum();
            testkit::assert_close!(dot, if i == j { 1.0 } else { 0.0 }, abs = 1e-12);
        }
    }
    // The arc's start point (11.201475, 0, 0) maps to the point at distance 11 from the
    // axis origin (0.201475, 0, 0) image.
    let c = t.apply_point([0.201475, 0.0, 0.0]);
    let p = t.apply_point([11.201475, 0.0, 0.0]);
    let r = ((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2) + (p[2] - c[2]).powi(2)).sqrt();
    testkit::assert_close!(r, 11.0, rel = 1e-12);
}

#[test]
fn write_then_read_gives_the_same_entities() {
    let f = m6();
    let mut out = Vec::new();
    f.write(&mut out, "m6.igs").unwrap();
    let g = iges::read(&out[..], "m6.igs").unwrap();
    assert_eq!(g.global, f.global);
    assert_eq!(g.start, f.start);
    assert_eq!(g.entities.len(), f.entities.len());
    for (a, b) in f.entities.iter().zip(&g.entities) {
        assert_eq!(a.de, b.de);
        assert_eq!(a.entity, b.entity);
        assert_eq!(a.extra, b.extra);
    }
    // Every written line is 80 columns.
    let text = String::from_utf8(out).unwrap();
    assert!(text.lines().all(|l| l.len() == 80));
}
