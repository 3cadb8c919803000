//! The whole chain linearised (`Study::linearise`, issue 22) on the default case (master,
//! line and surface levels; `waist_*` moves the junction; the symmetry plane slides): the
//! forward product of every design variable against central differences of
//! `Study::evaluate`, volume and wall, and the dot-product test ⟨J v, w⟩ = ⟨v, Jᵀ w⟩.
//!
//! The deformation solves run to 1e-12 here (the case's 1e-8 would leave FD noise of
//! about 1e-8 |X| / h).

use std::path::{Path, PathBuf};

use aeroshape::case::Case;
use aeroshape::case::load_design_values;
use aeroshape::study::Study;

fn case_dir(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/cases")
        .join(name)
}

/// The study of `case` in `dir` with tight deformation solves, and the design vector of `dv`.
fn tight_study(dir: &str, case: &str, dv: &str) -> (Study, Vec<f64>) {
    let dir = case_dir(dir);
    let path = dir.join(case);
    let mut c = Case::load(&path).expect("case");
    c.deform.rel_tol = 1e-12;
    c.deform.warm_start = false;
    let s = Study::new(c, &path).expect("study builds");
    let dv = load_design_values(&dir.join(dv)).expect("dv");
    let x = s.vector_from_values(&dv).expect("design vector");
    (s, x)
}

fn dot3(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| p[0] * q[0] + p[1] * q[1] + p[2] * q[2])
        .sum()
}

fn norm3(a: &[[f64; 3]]) -> f64 {
    dot3(a, a).sqrt()
}

/// |a − b| / |b| (infinite for b = 0).
fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let d: f64 = a.iter().zip(b).map(|(p, q)| (p - q).powi(2)).sum();
    let n: f64 = b.iter().map(|q| q * q).sum();
    if n > 0.0 {
        (d / n).sqrt()
    } else {
        f64::INFINITY
    }
}

/// A deterministic pseudo-random sequence in [−1, 1].
fn rng(seed: u64) -> impl FnMut() -> f64 {
    let mut s = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}

/// ⟨J v, w⟩ = ⟨v, Jᵀ w⟩ for the volume and the wall products, at the case's design vector.
#[test]
fn dot_product_test_volume_and_wall() {
    let (s, x) = tight_study("default", "case.ron", "dv.ron");
    let lin = s.linearise(&x).unwrap().with_rel_tol(1e-14);
    let n = s.baseline().n_nodes();
    for seed in [1u64, 2] {
        let mut r = rng(seed);
        let v: Vec<f64> = x.iter().map(|_| r()).collect();
        let w: Vec<[f64; 3]> = (0..n).map(|_| [r(), r(), r()]).collect();
        for wall in [false, true] {
            let (jv, jtw) = if wall {
                (lin.jvp_wall(&v).unwrap(), lin.vjp_wall(&w).unwrap())
            } else {
                (lin.jvp(&v).unwrap(), lin.vjp(&w).unwrap())
            };
            let a = dot3(&jv, &w);
            let b: f64 = v.iter().zip(&jtw).map(|(p, q)| p * q).sum();
            let scale = norm3(&jv) * norm3(&w);
            let rel = (a - b).abs() / scale;
            eprintln!("seed {seed} wall {wall}: {a:.15e} vs {b:.15e}, relative {rel:.2e}");
            assert!(rel < 1e-10, "dot-product test {rel:.3e}");
        }
    }
}

