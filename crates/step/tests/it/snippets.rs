//! Hand-written instances of the supported types, checked field by field.

use step::{ConicKind, ElementaryKind, Entity, Id, Trim, UnitKind};

use crate::wrap;

fn parse(data: &str) -> step::StepFile {
    let text = wrap(data);
    step::parse(text.as_bytes(), "s.stp").unwrap_or_else(|e| panic!("{e}\n{text}"))
}

fn get(f: &step::StepFile, id: u64) -> &Entity {
    f.entity(Id(id)).unwrap()
}

#[test]
fn inch_and_degree_units() {
    let f = parse(
        "#1 = ( LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT(.MILLI.,.METRE.) );\n\
         #2 = LENGTH_MEASURE_WITH_UNIT(LENGTH_MEASURE(25.4),#1);\n\
         #3 = DIMENSIONAL_EXPONENTS(1.,0.,0.,0.,0.,0.,0.);\n\
         #4 = ( CONVERSION_BASED_UNIT('INCH',#2) LENGTH_UNIT() NAMED_UNIT(#3) );\n\
         #5 = ( NAMED_UNIT(*) PLANE_ANGLE_UNIT() SI_UNIT($,.RADIAN.) );\n\
         #6 = PLANE_ANGLE_MEASURE_WITH_UNIT(PLANE_ANGLE_MEASURE(0.0174532925199),#5);\n\
         #7 = ( CONVERSION_BASED_UNIT('DEGREE',#6) NAMED_UNIT(#3) PLANE_ANGLE_UNIT() );\n\
         #8 = UNCERTAINTY_MEASURE_WITH_UNIT(LENGTH_MEASURE(1.E-05),#4,'distance_accuracy_value','');\n\
         #9 = ( GEOMETRIC_REPRESENTATION_CONTEXT(3) GLOBAL_UNCERTAINTY_ASSIGNED_CONTEXT((#8)) \
         GLOBAL_UNIT_ASSIGNED_CONTEXT((#4,#7)) REPRESENTATION_CONTEXT('',''));",
    );
    let Entity::NamedUnit(u) = get(&f, 4) else {
        panic!()
    };
    assert_eq!(u.kind, UnitKind::Length);
    let (k, m) = f.unit_factor(Id(9), Id(4)).unwrap();
    assert_eq!(k, UnitKind::Length);
    assert!((m - 0.0254).abs() < 1e-15);
    let units = f.units(Id(9)).unwrap();
    assert_eq!(units.length_name.as_deref(), Some("in"));
    assert!((units.plane_angle.unwrap() - std::f64::consts::PI / 180.0).abs() < 1e-12);
    assert!((units.uncertainty.unwrap() - 1e-5).abs() < 1e-18);
    let Entity::Context(c) = get(&f, 9) else {
        panic!()
    };
    assert_eq!(
        (c.dimension, c.units.clone()),
        (Some(3), vec![Id(4), Id(7)])
    );
}

