//! `aeroshape case init` then `param list` and `run`, the three-command workflow, on grids
//! whose markers carry no component names and no entity tags: the default case's grid as
//! SU2 with its markers renamed, the OpenCASCADE split wing (STEP) and the ONERA M6
//! (SolidWorks IGES), each with the Gmsh grid made from it. With every default variable at 30 % of its bound at once: no inverted cell,
//! wall nodes on the updated geometry (independent projection), far field exactly fixed,
//! symmetry nodes in their plane.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use geom_db::GeomDb;
use geom_db::eval::ParamCurve;
use geom_db::prelude::Point3;

pub(crate) fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_aeroshape"))
}

pub(crate) fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

pub(crate) fn ok(o: &Output) -> String {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// The default case's grid as SU2, markers renamed, no entity tags or parameters.
pub(crate) fn renamed_su2(dir: &Path) -> PathBuf {
    let mut g = mesh::io::read_path(&root().join("fixtures/cases/default/grid.msh")).unwrap();
    for (i, m) in g.markers.iter_mut().enumerate() {
        m.name = format!("zone_{i}");
    }
    g.classes = None;
    g.parametric = false;
    let p = dir.join("user.su2");
    let mut f = std::fs::File::create(&p).unwrap();
    mesh::io::write(&g, mesh::io::Format::Su2, &mut f).unwrap();
    p
}

/// `case init`, `param list`, then `run` with every variable at `frac` of its upper bound;
/// checks the outputs. Returns the init output.
fn three_commands(cad: &Path, grid: &Path, dir: &Path, frac: f64, require_vars: bool) -> String {
    let case = dir.join("case");
    let init = ok(&bin()
        .args(["case", "init"])
        .arg(cad)
        .arg(grid)
        .arg("-o")
        .arg(&case)
        .output()
        .unwrap());
    let list = ok(&bin()
        .args(["param", "list"])
        .arg(case.join("case.ron"))
        .arg("--json")
        .output()
        .unwrap());
    let list: serde_json::Value = serde_json::from_str(&list).unwrap();
    let vars = list["variables"].as_array().unwrap();
    assert!(!require_vars || !vars.is_empty(), "a default design space");
    let dv: Vec<String> = vars
        .iter()
        .map(|v| {
            format!(
                "{:?}: {}",
                v["name"].as_str().unwrap(),
                frac * v["upper"].as_f64().unwrap()
            )
        })
        .collect();
    let dv_path = dir.join("dv.ron");
    std::fs::write(&dv_path, format!("{{{}}}", dv.join(", "))).unwrap();
    let out = dir.join("out");
    ok(&bin()
        .arg("run")
        .arg(case.join("case.ron"))
        .arg("--dv")
        .arg(&dv_path)
        .arg("-o")
        .arg(&out)
        .arg("--no-pictures")
        .output()
        .unwrap());
    let rep: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(rep["evaluation"]["quality_after"]["inverted"], 0);
    // the roles case init wrote, read back from the case
    let c = aeroshape::case::Case::load(&case.join("case.ron")).unwrap();
    let base = mesh::io::read_path(&case.join("grid.msh")).unwrap();
    let moved = mesh::io::read_path(&out.join("deformed.su2")).unwrap();
    // the far-field displacement of the report against an independent maximum
    let (_, nodes, max) = crate::reach::far_field(&base, &moved, &c.wall);
    let ev = &rep["evaluation"];
    assert_eq!(
        ev["deform"]["report"]["far_field"]["nodes"]
            .as_u64()
            .unwrap() as usize,
        nodes
    );
    testkit::assert_close!(
        ev["far_field_max_displacement"].as_f64().unwrap(),
        max,
        rel = 1e-9,
        abs = 1e-15
    );
    for f in &c.fixed {
        for v in base.marker(f).unwrap().elements.node_set() {
            assert_eq!(
                moved.coords[v as usize], base.coords[v as usize],
                "fixed {f} node {v}"
            );
        }
    }
    for sl in &c.slide {
        let nodes = base.marker(sl).unwrap().elements.node_set();
        // each node moves within the marker's plane (fitted to the baseline nodes)
        let pts: Vec<[f64; 3]> = nodes.iter().map(|&v| base.coords[v as usize]).collect();
        let (_, n, _) = deform::bc::fit_plane(&pts, 3);
        let mut worst = 0.0f64;
        for &v in &nodes {
            let (p, q) = (base.coords[v as usize], moved.coords[v as usize]);
            let d: f64 = (0..3).map(|k| (q[k] - p[k]) * n[k]).sum();
            worst = worst.max(d.abs());
        }
        assert!(
            worst <= 1e-9 * base.bbox_diagonal(),
            "{sl}: a node left its plane by {worst:e}"
        );
    }
    // wall nodes on the updated geometry, by projection on every surface component
    let text = std::fs::read_to_string(out.join("geometry.ron")).unwrap();
    let db = GeomDb::from_ron_str(&text, "geometry.ron").unwrap();
    let lref = db.reference_length();
    let proj = surfgrid::classify::component_projectors(&db).unwrap();
    let mut worst = 0.0f64;
    for w in &c.wall {
        for v in base.marker(w).unwrap().elements.node_set() {
            let q = moved.coords[v as usize];
            let p = Point3::new(q[0], q[1], q[2]);
            let (d, _) = surfgrid::classify::node_distance(&proj, &p).unwrap();
            worst = worst.max(d / lref);
        }
    }
    assert!(
        worst <= 1e-8,
        "wall node {worst:e} of the model size off the updated geometry"
    );
    init
}

#[test]
fn init_list_and_run_on_a_renamed_su2_grid() {
    let dir = tempfile::tempdir().unwrap();
    let grid = renamed_su2(dir.path());
    let cad = root().join("fixtures/cases/default/wing_body.ron");
    let init = three_commands(&cad, &grid, dir.path(), 0.3, true);
    // by shape: the two body markers are wall, the plane slides, the box is the far field
    for want in ["wall", "slide", "fixed"] {
        assert!(init.contains(want), "{init}");
    }
    assert!(
        init.contains("far field: its box holds every other marker"),
        "{init}"
    );
    // the paper's variables: the wing master (planform, twist, thickness, camber), the
    // fuselage waist at the wing junction (Fig. 9), nose droop (Fig. 10) and stretch (Fig. 12)
    for want in [
        "fuselage.waist",
        "fuselage.droop",
        "fuselage.stretch",
        "wing.sweep",
        "wing.twist.tip",
        "wing.chord.tip",
        "wing.tmax.tip",
        "wing.camber.tip",
    ] {
        assert!(init.contains(want), "{want} missing: {init}");
    }
}

/// The OpenCASCADE split wing (upper and lower faces on separate surfaces, AP214 STEP) with
/// the Gmsh grid made from it (`fixtures/grids/split_wing.su2`): a wing master over the two
/// faces, every variable at 30 % of its bound at once.
#[test]
fn init_list_and_run_on_an_occ_step_split_wing_and_its_gmsh_grid() {
    let dir = tempfile::tempdir().unwrap();
    let cad = root().join("fixtures/cad/split_wing_ap214_m.stp");
    let grid = root().join("fixtures/grids/split_wing.su2");
    let init = three_commands(&cad, &grid, dir.path(), 0.3, true);
    assert!(init.contains("STEP uncertainty"), "{init}");
    assert!(init.contains("split at the leading edge"), "{init}");
    for want in ["wing.twist.root", "wing.tmax.root", "wing.sweep"] {
        assert!(init.contains(want), "{want} missing: {init}");
    }
}

/// The ONERA M6 of SU2's test cases (SolidWorks IGES, upper and lower faces separate) with
/// the Gmsh grid made from it (`fixtures/grids/oneram6.su2`): a wing master over the two
/// faces (twist, sweep, chord, thickness, camber), every variable at 30 % of its bound.
#[test]
fn init_list_and_run_on_the_m6_iges_and_its_gmsh_grid() {
    let dir = tempfile::tempdir().unwrap();
    let cad = root().join("fixtures/iges/geom_oneram6.igs");
    let grid = root().join("fixtures/grids/oneram6.su2");
    let init = three_commands(&cad, &grid, dir.path(), 0.3, true);
    assert!(init.contains("sewing gap"), "{init}");
    // The grid's wall nodes (on OpenCASCADE's edges, made from the file's curves) lie on the
    // imported model within 1e-8 of its size: each edge on the borders of two supports (the
    // tip edges: a wing surface's and a tip cap's, 3.5e-7 m apart) follows the one the
    // file's curve fits (5.1e-9 m; 3.5e-7 m on the other), and a tip thickness change keeps
    // the lower surface's boundary nodes on it.
    let db = GeomDb::from_ron_str(
        &std::fs::read_to_string(dir.path().join("case/geometry.ron")).unwrap(),
        "geometry.ron",
    )
    .unwrap();
    let dist: f64 = init
        .split("distance max ")
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no wall distance in {init}"));
    assert!(
        dist <= 1e-8 * db.reference_length(),
        "wall nodes {dist:e} off the imported model"
    );
    assert!(init.contains("split at the leading edge"), "{init}");
    for want in ["wall", "slide", "fixed"] {
        assert!(init.contains(want), "{init}");
    }
    for want in [
        "wing.sweep",
        "wing.twist.root",
        "wing.twist.tip",
        "wing.chord.tip",
        "wing.tmax.tip",
        "wing.camber.tip",
    ] {
        assert!(init.contains(want), "{want} missing: {init}");
    }
}

/// The OpenCASCADE wing-body (AP214 STEP: fuselage, wing, tip and tail caps) with the Gmsh
/// grid made from it (`fixtures/grids/wing_body.su2`), the user case of issue 20 on the
/// import of issue 19: `case init` finds the wing and the fuselage by shape and builds the
/// wing master and the waist; every variable at 30 % of its bound at once passes
/// [`three_commands`]'s checks. Then a tip twist at its bound: no inverted cell, and the
/// wing-fuselage junction, re-intersected (Eq. 12), is sampled by `run` (≥ 200 points,
/// `report.json`) and by this test's own projection on both surfaces, each within 1e-8 of
/// the model size.
#[test]
fn init_list_and_run_on_the_occ_wing_body_step_and_its_gmsh_grid() {
    let dir = tempfile::tempdir().unwrap();
    let cad = root().join("fixtures/cad/wing_body_ap214_m.stp");
    let grid = root().join("fixtures/grids/wing_body.su2");
    let init = three_commands(&cad, &grid, dir.path(), 0.3, true);
    assert!(init.contains("STEP uncertainty"), "{init}");
    for want in [
        "fuselage.waist",
        "wing.sweep",
        "wing.twist.tip",
        "wing.chord.tip",
        "wing.tmax.tip",
    ] {
        assert!(init.contains(want), "{want} missing: {init}");
    }
    let case = dir.path().join("case/case.ron");
    let c = aeroshape::case::Case::load(&case).unwrap();
    let twist = c
        .parametrisation
        .modifiers
        .iter()
        .flat_map(|m| m.variables())
        .find(|v| v.name == "wing.twist.tip")
        .unwrap()
        .upper;
    assert!(twist > 0.0);
    let dv = dir.path().join("twist.ron");
    std::fs::write(&dv, format!("{{\"wing.twist.tip\": {twist:e}}}")).unwrap();
    let out = dir.path().join("twist");
    ok(&bin()
        .arg("run")
        .arg(&case)
        .arg("--dv")
        .arg(&dv)
        .arg("-o")
        .arg(&out)
        .arg("--no-pictures")
        .output()
        .unwrap());
    let rep: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("report.json")).unwrap()).unwrap();
    assert_eq!(rep["evaluation"]["quality_after"]["inverted"], 0);
    let model = &rep["evaluation"]["model"];
    assert!(
        model["curves_reintersected"].as_u64().unwrap() >= 1,
        "{model}"
    );
    let db = GeomDb::from_ron_str(
        &std::fs::read_to_string(out.join("geometry.ron")).unwrap(),
        "geometry.ron",
    )
    .unwrap();
    let tol = 1e-8 * db.reference_length();
    let junctions = model["junctions"].as_array().unwrap();
    assert!(!junctions.is_empty(), "{model}");
    for j in junctions {
        assert!(j["samples"].as_u64().unwrap() >= 200, "{j}");
        for d in j["max"].as_array().unwrap() {
            assert!(d.as_f64().unwrap() <= tol, "{j}");
        }
    }
    // the junction moved with the wing, and this test's projection agrees
    let base = GeomDb::from_ron_str(
        &std::fs::read_to_string(dir.path().join("case/geometry.ron")).unwrap(),
        "geometry.ron",
    )
    .unwrap();
    let k = base
        .curves
        .iter()
        .position(|c| c.defining_surfaces.len() == 2)
        .expect("a junction with its two defining surfaces");
    let moved = (0..=20)
        .map(|i| {
            let t = base.curves[k].arcs.len() as f64 * i as f64 / 20.0;
            (base.curves[k].point(t) - db.curves[k].point(t)).norm()
        })
        .fold(0.0, f64::max);
    assert!(moved > 1e-4, "the junction did not move ({moved:e})");
    let gap = crate::cad_param::junction_gap(&db);
    assert!(
        gap <= tol,
        "junction {gap:e} off its surfaces (tolerance {tol:e})"
    );
}

