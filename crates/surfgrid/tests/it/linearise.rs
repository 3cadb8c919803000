//! The linearised surface-grid update (`Updater::linearise`) against central differences of
//! `Updater::update` through the model update, and the dot-product test, on two grids:
//! the Gmsh grid of the ONERA M6 IGES (`fixtures/grids/oneram6.su2` on
//! `fixtures/iges/geom_oneram6.igs`: neither made by aeroshape), and a grid generated on
//! the wing–body fixture whose junction is re-intersected (the junction moves in both
//! surfaces' parametric planes, so both are re-mapped and smoothed).

use geom_db::GeomDb;
use geom_db::linearise::ModelTangent;
use geom_db::prelude::{Point3, Vector3};
use intersect::update::{ModelBaseline, UpdateOptions as ModelOptions};
use surfgrid::{GenerateOptions, SurfaceGrid, UpdateOptions, Updater, generate};

use crate::common::{fixture, wing_body_field};

fn root() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A smooth field over space, scaled by the model size `l`.
fn field(p: &Point3, k: f64, l: f64) -> Vector3 {
    let q = p / l;
    Vector3::new(
        0.02 * (3.1 * q.x + k).sin() + 0.01 * q.y,
        0.015 * q.y * (2.3 * q.z + k).cos() + 0.01 * q.x,
        0.02 * q.z + 0.01 * (4.0 * q.x * q.y + k).sin(),
    ) * l
}

fn norm(v: &[Vector3]) -> f64 {
    v.iter().map(|x| x.norm_squared()).sum::<f64>().sqrt()
}

struct Outcome {
    rel: f64,
    dot_rel: f64,
    remapped: usize,
    smoothed: usize,
}

/// At control nodes moved by `s` × field, the forward product against central differences
/// of step `h` (relative to the norm), and the dot-product test.
fn check(db: &GeomDb, grid: &SurfaceGrid, s: f64, h: f64, junction_rel_tol: f64) -> Outcome {
    // the wall's size (an imported model's far field would dwarf it)
    let on = |i: &usize| !matches!(grid.support[*i], surfgrid::NodeSupport::Free);
    let (mut lo, mut hi) = (
        Vector3::repeat(f64::INFINITY),
        Vector3::repeat(f64::NEG_INFINITY),
    );
    for i in (0..grid.n_nodes()).filter(on) {
        lo = lo.inf(&grid.coords[i].coords);
        hi = hi.sup(&grid.coords[i].coords);
    }
    let l = (hi - lo).norm();
    let mopts = ModelOptions::default().with_junction_rel_tol(junction_rel_tol);
    let base = ModelBaseline::new(db, &mopts).unwrap();
    let x: Vec<Point3> = db
        .control_points()
        .iter()
        .map(|p| p + field(p, 0.3, l) * s)
        .collect();
    let (model, _) = base.update(&x).unwrap();
    let mlin = base.linearise(&x, &model).unwrap();
    let updater = Updater::new(grid);
    let opts = UpdateOptions::default();
    let (out, rep, lin) = updater.linearise(grid, db, &model, &opts).unwrap();
    assert!(out == updater.update(grid, db, &model, &opts).unwrap().0);
    let dp: Vec<Vector3> = db
        .control_points()
        .iter()
        .map(|p| field(p, 1.1, l) / l)
        .collect();
    let jv = lin.jvp(&mlin.jvp(&dp).unwrap()).unwrap();
    let at = |sign: f64| -> Vec<Point3> {
        let y: Vec<Point3> = x.iter().zip(&dp).map(|(p, d)| p + d * (sign * h)).collect();
        let (m, _) = base.update(&y).unwrap();
        updater.update(grid, db, &m, &opts).unwrap().0.coords
    };
    let (p, m) = (at(1.0), at(-1.0));
    let fd: Vec<Vector3> = p.iter().zip(&m).map(|(a, b)| (a - b) / (2.0 * h)).collect();
    let err: Vec<Vector3> = fd.iter().zip(&jv).map(|(a, b)| a - b).collect();
    let rel = norm(&err) / norm(&fd);
    // dot-product test through the model update: ⟨J dp, w⟩ = ⟨dp, Jᵀ w⟩
    let w: Vec<Vector3> = (0..grid.n_nodes())
        .map(|i| {
            let t = i as f64;
            Vector3::new((0.37 * t).sin(), (0.11 * t).cos(), (0.23 * t + 1.0).sin())
        })
        .collect();
    let mut bar: ModelTangent = mlin.zero_tangent();
    lin.vjp(&w, &mut bar).unwrap();
    let dpb = mlin.vjp(&bar).unwrap();
    let lhs: f64 = jv.iter().zip(&w).map(|(a, b)| a.dot(b)).sum();
    let rhs: f64 = dp.iter().zip(&dpb).map(|(a, b)| a.dot(b)).sum();
    let dot_rel = (lhs - rhs).abs() / (norm(&jv) * norm(&w));
    let remapped = rep.components.iter().filter(|c| c.remapped).count();
    let smoothed = rep.components.iter().filter(|c| c.passes > 0).count();
    eprintln!(
        "s = {s}, h = {h}: |FD| = {:.4e}, relative error {rel:.3e}; dot {lhs:.12e} vs {rhs:.12e} ({dot_rel:.2e}); {remapped} re-mapped, {smoothed} smoothed",
        norm(&fd)
    );
    Outcome {
        rel,
        dot_rel,
        remapped,
        smoothed,
    }
}

