//! Sliding on geom-db support curves and surfaces (paper §4.3, Eqs. 27–33).

use deform::{
    BoundaryConditions, DeformOptions, MarkerRole, RigidMotion, Support, Supports,
    deform_on_supports,
};
use geom_db::eval::{ParamCurve, ParamSurface};
use geom_db::prelude::{Point3, Vector3};
use geom_db::{Arc, CurveId, GeomDb, Patch, SupportCurve, SupportSurface, SurfaceId};
use mesh::Mesh;

const LX: f64 = 2.0;
const LY: f64 = 1.5;
const LZ: f64 = 2.2;

/// Height of the curved bottom face y = s(x, z) (quadratic, so a degree-2 patch is exact).
fn bulge(x: f64, z: f64, c: f64) -> f64 {
    let (a, b) = (x / LX, z / LZ);
    c * (0.6 * (a - 0.5).powi(2) - 0.4 * (b - 0.5).powi(2) + 0.1 * a * b)
}

/// A box [0, 2] × [s(x, z), 1.5] × [0, 2.2] with a block (the "wing") touching the bottom
/// face `y_m`, which lies on the surface y = s(x, z) (c = 0: the plane y = 0); the geometry
/// holds that surface (one bi-quadratic patch, (u, v) = (x / 2, z / 2.2)) and its four
/// border curves (in the planes x = 0, x = 2, z = 0, z = 2.2); the supports classify the
/// bottom face's nodes as Gmsh would (corners, border curves, surface).
pub(crate) fn bulged_box(c: f64) -> (Mesh, GeomDb, Vec<(u32, Support)>) {
    let mut m =
        deform::generate::box_with_block([8, 7, 9], [0.0; 3], [LX, LY, LZ], [3, 0, 3], [5, 3, 6]);
    let flat = m.coords.clone();
    for p in m.coords.iter_mut() {
        p[1] += bulge(p[0], p[2], c) * (1.0 - p[1] / LY);
    }
    let mut db = GeomDb::empty("bulged box");
    let surf = move |u: f64, v: f64| Point3::new(LX * u, bulge(LX * u, LZ * v, c), LZ * v);
    db.surfaces.push(SupportSurface::new(
        "bottom",
        1,
        1,
        vec![Patch::interpolate(2, 2, surf)],
    ));
    // Border curves: x = 0, x = LX (parameter z / LZ); z = 0, z = LZ (parameter x / LX).
    let xc = |x: f64| Arc::interpolate(2, move |t| surf(x / LX, t));
    let zc = |z: f64| Arc::interpolate(2, move |t| surf(t, z / LZ));
    for (name, arc) in [
        ("x=0", xc(0.0)),
        ("x=L", xc(LX)),
        ("z=0", zc(0.0)),
        ("z=L", zc(LZ)),
    ] {
        db.curves.push(SupportCurve::new(name, vec![arc]));
    }
    let mut sup = Vec::new();
    for v in m.marker("y_m").unwrap().elements.node_set() {
        let [x, _, z] = flat[v as usize];
        let on_x = [x == 0.0, x == LX];
        let on_z = [z == 0.0, z == LZ];
        let s = match (on_x, on_z) {
            ([false, false], [false, false]) => Support::Surface {
                surface: SurfaceId(0),
                uv: [x / LX, z / LZ],
            },
            ([a, b], [false, false]) if a || b => Support::Curve {
                curve: CurveId(if a { 0 } else { 1 }),
                t: z / LZ,
            },
            ([false, false], [a, b]) if a || b => Support::Curve {
                curve: CurveId(if a { 2 } else { 3 }),
                t: x / LX,
            },
            _ => Support::Corner,
        };
        sup.push((v, s));
    }
    // The wing's root nodes on y_m are classified too (moving wins over sliding).
    (m, db, sup)
}

fn pitch(angle: f64) -> RigidMotion {
    RigidMotion {
        angle_deg: angle,
        axis_point: [0.8, 0.0, 1.1],
        axis_dir: [0.0, 1.0, 0.0],
        translation: [0.0; 3],
    }
}

fn bc(angle: f64, bottom: MarkerRole) -> BoundaryConditions {
    BoundaryConditions {
        markers: vec![
            ("wing".into(), MarkerRole::Rigid(pitch(angle))),
            ("y_m".into(), bottom),
        ],
        displacements: vec![],
    }
}

