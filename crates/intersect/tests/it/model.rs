//! The model update on a small wing–body database built here from analytic data: a half
//! cylinder fuselage (axis x, radius 1) and a flat wing z = h crossing it, with the junction
//! curve, leading/trailing edges, tip and four corners.

use geom_db::eval::{ParamCurve, ParamSurface};
use geom_db::prelude::Point3;
use geom_db::{
    Arc, Corner, CornerId, CurveCompId, CurveComponent, CurveId, GeomDb, Orientation,
    OrientedCurve, Patch, Side, SupportCurve, SupportSurface, SurfaceComponent, SurfaceId,
};
use intersect::update::{ModelBaseline, UpdateOptions, update_model};
use std::f64::consts::FRAC_PI_2;
use testkit::assert_close;

const H: f64 = 0.1;

fn fuselage(r: f64) -> SupportSurface {
    // x = -0.5 + u over 2 patches (degree 3), φ ∈ [-π/2, π/2] over 4 patches (degree 5)
    let (du, dv) = (3usize, 5usize);
    let xu = geom_db::control::nodes(du);
    let xv = geom_db::control::nodes(dv);
    let mut patches = Vec::new();
    for j in 0..4 {
        for i in 0..2 {
            let mut pts = Vec::new();
            for a in 0..=du {
                for b in 0..=dv {
                    let x = -0.5 + i as f64 + xu[a];
                    let phi = -FRAC_PI_2 + (j as f64 + xv[b]) * FRAC_PI_2 / 2.0;
                    pts.push(Point3::new(x, r * phi.cos(), r * phi.sin()));
                }
            }
            patches.push(Patch::from_control_points(du, dv, &pts));
        }
    }
    SupportSurface::new("fuselage", 2, 4, patches)
}

fn wing() -> SupportSurface {
    // x ∈ [0, 1] (1 patch, degree 1), y = 0.5 + 1.25 v over 2 patches (degree 3), z = H
    let xv = geom_db::control::nodes(3);
    let mut patches = Vec::new();
    for j in 0..2 {
        let mut pts = Vec::new();
        for a in 0..=1 {
            for b in 0..=3 {
                pts.push(Point3::new(a as f64, 0.5 + 1.25 * (j as f64 + xv[b]), H));
            }
        }
        patches.push(Patch::from_control_points(1, 3, &pts));
    }
    SupportSurface::new("wing", 1, 2, patches)
}

/// The point of the fuselage at station x with z = h (1-D Newton in v on the polynomial).
fn fuselage_at_height(f: &SupportSurface, x: f64, h: f64) -> (Point3, f64) {
    let u = x + 0.5;
    let mut v = 2.0 + (h / 1.0).asin() / (FRAC_PI_2 / 2.0);
    for _ in 0..50 {
        let d = f.derivs(u, v);
        v -= (d.point.z - h) / d.dv.z;
    }
    let p = f.point(u, v);
    assert!(
        (p.z - h).abs() < 1e-14 && (p.x - x).abs() < 1e-13,
        "{p:?} {x} {h}"
    );
    (p, v)
}

pub fn wing_body() -> GeomDb {
    let fus = fuselage(1.0);
    let w = wing();
    let mut db = GeomDb::empty("wing-body test");
    // junction: 2 arcs of degree 5 along x ∈ [0, 1]
    let x5 = geom_db::control::nodes(5);
    let arcs: Vec<Arc> = (0..2)
        .map(|a| {
            let pts: Vec<Point3> = x5
                .iter()
                .map(|&s| fuselage_at_height(&fus, 0.5 * (a as f64 + s), H).0)
                .collect();
            Arc::from_control_points(&pts)
        })
        .collect();
    let mut junction = SupportCurve::new("junction", arcs);
    junction.defining_surfaces = vec![SurfaceId(0), SurfaceId(1)];
    let le = SupportCurve::new(
        "leading edge",
        vec![
            w.patches[0].border(Side::UMin),
            w.patches[1].border(Side::UMin),
        ],
    );
    let te = SupportCurve::new(
        "trailing edge",
        vec![
            w.patches[0].border(Side::UMax),
            w.patches[1].border(Side::UMax),
        ],
    );
    let tip = SupportCurve::new("tip", vec![w.patches[1].border(Side::VMax)]);
    let yj = fuselage_at_height(&fus, 0.0, H).0.y;
    let tj = (yj - 0.5) / 1.25;
    let j0 = junction.point(0.0);
    let j1 = junction.point(2.0);
    db.surfaces = vec![fus, w];
    db.curves = vec![junction, le, te, tip];
    db.corners = vec![
        Corner {
            point: j0,
            name: "root LE".into(),
        },
        Corner {
            point: j1,
            name: "root TE".into(),
        },
        Corner {
            point: Point3::new(0.0, 3.0, H),
            name: "tip LE".into(),
        },
        Corner {
            point: Point3::new(1.0, 3.0, H),
            name: "tip TE".into(),
        },
    ];
    let comp = |name: &str, c: u32, t0: f64, t1: f64, s: u32, e: u32| CurveComponent {
        name: name.into(),
        curve: CurveId(c),
        t0,
        t1,
        start: CornerId(s),
        end: CornerId(e),
    };
    db.curve_components = vec![
        comp("junction", 0, 0.0, 2.0, 0, 1),
        comp("LE", 1, tj, 2.0, 0, 2),
        comp("TE", 2, tj, 2.0, 1, 3),
        comp("tip", 3, 0.0, 1.0, 2, 3),
    ];
    let oc = |c: u32, reversed: bool| OrientedCurve {
        comp: CurveCompId(c),
        reversed,
    };
    db.surface_components = vec![SurfaceComponent {
        name: "wing".into(),
        surface: SurfaceId(1),
        loops: vec![vec![oc(0, false), oc(2, false), oc(3, true), oc(1, true)]],
        inward: Orientation::Positive,
    }];
    db.assign_control_nodes().unwrap();
    db.validate().unwrap();
    db
}