/// The ONERA M6 of SU2's test cases (SolidWorks IGES, imported) with Gmsh's grid, its wall
/// tied to the geometry by classification (Gmsh's wall triangles face the other way: the
/// classification reverses them in (u, v), or every re-map would fail).
#[test]
fn gmsh_grid_on_the_imported_m6_matches_central_differences() {
    let cad = root().join("fixtures/iges/geom_oneram6.igs");
    let bytes = std::fs::read(&cad).unwrap();
    let (mut db, _) = geom_db::import::import_bytes(
        &bytes,
        &cad.display().to_string(),
        &geom_db::import::ImportOptions::default(),
    )
    .unwrap();
    db.assign_control_nodes().unwrap();
    let mesh = mesh::io::read_path(&root().join("fixtures/grids/oneram6.su2")).unwrap();
    let wall = ["wing".to_string()];
    let copts = surfgrid::ClassifyOptions { rel_tol: 1e-5 };
    let (grid, _) = surfgrid::classify_wall(&db, &mesh, &wall, &copts).unwrap();
    for s in [0.0, 1.0] {
        // the IGES's own gaps (a corner lies 5.9e-5, 1.8e-6 of the model, off a surface at
        // the baseline; 3.6e-4 once moved: the imported model has no live junction) are not
        // what is tested here
        let o = check(&db, &grid, s, 3e-3, 1e-3);
        assert!(o.remapped > 0 || s == 0.0);
        assert!(o.rel < 1e-6, "relative error {:.3e}", o.rel);
        assert!(o.dot_rel < 1e-10, "dot-product test {:.3e}", o.dot_rel);
    }
}

/// The project's wing–body with a generated grid: the junction is re-intersected and moves,
/// both surfaces are re-mapped.
#[test]
fn generated_grid_with_a_moving_junction_matches_central_differences() {
    let db = fixture("wing_body");
    let g = generate(
        &db,
        &wing_body_field(&db, 0.15),
        &GenerateOptions::default(),
    )
    .unwrap();
    // Step study (s = 6, where smoothing runs): the error is noise ∝ 3.7e-10 / h below
    // h = 3e-4 (1.7e-6 there, 3.7e-4 at 1e-6) and a changed smoothing decision from
    // h = 1e-3 (3.5e-4); h = 6e-4 gives 6.3e-7. Without smoothing h = 3e-3 gives 2e-7.
    for (s, h) in [(0.0, 3e-3), (1.0, 3e-3), (6.0, 6e-4)] {
        let o = check(&db, &g, s, h, ModelOptions::default().junction_rel_tol);
        assert!(o.remapped >= 2 || s == 0.0);
        assert!(o.smoothed > 0 || s < 6.0, "the large change smooths");
        assert!(o.rel < 1e-6, "relative error {:.3e}", o.rel);
        assert!(o.dot_rel < 1e-10, "dot-product test {:.3e}", o.dot_rel);
    }
}
