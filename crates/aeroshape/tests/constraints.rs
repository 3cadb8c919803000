//! Geometric constraints on the CAD model (issue 46): the measures on a closed analytic-like
//! model (the cube sphere: volume by the divergence theorem along any axis, thickness through
//! the centre, area) and, on the default wing-body case, their Jacobian through the model
//! update against central differences of `Study::constraints`, with a design change that
//! moves the surfaces, and the reverse product's dot-product test.

use std::path::{Path, PathBuf};

use aeroshape::case::{Case, load_design_values};
use aeroshape::constraints::{ConstraintSpec, Measure, Stations, measure};
use aeroshape::study::Study;
use geom_db::eval::ParamSurface;
use geom_db::{GeomDb, SurfaceId};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures")
}

fn spec(name: &str, measure: Measure, relative: bool) -> ConstraintSpec {
    ConstraintSpec {
        name: name.into(),
        measure,
        relative,
        lower: if relative { Some(1.0) } else { None },
        upper: None,
    }
}

fn value(db: &GeomDb, m: Measure) -> f64 {
    let v = measure(db, &spec("m", m, false)).expect("measured");
    assert_eq!(v.len(), 1);
    v[0].value
}

fn read_geometry(path: &Path) -> GeomDb {
    let text = std::fs::read_to_string(path).expect("geometry file");
    GeomDb::from_ron_str(&text, &path.display().to_string()).expect("geometry")
}

fn sphere() -> GeomDb {
    read_geometry(&fixtures().join("geom/sphere.ron"))
}

#[test]
fn constraints_sphere_volume_is_the_same_along_every_axis() {
    let db = sphere();
    let all: Vec<SurfaceId> = (0..db.surfaces.len() as u32).map(SurfaceId).collect();
    let vols: Vec<f64> = [
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 2.0, -0.5],
    ]
    .into_iter()
    .map(|axis| {
        value(
            &db,
            Measure::Volume {
                surfaces: all.clone(),
                axis,
            },
        )
    })
    .collect();
    let exact = 4.0 / 3.0 * std::f64::consts::PI;
    for v in &vols {
        // the closed surface: every axis gives the same integral (exact quadrature; the
        // patches meet to about 1e-12), and the cube sphere's polynomial patches approximate
        // the unit sphere
        assert!((v - vols[0]).abs() <= 1e-10 * exact, "{vols:?}");
        assert!((v - exact).abs() <= 1e-5 * exact, "{v} vs {exact}");
    }
    // one face fewer is not a closed part: the axes disagree
    let open: Vec<SurfaceId> = all[1..].to_vec();
    let (a, b) = (
        value(
            &db,
            Measure::Volume {
                surfaces: open.clone(),
                axis: [1.0, 0.0, 0.0],
            },
        ),
        value(
            &db,
            Measure::Volume {
                surfaces: open,
                axis: [0.0, 1.0, 0.0],
            },
        ),
    );
    assert!((a - b).abs() > 1e-3, "{a} {b}");
    let area = value(&db, Measure::Area { surfaces: all });
    let exact = 4.0 * std::f64::consts::PI;
    assert!((area - exact).abs() <= 1e-5 * exact, "{area} vs {exact}");
}

#[test]
fn constraints_sphere_thickness_through_the_centre_is_the_diameter() {
    let db = sphere();
    let all: Vec<SurfaceId> = (0..db.surfaces.len() as u32).map(SurfaceId).collect();
    for direction in [[0.0, 0.0, 1.0], [1.0, 1.0, 1.0], [0.3, -0.2, 0.9]] {
        let m = measure(
            &db,
            &spec(
                "t",
                Measure::Thickness {
                    surfaces: all.clone(),
                    stations: Stations::Points(vec![[0.0, 0.0, 0.0], [0.5, 0.0, 0.0]]),
                    direction,
                },
                false,
            ),
        )
        .expect("thickness");
        assert_eq!(m.len(), 2);
        assert_eq!(m[1].name, "t[1]");
        assert!(
            (m[0].value - 2.0).abs() < 1e-5,
            "{direction:?}: {}",
            m[0].value
        );
        // off centre along z: the chord 2 √(1 − 0.25) of the unit circle
        if direction == [0.0, 0.0, 1.0] {
            assert!((m[1].value - 3f64.sqrt()).abs() < 1e-5, "{}", m[1].value);
        }
        // the two points lie on the surfaces, on the line
        let th = m[0].thickness().expect("a thickness");
        for (h, p) in [th.lower, th.upper].iter().zip(th.points()) {
            let q = db.surface(h.surface).point(h.uv[0], h.uv[1]);
            assert!((q - p).norm() < 1e-9, "{q} {p}");
        }
    }
}

