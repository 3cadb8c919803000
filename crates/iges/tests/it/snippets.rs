//! Hand-written snippets of each supported entity type, read and checked field by field.

use iges::{DeId, Entity};

use crate::{Snip, build};

fn snip(ty: i32, params: &str) -> Snip<'_> {
    Snip {
        ty,
        form: 0,
        transform: 0,
        params,
    }
}

fn read(snips: &[Snip]) -> iges::IgesFile {
    let text = build(snips);
    iges::read(text.as_bytes(), "snip.igs").unwrap_or_else(|e| panic!("{e}\n{text}"))
}

fn id(line: u32) -> DeId {
    DeId::from_pointer(line as i64, 1000).unwrap()
}

#[test]
fn curves() {
    let f = read(&[
        snip(100, "100,2.,0.,0.,1.,0.,-1.,0.;"),
        snip(102, "102,2,1,5;"),
        snip(110, "110,1.,0.,2.,-1.,0.,2.;"),
        snip(104, "104,1.,0.,4.,0.,0.,-4.,0.5,2.,0.,-2.,0.;"),
        snip(
            112,
            "112,3,2,3,1,0.,1.,2.,1.,2.,0.,0.,0.,1.,0.,-1.,5.,0.,0.,5.,5.,2.,0.,1.,2.,1.,0.,\
             4.,5.,0.,0.;",
        ),
        snip(
            126,
            "126,2,2,1,0,0,0,0.,0.,0.,1.,1.,1.,1.,0.70710678118654757,1.,1.,0.,0.,1.,1.,0.,\
             0.,1.,0.,0.,1.,0.,0.,1.;",
        ),
        snip(116, "116,1.5,-2.5,3.D1;"),
    ]);
    let Entity::CircularArc(a) = &f.get(id(1)).unwrap().entity else {
        panic!()
    };
    assert_eq!(
        (a.z, a.center, a.start, a.end),
        (2.0, [0.0, 0.0], [1.0, 0.0], [-1.0, 0.0])
    );
    let Entity::CompositeCurve(c) = &f.get(id(3)).unwrap().entity else {
        panic!()
    };
    assert_eq!(c.curves, vec![id(1), id(5)]);
    let Entity::Line(l) = &f.get(id(5)).unwrap().entity else {
        panic!()
    };
    assert_eq!((l.start, l.end), ([1.0, 0.0, 2.0], [-1.0, 0.0, 2.0]));
    let Entity::ConicArc(c) = &f.get(id(7)).unwrap().entity else {
        panic!()
    };
    assert_eq!(c.coefficients, [1.0, 0.0, 4.0, 0.0, 0.0, -4.0]);
    assert_eq!((c.z, c.start, c.end), (0.5, [2.0, 0.0], [-2.0, 0.0]));
    let Entity::SplineCurve(s) = &f.get(id(9)).unwrap().entity else {
        panic!()
    };
    assert_eq!((s.spline_type, s.continuity, s.dimension), (3, 2, 3));
    assert_eq!(s.breakpoints, vec![0.0, 1.0]);
    assert_eq!(
        s.segments[0],
        [
            [2.0, 1.0, 2.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
            [-1.0, 5.0, 0.0, 0.0]
        ]
    );
    assert_eq!(s.terminal[0], [5.0, 5.0, 2.0, 0.0]);
    assert_eq!(s.terminal[2], [4.0, 5.0, 0.0, 0.0]);
    let Entity::BSplineCurve(b) = &f.get(id(11)).unwrap().entity else {
        panic!()
    };
    assert_eq!(b.degree, 2);
    assert!(b.planar && !b.closed && !b.polynomial && !b.periodic);
    assert_eq!(b.knots, vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0]);
    assert_eq!(b.weights, vec![1.0, 0.70710678118654757, 1.0]);
    assert_eq!(
        b.control_points,
        vec![[1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]]
    );
    assert_eq!((b.range, b.normal), ([0.0, 1.0], Some([0.0, 0.0, 1.0])));
    let Entity::Point(p) = &f.get(id(13)).unwrap().entity else {
        panic!()
    };
    assert_eq!((p.point, p.symbol), ([1.5, -2.5, 30.0], None));
}

