//! End-to-end tests of the chain (`aeroshape::Study`) on the committed cases
//! `fixtures/cases/sphere` (cube sphere in a far-field box, 1.4k nodes) and
//! `fixtures/cases/default` (the wing-body half model with its symmetry plane, 4.2k nodes):
//! the identity of the zero perturbation, the case's design vector (no inverted cell, wall
//! nodes on their supports, curve nodes — the wing/body junction — on both adjacent
//! surfaces, checked by independent projections on the updated geometry) and the absence
//! of state carried between evaluations.

use std::path::{Path, PathBuf};

use aeroshape::Study;
use aeroshape::case::load_design_values;
use geom_db::GeomDb;
use geom_db::prelude::Point3;
use intersect::project::{ProjectOptions, SurfaceProjector};
use surfgrid::NodeSupport;

fn case_dir(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/cases")
        .join(name)
}

fn study(name: &str) -> (Study, Vec<f64>) {
    study_files(name, "case.ron", "dv.ron")
}

fn study_files(name: &str, case: &str, dv: &str) -> (Study, Vec<f64>) {
    let dir = case_dir(name);
    let s = Study::load(&dir.join(case)).expect("study builds");
    let dv = load_design_values(&dir.join(dv)).expect("dv.ron");
    let x = s.vector_from_values(&dv).expect("design vector");
    (s, x)
}

/// Largest distance of the wall nodes from their support surfaces (nodes inside a component)
/// and of the curve nodes from every surface adjacent to their curve, both relative to the
/// reference length, by projection (Eq. 11) on the updated geometry.
fn support_distances(db: &GeomDb, coords: &[[f64; 3]], support: &[NodeSupport]) -> (f64, f64) {
    let lref = db.reference_length();
    let popts = ProjectOptions::default().with_length_scale(lref);
    let proj: Vec<SurfaceProjector<'_, geom_db::SupportSurface>> = db
        .surface_components
        .iter()
        .map(|c| SurfaceProjector::new(c.name.clone(), db.surface(c.surface), &popts).unwrap())
        .collect();
    let (mut surf, mut curve) = (0.0f64, 0.0f64);
    for (i, s) in support.iter().enumerate() {
        let p = Point3::new(coords[i][0], coords[i][1], coords[i][2]);
        match *s {
            NodeSupport::Surface { comp, uv } => {
                let f = proj[comp.index()].project_from(&p, uv);
                let d = if f.report.converged {
                    f.distance
                } else {
                    proj[comp.index()].project(&p).unwrap().distance
                };
                surf = surf.max(d / lref);
            }
            NodeSupport::Curve { comp, .. } => {
                for (k, sc) in db.surface_components.iter().enumerate() {
                    if sc.loops.iter().flatten().any(|oc| oc.comp == comp) {
                        let d = proj[k].project(&p).unwrap().distance;
                        curve = curve.max(d / lref);
                    }
                }
            }
            _ => {}
        }
    }
    (surf, curve)
}

const CASES: [&str; 2] = ["sphere", "default"];

#[test]
fn zero_design_vector_gives_the_baseline_bit_for_bit() {
    for case in CASES {
        zero_design_vector(case);
    }
}

fn zero_design_vector(case: &str) {
    let (s, _) = study(case);
    let ev = s.evaluate(&s.initial()).unwrap();
    assert_eq!(ev.grid.coords, s.baseline().coords);
    assert_eq!(ev.grid.cells, s.baseline().cells);
    assert_eq!(ev.report.param.nodes_moved, 0);
    assert_eq!(ev.report.quality_after.inverted, 0);
}

#[test]
fn design_vector_moves_the_wall_onto_the_new_geometry() {
    for case in CASES {
        design_vector(case);
    }
}

#[test]
fn wing_master_case_moves_the_wing_onto_the_new_geometry() {
    let (s, x) = study_files("default", "case_wingmaster.ron", "dv_wingmaster.ron");
    check_design_vector("default (wing master)", &s, &x);
}

fn design_vector(case: &str) {
    let (s, x) = study(case);
    check_design_vector(case, &s, &x);
}

