//! The wing master (issue 7 item 6) on the wing of `fixtures/geom/wing_body.ron`: identity at
//! zero deviation, analytic twist, sweep and span, Tmax measured on the regenerated section,
//! the exact Jacobian against differences, and the model update through `param` and
//! `intersect` with the junction re-intersected.

use std::path::PathBuf;
use std::sync::Arc;

use geom_db::eval::{ParamCurve, ParamSurface};
use geom_db::prelude::{Point3, Vector3};
use geom_db::{GeomDb, SurfaceId};
use param::{
    DesignVariable, Links, MasterModifier, MasterSource, MasterSources, MasterSpec, Modifier,
    Parametrisation,
};
use wingmaster::{WingMaster, WingMasterSpec};

pub fn wing_body() -> GeomDb {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/geom/wing_body.ron");
    let text = std::fs::read_to_string(&p).unwrap();
    GeomDb::from_ron_str(&text, &p.display().to_string()).unwrap()
}

/// The spec used by the tests: root and tip key sections of the wing surface.
pub const SPEC: &str = r#"(
    surface: 1,
    spanwise: V,
    n_s: 121,
    n_t: 11,
    planform: (sweep: "sweep", dihedral: "dihedral", span: "span"),
    key_sections: [
        (t: 0.0, twist: "root_twist", thickness: {"tmax": "root_tmax"}),
        (t: 1.0, twist: "tip_twist", chord: "tip_chord", shift: (None, None, "tip_dz"),
         thickness: {"tmax": "tip_tmax", "xtmax": "tip_xtmax"}, camber: {3: "tip_camber3"}),
    ],
)"#;

pub fn spec() -> WingMasterSpec {
    WingMasterSpec::from_ron_str(SPEC, "SPEC").unwrap()
}

pub fn names() -> Vec<String> {
    spec().variable_names()
}

pub fn bind(db: &GeomDb) -> WingMaster {
    let n = names();
    spec().bind(db, &n, &vec![0.0; n.len()]).unwrap()
}

pub fn x_with(pairs: &[(&str, f64)]) -> Vec<f64> {
    let n = names();
    let mut x = vec![0.0; n.len()];
    for (k, v) in pairs {
        x[n.iter().position(|m| m == k).unwrap()] = *v;
    }
    x
}

const TIP: usize = 10;

fn bits(p: &[Point3]) -> Vec<[u64; 3]> {
    p.iter()
        .map(|q| [q.x.to_bits(), q.y.to_bits(), q.z.to_bits()])
        .collect()
}

fn station(g: &param::MasterGrid, j: usize) -> &[Point3] {
    &g.points[j * g.n_s..(j + 1) * g.n_s]
}

fn rot_y(theta: f64, v: Vector3) -> Vector3 {
    nalgebra::Rotation3::from_axis_angle(&Vector3::y_axis(), theta) * v
}

/// The parametrisation: one master modifier on the wing and its tip cap.
fn parametrisation() -> Parametrisation {
    Parametrisation {
        modifiers: vec![Modifier::Master(MasterModifier {
            name: "wing".into(),
            links: Links {
                surfaces: vec![SurfaceId(1), SurfaceId(2)],
                ..Links::default()
            },
            source: MasterSpec::External("wing".into()),
            variables: names()
                .iter()
                .map(|n| DesignVariable::new(n, -1.0, 1.0))
                .collect(),
        })],
        constraints: vec![],
    }
}

fn sources(wm: WingMaster) -> MasterSources {
    let mut m = MasterSources::new();
    m.insert("wing".into(), Arc::new(wm) as Arc<dyn MasterSource>);
    m
}

/// The control nodes of surface 1 at the tip (v = 1) with their u.
fn tip_nodes(db: &GeomDb) -> Vec<(usize, f64)> {
    let s = db.surface(SurfaceId(1));
    let mut out: Vec<(usize, f64)> = Vec::new();
    for (pi, (ids, p)) in s.control.nodes.iter().zip(&s.patches).enumerate() {
        let xu = geom_db::control::nodes(p.deg_u);
        let xv = geom_db::control::nodes(p.deg_v);
        for (a, &x) in xu.iter().enumerate() {
            for (b, &y) in xv.iter().enumerate() {
                let id = ids[a * xv.len() + b].index();
                if y == 1.0 && !out.iter().any(|o| o.0 == id) {
                    out.push((id, (pi % s.n_u) as f64 + x));
                }
            }
        }
    }
    out
}

