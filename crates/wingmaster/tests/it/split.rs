//! The wing master over a wing split at the leading edge (`WingMasterSpec::second`): the
//! OpenCASCADE split wing of `fixtures/cad/split_wing_ap214_m.stp` (upper and lower faces on
//! separate surfaces), against the figures of its construction (fixtures/cad/README.md:
//! root chord 0.8059 m, taper 0.562, semi-span 1.1963 m, 30° leading-edge sweep, twist −2°
//! at the tip).

use std::path::PathBuf;

use geom_db::GeomDb;
use geom_db::import::{ImportOptions, import_bytes};
use param::MasterSource;
use wingmaster::WingMasterSpec;

fn split_wing() -> GeomDb {
    let p =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/cad/split_wing_ap214_m.stp");
    let bytes = std::fs::read(&p).unwrap();
    import_bytes(&bytes, &p.display().to_string(), &ImportOptions::default())
        .unwrap()
        .0
}

/// The two faces as `aeroshape case init` finds them: surface 0 from the leading edge to the
/// trailing edge (sampled backwards), surface 1 from the leading edge to the trailing edge.
const SPEC: &str = r#"(
    surface: 0,
    spanwise: V,
    reverse_section: true,
    second: (surface: 1, spanwise: V),
    n_s: 81,
    n_t: 11,
    key_sections: [
        (t: 0.0, twist: "root_twist"),
        (t: 1.0, twist: "tip_twist", thickness: {"tmax": "tip_tmax"}),
    ],
)"#;

#[test]
fn a_split_wing_samples_both_faces_with_the_constructed_planform() {
    let db = split_wing();
    let spec = WingMasterSpec::from_ron_str(SPEC, "SPEC").unwrap();
    let names = spec.variable_names();
    let m = spec.bind(&db, &names, &vec![0.0; names.len()]).unwrap();
    let (root, tip) = (m.key_frame(0), m.key_frame(1));
    // chords of the construction (to the sampling: the leading edge is a sample)
    assert!(
        (root.chord - 0.8059).abs() < 2e-3 * 0.8059,
        "root chord {}",
        root.chord
    );
    assert!(
        (tip.chord - 0.562 * 0.8059).abs() < 2e-3 * 0.8059,
        "tip chord {}",
        tip.chord
    );
    // 30° leading-edge sweep over the semi-span
    let le = tip.leading_edge - root.leading_edge;
    assert!((le.y - 1.1963).abs() < 1e-6, "span {}", le.y);
    let sweep = (le.x / le.y).atan().to_degrees();
    assert!((sweep - 30.0).abs() < 0.2, "leading-edge sweep {sweep}°");
    // −2° of twist at the tip: the chord lines differ by 2°
    let twist = (tip.x.dot(&root.x)).clamp(-1.0, 1.0).acos().to_degrees();
    assert!((twist - 2.0).abs() < 0.1, "twist {twist}°");
    // half of each section on each face, joined at the leading edge
    let g = m.initial();
    let (s0, s1) = (&db.surfaces[0], &db.surfaces[1]);
    let on = |s: &geom_db::SupportSurface, p: &geom_db::prelude::Point3| {
        let proj = intersect::project::SurfaceProjector::new(
            "s",
            s,
            &intersect::project::ProjectOptions::default(),
        )
        .unwrap();
        proj.project(p).unwrap().distance
    };
    let n_s = 81;
    for j in [0, 5, 10] {
        for i in [1, 20, 39] {
            assert!(
                on(s0, &g.points[j * n_s + i]) < 1e-9,
                "station {j} sample {i}"
            );
        }
        for i in [41, 60, 79] {
            assert!(
                on(s1, &g.points[j * n_s + i]) < 1e-9,
                "station {j} sample {i}"
            );
        }
    }
    // a zero deviation gives the samples back; a tip twist moves the tip only
    let x0 = vec![0.0; names.len()];
    assert_eq!(m.generate(&x0).unwrap().points, g.points);
    let mut x = x0.clone();
    x[names.iter().position(|n| n == "tip_twist").unwrap()] = 0.01;
    let moved = m.generate(&x).unwrap();
    assert_eq!(moved.points[..n_s], g.points[..n_s]);
    assert_ne!(moved.points[10 * n_s..], g.points[10 * n_s..]);
}