#[test]
fn geometry_and_topology() {
    let f = parse(
        "#1 = CARTESIAN_POINT('',(0.,0.,0.));\n\
         #2 = DIRECTION('',(0.,0.,1.));\n\
         #3 = DIRECTION('',(1.,0.,0.));\n\
         #4 = AXIS2_PLACEMENT_3D('',#1,#2,#3);\n\
         #5 = ELLIPSE('',#4,3.,2.);\n\
         #6 = VECTOR('',#3,2.5);\n\
         #7 = LINE('',#1,#6);\n\
         #8 = TRIMMED_CURVE('',#7,(PARAMETER_VALUE(0.),#1),(PARAMETER_VALUE(1.)),.T.,.PARAMETER.);\n\
         #9 = TOROIDAL_SURFACE('',#4,5.,1.);\n\
         #10 = CONICAL_SURFACE('',#4,2.,0.5);\n\
         #11 = B_SPLINE_CURVE_WITH_KNOTS('',2,(#1,#1,#1),.UNSPECIFIED.,.F.,.U.,(3,3),(0.,1.),.UNSPECIFIED.);\n\
         #12 = VERTEX_POINT('',#1);\n\
         #13 = EDGE_CURVE('',#12,#12,#5,.T.);\n\
         #14 = ORIENTED_EDGE('',*,*,#13,.F.);\n\
         #15 = EDGE_LOOP('',(#14));\n\
         #16 = FACE_OUTER_BOUND('',#15,.T.);\n\
         #17 = ADVANCED_FACE('',(#16),#9,.F.);\n\
         #18 = OPEN_SHELL('',(#17));\n\
         #19 = SHELL_BASED_SURFACE_MODEL('',(#18));\n\
         #20 = AXIS1_PLACEMENT('',#1,#2);\n\
         #21 = SURFACE_OF_REVOLUTION('',#5,#20);\n\
         #22 = SURFACE_OF_LINEAR_EXTRUSION('',#11,#6);\n\
         #23 = OFFSET_SURFACE('',#21,0.25,.F.);\n\
         #24 = POLYLINE('',(#1,#1));\n\
         #25 = CLOSED_SHELL('',(#17));\n\
         #26 = MANIFOLD_SOLID_BREP('',#25);\n\
         #27 = ( BOUNDED_CURVE() B_SPLINE_CURVE(1,(#1,#1),.POLYLINE_FORM.,.F.,.F.) \
         B_SPLINE_CURVE_WITH_KNOTS((2,2),(0.,2.),.UNSPECIFIED.) CURVE() \
         GEOMETRIC_REPRESENTATION_ITEM() RATIONAL_B_SPLINE_CURVE((1.,2.)) REPRESENTATION_ITEM('') );",
    );
    let Entity::Conic(c) = get(&f, 5) else {
        panic!()
    };
    assert_eq!(
        (c.kind, c.position, c.a, c.b),
        (ConicKind::Ellipse, Id(4), 3.0, 2.0)
    );
    let Entity::Vector(v) = get(&f, 6) else {
        panic!()
    };
    assert_eq!((v.orientation, v.magnitude), (Id(3), 2.5));
    let Entity::TrimmedCurve(t) = get(&f, 8) else {
        panic!()
    };
    assert_eq!(t.trim1, vec![Trim::Parameter(0.0), Trim::Point(Id(1))]);
    assert_eq!(t.trim2, vec![Trim::Parameter(1.0)]);
    assert!(t.sense);
    assert_eq!(t.master, "PARAMETER");
    let Entity::Elementary(s) = get(&f, 9) else {
        panic!()
    };
    assert_eq!(
        (s.kind, s.radius, s.second),
        (ElementaryKind::Torus, 5.0, 1.0)
    );
    let Entity::Elementary(s) = get(&f, 10) else {
        panic!()
    };
    assert_eq!(
        (s.kind, s.radius, s.second),
        (ElementaryKind::Cone, 2.0, 0.5)
    );
    let Entity::BSplineCurve(b) = get(&f, 11) else {
        panic!()
    };
    assert_eq!(
        (b.degree, b.closed, b.weights.clone()),
        (2, Some(false), None)
    );
    assert_eq!(
        (b.knots.clone(), b.multiplicities.clone()),
        (vec![0.0, 1.0], vec![3, 3])
    );
    let Entity::EdgeCurve(e) = get(&f, 13) else {
        panic!()
    };
    assert_eq!(
        (e.start, e.end, e.curve, e.same_sense),
        (Id(12), Id(12), Id(5), true)
    );
    let Entity::OrientedEdge(o) = get(&f, 14) else {
        panic!()
    };
    assert_eq!((o.edge, o.orientation), (Id(13), false));
    let Entity::FaceBound(b) = get(&f, 16) else {
        panic!()
    };
    assert!(b.outer && b.orientation);
    let Entity::Face(fc) = get(&f, 17) else {
        panic!()
    };
    assert_eq!(
        (fc.bounds.clone(), fc.surface, fc.same_sense),
        (vec![Id(16)], Id(9), false)
    );
    let Entity::Shell(s) = get(&f, 18) else {
        panic!()
    };
    assert!(!s.closed);
    let Entity::ShellBasedSurfaceModel(m) = get(&f, 19) else {
        panic!()
    };
    assert_eq!(m.shells, vec![Id(18)]);
    let Entity::SurfaceOfRevolution(r) = get(&f, 21) else {
        panic!()
    };
    assert_eq!((r.curve, r.axis), (Id(5), Id(20)));
    let Entity::SurfaceOfLinearExtrusion(x) = get(&f, 22) else {
        panic!()
    };
    assert_eq!((x.curve, x.direction), (Id(11), Id(6)));
    let Entity::OffsetSurface(o) = get(&f, 23) else {
        panic!()
    };
    assert_eq!((o.surface, o.distance), (Id(21), 0.25));
    let Entity::ManifoldSolidBrep(s) = get(&f, 26) else {
        panic!()
    };
    assert_eq!((s.outer, s.voids.len()), (Id(25), 0));
    let Entity::BSplineCurve(b) = get(&f, 27) else {
        panic!()
    };
    assert_eq!((b.degree, b.weights.clone()), (1, Some(vec![1.0, 2.0])));
    // Lookups check types and name the referring instance.
    let e = f.point(Id(17), Id(9), "vertex").unwrap_err().to_string();
    assert_eq!(
        e,
        "s.stp: #17 (line 23, ADVANCED_FACE): parameter 0 (vertex): #9 is a TOROIDAL_SURFACE, \
         expected CARTESIAN_POINT"
    );
}

