//! Issue 19, "done when": the OpenCASCADE wing-body imported from STEP (the closed wing
//! and the periodic one) is parametrisable at once. `param list` works on a case built on
//! it; `param apply` with a tip twist of ±3°, a sweep of 5 % of the span, a tip section
//! (thickness and chord) scaled by ±10 % and a fuselage waist of 2 % of its radius at the
//! junction succeeds and moves the model. The junctions (curves with two defining surfaces,
//! re-intersected by Eq. 12) are sampled at 4 points per arc (at least 200) and their
//! distance to both surfaces measured by this test's own projection (geom-db's global point
//! inversion, an upper bound): within 1e-8 of the model size after the import and after
//! every change. The ignored test measures the same with OpenCASCADE (`cargo xtask regress`).

use std::path::{Path, PathBuf};
use std::process::Command;

use geom_db::GeomDb;
use geom_db::eval::{ParamCurve, ParamSurface};
use geom_db::invert::{InvertOptions, SurfaceInverter};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_aeroshape"))
}

fn cad(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/cad")
        .join(name)
}

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn load(path: &Path) -> GeomDb {
    GeomDb::from_ron_str(&std::fs::read_to_string(path).unwrap(), "g").unwrap()
}

/// The surface of the (first) component whose name starts with `role.`.
fn surface_of(db: &GeomDb, role: &str) -> usize {
    db.surface_components
        .iter()
        .find(|c| c.name.starts_with(&format!("{role}.")))
        .unwrap_or_else(|| panic!("no {role}"))
        .surface
        .index()
}

/// The case: tip twist, sweep and tip scale (thickness and chord ±10 %, the tip cap with
/// them) by the wing's station master (deviations at the tip interpolated linearly from the
/// root), and a fuselage waist by a normal offset of the fuselage decaying from its
/// iso-line through the junction.
fn case_text(db: &GeomDb) -> String {
    let wing = surface_of(db, "wing");
    let tip = surface_of(db, "wing_tip");
    let fus = surface_of(db, "fuselage");
    // The fuselage's iso-line through the middle of the junction (in x), and the
    // parametric width of ±1 m along it.
    let junction: Vec<geom_db::prelude::Point3> = db
        .curves
        .iter()
        .filter(|c| {
            let mut s: Vec<usize> = c.defining_surfaces.iter().map(|s| s.index()).collect();
            s.sort_unstable();
            s == [wing.min(fus), wing.max(fus)]
        })
        .flat_map(|c| (0..=64).map(move |k| c.point(c.arcs.len() as f64 * k as f64 / 64.0)))
        .collect();
    assert!(
        !junction.is_empty(),
        "the junction has its two defining surfaces"
    );
    let xj = junction.iter().map(|p| p.x).sum::<f64>() / junction.len() as f64;
    let fs = db.surface(geom_db::SurfaceId::from_index(fus));
    let ([u0, u1], [v0, v1]) = fs.domain();
    let along = |v: f64| fs.point(0.5 * (u0 + u1), v).x;
    let vs: Vec<f64> = (0..=4000)
        .map(|k| v0 + (v1 - v0) * k as f64 / 4000.0)
        .collect();
    let nearest = |x: f64| {
        *vs.iter()
            .min_by(|a, b| (along(**a) - x).abs().total_cmp(&(along(**b) - x).abs()))
            .unwrap()
    };
    let vj = nearest(xj);
    let width = (nearest(xj + 1.0) - nearest(xj - 1.0)).abs();
    format!(
        r#"(
  format_version: 1,
  geometry: "geom.ron",
  parametrisation: (
    modifiers: [
      Master(
        name: "planform",
        links: (surfaces: [{wing}, {tip}]),
        source: Stations(
          surface: {wing},
          spanwise: V,
          n_s: 161,
          n_t: 9,
          axis: (0.0, 1.0, 0.0),
          reference: ((3.5, 0.0, -0.1), (5.5315, 5.0, 0.15)),
          stations: [
            (t: 0.0),
            (t: 1.0, twist: "twist", scale: "tip_scale", shift: ("sweep", None, None)),
          ],
        ),
        variables: [
          (name: "twist", lower: -0.1, upper: 0.1, scale: 0.01, group: "wing"),
          (name: "sweep", lower: -0.5, upper: 0.5, scale: 0.1, group: "wing"),
          (name: "tip_scale", lower: -0.3, upper: 0.3, scale: 0.1, group: "wing"),
        ],
      ),
      Line(
        name: "waist",
        line: Iso(surface: {fus}, fixed: V, at: {vj:e}),
        basis: Bernstein(degree: 0),
        direction: Normal,
        decay: Cosine(width: {width:e}),
        variables: [(name: "waist", lower: -0.05, upper: 0.05, scale: 0.01, group: "fuselage")],
      ),
    ],
    constraints: [],
  ),
)
"#
    )
}