/// The default case with constraints on its wing (surface 1, tip cap 2): thickness at a
/// 3 × 2 grid between 30 % and 90 % of the span, the wing's volume and its area.
fn default_study() -> (Study, Vec<f64>) {
    let dir = fixtures().join("cases/default");
    let path = dir.join("case.ron");
    let mut case = Case::load(&path).expect("case");
    let db = read_geometry(&dir.join(&case.geometry));
    let wing = db.surface(SurfaceId(1));
    let at = |u: f64, v: f64| {
        let p = wing.point(u, v);
        [p.x, p.y, p.z]
    };
    // u = 2: leading edge, u = 0: trailing edge
    let (le_root, te_root, le_tip, te_tip) =
        (at(2.0, 0.3), at(0.0, 0.3), at(2.0, 0.9), at(0.0, 0.9));
    case.constraints = vec![
        spec(
            "thickness",
            Measure::Thickness {
                surfaces: vec![SurfaceId(1)],
                stations: Stations::Grid {
                    le_root,
                    te_root,
                    le_tip,
                    te_tip,
                    chordwise: vec![0.2, 0.45, 0.7],
                    spanwise: vec![0.0, 1.0],
                },
                direction: [0.0, 0.0, 1.0],
            },
            true,
        ),
        spec(
            "volume",
            Measure::Volume {
                surfaces: vec![SurfaceId(1), SurfaceId(2)],
                axis: [0.0, 0.0, 1.0],
            },
            true,
        ),
        spec(
            "area",
            Measure::Area {
                surfaces: vec![SurfaceId(1)],
            },
            false,
        ),
        // the half fuselage, open on the symmetry plane y = 0 (parallel to the axis z)
        spec(
            "fuselage volume",
            Measure::Volume {
                surfaces: vec![SurfaceId(0)],
                axis: [0.0, 0.0, 1.0],
            },
            false,
        ),
    ];
    let s = Study::new(case, &path).expect("study");
    let dv = load_design_values(&dir.join("dv.ron")).expect("dv");
    let mut x = s.vector_from_values(&dv).expect("x");
    // the stations are fixed in space: no sweep, which would move the tip's leading edge
    // past the stations at 20 % chord
    let sweep = s
        .registry()
        .names()
        .iter()
        .position(|n| *n == "sweep")
        .expect("sweep");
    x[sweep] = 0.0;
    (s, x)
}

fn norm(a: &[f64]) -> f64 {
    a.iter().map(|v| v * v).sum::<f64>().sqrt()
}

/// |a − b| / |b| (infinite for b = 0).
fn rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let d: Vec<f64> = a.iter().zip(b).map(|(p, q)| p - q).collect();
    if norm(b) > 0.0 {
        norm(&d) / norm(b)
    } else {
        f64::INFINITY
    }
}