/// Control nodes of support surface `s` moved by `f`.
fn move_surface_nodes(db: &GeomDb, s: usize, f: impl Fn(&Point3) -> Point3) -> Vec<Point3> {
    db.control_points_with_surface_moved(geom_db::SurfaceId::from_index(s), f)
}

#[test]
fn zero_change_returns_the_initial_model_bit_for_bit() {
    let db = wing_body();
    let (new, rep) = update_model(&db, db.control_points(), &UpdateOptions::default()).unwrap();
    assert_eq!(new.to_ron_string(), db.to_ron_string());
    assert!(rep.surfaces_changed.is_empty());
    assert!(rep.curves.iter().all(|c| !c.reintersected));
    assert!(rep.corners.iter().all(|c| !c.updated));
}

#[test]
fn fuselage_radius_plus_minus_5_percent() {
    let db = wing_body();
    let base =
        ModelBaseline::new(&db, &UpdateOptions::default().with_deviation_samples(200)).unwrap();
    let scale = db.reference_length();
    for k in [1.05, 0.95] {
        let nodes = move_surface_nodes(&db, 0, |p| Point3::new(p.x, p.y * k, p.z * k));
        let (new, rep) = base.update(&nodes).unwrap();
        assert_eq!(rep.surfaces_changed, vec![SurfaceId(0)]);
        let j = &rep.curves[0];
        assert!(j.reintersected && j.fallbacks == 0, "{j:?}");
        let dev = rep.max_deviation.unwrap();
        eprintln!(
            "fuselage ×{k}: junction residual {:e}, deviation {dev:e} (scale {scale})",
            j.residual
        );
        assert!(dev <= 1e-10 * scale, "deviation {dev:e}");
        // analytic truth: the scaled fuselage at height H, at every sample
        let fus = &new.surfaces[0];
        let jc = &new.curves[0];
        for i in 0..=400 {
            let t = 2.0 * i as f64 / 400.0;
            let p = jc.point(t);
            let (q, _) = fuselage_at_height(fus, p.x, H);
            assert!(
                (p - q).norm() < 1e-10 * scale,
                "t {t}: {:e}",
                (p - q).norm()
            );
        }
        // corners follow: root LE on the leading edge x = 0 at the new junction
        let (q0, _) = fuselage_at_height(fus, 0.0, H);
        assert_close!(
            new.corners[0].point.coords.as_slice(),
            q0.coords.as_slice(),
            abs = 1e-12
        );
        let (q1, _) = fuselage_at_height(fus, 1.0, H);
        assert_close!(
            new.corners[1].point.coords.as_slice(),
            q1.coords.as_slice(),
            abs = 1e-12
        );
        // the LE component now starts where the leading edge meets the new junction
        let le = &new.curve_components[1];
        assert_close!(le.t0, (q0.y - 0.5) / 1.25, abs = 1e-12);
        assert!(rep.max_corner_residual < 1e-12);
        // tip corners untouched
        assert_eq!(new.corners[2], db.corners[2]);
    }
}

#[test]
fn wing_root_up_2_percent_chord() {
    let db = wing_body();
    let scale = db.reference_length();
    // root edge of the wing (y = 0.5) up by 0.02 chord; the tip stays
    let nodes = move_surface_nodes(&db, 1, |p| {
        if (p.y - 0.5).abs() < 1e-12 {
            Point3::new(p.x, p.y, p.z + 0.02)
        } else {
            *p
        }
    });
    let (new, rep) = update_model(
        &db,
        &nodes,
        &UpdateOptions::default().with_deviation_samples(200),
    )
    .unwrap();
    let j = &rep.curves[0];
    let dev = rep.max_deviation.unwrap();
    eprintln!(
        "wing root +2% chord: junction residual {:e}, max move {:e}, deviation {dev:e}",
        j.residual, j.max_move
    );
    assert!(j.max_move > 1e-3);
    assert!(dev <= 1e-8 * scale, "deviation {dev:e}");
    // corners are on the moved leading / trailing edges and on the fuselage
    for k in 0..2 {
        let c = new.corners[k].point;
        assert_close!(c.x, k as f64, abs = 1e-12);
        assert_close!(c.y * c.y + c.z * c.z, 1.0, abs = 1e-5); // fuselage is a polynomial circle
    }
}

#[test]
fn update_is_thread_count_independent() {
    let db = wing_body();
    let nodes = move_surface_nodes(&db, 0, |p| Point3::new(p.x, p.y * 1.03, p.z * 1.02));
    let opts = UpdateOptions::default();
    let (a, ra) = update_model(&db, &nodes, &opts).unwrap();
    let (b, rb) = testkit::with_threads(1, || update_model(&db, &nodes, &opts).unwrap());
    assert_eq!(a.to_ron_string(), b.to_ron_string());
    assert_eq!(ra, rb);
}

#[test]
fn a_wing_pulled_out_of_the_fuselage_is_an_error_naming_the_curve() {
    let db = wing_body();
    // lift the whole wing above the fuselage
    let nodes = move_surface_nodes(&db, 1, |p| Point3::new(p.x, p.y, p.z + 1.5));
    let err = update_model(&db, &nodes, &UpdateOptions::default())
        .unwrap_err()
        .to_string();
    assert!(err.contains("curve 0 (junction)"), "{err}");
}