fn check_design_vector(case: &str, s: &Study, x: &[f64]) {
    let ev = s.evaluate(x).unwrap();
    let r = &ev.report;
    assert!(r.param.nodes_moved > 0 && r.surface.moved_nodes > 0);
    assert!(!r.deform.skipped && r.deform.iterations() > 0);
    assert_eq!(r.quality_after.inverted, 0, "{case}: {r:#?}");
    // the reported cell quality is that of the returned grid, bit for bit
    let q = mesh::quality::cell_quality(&ev.grid);
    assert!(
        q.iter()
            .zip(&ev.cell_quality)
            .all(|(a, b)| a.to_bits() == b.to_bits()),
        "{case}: cell quality of the returned grid"
    );
    // every re-intersected junction sampled (≥ 200 per arc) and within 1e-8 of the model
    // size of both surfaces; the report says so
    let m = &r.model;
    assert!(
        m.curves_reintersected > 0 && !m.junctions.is_empty(),
        "{case}: {m:#?}"
    );
    for j in &m.junctions {
        assert!(j.samples >= 200 * j.degrees.len(), "{case}: {j:?}");
        assert!(
            j.max[0].max(j.max[1]) <= m.junction_tolerance,
            "{case}: {j:?}"
        );
    }
    assert!(m.curve_deviation_rel.unwrap() <= 1e-8, "{case}: {m:#?}");
    assert!(
        m.corner_distance.unwrap() <= m.junction_tolerance,
        "{case}: {m:#?}"
    );
    eprintln!("{case}: {}", m.junction_summary());
    // the wall moved by a visible amount
    let moved = ev
        .grid
        .coords
        .iter()
        .zip(&s.baseline().coords)
        .map(|(a, b)| {
            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
        })
        .fold(0.0, f64::max);
    assert!(moved > 1e-2, "{case}: largest node motion {moved}");
    // wall nodes on their supports, curve nodes on both adjacent surfaces
    let (surf, curve) = support_distances(&ev.geometry, &ev.grid.coords, &ev.surface.support);
    assert!(
        surf <= 1e-10,
        "wall node off its support by {surf:e} (relative)"
    );
    assert!(
        curve <= 1e-8,
        "curve node off an adjacent surface by {curve:e} (relative)"
    );
    // symmetry-plane nodes stayed in the plane y = 0
    if let Some(m) = s.baseline().marker("symmetry") {
        let lref = ev.geometry.reference_length();
        for v in m.elements.node_set() {
            let (a, b) = (ev.grid.coords[v as usize], s.baseline().coords[v as usize]);
            assert!(
                (a[1] - b[1]).abs() <= 1e-9 * lref,
                "{case}: node {v} left the symmetry plane: {a:?}"
            );
        }
    }
    // the far field did not move
    let ff = s.baseline().marker("farfield").unwrap().elements.node_set();
    for v in ff {
        assert_eq!(ev.grid.coords[v as usize], s.baseline().coords[v as usize]);
    }
}

#[test]
fn no_state_leaks_between_evaluations() {
    let (s, x) = study("default");
    let a = s.evaluate(&x).unwrap();
    let zero = s.evaluate(&s.initial()).unwrap();
    assert_eq!(zero.grid.coords, s.baseline().coords);
    let b = s.evaluate(&x).unwrap();
    assert_eq!(a.grid.coords, b.grid.coords);
}

#[test]
fn warm_start_agrees_with_a_cold_evaluation_and_saves_the_solves() {
    let (s, x) = study("default");
    // A nearby vector first, as an optimiser's previous step.
    let near: Vec<f64> = x.iter().map(|v| 0.9 * v).collect();
    s.evaluate(&near).unwrap();
    let warm = s.evaluate(&x).unwrap();
    s.forget_warm_start();
    let cold = s.evaluate(&x).unwrap();
    let r = (&warm.report.deform, &cold.report.deform);
    assert!(
        r.0.iterations() + r.0.rotation_iterations() < r.1.iterations() + r.1.rotation_iterations(),
        "warm {r:?}"
    );
    // The solves stop at a relative residual of 1e-8 and the sliding at 1e-9 of the motion:
    // the two answers agree far below the wall motion (0.3 at most).
    let err = testkit::max_coordinate_difference(&warm.grid.coords, &cold.grid.coords);
    assert!(err < 1e-7, "warm vs cold: {err:.3e}");
    assert_eq!(warm.report.quality_after.inverted, 0);
    // The same vector again: no solver iteration, the same grid to round-off.
    let again = s.evaluate(&x).unwrap();
    assert_eq!(again.report.deform.iterations(), 0);
    assert_eq!(again.report.deform.rotation_iterations(), 0);
    let err = testkit::max_coordinate_difference(&again.grid.coords, &cold.grid.coords);
    assert!(err < 1e-13, "repeat: {err:.3e}");
}