/// Distance from p to the polyline.
fn polyline_distance(line: &[Point3], p: Point3) -> f64 {
    line.windows(2)
        .map(|w| {
            let d = w[1] - w[0];
            let t = ((p - w[0]).dot(&d) / d.norm_squared()).clamp(0.0, 1.0);
            (w[0] + d * t - p).norm()
        })
        .fold(f64::INFINITY, f64::min)
}

/// Maximum thickness of a section given by its points (Selig-like loop), measured normal to
/// the chord in the frame (x̂, ẑ): both surfaces interpolated linearly on 2001 abscissae.
fn max_thickness(pts: &[Point3], le: Point3, x: Vector3, z: Vector3) -> f64 {
    let xz: Vec<[f64; 2]> = pts
        .iter()
        .map(|p| [(p - le).dot(&x), (p - le).dot(&z)])
        .collect();
    let ile = (0..xz.len())
        .min_by(|&a, &b| xz[a][0].total_cmp(&xz[b][0]))
        .unwrap();
    let mut a: Vec<[f64; 2]> = xz[..=ile].to_vec();
    a.reverse();
    let b: Vec<[f64; 2]> = xz[ile..].to_vec();
    let interp = |s: &[[f64; 2]], x: f64| {
        let k = s
            .windows(2)
            .position(|w| w[0][0] <= x && x <= w[1][0])
            .unwrap();
        let (p, q) = (s[k], s[k + 1]);
        p[1] + (q[1] - p[1]) * (x - p[0]) / (q[0] - p[0])
    };
    let c = xz.iter().map(|p| p[0]).fold(0.0, f64::max);
    (1..2000)
        .map(|k| {
            let xx = c * k as f64 / 2000.0;
            (interp(&a, xx) - interp(&b, xx)).abs()
        })
        .fold(0.0, f64::max)
}

#[test]
fn zero_deviation_is_the_sampled_surface_bit_for_bit() {
    let db = wing_body();
    let wm = bind(&db);
    let g = wm.generate(&vec![0.0; names().len()]).unwrap();
    assert_eq!(bits(&g.points), bits(&wm.initial().points));
    let s = db.surface(SurfaceId(1));
    for j in 0..11 {
        for i in 0..121 {
            let want = ParamSurface::point(s, i as f64 / 120.0 * 4.0, j as f64 / 10.0 * 1.0);
            assert_eq!(bits(&[g.points[j * 121 + i]]), bits(&[want]));
        }
    }
    // through param and the model update: nothing moves (sources from the spec map)
    drop(wm);
    let p = parametrisation();
    let specs = std::collections::BTreeMap::from([("wing".to_string(), spec())]);
    let src = wingmaster::master::master_sources(&db, &p, &specs).unwrap();
    let prep = p.bind(&db, &src).unwrap();
    let x0 = prep.registry().initial();
    let pts = prep.apply(&x0).unwrap();
    assert_eq!(bits(&pts), bits(db.control_points()));
    let (new, report) = intersect::update::update_model(&db, &pts, &Default::default()).unwrap();
    assert!(report.surfaces_changed.is_empty());
    assert_eq!(new.surfaces, db.surfaces);
}