/// A geometric database without control nodes is refused in one line naming the file.
#[test]
fn init_refuses_a_geometry_without_control_nodes() {
    let dir = tempfile::tempdir().unwrap();
    let grid = renamed_su2(dir.path());
    let text =
        std::fs::read_to_string(root().join("fixtures/cases/default/wing_body.ron")).unwrap();
    let mut db = GeomDb::from_ron_str(&text, "wing_body.ron").unwrap();
    db.control_nodes.clear();
    for c in &mut db.curves {
        c.control = Default::default();
    }
    for s in &mut db.surfaces {
        s.control = Default::default();
    }
    let cad = dir.path().join("bare.ron");
    let mut f = std::fs::File::create(&cad).unwrap();
    db.write_ron(&mut f).unwrap();
    drop(f);
    let o = bin()
        .args(["case", "init"])
        .arg(&cad)
        .arg(&grid)
        .arg("-o")
        .arg(dir.path().join("case"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(
        err.contains("bare.ron: the geometry has no control nodes"),
        "{err}"
    );
    assert!(!dir.path().join("case/case.ron").exists());
}

/// `case check` on the default case: the whole box fails (its nose droop and stretch crush
/// the same cells together, issue 44), the box is shrunk, and the case written with the
/// shrunk bounds loads with every bound scaled about the initial design by its variable's
/// scale in the JSON (each between the common scale printed and 1);
/// the JSON holds every sample and the picture is a PNG.
#[test]
fn check_shrinks_the_default_box_and_writes_the_shrunk_case() {
    let dir = tempfile::tempdir().unwrap();
    let case = root().join("fixtures/cases/default/case.ron");
    let (shrunk, json, png) = (
        dir.path().join("shrunk.ron"),
        dir.path().join("box.json"),
        dir.path().join("pairs.png"),
    );
    let out = ok(&bin()
        .args(["case", "check"])
        .arg(&case)
        .args(["--samples", "4", "--corners", "2", "--shrink-steps", "2"])
        .arg("-o")
        .arg(&shrunk)
        .arg("--json")
        .arg(&json)
        .arg("--picture")
        .arg(&png)
        .output()
        .unwrap());
    assert!(out.contains("whole box: "), "{out}");
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(
        r["unit"].as_array().unwrap().len(),
        6,
        "2 corners + 4 samples"
    );
    let full = r["rounds"][0]["results"].as_array().unwrap();
    assert!(
        full.iter().any(|s| s["valid"] == false),
        "the default box fails somewhere: {out}"
    );
    let scale = r["scale"].as_f64().unwrap();
    assert!(scale > 0.0 && scale < 1.0, "{out}");
    assert!(out.contains(&format!("common scale {scale:.4}")), "{out}");
    let scales: Vec<f64> = r["scales"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_f64().unwrap())
        .collect();
    assert!(
        scales.iter().all(|&s| (scale..=1.0).contains(&s)),
        "{scales:?}"
    );
    let (a, b) = (
        aeroshape::case::Case::load(&case).unwrap(),
        aeroshape::case::Case::load(&shrunk).unwrap(),
    );
    let vars = |c: &aeroshape::case::Case| -> Vec<param::DesignVariable> {
        c.parametrisation
            .modifiers
            .iter()
            .flat_map(|m| m.variables())
            .cloned()
            .collect()
    };
    let (va, vb) = (vars(&a), vars(&b));
    assert_eq!(va.len(), vb.len());
    for ((x, y), s) in va.iter().zip(&vb).zip(&scales) {
        for (l, m) in [(x.lower, y.lower), (x.upper, y.upper)] {
            testkit::assert_close!(m, x.value + s * (l - x.value), rel = 1e-12, abs = 1e-15);
        }
    }
    // the shrunk case runs from its own folder (paths made absolute)
    ok(&bin().args(["param", "list"]).arg(&shrunk).output().unwrap());
    assert_eq!(&std::fs::read(&png).unwrap()[1..4], b"PNG");
}

/// A design that inverts cells (a corner of the default box: the nose drooped and sheared,
/// the top stretched forward and the bottom aft) exits 1 and leaves the failed grid and what
/// moved its cells: `failed.json` names the cells with their kinds, and the nose variables
/// first; `failed.vtu` holds the grid, in which the named tetrahedron's volume, computed
/// here from its nodes, has turned negative from positive in the baseline.
#[test]
fn run_writes_the_failed_grid_and_the_variables_that_moved_its_cells() {
    let dir = tempfile::tempdir().unwrap();
    let dv = dir.path().join("corner.ron");
    std::fs::write(
        &dv,
        "{\"twist\": 0.1, \"taper\": -0.3, \"sweep\": -0.8, \"dihedral\": 0.3, \
         \"thick_lower\": 0.03, \"thick_upper\": -0.03, \"waist_bottom\": -0.2, \
         \"waist_top\": -0.2, \"droop_bottom\": -0.3, \"droop_top\": -0.3, \
         \"stretch_bottom\": -0.5, \"stretch_top\": 0.5}",
    )
    .unwrap();
    let out = dir.path().join("out");
    let case = root().join("fixtures/cases/default/case.ron");
    let o = bin()
        .arg("run")
        .arg(&case)
        .arg("--dv")
        .arg(&dv)
        .arg("-o")
        .arg(&out)
        .arg("--no-pictures")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("failed.vtu") && err.contains("inverted cells"),
        "{err}"
    );
    let f: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("failed.json")).unwrap()).unwrap();
    let cells = f["cells"].as_array().unwrap();
    assert!(!cells.is_empty() && f["inverted"].as_u64().unwrap() >= cells.len() as u64);
    let grid = mesh::io::read_path(&out.join("failed.vtu")).unwrap();
    let base = mesh::io::read_path(&root().join("fixtures/cases/default/grid.msh")).unwrap();
    let vol = |x: &[[f64; 3]], n: &[usize]| {
        let e = |k: usize| [0, 1, 2].map(|c| x[n[k]][c] - x[n[0]][c]);
        let (a, b, c) = (e(1), e(2), e(3));
        a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
            + a[2] * (b[0] * c[1] - b[1] * c[0])
    };
    for c in cells {
        assert!(c["quality"][0].as_f64().unwrap() <= 0.0, "{c}");
        assert!(c["quality"][1].as_f64().unwrap() > 0.0, "{c}");
        let first = c["moved_by"][0][0].as_str().unwrap();
        assert!(
            first.starts_with("stretch") || first.starts_with("droop"),
            "{c}"
        );
        if c["kind"] == "tetra" {
            let n: Vec<usize> = c["nodes"]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v[0].as_u64().unwrap() as usize)
                .collect();
            assert!(vol(&base.coords, &n) > 0.0, "{c}");
            assert!(vol(&grid.coords, &n) <= 0.0, "{c}");
        }
    }
}