#[test]
fn nodes_slide_on_a_curved_support_surface_and_stay_on_it() {
    let (m, db, nodes) = bulged_box(1.0);
    let supports = Supports { db: &db, nodes };
    let d = deform_on_supports(
        &m,
        &bc(-8.0, MarkerRole::SlideOnSupport),
        &supports,
        &DeformOptions::default(),
    )
    .unwrap();
    let r = &d.report;
    assert_eq!(r.quality_after.n_nonpositive, 0);
    assert!(r.sliding_on_supports > 40, "{}", r.sliding_on_supports);
    // The outer iteration re-linearised at least once (the support is curved).
    assert!(r.slide_iterations >= 2, "{r:?}");
    assert!(r.slide_update <= 1e-9, "{}", r.slide_update);
    let scale = 3.0;
    let motion = pitch(-8.0);
    let wing = m.marker("wing").unwrap().elements.node_set();
    let surf = &db.surfaces[0];
    let mut slid = 0.0f64;
    let mut on_curves = 0;
    for &(v, s) in &supports.nodes {
        let p = d.coords[v as usize];
        let p0 = m.coords[v as usize];
        if wing.binary_search(&v).is_ok() {
            // Precedence: moving beats sliding, the node moved once, by the rigid motion.
            assert_eq!(p, motion.apply(p0, 1.0), "wing root node {v}");
            continue;
        }
        // On the support surface y = s(x, z) (exact truth, independent of the patch).
        let dev = (p[1] - bulge(p[0], p[2], 1.0)).abs();
        assert!(dev <= 1e-12 * scale, "node {v}: {dev:e} off the surface");
        match s {
            Support::Corner => assert_eq!(p, p0, "corner {v} is frozen"),
            Support::Curve { curve, .. } => {
                // Curve nodes stay in their border plane (and on the surface, above).
                let (k, val) = [(0, 0.0), (0, LX), (2, 0.0), (2, LZ)][curve.index()];
                assert!((p[k] - val).abs() <= 1e-12 * scale, "curve node {v}: {p:?}");
                on_curves += 1;
            }
            Support::Surface { .. } => {}
        }
        slid = slid.max(((p[0] - p0[0]).powi(2) + (p[2] - p0[2]).powi(2)).sqrt());
    }
    assert!(on_curves > 10, "{on_curves}");
    assert!(slid > 5e-3, "nodes did slide: {slid}");
    // The returned parameters are the node's: r(u, v) = x exactly.
    assert_eq!(d.supports.len(), r.sliding_on_supports);
    for &(v, s) in &d.supports {
        let p = d.coords[v as usize];
        let q = match s {
            Support::Surface { uv, .. } => surf.point(uv[0], uv[1]),
            Support::Curve { curve, t } => db.curves[curve.index()].point(t),
            Support::Corner => unreachable!("corners are not returned"),
        };
        assert_eq!(p, [q.x, q.y, q.z], "node {v}");
    }
}

#[test]
fn flat_support_gives_the_sliding_plane_solution() {
    // A planar support surface (c = 0) must reproduce the projected-CG plane sliding (the
    // seam nodes slide along the box edges in both methods, corners frozen in both).
    let (m, db, nodes) = bulged_box(0.0);
    let supports = Supports { db: &db, nodes };
    let opts = DeformOptions {
        rel_tol: 1e-12,
        ..Default::default()
    };
    let a =
        deform_on_supports(&m, &bc(-8.0, MarkerRole::SlideOnSupport), &supports, &opts).unwrap();
    let b = deform::deform(&m, &bc(-8.0, MarkerRole::SlidePlane), &opts).unwrap();
    let err = testkit::max_coordinate_difference(&a.coords, &b.coords);
    assert!(err < 1e-9, "support vs plane sliding: {err:e}");
    let moved = testkit::max_coordinate_difference(&m.coords, &a.coords);
    assert!(moved > 0.05, "{moved}");
}

#[test]
fn zero_motion_with_supports_is_bit_for_bit_identity() {
    let (m, db, nodes) = bulged_box(1.0);
    let supports = Supports { db: &db, nodes };
    let d = deform_on_supports(
        &m,
        &bc(0.0, MarkerRole::SlideOnSupport),
        &supports,
        &DeformOptions::default(),
    )
    .unwrap();
    assert!(
        d.coords
            .iter()
            .zip(&m.coords)
            .all(|(a, b)| a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits()))
    );
    assert_eq!(d.report.iterations, 0);
}