#[test]
fn tip_twist_rotates_the_tip_section_about_its_axis() {
    let db = wing_body();
    let wm = bind(&db);
    let theta = 0.05;
    let g = wm.generate(&x_with(&[("tip_twist", theta)])).unwrap();
    let g0 = wm.initial();
    let lref = 10.0;
    for j in 0..=TIP {
        let f = wm.station_frame(j);
        // twist interpolated linearly in y between the root (0) and the tip (θ)
        let w = (f.y - wm.key_frame(0).y) / (wm.key_frame(1).y - wm.key_frame(0).y);
        for (p, p0) in station(&g, j).iter().zip(station(g0, j)) {
            let want = f.reference + rot_y(theta * w, p0 - f.reference);
            assert!(
                (p - want).norm() < 1e-12 * lref,
                "station {j}: {p} vs {want}"
            );
        }
    }
    assert_eq!(bits(station(&g, 0)), bits(station(g0, 0)));
    // through param and the model update: the updated wing surface at its tip control nodes
    let tip_axis = wm.station_frame(TIP).reference;
    let tip_line = station(g0, TIP).to_vec();
    let prep = parametrisation().bind(&db, &sources(wm)).unwrap();
    let x = x_with(&[("tip_twist", theta)]);
    let pts = prep.apply(&x).unwrap();
    let (new, report) = intersect::update::update_model(&db, &pts, &Default::default()).unwrap();
    assert!(report.max_curve_residual <= 1e-8 * report.length_scale);
    let mut worst = 0.0f64;
    for (id, u) in tip_nodes(&db) {
        let p0 = db.control_points()[id];
        let want = tip_axis + rot_y(theta, p0 - tip_axis);
        let got = ParamSurface::point(new.surface(SurfaceId(1)), u, 1.0);
        // the node moves with the foot of its projection on the (polyline) master: the
        // rotation is exact up to θ × (distance from the node to the master)
        let d = polyline_distance(&tip_line, p0);
        let e = (got - want).norm();
        assert!(
            e <= theta * d + 1e-10 * lref,
            "node {id}: error {e}, distance {d}"
        );
        worst = worst.max(e);
    }
    eprintln!("tip twist: worst node error {worst:.3e}");
}

#[test]
fn tmax_change_changes_the_measured_max_thickness() {
    let db = wing_body();
    let wm = bind(&db);
    for (name, j, key) in [("tip_tmax", TIP, 1), ("root_tmax", 0, 0)] {
        let dt = 0.01;
        let g = wm.generate(&x_with(&[(name, dt)])).unwrap();
        let f = wm.station_frame(j);
        let t0 = max_thickness(station(wm.initial(), j), f.leading_edge, f.x, f.z);
        let t1 = max_thickness(station(&g, j), f.leading_edge, f.x, f.z);
        let want = dt * wm.key_fit(key).frame.chord;
        eprintln!("{name}: {t0} → {t1}, change {} want {want}", t1 - t0);
        assert!(
            ((t1 - t0) - want).abs() < 0.01 * want,
            "{name}: {} vs {want}",
            t1 - t0
        );
        // the other end of the wing is untouched
        let other = TIP - j;
        assert_eq!(bits(station(&g, other)), bits(station(wm.initial(), other)));
    }
}

#[test]
fn sweep_and_span_move_the_leading_edges_analytically() {
    let db = wing_body();
    let wm = bind(&db);
    let (sweep0, _) = wm.initial_sweep_dihedral();
    let (y_root, y_tip) = (wm.key_frame(0).y, wm.key_frame(1).y);
    let dl = 0.05;
    let g = wm.generate(&x_with(&[("sweep", dl)])).unwrap();
    for j in 0..=TIP {
        let f = wm.station_frame(j);
        let shift = ((sweep0 + dl).tan() - sweep0.tan()) * (f.y - y_root);
        for (p, p0) in station(&g, j).iter().zip(station(wm.initial(), j)) {
            let d = p - p0;
            assert!(
                (d - Vector3::new(shift, 0.0, 0.0)).norm() < 1e-12,
                "station {j}: {d}"
            );
        }
        // measured: the leading edge of the regenerated section
        let fnew = wingmaster::master::section_frame(station(&g, j), Vector3::y(), 0.0).unwrap();
        assert!((fnew.leading_edge.x - f.leading_edge.x - shift).abs() < 1e-12);
    }
    // sweep of the regenerated reference line
    let (fr, ft) = (
        wingmaster::master::section_frame(station(&g, 0), Vector3::y(), 0.0).unwrap(),
        wingmaster::master::section_frame(station(&g, TIP), Vector3::y(), 0.0).unwrap(),
    );
    let sweep = ((ft.reference.x - fr.reference.x) / (ft.y - fr.y)).atan();
    assert!(
        (sweep - (sweep0 + dl)).abs() < 1e-12,
        "{sweep} vs {}",
        sweep0 + dl
    );
    // span: the tip moves along the reference line by Δb / cos of its inclination, sweep kept
    let db_ = 0.4;
    let g = wm.generate(&x_with(&[("span", db_)])).unwrap();
    let ft = wingmaster::master::section_frame(station(&g, TIP), Vector3::y(), 0.0).unwrap();
    assert!((ft.y - y_tip - db_).abs() < 1e-12);
    let sweep = ((ft.reference.x - wm.key_frame(0).reference.x) / (ft.y - y_root)).atan();
    assert!((sweep - sweep0).abs() < 1e-12);
}

