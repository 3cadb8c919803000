//! The fuselage's nose droop (Fig. 10) and stretch (Fig. 12) that `case init` builds, each
//! alone at either bound through `run`, on the default wing-body case (its grid as SU2 with
//! the markers renamed): measured on the geometry `run` writes (points sampled on every
//! support surface) and on the deformed grid, against the baseline `case init` wrote.
//!
//! The OpenCASCADE wing-body STEP cannot be used here yet: its import names every face
//! `body`, so `case init` finds no fuselage in it (the CAD-import issue).

use std::path::Path;

use geom_db::eval::ParamSurface;
use geom_db::prelude::Point3;
use geom_db::{GeomDb, SurfaceId};
use param::{LineSupport, Modifier};

use crate::case::{bin, ok, renamed_su2, root};

fn read_db(path: &Path) -> GeomDb {
    let text = std::fs::read_to_string(path).unwrap();
    GeomDb::from_ron_str(&text, &path.display().to_string()).unwrap()
}

/// Points of support surface `s`: 8 × 8 intervals per patch, patch corners included.
fn samples(db: &GeomDb, s: usize) -> Vec<Point3> {
    let surf = db.surface(SurfaceId(s as u32));
    let ([u0, u1], [v0, v1]) = surf.domain();
    let (nu, nv) = (8 * surf.n_u, 8 * surf.n_v);
    let mut out = Vec::new();
    for i in 0..=nu {
        for j in 0..=nv {
            out.push(surf.point(
                u0 + (u1 - u0) * i as f64 / nu as f64,
                v0 + (v1 - v0) * j as f64 / nv as f64,
            ));
        }
    }
    out
}

/// The box of the samples of every support surface.
fn bbox(db: &GeomDb) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for s in 0..db.surfaces.len() {
        for p in samples(db, s) {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
    }
    (lo, hi)
}

/// The sample of lowest x over every support surface (the nose tip).
fn nose_tip(db: &GeomDb) -> Point3 {
    (0..db.surfaces.len())
        .flat_map(|s| samples(db, s))
        .min_by(|a, b| a.x.total_cmp(&b.x))
        .unwrap()
}