#[test]
fn wrong_length_design_vector_is_an_error() {
    let (s, _) = study("sphere");
    let e = s.evaluate(&[0.0]).unwrap_err();
    assert!(
        matches!(
            e,
            aeroshape::study::StudyError::Param(param::Error::VectorLength { found: 1, .. })
        ),
        "{e:?}"
    );
}

#[test]
fn wall_distance_stiffness_from_the_case_file() {
    // The default case with `deform: (stiffness: WallDistance)`: read from RON like a user's
    // case file, then the same checks as the default design vector.
    let dir = case_dir("default");
    let path = dir.join("case.ron");
    let mut case = aeroshape::case::Case::load(&path).unwrap();
    let text = "(stiffness: WallDistance)";
    case.deform = ron::from_str(text).unwrap();
    assert_eq!(
        case.deform.options().stiffness,
        deform::Stiffness::WallDistance
    );
    let s = Study::new(case, &path).unwrap();
    let dv = load_design_values(&dir.join("dv.ron")).unwrap();
    let x = s.vector_from_values(&dv).unwrap();
    check_design_vector("default, wall distance", &s, &x);
}

/// Fig. 9 of the paper: the default case's waist moves the fuselage at the wing junction.
/// Every variable of the case moves control nodes; `waist_bottom` alone takes fuselage wall
/// nodes off the baseline fuselage surface near the wing (x in [3, 6]), while those of the
/// nose and tail stay on it (they may only slide along it, by the surface-grid re-map).
#[test]
fn waist_alone_moves_the_fuselage_at_the_junction() {
    let (s, _) = study("default");
    let reach = aeroshape::reach::variable_reach_of(&s).unwrap();
    for r in &reach {
        assert!(r.nodes_moved > 0, "{r:?}");
    }
    let i = s.registry().index_of("waist_bottom").unwrap();
    let mut x = s.initial();
    x[i] = -0.05;
    let ev = s.evaluate(&x).unwrap();
    assert_eq!(ev.report.quality_after.inverted, 0);
    let db = s.geometry();
    let popts = ProjectOptions::default().with_length_scale(db.reference_length());
    let fc = db
        .surface_components
        .iter()
        .find(|c| c.name == "fuselage")
        .unwrap();
    let pr = SurfaceProjector::new("fuselage", db.surface(fc.surface), &popts).unwrap();
    let base = s.baseline();
    let (mut near, mut far) = (0.0f64, 0.0f64);
    for &v in &base.marker("fuselage").unwrap().elements.node_set() {
        let (p, q) = (base.coords[v as usize], ev.grid.coords[v as usize]);
        let off = pr.project(&Point3::new(q[0], q[1], q[2])).unwrap().distance;
        if (3.0..=6.0).contains(&p[0]) {
            near = near.max(off);
        } else if !(1.5..=7.5).contains(&p[0]) {
            far = far.max(off);
        }
    }
    assert!(
        near > 0.01,
        "the waist takes the fuselage near the wing off its surface by {near:e}"
    );
    assert!(
        far < 1e-8,
        "nose and tail stay on the baseline fuselage ({far:e})"
    );
}

/// A design variable that moves no control node is an error naming it when the case is
/// loaded: a spanwise bump on the wing, whose support surface has control nodes only at the
/// root and the tip, where the bump vanishes (the pattern of the old default waist).
#[test]
fn dead_design_variable_is_an_error_naming_it() {
    let path = case_dir("default").join("case.ron");
    let mut case = aeroshape::case::Case::load(&path).unwrap();
    let text = r#"Surface(
        name: "spanwise",
        surfaces: [1],
        basis_u: Bernstein(degree: 1),
        basis_v: Bernstein(degree: 2),
        active_u: [0],
        active_v: [1],
        form: Tensor(variables: [(name: "dead", lower: -0.1, upper: 0.1)]),
    )"#;
    let m: param::Modifier = param::ron_options().from_str(text).unwrap();
    case.parametrisation.modifiers.push(m);
    let e = Study::new(case, &path).unwrap_err();
    assert!(
        matches!(&e, aeroshape::study::StudyError::Case(aeroshape::case::CaseError::DeadVariable { variable, .. }) if variable == "dead"),
        "{e}"
    );
    assert!(
        e.to_string()
            .contains("\"dead\" (modifier \"spanwise\") moves no control node"),
        "{e}"
    );
}