/// Every design variable's column, volume and wall, against central differences; a column
/// that is zero (or wrong) fails, since every variable moves the wall.
#[test]
fn every_design_variable_matches_central_differences() {
    let (s, x) = tight_study("default", "case.ron", "dv.ron");
    let names: Vec<String> = s.registry().names().iter().map(|n| n.to_string()).collect();
    let lref = s.geometry().reference_length();
    let lin = s.linearise(&x).unwrap();
    let mut junction = false;
    for (l, name) in names.iter().enumerate() {
        let mut e = vec![0.0; x.len()];
        e[l] = 1.0;
        // the step moving the wall by at most 1e-4 of the model's size
        let jw = lin.jvp_wall(&e).unwrap();
        let m = jw
            .iter()
            .map(|p| (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt())
            .fold(0.0, f64::max);
        assert!(m > 0.0, "{name} moves the wall");
        let h = 1e-4 * lref / m;
        for wall in [false, true] {
            let c = s.check_jvp(&x, &e, h, wall).unwrap();
            eprintln!(
                "{name} (h = {h:.1e}, wall {wall}): |FD| {:.4e}, |J e| {:.4e}, relative error {:.2e}",
                c.fd_norm, c.product_norm, c.rel_error
            );
            assert!(c.fd_norm > 0.0, "{name} moves the grid");
            assert!(
                c.rel_error < 1e-6,
                "{name}: relative error {:.3e}",
                c.rel_error
            );
        }
        // the nodes on the re-intersected junction (a curve with two defining surfaces)
        let db = s.geometry();
        let on_junction = |i: usize| match s.baseline_surface().support[i] {
            surfgrid::NodeSupport::Curve { comp, .. } => {
                db.curve(db.curve_component(comp).curve)
                    .defining_surfaces
                    .len()
                    == 2
            }
            _ => false,
        };
        let jm = (0..jw.len())
            .filter(|&i| on_junction(i))
            .map(|i| (jw[i][0] * jw[i][0] + jw[i][1] * jw[i][1] + jw[i][2] * jw[i][2]).sqrt())
            .fold(0.0, f64::max);
        eprintln!("{name}: largest junction-node derivative {jm:.3e} (wall {m:.3e})");
        junction |= jm > 1e-3 * m && name.starts_with("waist");
    }
    assert!(junction, "a variable that moves the junction is checked");
}

/// The fuselage variables `case init` builds on the default geometry and grid — the waist
/// (surface level, Eq. 38) and the nose droop and stretch (lines along the fuselage axis,
/// Eq. 36) — against central differences, volume and wall, at a design vector with each at
/// 30 % of its bound; droop and stretch move the nose and leave the junction's nodes still.
#[test]
fn init_fuselage_variables_match_central_differences() {
    let dir = tempfile::tempdir().unwrap();
    let src = case_dir("default");
    let text = std::fs::read_to_string(src.join("wing_body.ron")).unwrap();
    let db = geom_db::GeomDb::from_ron_str(&text, "wing_body.ron").unwrap();
    let grid = mesh::io::read_path(&src.join("grid.msh")).unwrap();
    let opts = aeroshape::init::InitOptions::default();
    aeroshape::init::init_case(&db, &grid, &[], dir.path(), &opts).unwrap();
    let path = dir.path().join("case.ron");
    let mut c = Case::load(&path).expect("case");
    c.deform.rel_tol = 1e-12;
    c.deform.warm_start = false;
    let s = Study::new(c, &path).expect("study builds");
    let vars = s.registry().variables();
    let fuselage: Vec<usize> = (0..vars.len())
        .filter(|&i| vars[i].name.starts_with("fuselage."))
        .collect();
    let names: Vec<&str> = fuselage.iter().map(|&i| vars[i].name.as_str()).collect();
    assert_eq!(
        names,
        ["fuselage.waist", "fuselage.droop", "fuselage.stretch"]
    );
    let mut x = s.initial();
    for &i in &fuselage {
        x[i] = 0.3 * vars[i].upper;
    }
    let lref = s.geometry().reference_length();
    let lin = s.linearise(&x).unwrap();
    let db = s.geometry();
    let on_junction = |i: usize| match s.baseline_surface().support[i] {
        surfgrid::NodeSupport::Curve { comp, .. } => {
            db.curve(db.curve_component(comp).curve)
                .defining_surfaces
                .len()
                == 2
        }
        _ => false,
    };
    for &l in &fuselage {
        let name = &vars[l].name;
        let mut e = vec![0.0; x.len()];
        e[l] = 1.0;
        let jw = lin.jvp_wall(&e).unwrap();
        let norm = |p: &[f64; 3]| (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        let m = jw.iter().map(norm).fold(0.0, f64::max);
        assert!(m > 0.0, "{name} moves the wall");
        let h = 1e-4 * lref / m;
        for wall in [false, true] {
            let c = s.check_jvp(&x, &e, h, wall).unwrap();
            eprintln!(
                "{name} (h = {h:.1e}, wall {wall}): |FD| {:.4e}, |J e| {:.4e}, relative error {:.2e}",
                c.fd_norm, c.product_norm, c.rel_error
            );
            assert!(c.fd_norm > 0.0, "{name} moves the grid");
            assert!(
                c.rel_error < 1e-6,
                "{name}: relative error {:.3e}",
                c.rel_error
            );
        }
        let jm = (0..jw.len())
            .filter(|&i| on_junction(i))
            .map(|i| norm(&jw[i]))
            .fold(0.0, f64::max);
        eprintln!("{name}: largest junction-node derivative {jm:.3e} (wall {m:.3e})");
        if name != "fuselage.waist" {
            // the nose tip (the foremost wall node that moves) moves by the variable itself,
            // down or forward (s = 1 there); the junction does not move
            let coords = &s.baseline().coords;
            let tip = (0..jw.len())
                .filter(|&i| norm(&jw[i]) > 0.0)
                .min_by(|&a, &b| coords[a][0].total_cmp(&coords[b][0]))
                .unwrap();
            let want = if name == "fuselage.droop" {
                [0.0, 0.0, -1.0]
            } else {
                [-1.0, 0.0, 0.0]
            };
            let d = [
                jw[tip][0] - want[0],
                jw[tip][1] - want[1],
                jw[tip][2] - want[2],
            ];
            assert!(
                coords[tip][0].abs() < 1e-12 && norm(&d) < 1e-9,
                "{name}: node {tip} at {:?} moves along {:?}",
                coords[tip],
                jw[tip]
            );
            assert!(jm < 1e-9 * m, "{name} moves the junction: {jm:.3e}");
        }
    }
}

/// `Study::linearise` just after `Study::evaluate` at the same x reuses that evaluation (an
/// optimiser evaluates first): the linearisation is at the evaluation's grid bit for bit (a
/// warm-started one, which a cold evaluation does not reproduce bit for bit), and its
/// products agree with those of a linearisation that evaluated x itself to the solvers'
/// tolerance.
#[test]
fn linearise_after_evaluate_reuses_the_evaluation() {
    let dir = case_dir("default");
    let s = Study::load(&dir.join("case.ron")).expect("study");
    assert!(s.case().deform.warm_start, "the default case warm-starts");
    let x = s
        .vector_from_values(&load_design_values(&dir.join("dv.ron")).expect("dv"))
        .expect("design vector");
    let step: Vec<f64> = x.iter().map(|v| 1.01 * v).collect();
    s.evaluate(&step).unwrap();
    // warm-started from the step's solution
    let ev = s.evaluate(&x).unwrap();
    let reused = s.linearise(&x).unwrap();
    assert!(reused.coords() == ev.grid.coords.as_slice());
    assert!(reused.surface().coords == ev.surface.coords);
    // the last evaluation elsewhere: x evaluated cold by the linearisation
    s.evaluate(&step).unwrap();
    let cold = s.linearise(&x).unwrap();
    assert!(
        cold.coords() != ev.grid.coords.as_slice(),
        "warm and cold differ"
    );
    let n = s.baseline().n_nodes();
    let mut r = rng(7);
    let w: Vec<[f64; 3]> = (0..n).map(|_| [r(), r(), r()]).collect();
    let (a, b) = (reused.vjp(&w).unwrap(), cold.vjp(&w).unwrap());
    let rel = rel_diff(&a, &b);
    eprintln!("reused against cold: |Δ gradient| / |gradient| = {rel:.2e}");
    assert!(rel < 1e-6, "{rel:e}");
    // The study warm-starts the adjoint solves from the last reverse product's (here: the
    // cold linearisation's, at a nearby grid); forgetting the warm start starts them from
    // zero. Both give the product to the solver tolerance.
    let warm = reused.vjp(&w).unwrap();
    s.forget_warm_start();
    let zero = reused.vjp(&w).unwrap();
    let rel = rel_diff(&warm, &zero);
    eprintln!("warm-started adjoint against cold: {rel:.2e}");
    assert!(rel < 1e-6, "{rel:e}");
}