#[test]
fn surfaces() {
    // A 114 with one bilinear patch x = s, y = t, z = s t, written with the 48 x 3
    // arbitrary closing values of the specification.
    let mut p114 = String::from("114,1,1,1,1,0.,1.,0.,2.,");
    let mut coef = vec![0.0; 48];
    coef[1] = 1.0; // x: B (s)
    coef[16 + 4] = 1.0; // y: E (t)
    coef[32 + 5] = 1.0; // z: F (t s)
    for c in coef.iter().chain(std::iter::repeat_n(&0.0, 48 * 3)) {
        p114 += &format!("{c:?},");
    }
    p114.pop();
    p114.push(';');
    let f = read(&[
        snip(110, "110,0.,0.,0.,0.,0.,1.;"),
        snip(110, "110,1.,0.,0.,1.,0.,1.;"),
        snip(118, "118,1,3,1,0;"),
        snip(120, "120,1,3,0.,3.14159;"),
        snip(122, "122,3,0.,5.,0.;"),
        snip(
            128,
            "128,1,1,1,1,0,0,1,0,0,0.,0.,1.,1.,0.,0.,1.,1.,1.,1.,1.,1.,0.,0.,0.,1.,0.,0.,\
             0.,1.,0.,1.,1.,1.,0.,1.,0.,1.;",
        ),
        snip(114, &p114),
    ]);
    let Entity::RuledSurface(r) = &f.get(id(5)).unwrap().entity else {
        panic!()
    };
    assert_eq!(
        (r.curve1, r.curve2, r.reversed, r.developable),
        (id(1), id(3), true, false)
    );
    let Entity::SurfaceOfRevolution(s) = &f.get(id(7)).unwrap().entity else {
        panic!()
    };
    assert_eq!(
        (s.axis, s.generatrix, s.start_angle, s.end_angle),
        (id(1), id(3), 0.0, 3.14159)
    );
    let Entity::TabulatedCylinder(t) = &f.get(id(9)).unwrap().entity else {
        panic!()
    };
    assert_eq!((t.directrix, t.end), (id(3), [0.0, 5.0, 0.0]));
    let Entity::BSplineSurface(b) = &f.get(id(11)).unwrap().entity else {
        panic!()
    };
    assert_eq!((b.n_u, b.n_v, b.degree_u, b.degree_v), (2, 2, 1, 1));
    assert!(b.polynomial);
    assert_eq!(b.control_point(1, 0), [1.0, 0.0, 0.0]);
    assert_eq!(b.control_point(0, 1), [0.0, 1.0, 0.0]);
    assert_eq!(b.control_point(1, 1), [1.0, 1.0, 1.0]);
    assert_eq!((b.u_range, b.v_range), ([0.0, 1.0], [0.0, 1.0]));
    let Entity::SplineSurface(s) = &f.get(id(13)).unwrap().entity else {
        panic!()
    };
    assert_eq!(s.n_patches(), (1, 1));
    assert_eq!(
        (s.u_breaks.clone(), s.v_breaks.clone()),
        (vec![0.0, 1.0], vec![0.0, 2.0])
    );
    let p = s.patch(0, 0);
    assert_eq!((p[0][1], p[1][4], p[2][5]), (1.0, 1.0, 1.0));
    assert_eq!(p.iter().flatten().filter(|&&c| c != 0.0).count(), 3);
}