/// Largest distance of the junctions (curves with two defining surfaces) from their
/// surfaces, 4 samples per arc of each curve component (at least 200).
pub(crate) fn junction_gap(db: &GeomDb) -> f64 {
    let opts = InvertOptions::for_model(db);
    let mut worst: f64 = 0.0;
    for cc in &db.curve_components {
        let c = db.curve(cc.curve);
        if c.defining_surfaces.len() != 2 {
            continue;
        }
        let n = (4 * c.arcs.len()).max(200);
        for s in &c.defining_surfaces {
            let inv = SurfaceInverter::new("s", db.surface(*s), &opts).unwrap();
            for k in 0..n {
                let p = c.point(cc.param_at(k as f64 / (n - 1) as f64));
                worst = worst.max(inv.nearest_indexed(&p, k).unwrap().distance);
            }
        }
    }
    worst
}

/// The design-variable changes of the issue: tip twist ±3°, sweep 5 % of the span, tip
/// scale ±10 %, fuselage waist ±2 % of its radius (0.8 m; span 5 m).
fn changes() -> Vec<(&'static str, f64)> {
    let (waist, sweep, twist) = (0.02 * 0.8, 0.05 * 5.0, 3f64.to_radians());
    vec![
        ("twist", twist),
        ("twist", -twist),
        ("sweep", sweep),
        ("tip_scale", 0.1),
        ("tip_scale", -0.1),
        ("waist", -waist),
        ("waist", waist),
    ]
}

/// Imports `file` into `dir`, builds the case, runs `param list`, then `param apply` for
/// every change: the imported model and (name, value, changed model) per change.
fn import_and_apply(file: &str, dir: &Path) -> (GeomDb, Vec<(&'static str, f64, GeomDb)>) {
    let geom = dir.join("geom.ron");
    let o = bin()
        .args(["geom", "import"])
        .arg(cad(file))
        .arg("-o")
        .arg(&geom)
        .output()
        .unwrap();
    assert!(o.status.success(), "{file}: {}", stderr(&o));
    let db = load(&geom);
    assert!(!db.control_nodes.is_empty(), "{file}");
    let case = dir.join("case.ron");
    std::fs::write(&case, case_text(&db)).unwrap();
    let o = bin().args(["param", "list"]).arg(&case).output().unwrap();
    assert!(o.status.success(), "{file}: {}", stderr(&o));
    let mut out = Vec::new();
    for (name, value) in changes() {
        let dv = dir.join("dv.ron");
        std::fs::write(&dv, format!("{{\"{name}\": {value:e}}}")).unwrap();
        let changed = dir.join(format!("out_{name}_{value:.4}.ron"));
        let o = bin()
            .args(["param", "apply"])
            .arg(&case)
            .arg("--dv")
            .arg(&dv)
            .arg("-o")
            .arg(&changed)
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{file} {name} = {value}: {}",
            stderr(&o)
        );
        out.push((name, value, load(&changed)));
    }
    (db, out)
}

/// The STEP files: the closed wing (rational B-spline) and the periodic one.
const FILES: [&str; 2] = ["wing_body_ap214_m.stp", "wing_body_periodic_ap214_m.stp"];

#[test]
fn imported_wing_body_takes_twist_sweep_thickness_and_waist() {
    let mut worst = Vec::new();
    // IGES faces and IGES B-rep import to the same model as STEP within 3e-11 m (the
    // files' 10 significant digits), so the suite runs STEP.
    for file in FILES {
        let dir = tempfile::tempdir().unwrap();
        let (db, changed) = import_and_apply(file, dir.path());
        let size = db.reference_length();
        let tol = 1e-8 * size;
        let gap = junction_gap(&db);
        assert!(gap <= tol, "{file}: imported junction gap {gap:e}");
        for (name, value, moved) in changed {
            let gap = junction_gap(&moved);
            eprintln!("{file} {name} = {value:.4}: junction gap {gap:.3e} (model size {size:.4})");
            // The variable did something: control nodes moved by about its size.
            let moved_by = db
                .control_nodes
                .iter()
                .zip(&moved.control_nodes)
                .map(|(a, b)| (a - b).norm())
                .fold(0.0, f64::max);
            assert!(
                moved_by >= 0.01 * value.abs(),
                "{file} {name} = {value}: {moved_by}"
            );
            worst.push((file, name, value, gap, tol));
        }
    }
    for &(file, name, value, gap, tol) in &worst {
        eprintln!("{file} {name} = {value:.4}: sampled junction gap {gap:.3e}");
        assert!(
            gap <= tol,
            "{file} {name} = {value}: junction gap {gap:e} > {tol:e}"
        );
    }
}