#[test]
fn jacobian_is_exact() {
    let db = wing_body();
    let wm = bind(&db);
    let n = names();
    let x: Vec<f64> = (0..n.len())
        .map(|k| 0.0005 * (k as f64 + 1.0) * if k % 2 == 0 { 1.0 } else { -1.0 })
        .collect();
    let jac = wm.jacobian(&x).unwrap().unwrap();
    for l in 0..n.len() {
        let h = 1e-6;
        let (mut xp, mut xm) = (x.clone(), x.clone());
        xp[l] += h;
        xm[l] -= h;
        let (gp, gm) = (wm.generate(&xp).unwrap(), wm.generate(&xm).unwrap());
        let mut worst = 0.0f64;
        let mut size = 0.0f64;
        for k in 0..gp.points.len() {
            let fd = (gp.points[k] - gm.points[k]) / (2.0 * h);
            worst = worst.max((fd - jac[k][l]).norm());
            size = size.max(jac[k][l].norm());
        }
        assert!(
            worst <= 1e-6 * size.max(1e-3),
            "{}: {worst} (size {size})",
            n[l]
        );
    }
}

#[test]
fn wing_body_update_keeps_the_junction() {
    let db = wing_body();
    let wm = bind(&db);
    let prep = parametrisation().bind(&db, &sources(wm)).unwrap();
    let x = x_with(&[
        ("tip_twist", 0.05),
        ("root_twist", 0.01),
        ("sweep", 0.03),
        ("tip_tmax", 0.01),
        ("root_tmax", -0.005),
        ("tip_camber3", 0.005),
        ("tip_chord", -0.05),
    ]);
    let pts = prep.apply(&x).unwrap();
    let opts = intersect::update::UpdateOptions::default().with_deviation_samples(8);
    let (new, report) = intersect::update::update_model(&db, &pts, &opts).unwrap();
    assert!(report.surfaces_changed.contains(&SurfaceId(1)));
    let rel = report.max_curve_residual / report.length_scale;
    let dev = report.max_deviation.unwrap() / report.length_scale;
    eprintln!("junction: residual {rel:.2e}, deviation {dev:.2e} (relative)");
    assert!(rel <= 1e-8, "{rel}");
    // the junction moved with the wing
    let j0 = db.curve(geom_db::CurveId(0)).point(0.5);
    let j1 = new.curve(geom_db::CurveId(0)).point(0.5);
    assert!((j1 - j0).norm() > 1e-4);
}

#[test]
fn spec_round_trip_and_errors() {
    let s = spec();
    let back = WingMasterSpec::from_ron_str(&s.to_ron_string(), "x").unwrap();
    assert_eq!(back, s);
    let db = wing_body();
    let n = names();
    let x0 = vec![0.0; n.len()];
    let e = s.bind(&db, &n[1..], &x0[1..]).unwrap_err().to_string();
    assert!(e.contains("'sweep'"), "{e}");
    let mut more = n.clone();
    more.push("loose".into());
    let e = s
        .bind(&db, &more, &vec![0.0; more.len()])
        .unwrap_err()
        .to_string();
    assert!(e.contains("'loose' is not used"), "{e}");
    let mut bad = s.clone();
    bad.key_sections[1]
        .thickness
        .insert("tmx".into(), "tip_tmax".into());
    let e = bad.bind(&db, &n, &x0).unwrap_err().to_string();
    assert!(e.contains("key section 1") && e.contains("'tmx'"), "{e}");
    let mut bad = s.clone();
    bad.key_sections[1].t = 0.0;
    let e = bad.bind(&db, &n, &x0).unwrap_err().to_string();
    assert!(e.contains("t must increase"), "{e}");
    let e = WingMasterSpec::from_ron_str("(surface: 1, spanwise: V, n_s: 10,)", "w.ron")
        .unwrap_err()
        .to_string();
    assert!(e.contains("w.ron:"), "{e}");
    // an invalid thickness at generate names the key section
    let wm = s.bind(&db, &n, &x0).unwrap();
    let e = wm.generate(&x_with(&[("tip_tmax", -0.5)])).unwrap_err();
    assert!(e.to_string().contains("key section 1"), "{e}");
    // the typed error comes through the boxed `param::MasterError`
    match e.downcast_ref::<wingmaster::Error>() {
        Some(wingmaster::Error::KeySection { key: 1, source }) => {
            assert!(
                matches!(**source, wingmaster::Error::InvalidSection { .. }),
                "{source:?}"
            );
        }
        other => panic!("{other:?}"),
    }
}