#[test]
fn trims_and_transforms() {
    let f = read(&[
        snip(
            128,
            "128,1,1,1,1,0,0,1,0,0,0.,0.,1.,1.,0.,0.,1.,1.,1.,1.,1.,1.,0.,0.,0.,1.,0.,0.,0.,1.,0.,1.,1.,0.,0.,1.,0.,1.;",
        ),
        snip(110, "110,0.,0.,0.,1.,1.,0.;"),
        snip(110, "110,0.,0.,0.,1.,1.,0.;"),
        snip(142, "142,0,1,3,5,2;"),
        snip(144, "144,1,1,1,7,7;"),
        snip(141, "141,1,1,1,2,5,2,1,3,5,1,0;"),
        snip(143, "143,1,1,1,11;"),
        snip(124, "124,0.,-1.,0.,10.,1.,0.,0.,20.,0.,0.,1.,30.;"),
        Snip {
            ty: 124,
            form: 0,
            transform: 15,
            params: "124,2.,0.,0.,0.,0.,2.,0.,0.,0.,0.,2.,0.;",
        },
        Snip {
            ty: 110,
            form: 0,
            transform: 17,
            params: "110,1.,0.,0.,0.,1.,0.;",
        },
        snip(314, "314,100.,50.,0.,6HOrange;"),
        snip(406, "406,2,1,3HABC;"),
    ]);
    let Entity::CurveOnSurface(c) = &f.get(id(7)).unwrap().entity else {
        panic!()
    };
    assert_eq!(
        (
            c.creation,
            c.surface,
            c.param_curve,
            c.model_curve,
            c.preferred
        ),
        (0, id(1), Some(id(3)), Some(id(5)), 2)
    );
    let Entity::TrimmedSurface(t) = &f.get(id(9)).unwrap().entity else {
        panic!()
    };
    assert_eq!(
        (t.surface, t.outer, t.inner.clone()),
        (id(1), Some(id(7)), vec![id(7)])
    );
    let Entity::Boundary(b) = &f.get(id(11)).unwrap().entity else {
        panic!()
    };
    assert_eq!((b.kind, b.preferred, b.surface), (1, 1, id(1)));
    assert_eq!(b.curves.len(), 2);
    assert_eq!(
        (
            b.curves[0].model_curve,
            b.curves[0].reversed,
            b.curves[0].param_curves.clone()
        ),
        (id(5), true, vec![id(3)])
    );
    assert_eq!(
        (b.curves[1].reversed, b.curves[1].param_curves.len()),
        (false, 0)
    );
    let Entity::BoundedSurface(s) = &f.get(id(13)).unwrap().entity else {
        panic!()
    };
    assert_eq!(
        (s.kind, s.surface, s.boundaries.clone()),
        (1, id(1), vec![id(11)])
    );
    // The line D19 is transformed by D17 (scale 2) then D15 (rotation about z by 90
    // degrees, translation (10, 20, 30)).
    let t = f.transform(id(19)).unwrap().unwrap();
    assert_eq!(t.apply_point([1.0, 0.0, 0.0]), [10.0, 22.0, 30.0]);
    assert_eq!(t.apply_point([0.0, 1.0, 0.0]), [8.0, 20.0, 30.0]);
    assert!(f.transform(id(1)).unwrap().is_none());
    let Entity::ColorDefinition(c) = &f.get(id(21)).unwrap().entity else {
        panic!()
    };
    assert_eq!(
        (c.rgb, c.name.as_deref()),
        ([100.0, 50.0, 0.0], Some("Orange"))
    );
    // The unknown 406 is kept raw and listed.
    let Entity::Unknown(p) = &f.get(id(23)).unwrap().entity else {
        panic!()
    };
    assert_eq!(p.len(), 3);
    assert_eq!(f.warnings.len(), 1);
    assert_eq!(f.warnings[0].de, id(23));
    assert!(
        f.warnings[0].to_string().contains("type 406"),
        "{}",
        f.warnings[0]
    );
}

#[test]
fn brep() {
    let f = read(&[
        snip(502, "502,3,0.,0.,0.,1.,0.,0.,0.,1.,0.;"),
        snip(110, "110,0.,0.,0.,1.,0.,0.;"),
        snip(110, "110,1.,0.,0.,0.,1.,0.;"),
        snip(110, "110,0.,1.,0.,0.,0.,0.;"),
        snip(504, "504,3,3,1,1,1,2,5,1,2,1,3,7,1,3,1,1;"),
        snip(508, "508,3,0,9,1,1,0,0,9,2,1,1,0,3,0,9,3,0,0;"),
        snip(108, "108,0.,0.,1.,0.,0,0.,0.,0.,0.;"),
        snip(510, "510,13,1,1,11;"),
        snip(514, "514,1,15,1;"),
        snip(186, "186,17,1,0;"),
    ]);
    let Entity::VertexList(v) = &f.get(id(1)).unwrap().entity else {
        panic!()
    };
    assert_eq!(v.vertices, vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
    let Entity::EdgeList(e) = &f.get(id(9)).unwrap().entity else {
        panic!()
    };
    assert_eq!(e.edges.len(), 3);
    assert_eq!(
        (
            e.edges[1].curve,
            e.edges[1].start_list,
            e.edges[1].start_index,
            e.edges[1].end_index
        ),
        (id(5), id(1), 2, 3)
    );
    let Entity::Loop(l) = &f.get(id(11)).unwrap().entity else {
        panic!()
    };
    assert_eq!(l.edges.len(), 3);
    assert_eq!(
        (
            l.edges[1].index,
            l.edges[1].agrees,
            l.edges[1].param_curves.clone()
        ),
        (2, true, vec![(false, id(3))])
    );
    assert!(!l.edges[2].agrees);
    let Entity::Face(fc) = &f.get(id(15)).unwrap().entity else {
        panic!()
    };
    assert_eq!(
        (fc.surface, fc.outer_loop_first, fc.loops.clone()),
        (id(13), true, vec![id(11)])
    );
    let Entity::Shell(s) = &f.get(id(17)).unwrap().entity else {
        panic!()
    };
    assert_eq!(s.faces, vec![(id(15), true)]);
    let Entity::ManifoldSolid(m) = &f.get(id(19)).unwrap().entity else {
        panic!()
    };
    assert_eq!((m.shell, m.shell_agrees, m.voids.len()), (id(17), true, 0));
    let Entity::Plane(p) = &f.get(id(13)).unwrap().entity else {
        panic!()
    };
    assert_eq!((p.coefficients, p.boundary), ([0.0, 0.0, 1.0, 0.0], None));
    assert!(f.warnings.is_empty());
}

fn snip_form(ty: i32, form: i32, params: &str) -> Snip<'_> {
    Snip {
        ty,
        form,
        transform: 0,
        params,
    }
}