#[test]
fn errors_name_the_instance() {
    let err = |data: &str| {
        step::parse(wrap(data).as_bytes(), "e.stp")
            .unwrap_err()
            .to_string()
    };
    assert_eq!(
        err("#1 = CARTESIAN_POINT('',(0.,0.,0.));\n#2 = VERTEX_POINT('',#3);"),
        "e.stp: #2 (line 8, VERTEX_POINT): parameter 2 (reference): #3 names no instance of the file"
    );
    assert_eq!(
        err("#1 = CARTESIAN_POINT('',(0.,0.,0.));\n#1 = CARTESIAN_POINT('',(0.,0.,0.));"),
        "e.stp: #1 (line 8, CARTESIAN_POINT): the name is also used at line 7"
    );
    assert_eq!(
        err("#1 = EDGE_LOOP('');"),
        "e.stp: #1 (line 7, EDGE_LOOP): EDGE_LOOP has 1 parameters, 2 expected"
    );
    assert_eq!(
        err("#1 = CARTESIAN_POINT('',(0.,0.,0.));\n\
             #2 = B_SPLINE_CURVE_WITH_KNOTS('',2,(#1,#1,#1),.UNSPECIFIED.,.F.,.U.,(3,2),(0.,1.),.UNSPECIFIED.);"),
        "e.stp: #2 (line 8, B_SPLINE_CURVE_WITH_KNOTS): knots: the multiplicities add up to 5, \
         but 3 control points of degree 2 need 6"
    );
    assert_eq!(
        err("#1 = ( B_SPLINE_CURVE_WITH_KNOTS((2,2),(0.,2.),.UNSPECIFIED.) CURVE() );"),
        "e.stp: #1 (line 7, (B_SPLINE_CURVE_WITH_KNOTS CURVE)): complex instance lacks B_SPLINE_CURVE"
    );
    assert_eq!(
        err("#1 = ( B_SPLINE_CURVE(1,(#1,#1),.POLYLINE_FORM.,.F.,.F.) \
             B_SPLINE_CURVE_WITH_KNOTS((2,x),(0.,2.),.UNSPECIFIED.) );")
        .rsplit(": ")
        .next()
        .unwrap(),
        "expected '(', found '),(0.,2.),.U'"
    );
    assert_eq!(
        err("#1 = ( B_SPLINE_CURVE(1,(#1,#1),.POLYLINE_FORM.,.F.,.F.) \
             B_SPLINE_CURVE_WITH_KNOTS((2,2.5),(0.,2.),.UNSPECIFIED.) );"),
        "e.stp: #1 (line 7, (B_SPLINE_CURVE B_SPLINE_CURVE_WITH_KNOTS)): parameter 1 \
         (knot_multiplicities) of B_SPLINE_CURVE_WITH_KNOTS: item 2: expected an integer ≥ 0, found 2.5"
    );
}