/// A wing lofted from a planform and two sections, then bound as a wing master: the key
/// section fits recover the sections' parameters and the planform's frames.
#[test]
fn lofted_wing_round_trip() {
    use wingmaster::planform::{Planform, PlanformSpec};
    use wingmaster::{CamberLine, SectionParams, ThicknessParams};
    let pf = Planform::resolve(&PlanformSpec {
        span: Some(10.0),
        root_chord: Some(2.0),
        stations: vec![1.0],
        taper: vec![0.4],
        sweep: vec![25f64.to_radians()],
        dihedral: vec![3f64.to_radians()],
        ..Default::default()
    })
    .unwrap();
    let mut camber = CamberLine::flat(6).unwrap().points().to_vec();
    camber[2][1] = 0.02;
    camber[3][1] = 0.015;
    let root = SectionParams {
        name: "root".into(),
        thickness: ThicknessParams::naca_like(0.14),
        camber,
        te_thickness: 0.0,
    };
    let tip = SectionParams {
        name: "tip".into(),
        thickness: ThicknessParams::naca_like(0.10),
        camber: CamberLine::flat(6).unwrap().points().to_vec(),
        te_thickness: 0.0,
    };
    let secs = [root.build().unwrap(), tip.build().unwrap()];
    let twist = [0.0, -0.05];
    let (surf, rep) = wingmaster::loft::wing_surface("wing", &pf, &secs, &twist, 2, 10).unwrap();
    eprintln!("loft interpolation error {:.2e}", rep.max_error);
    assert!(rep.max_error < 1e-4 * 2.0, "{}", rep.max_error);
    // the surface at v = 0 (root) and v = 1 (tip) passes through the leading edges
    let le_tip = ParamSurface::point(&surf, 2.0, 1.0);
    assert!((le_tip - Point3::new(pf.x_le[1], pf.y[1], pf.z[1])).norm() < 1e-12);
    let mut db = GeomDb::empty("lofted wing");
    db.surfaces.push(surf);
    let spec = WingMasterSpec::from_ron_str(
        r#"(surface: 0, spanwise: V, n_s: 161, n_t: 5, camber_points: 6,
            key_sections: [(t: 0.0, twist: "a"), (t: 1.0, twist: "b")])"#,
        "loft",
    )
    .unwrap();
    let wm = spec
        .bind(&db, &["a".into(), "b".into()], &[0.0, 0.0])
        .unwrap();
    for (k, (sp, tw)) in [(&root, twist[0]), (&tip, twist[1])]
        .into_iter()
        .enumerate()
    {
        let f = wm.key_fit(k);
        let th = &f.params.thickness;
        eprintln!(
            "key {k}: tmax {} (want {}), chord {} (want {}), max error {:.2e}",
            th.tmax, sp.thickness.tmax, f.frame.chord, pf.chords[k], f.max_error
        );
        assert!((th.tmax - sp.thickness.tmax).abs() < 1e-4);
        assert!((th.xtmax - sp.thickness.xtmax).abs() < 1e-3);
        assert!((f.frame.chord - pf.chords[k]).abs() < 1e-4 * pf.chords[k]);
        // the twist (nose up about the leading edge) shows in the chord direction x̂
        let x = wm.key_frame(k).x;
        assert!(
            (x - Vector3::new(tw.cos(), 0.0, -tw.sin())).norm() < 1e-4,
            "{x}"
        );
        assert!(f.max_error < 1e-4);
    }
}