/// The analytic surfaces 190–198 as OpenCASCADE writes them (form 1, parameters copied
/// from its B-rep output), and a form-0 sphere without axis.
#[test]
fn analytic_surfaces() {
    let f = read(&[
        snip(116, "116,0.,0.,2.,0;"),
        snip(123, "123,0.,0.,1.;"),
        snip(123, "123,1.,0.,-0.;"),
        snip_form(190, 1, "190,1,3,5;"),
        snip_form(192, 1, "192,1,3,1.5,5;"),
        snip_form(194, 1, "194,1,3,3.,26.565051177,5;"),
        snip_form(196, 1, "196,1,2.5,3,5;"),
        snip_form(198, 1, "198,1,3,3.,0.5,5;"),
        snip(196, "196,1,4.;"),
        snip(192, "192,1,3,2.;"),
    ]);
    let get = |k: u32| &f.get(id(k)).unwrap().entity;
    let Entity::Point(p) = get(1) else { panic!() };
    assert_eq!(p.point, [0.0, 0.0, 2.0]);
    let Entity::Direction(d) = get(5) else {
        panic!()
    };
    assert_eq!(d.direction, [1.0, 0.0, -0.0]);
    let Entity::PlaneSurface(s) = get(7) else {
        panic!()
    };
    assert_eq!(
        (s.location, s.normal, s.refdir),
        (id(1), id(3), Some(id(5)))
    );
    let Entity::CylindricalSurface(s) = get(9) else {
        panic!()
    };
    assert_eq!(
        (s.location, s.axis, s.radius, s.refdir),
        (id(1), id(3), 1.5, Some(id(5)))
    );
    let Entity::ConicalSurface(s) = get(11) else {
        panic!()
    };
    assert_eq!(
        (s.location, s.axis, s.radius, s.semi_angle, s.refdir),
        (id(1), id(3), 3.0, 26.565051177, Some(id(5)))
    );
    let Entity::SphericalSurface(s) = get(13) else {
        panic!()
    };
    assert_eq!(
        (s.center, s.radius, s.axis, s.refdir),
        (id(1), 2.5, Some(id(3)), Some(id(5)))
    );
    let Entity::ToroidalSurface(s) = get(15) else {
        panic!()
    };
    assert_eq!(
        (s.center, s.axis, s.major, s.minor, s.refdir),
        (id(1), id(3), 3.0, 0.5, Some(id(5)))
    );
    let Entity::SphericalSurface(s) = get(17) else {
        panic!()
    };
    assert_eq!(
        (s.center, s.radius, s.axis, s.refdir),
        (id(1), 4.0, None, None)
    );
    let Entity::CylindricalSurface(s) = get(19) else {
        panic!()
    };
    assert_eq!((s.radius, s.refdir), (2.0, None));
    assert!(f.warnings.is_empty());
    // Every pointer is listed.
    assert_eq!(get(15).pointers(), vec![id(1), id(3), id(5)]);
}