#[test]
fn droop_and_stretch_at_either_bound_move_the_nose_and_keep_the_rest() {
    let dir = tempfile::tempdir().unwrap();
    let grid = renamed_su2(dir.path());
    let cad = root().join("fixtures/cases/default/wing_body.ron");
    let case = dir.path().join("case");
    let init = ok(&bin()
        .args(["case", "init"])
        .arg(&cad)
        .arg(&grid)
        .arg("-o")
        .arg(&case)
        .output()
        .unwrap());
    assert!(init.contains("nose droop along -z"), "{init}");
    let c = aeroshape::case::Case::load(&case.join("case.ron")).unwrap();
    // the section where both start: the first patch reaching the junction, which on this
    // fuselage (nose u ∈ [0, 1] over x ∈ [0, 2], cylinder u ∈ [1, 2]) is x = 2
    let mut section = Vec::new();
    let mut upper = Vec::new();
    for want in ["fuselage.droop", "fuselage.stretch"] {
        let m = c
            .parametrisation
            .modifiers
            .iter()
            .find(|m| m.name() == want)
            .unwrap_or_else(|| panic!("{want} missing: {init}"));
        let Modifier::Line(l) = m else {
            panic!("{want} is not a line modifier")
        };
        let LineSupport::Axis(a) = &l.line else {
            panic!("{want} is not along an axis")
        };
        section.push(a.point.x);
        upper.push(l.variables[0].upper);
        assert_eq!(l.variables[0].lower, -l.variables[0].upper);
        assert!(init.contains(want), "{init}");
    }
    assert_eq!(section[0], section[1]);
    let xs = section[0];
    assert!((xs - 2.0).abs() < 1e-9, "section at x = {xs}");
    let base_db = read_db(&case.join("geometry.ron"));
    let lref = base_db.reference_length();
    let base_grid = mesh::io::read_path(&case.join("grid.msh")).unwrap();
    let wall: Vec<u32> = c
        .wall
        .iter()
        .flat_map(|w| base_grid.marker(w).unwrap().elements.node_set())
        .collect();
    let grid_tip = *wall
        .iter()
        .min_by(|&&a, &&b| {
            base_grid.coords[a as usize][0].total_cmp(&base_grid.coords[b as usize][0])
        })
        .unwrap();
    let (tip0, (lo0, hi0)) = (nose_tip(&base_db), bbox(&base_db));
    // the patches behind the section in the baseline (every control node at x ≥ x_s)
    let behind = |s: usize, p: usize| {
        base_db.surfaces[s].control.nodes[p]
            .iter()
            .all(|n| base_db.control_nodes[n.index()].x >= xs)
    };
    for (k, name) in ["fuselage.droop", "fuselage.stretch"].iter().enumerate() {
        for sign in [1.0, -1.0] {
            let v = sign * upper[k];
            let dv = dir.path().join("dv.ron");
            std::fs::write(&dv, format!("{{{name:?}: {v}}}")).unwrap();
            let out = dir.path().join(format!("out_{k}_{sign}"));
            ok(&bin()
                .arg("run")
                .arg(case.join("case.ron"))
                .arg("--dv")
                .arg(&dv)
                .arg("-o")
                .arg(&out)
                .arg("--no-pictures")
                .output()
                .unwrap());
            let rep: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap())
                    .unwrap();
            assert_eq!(
                rep["evaluation"]["quality_after"]["inverted"], 0,
                "{name} = {v}"
            );
            let db = read_db(&out.join("geometry.ron"));
            // the expected motion of the nose tip: down by v, or forward by v
            let want = if k == 0 {
                [0.0, 0.0, -v]
            } else {
                [-v, 0.0, 0.0]
            };
            let tip = nose_tip(&db);
            let moved = tip - tip0;
            for c in 0..3 {
                assert!(
                    (moved[c] - want[c]).abs() <= 1e-9 * lref,
                    "{name} = {v}: the nose tip moved by {moved:?}, want {want:?}"
                );
            }
            // the box: a stretch lengthens the fuselage by v at the nose; a droop keeps
            // the length
            let (lo, hi) = bbox(&db);
            assert!(
                (lo[0] - lo0[0] - want[0]).abs() <= 1e-9 * lref,
                "{name}: x from {lo:?}"
            );
            assert!((hi[0] - hi0[0]).abs() <= 1e-12 * lref);
            let length = hi[0] - lo[0];
            eprintln!(
                "{name} = {v:+.6}: nose tip {tip0:?} -> {tip:?}, length {:.12} -> {length:.12}",
                hi0[0] - lo0[0]
            );
            // every patch behind the section keeps its bits, the wing's included
            let mut kept = 0;
            for s in 0..db.surfaces.len() {
                for p in 0..db.surfaces[s].patches.len() {
                    if behind(s, p) {
                        kept += 1;
                        let bits = |db: &GeomDb| -> Vec<u64> {
                            db.surfaces[s].patches[p]
                                .coeffs
                                .iter()
                                .flat_map(|q| {
                                    q.coords.iter().map(|c| c.to_bits()).collect::<Vec<_>>()
                                })
                                .collect()
                        };
                        assert_eq!(bits(&db), bits(&base_db), "{name}: surface {s} patch {p}");
                    }
                }
            }
            assert_eq!(
                kept,
                db.surfaces.iter().map(|s| s.patches.len()).sum::<usize>() - 2
            );
            // the grid: the nose tip node moves by the same vector; the wall nodes behind
            // the section stay (to the junction's re-intersection, ~1e-12 of the model)
            let moved_grid = mesh::io::read_path(&out.join("deformed.su2")).unwrap();
            let (a, b) = (
                base_grid.coords[grid_tip as usize],
                moved_grid.coords[grid_tip as usize],
            );
            for c in 0..3 {
                assert!(
                    (b[c] - a[c] - want[c]).abs() <= 1e-12 * lref,
                    "{name}: grid tip {a:?} -> {b:?}"
                );
            }
            let mut worst = 0.0f64;
            for &n in &wall {
                let (a, b) = (base_grid.coords[n as usize], moved_grid.coords[n as usize]);
                if a[0] >= xs {
                    let d = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2) + (b[2] - a[2]).powi(2))
                        .sqrt();
                    worst = worst.max(d);
                }
            }
            eprintln!("{name} = {v:+.6}: wall nodes behind x = {xs}: largest move {worst:.3e}");
            assert!(
                worst <= 1e-10 * lref,
                "{name}: a wall node behind the section moved {worst:e}"
            );
        }
    }
}