/// On an unswept lofted wing (Λ₀ = 0) a sweep change ΔΛ shifts every leading edge by
/// tan(ΔΛ)·(y − y_root) along x, and a dihedral change ΔΓ raises it by tan(ΔΓ)·(y − y_root).
#[test]
fn sweep_of_an_unswept_wing_is_tan_delta_times_y() {
    use wingmaster::planform::{Planform, PlanformSpec};
    use wingmaster::{CamberLine, SectionParams, ThicknessParams};
    let pf = Planform::resolve(&PlanformSpec {
        span: Some(8.0),
        root_chord: Some(1.5),
        stations: vec![0.5, 1.0],
        taper: vec![0.8, 0.5],
        ..Default::default()
    })
    .unwrap();
    let sec = SectionParams {
        name: "s".into(),
        thickness: ThicknessParams::naca_like(0.12),
        camber: CamberLine::flat(6).unwrap().points().to_vec(),
        te_thickness: 0.0,
    }
    .build()
    .unwrap();
    let secs = [sec.clone(), sec.clone(), sec];
    let (surf, _) = wingmaster::loft::wing_surface("wing", &pf, &secs, &[0.0; 3], 2, 8).unwrap();
    let mut db = GeomDb::empty("unswept wing");
    db.surfaces.push(surf);
    let spec = WingMasterSpec::from_ron_str(
        r#"(surface: 0, spanwise: V, n_s: 81, n_t: 9, camber_points: 6,
            planform: (sweep: "sweep", dihedral: "dihedral"),
            key_sections: [(t: 0.0), (t: 1.0)])"#,
        "unswept",
    )
    .unwrap();
    let names: Vec<String> = vec!["sweep".into(), "dihedral".into()];
    let wm = spec.bind(&db, &names, &[0.0, 0.0]).unwrap();
    let (s0, d0) = wm.initial_sweep_dihedral();
    assert!(s0.abs() < 1e-12 && d0.abs() < 1e-12, "{s0} {d0}");
    let (dl, dg) = (0.1, 0.05);
    let g = wm.generate(&[dl, dg]).unwrap();
    for j in 0..9 {
        let f0 = wm.station_frame(j);
        let f1 = wingmaster::master::section_frame(station(&g, j), Vector3::y(), 0.0).unwrap();
        let eta = f0.y - wm.key_frame(0).y;
        let d = f1.leading_edge - f0.leading_edge;
        let want = Vector3::new(dl.tan() * eta, 0.0, dg.tan() * eta);
        assert!((d - want).norm() < 1e-12, "station {j}: {d} vs {want}");
    }
}

/// The control-node Jacobian of `param` with the wing master's exact master Jacobian agrees
/// with central differences of the control-node positions.
#[test]
fn control_node_jacobian_through_param() {
    let db = wing_body();
    let prep = parametrisation().bind(&db, &sources(bind(&db))).unwrap();
    let n = names();
    let x: Vec<f64> = (0..n.len()).map(|k| 0.0007 * (k as f64 + 1.0)).collect();
    let (_, j) = prep.apply_with_jacobian(&x).unwrap();
    for l in 0..n.len() {
        let h = 1e-6;
        let (mut xp, mut xm) = (x.clone(), x.clone());
        xp[l] += h;
        xm[l] -= h;
        let (pp, pm) = (prep.apply(&xp).unwrap(), prep.apply(&xm).unwrap());
        let col = param::jacobian::column(&j, l);
        let (mut err, mut size) = (0.0f64, 0.0f64);
        for (k, (a, b)) in pp.iter().zip(&pm).enumerate() {
            for c in 0..3 {
                let fd = (a[c] - b[c]) / (2.0 * h);
                size = size.max(fd.abs());
                err = err.max((col[3 * k + c] - fd).abs());
            }
        }
        assert!(
            err <= 1e-6 * size.max(1e-3),
            "{}: {err} (size {size})",
            n[l]
        );
    }
}