/// 106 in its three layouts, 108 bounded, 130 and 140.
#[test]
fn copious_data_plane_and_offsets() {
    let f = read(&[
        snip_form(106, 11, "106,1,3,0.5,0.,0.,1.,0.,1.,1.;"),
        snip_form(106, 12, "106,2,2,0.,0.,0.,1.,2.,3.;"),
        snip_form(106, 13, "106,3,2,0.,0.,0.,0.,0.,1.,1.,2.,3.,1.,0.,0.;"),
        snip_form(108, 1, "108,0.,0.,1.,0.5,1,0.,0.,0.5,1.;"),
        snip(130, "130,1,1,0,0,0,0.25,0.,0.,0.,0.,0.,1.,0.,1.;"),
        snip(140, "140,0.,0.,1.,0.1,7;"),
    ]);
    let get = |k: u32| &f.get(id(k)).unwrap().entity;
    let Entity::CopiousData(c) = get(1) else {
        panic!()
    };
    assert_eq!((c.ip, c.z), (1, 0.5));
    assert_eq!(
        c.points,
        vec![[0.0, 0.0, 0.5], [1.0, 0.0, 0.5], [1.0, 1.0, 0.5]]
    );
    let Entity::CopiousData(c) = get(3) else {
        panic!()
    };
    assert_eq!(c.points, vec![[0.0; 3], [1.0, 2.0, 3.0]]);
    let Entity::CopiousData(c) = get(5) else {
        panic!()
    };
    assert_eq!(c.points, vec![[0.0; 3], [1.0, 2.0, 3.0]]);
    assert_eq!(c.vectors, vec![[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]);
    let Entity::Plane(p) = get(7) else { panic!() };
    assert_eq!(
        (p.coefficients, p.boundary, p.symbol_size),
        ([0.0, 0.0, 1.0, 0.5], Some(id(1)), 1.0)
    );
    let Entity::OffsetCurve(o) = get(9) else {
        panic!()
    };
    assert_eq!(
        (o.base, o.flag, o.function, o.d1, o.normal, o.range),
        (id(1), 1, None, 0.25, [0.0, 0.0, 1.0], [0.0, 1.0])
    );
    let Entity::OffsetSurface(o) = get(11) else {
        panic!()
    };
    assert_eq!(
        (o.indicator, o.distance, o.surface),
        ([0.0, 0.0, 1.0], 0.1, id(7))
    );
    assert!(f.warnings.is_empty());
    // An interpretation flag out of range names its parameter.
    let text = crate::build(&[snip(106, "106,4,1,0.;")]);
    let e = iges::read(text.as_bytes(), "c.igs")
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        "c.igs: entity at D line 1 (type 106): parameter 1: expected 1, 2 or 3 (IP), found '4'"
    );
}

#[test]
fn errors_name_the_directory_line() {
    let err = |snips: &[Snip]| {
        iges::read(build(snips).as_bytes(), "geom.igs")
            .unwrap_err()
            .to_string()
    };
    let e = err(&[
        snip(110, "110,0.,0.,0.,1.,0.,0.;"),
        snip(128, "128,1,1,1,1,0,0,1,0,0,0.,0.,1.,1.,0.,0.,x,1.;"),
    ]);
    assert_eq!(
        e,
        "geom.igs: entity at D line 3 (type 128): parameter 16: expected a number, found 'x'"
    );
    let e = err(&[snip(102, "102,2,1,9;")]);
    assert!(
        e.starts_with("geom.igs: entity at D line 1 (type 102): parameter 3: pointer 9"),
        "{e}"
    );
    let e = err(&[snip(102, "102,5,1;")]);
    assert!(
        e.contains("D line 1 (type 102): parameter 1: N (number of curves) = 5 is invalid"),
        "{e}"
    );
    let e = err(&[snip(126, "126,1000000000,3,0,0,0,0,0.,1.;")]);
    assert!(
        e.contains("D line 1 (type 126): parameter 1: K (upper index of sum)"),
        "{e}"
    );
    let e = err(&[snip(110, "110,0.,0.,0.,1.,0.;")]);
    assert!(
        e.contains("D line 1 (type 110): parameter 6: missing"),
        "{e}"
    );
    let e = err(&[snip(144, "144,1,1,0,3HABC;")]);
    assert!(e.contains("parameter 4: expected an integer"), "{e}");
    let e = err(&[Snip {
        ty: 110,
        form: 0,
        transform: 1,
        params: "110,0.,0.,0.,1.,0.,0.;",
    }]);
    assert!(e.contains("D line 1 (type 110): directory field 7"), "{e}");
    let e = err(&[snip(110, "110,0.,0.,0.,1.,0.,0.")]);
    assert!(
        e.contains("D line 1 (type 110): parameter data at P line 1"),
        "{e}"
    );
    assert!(e.contains("truncated"), "{e}");
    assert!(!e.contains('\n'));
}