/// OpenCASCADE's view of the changed models: each is written as IGES (geom-db's
/// `to_iges`), its junction sampled at 200 points (at least 2 per arc; OpenCASCADE takes
/// about 0.1 s a point here), and `fixtures/cad/oracle.py
/// distance --face F,W` measures each sample's distance to the fuselage and wing faces with
/// OpenCASCADE's own foot of the normal. Run by `cargo xtask regress`; skipped with a
/// message when `import OCP` fails.
#[test]
#[ignore = "needs OpenCASCADE (cadquery-ocp); run by cargo xtask regress"]
fn occ_agrees_the_changed_junctions_are_on_both_surfaces() {
    let probe = Command::new("python3").args(["-c", "import OCP"]).output();
    if !probe.is_ok_and(|o| o.status.success()) {
        eprintln!("skipped: OpenCASCADE (python3 -c 'import OCP') is not installed");
        return;
    }
    for file in FILES {
        let dir = tempfile::tempdir().unwrap();
        let (db, changed) = import_and_apply(file, dir.path());
        let tol = 1e-8 * db.reference_length();
        for (name, value, moved) in changed {
            let d = occ_junction_distance(&moved, dir.path());
            eprintln!(
                "{file} {name} = {value:.4}: OpenCASCADE junction distance {:.3e} / {:.3e}",
                d[0], d[1]
            );
            assert!(d[0] <= tol && d[1] <= tol, "{file} {name} = {value}: {d:?}");
        }
    }
}

/// The largest distance of every junction's samples (200, at least 2 per arc) to the faces of its two
/// defining surfaces, by `oracle.py distance` on the model written as IGES.
fn occ_junction_distance(db: &GeomDb, dir: &Path) -> [f64; 2] {
    let igs = dir.join("changed.igs");
    let mut text = Vec::new();
    geom_db::import::to_iges(db, "changed.igs")
        .write(&mut text, "changed.igs")
        .unwrap();
    std::fs::write(&igs, &text).unwrap();
    let face_of = |s: geom_db::SurfaceId| {
        db.surface_components
            .iter()
            .position(|c| c.surface == s)
            .unwrap()
    };
    let mut worst = [0.0f64; 2];
    for c in db.curves.iter().filter(|c| c.defining_surfaces.len() == 2) {
        let faces = [
            face_of(c.defining_surfaces[0]),
            face_of(c.defining_surfaces[1]),
        ];
        let n = (2 * c.arcs.len()).max(200);
        let mut csv = String::from("x,y,z\n");
        for k in 0..=n {
            let p = c.point(c.arcs.len() as f64 * k as f64 / n as f64);
            csv.push_str(&format!("{:.17e},{:.17e},{:.17e}\n", p.x, p.y, p.z));
        }
        let pts = dir.join("junction.csv");
        std::fs::write(&pts, csv).unwrap();
        let out = Command::new("python3")
            .arg(cad("oracle.py"))
            .arg("distance")
            .arg(&igs)
            .arg(&pts)
            .arg("--face")
            .arg(format!("{},{}", faces[0], faces[1]))
            .output()
            .unwrap();
        assert!(out.status.success(), "oracle: {}", stderr(&out));
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let unit = match v["unit"].as_str().map(str::to_ascii_lowercase).as_deref() {
            Some("mm") => 1e-3,
            Some("m") | None => 1.0,
            Some(u) => panic!("unexpected unit {u}"),
        };
        for p in v["points"].as_array().unwrap() {
            for (k, f) in faces.iter().enumerate() {
                let d = p["per_face"][f.to_string()]["distance"].as_f64().unwrap() * unit;
                worst[k] = worst[k].max(d);
            }
        }
    }
    worst
}