#[test]
fn constraints_jacobian_agrees_with_central_differences() {
    let (s, x) = default_study();
    let x0 = s.initial();
    // the initial design: every relative constraint is 1
    let c0 = s.constraints(&x0).expect("constraints at x0");
    assert_eq!(c0.len(), 9);
    for (k, c) in c0.iter().enumerate().take(7) {
        assert!((c - 1.0).abs() < 1e-12, "constraint {k}: {c}");
    }
    // the design change moves the surfaces: the tip-side thickness and the volume change
    let c = s.constraints(&x).expect("constraints at x");
    assert!(
        (c[3..6].iter().map(|v| (v - 1.0).abs()).fold(0.0, f64::max)) > 1e-3,
        "{c:?}"
    );
    assert!((c[6] - 1.0).abs() > 1e-4, "volume ratio {}", c[6]);
    let jac = s.constraints_jacobian(&x).expect("jacobian");
    assert_eq!(jac.rows.len(), 9);
    let names = s.registry().names();
    // fourth-order central differences, step a tenth of each variable's scale (the model
    // update's round-off, about 1e-12 of the model size, stays far below the step's effect)
    let n_rows = jac.rows.len();
    let mut fd = vec![vec![0.0; names.len()]; n_rows];
    for l in 0..names.len() {
        let h = 0.1 * s.registry().variables()[l].scale;
        let step = |a: f64| {
            let mut y = x.clone();
            y[l] += a;
            s.constraints(&y).expect("constraints")
        };
        let (p1, m1, p2, m2) = (step(h), step(-h), step(2.0 * h), step(-2.0 * h));
        for (k, row) in fd.iter_mut().enumerate() {
            row[l] = (8.0 * (p1[k] - m1[k]) - (p2[k] - m2[k])) / (12.0 * h);
        }
    }
    // each constraint's gradient: |exact − central difference| / |central difference|
    for (k, (an, fd)) in jac.jacobian.iter().zip(&fd).enumerate() {
        let rel = rel_diff(an, fd);
        eprintln!(
            "{}: |gradient| {:.6e}, relative difference to central differences {rel:.2e}",
            jac.rows[k].name,
            norm(fd)
        );
        assert!(rel < 1e-6, "{}: {an:?} vs {fd:?}", jac.rows[k].name);
    }
    // the thickness variables move the thickness, twist and sweep the volume…
    let col = |n: &str| names.iter().position(|v| *v == n).expect("variable");
    assert!(jac.jacobian[4][col("thick_upper")].abs() > 1e-2);
    assert!(jac.jacobian[6][col("thick_lower")].abs() > 1e-3);
    // …and the fuselage's surface variables its volume
    for v in ["waist_top", "droop_top", "stretch_top"] {
        assert!(jac.jacobian[8][col(v)].abs() > 1e-3, "{v}");
    }
}

#[test]
fn constraints_reverse_product_is_the_transpose() {
    let (s, x) = default_study();
    let jac = s.constraints_jacobian(&x).expect("jacobian");
    let w: Vec<f64> = (0..jac.rows.len()).map(|k| 1.0 + 0.37 * k as f64).collect();
    let xb = s.constraints_vjp(&x, &w).expect("vjp");
    for (l, g) in xb.iter().enumerate() {
        let jt: f64 = jac.jacobian.iter().zip(&w).map(|(r, wk)| r[l] * wk).sum();
        assert!(
            (g - jt).abs() <= 1e-10 * jt.abs().max(1.0),
            "variable {l}: {g} vs {jt}"
        );
    }
}

#[test]
fn constraints_bad_surface_and_missed_line_are_errors() {
    let db = sphere();
    let e = measure(
        &db,
        &spec(
            "t",
            Measure::Thickness {
                surfaces: vec![SurfaceId(0)],
                stations: Stations::Points(vec![[5.0, 5.0, 0.0]]),
                direction: [0.0, 0.0, 1.0],
            },
            false,
        ),
    )
    .unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("station 0") && msg.contains("0 point"),
        "{msg}"
    );
    let e = measure(
        &db,
        &spec(
            "v",
            Measure::Volume {
                surfaces: vec![SurfaceId(0)],
                axis: [0.0, 0.0, 0.0],
            },
            false,
        ),
    )
    .unwrap_err();
    assert!(e.to_string().contains("not a direction"), "{e}");
}

#[test]
fn constraints_section_is_optional_in_case_files() {
    let case = Case::load(&fixtures().join("cases/default/case.ron")).expect("old case loads");
    assert!(case.constraints.is_empty());
    let text = r#"(format_version: 1, geometry: "g.ron", constraints: [
        (name: "t", measure: Thickness(surfaces: [1], stations: Points([(4.0, 2.0, 0.0)])),
         relative: true, lower: Some(1.0)),
        (name: "v", measure: Volume(surfaces: [1, 2])),
    ])"#;
    let c = Case::from_ron_str(text, "case.ron").expect("parses");
    assert_eq!(c.constraints.len(), 2);
    assert_eq!(c.constraints[0].lower, Some(1.0));
}