#[test]
fn support_errors_name_the_node_and_entity() {
    let (m, db, mut nodes) = bulged_box(1.0);
    // Without supports.
    let e = deform::deform(
        &m,
        &bc(-8.0, MarkerRole::SlideOnSupport),
        &Default::default(),
    )
    .unwrap_err();
    assert!(e.to_string().contains("marker y_m"), "{e}");
    // A node whose parameters put it far from where it is.
    let k = nodes
        .iter()
        .position(|(_, s)| matches!(s, Support::Curve { .. }))
        .unwrap();
    let (v, _) = nodes[k];
    nodes[k].1 = Support::Curve {
        curve: CurveId(7),
        t: 0.5,
    };
    let sp = Supports { db: &db, nodes };
    let e = deform_on_supports(
        &m,
        &bc(-8.0, MarkerRole::SlideOnSupport),
        &sp,
        &Default::default(),
    )
    .unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains(&format!("node {v}")) && msg.contains("support curve 7"),
        "{msg}"
    );
    // A node missing from the supports.
    let mut nodes = sp.nodes.clone();
    nodes.remove(k);
    let sp = Supports { db: &db, nodes };
    let e = deform_on_supports(
        &m,
        &bc(-8.0, MarkerRole::SlideOnSupport),
        &sp,
        &Default::default(),
    )
    .unwrap_err();
    assert!(
        e.to_string().contains(&format!("node {v} on marker y_m")),
        "{e}"
    );
}

/// A cylindrical shell r ∈ [1, 1.6], θ ∈ [20°, 70°], z ∈ [0.4, 1.6] whose inner face lies
/// on the side surface of `fixtures/geom/cylinder.ron` (radius 1, power-basis patches).
#[test]
fn nodes_slide_on_the_cylinder_fixture_and_stay_on_it() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/geom/cylinder.ron"
    ))
    .unwrap();
    let db = GeomDb::from_ron_str(&text, "cylinder.ron").unwrap();
    let side = db
        .surfaces
        .iter()
        .position(|s| s.name == "side")
        .expect("side surface");
    let sid = SurfaceId(side as u32);
    let mut m = mesh::generate::box_tets(6, 10, 8, [0.0; 3], [1.0; 3]);
    let mut nodes = Vec::new();
    let inner = m.marker("x_m").unwrap().elements.node_set();
    for p in m.coords.iter_mut() {
        let (r, th, z) = (
            1.0 + 0.6 * p[0],
            (20.0 + 50.0 * p[1]).to_radians(),
            0.4 + 1.2 * p[2],
        );
        *p = [r * th.cos(), r * th.sin(), z];
    }
    for &v in &inner {
        let x = Vector3::from(m.coords[v as usize]);
        let inv = geom_db::invert::SurfaceInverter::new(
            "side",
            &db.surfaces[side],
            &geom_db::invert::InvertOptions::for_model(&db),
        )
        .unwrap();
        let f = inv.project(&Point3::from(x)).unwrap();
        let (uv, dist) = (f.uv, f.distance);
        assert!(dist < 1e-9, "node {v}: {dist:e} from the side surface");
        let q = db.surfaces[side].point(uv[0], uv[1]);
        m.coords[v as usize] = [q.x, q.y, q.z];
        nodes.push((v, Support::Surface { surface: sid, uv }));
    }
    let turn = RigidMotion {
        angle_deg: 4.0,
        axis_point: [0.0; 3],
        axis_dir: [0.0, 0.0, 1.0],
        translation: [0.0; 3],
    };
    let bc = BoundaryConditions {
        markers: vec![
            ("x_p".into(), MarkerRole::Rigid(turn)),
            ("x_m".into(), MarkerRole::SlideOnSupport),
        ],
        displacements: vec![],
    };
    let sp = Supports { db: &db, nodes };
    let d = deform_on_supports(&m, &bc, &sp, &DeformOptions::default()).unwrap();
    assert_eq!(d.report.quality_after.n_nonpositive, 0);
    let mut turned = 0.0f64;
    for &(v, s) in &d.supports {
        let p = d.coords[v as usize];
        let Support::Surface { uv, .. } = s else {
            panic!("node {v}: {s:?}");
        };
        let q = db.surfaces[side].point(uv[0], uv[1]);
        assert_eq!(p, [q.x, q.y, q.z]);
        // On the cylinder of radius 1 (the fixture approximates it to ~1e-11).
        let r = (p[0] * p[0] + p[1] * p[1]).sqrt();
        assert!((r - 1.0).abs() < 1e-9, "node {v}: r = {r}");
        let p0 = m.coords[v as usize];
        turned = turned.max((p[1].atan2(p[0]) - p0[1].atan2(p0[0])).abs().to_degrees());
    }
    // Interior nodes of the inner face turned with the outer face (edge nodes are frozen:
    // they also lie on the fixed side and end faces).
    assert!(d.supports.len() >= 5 * 7, "{}", d.supports.len());
    assert!(turned > 0.5, "largest turn {turned}°");
    // Edge nodes of the inner face did not move.
    for &v in &m.marker("z_m").unwrap().elements.node_set() {
        if inner.binary_search(&v).is_ok() {
            assert_eq!(d.coords[v as usize], m.coords[v as usize]);
        }
    }
}
