//! `aeroshape param list|apply` end to end on the wing-body case (one modifier of each
//! level), and the exact Jacobian of that case against central differences.

use std::path::{Path, PathBuf};
use std::process::Command;

use aeroshape::case::{Case, load_design_values};
use geom_db::GeomDb;
use param::{MasterSources, Parametrisation, Prepared};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_aeroshape"))
}

fn root() -> PathBuf {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../..")).to_path_buf()
}

fn case_path() -> PathBuf {
    root().join("fixtures/cases/wing_body_param.ron")
}

fn dv_path() -> PathBuf {
    root().join("fixtures/cases/wing_body_dv.ron")
}

fn load() -> (Case, GeomDb) {
    let case = Case::load(&case_path()).unwrap();
    let g = case.geometry_path(&case_path());
    let db = GeomDb::from_ron_str(&std::fs::read_to_string(&g).unwrap(), "g").unwrap();
    (case, db)
}

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn list_prints_variables_modifiers_and_constraints() {
    let o = bin()
        .args(["param", "list"])
        .arg(case_path())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8(o.stdout).unwrap();
    for want in [
        "tip_twist",
        "hh_30",
        "crown_4",
        "fb_3_1",
        "m_dihedral",
        "total tip twist <= 0.08",
    ] {
        assert!(text.contains(want), "missing {want} in\n{text}");
    }
    let o = bin()
        .args(["param", "list", "--json"])
        .arg(case_path())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["variables"].as_array().unwrap().len(), 18);
    let levels: Vec<&str> = v["modifiers"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["level"].as_str().unwrap())
        .collect();
    assert_eq!(levels, ["node", "line", "line", "surface", "master"]);
    assert!(
        v["modifiers"]
            .as_array()
            .unwrap()
            .iter()
            .all(|m| m["nodes_moved"].as_u64().unwrap() > 0)
    );
    assert_eq!(v["constraints"]["names"].as_array().unwrap().len(), 2);
}

#[test]
fn apply_without_dv_reproduces_the_geometry_byte_for_byte() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("g.ron");
    let o = bin()
        .args(["param", "apply"])
        .arg(case_path())
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let a = std::fs::read(&out).unwrap();
    let b = std::fs::read(root().join("fixtures/geom/wing_body.ron")).unwrap();
    assert!(a == b, "zero design vector changed the geometry file");
}

#[test]
fn apply_writes_updated_geometry_and_jacobian() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("g.ron");
    let jac = dir.path().join("j.json");
    let o = bin()
        .args(["param", "apply"])
        .arg(case_path())
        .arg("--dv")
        .arg(dv_path())
        .arg("-o")
        .arg(&out)
        .arg("--jacobian")
        .arg(&jac)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8(o.stdout).unwrap();
    assert!(text.contains("curves re-intersected"), "{text}");
    // the output is a valid database whose surface control nodes are the parametrisation's
    let (case, db) = load();
    let new = GeomDb::from_ron_str(&std::fs::read_to_string(&out).unwrap(), "out").unwrap();
    let prep = case
        .parametrisation
        .bind(&db, &MasterSources::new())
        .unwrap();
    let x = prep
        .registry()
        .vector_from_values(&load_design_values(&dv_path()).unwrap())
        .unwrap();
    let (pts, j) = prep.apply_with_jacobian(&x).unwrap();
    for s in &db.surfaces {
        for id in s.control.nodes.iter().flatten() {
            let (a, b) = (new.control_points()[id.index()], pts[id.index()]);
            assert!((a - b).norm() <= 1e-12 * db.reference_length(), "{id}");
        }
    }
    assert!(new.control_points() != db.control_points());
    // the Jacobian file's shape (its values: the next test, against central differences)
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&jac).unwrap()).unwrap();
    assert_eq!(v["n_cols"], 18);
    // a row per control node of the geometry written (the junction's re-fit added some)
    assert_eq!(
        v["n_rows"].as_u64().unwrap() as usize,
        3 * new.control_points().len()
    );
    // every modifier entry is there, plus the junction's rows
    assert!(v["values"].as_array().unwrap().len() > j.data().len());
}

/// Runs `param apply` at the design vector `x` (every variable named, full precision),
/// returning the written geometry's control nodes flattened.
fn apply_at(dir: &Path, names: &[String], x: &[f64], tag: &str) -> Vec<f64> {
    let dv = dir.join(format!("dv{tag}.ron"));
    let body: Vec<String> = names
        .iter()
        .zip(x)
        .map(|(n, v)| format!("  \"{n}\": {v:?},"))
        .collect();
    std::fs::write(&dv, format!("{{\n{}\n}}\n", body.join("\n"))).unwrap();
    let out = dir.join(format!("g{tag}.ron"));
    let o = bin()
        .args(["param", "apply"])
        .arg(case_path())
        .arg("--dv")
        .arg(&dv)
        .arg("-o")
        .arg(&out)
        .arg("--allow-infeasible")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let db = GeomDb::from_ron_str(&std::fs::read_to_string(&out).unwrap(), "out").unwrap();
    db.control_points()
        .iter()
        .flat_map(|p| [p.x, p.y, p.z])
        .collect()
}

/// The written Jacobian is the written geometry's: every column against fourth-order
/// central differences of `param apply` itself (the geometry files it writes), the
/// junction's rows included, through the re-fit the update makes at this design vector
/// (the modifiers' own Jacobian leaves those rows zero: off by 16–57 % before).
#[test]
fn jacobian_of_the_written_geometry_matches_central_differences_of_apply() {
    let dir = tempfile::tempdir().unwrap();
    let (out, jac) = (dir.path().join("g.ron"), dir.path().join("j.json"));
    let o = bin()
        .args(["param", "apply"])
        .arg(case_path())
        .arg("--dv")
        .arg(dv_path())
        .arg("-o")
        .arg(&out)
        .arg("--jacobian")
        .arg(&jac)
        .arg("--report")
        .arg(dir.path().join("r.json"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let r: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("r.json")).unwrap()).unwrap();
    assert!(
        r["update"]["refits"].as_u64().unwrap() > 0,
        "the case's design vector re-fits a junction"
    );
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&jac).unwrap()).unwrap();
    let get = |k: &str| -> Vec<f64> {
        v[k].as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect()
    };
    let (ptr, cols, vals) = (get("row_ptr"), get("col_idx"), get("values"));
    let (n_rows, n_cols) = (
        v["n_rows"].as_u64().unwrap() as usize,
        v["n_cols"].as_u64().unwrap() as usize,
    );
    let mut dense = vec![vec![0.0; n_rows]; n_cols];
    for r in 0..n_rows {
        for k in ptr[r] as usize..ptr[r + 1] as usize {
            dense[cols[k] as usize][r] = vals[k];
        }
    }
    let (case, db) = load();
    let prep = case
        .parametrisation
        .bind(&db, &MasterSources::new())
        .unwrap();
    let reg = prep.registry();
    let names: Vec<String> = reg.variables().iter().map(|v| v.name.clone()).collect();
    assert_eq!(n_cols, names.len());
    let x = reg
        .vector_from_values(&load_design_values(&dv_path()).unwrap())
        .unwrap();
    let (_, jp) = prep.apply_with_jacobian(&x).unwrap();
    // junction nodes: control nodes of no surface (the re-fit's new nodes included)
    let on_surface = |i: usize| {
        db.surfaces
            .iter()
            .any(|s| s.control.nodes.iter().flatten().any(|id| id.index() == i))
    };
    let junction: Vec<usize> = (0..n_rows / 3).filter(|&i| !on_surface(i)).collect();
    assert!(!junction.is_empty());
    assert!(
        n_rows / 3 > db.control_nodes.len(),
        "the re-fit adds control nodes"
    );
    let mut junction_cols = 0;
    for (l, var) in reg.variables().iter().enumerate() {
        // fourth-order differences, step twice the variable's scale within its bounds: the
        // update's noise (the re-fit's seed feet, ~5e-10 of the model size) over h is 4e-6
        // at h = 0.1 scale, 7e-8 at 2 scales; the truncation error O(h⁴) stays below it
        let h = (2.0 * var.scale)
            .min((var.upper - x[l]) / 2.0)
            .min((x[l] - var.lower) / 2.0);
        let at = |s: f64, tag: &str| {
            let mut y = x.clone();
            y[l] += s * h;
            apply_at(dir.path(), &names, &y, tag)
        };
        let (p1, m1, p2, m2) = (at(1.0, "p1"), at(-1.0, "m1"), at(2.0, "p2"), at(-2.0, "m2"));
        assert_eq!(p1.len(), n_rows, "{}: rows", var.name);
        let fd: Vec<f64> = (0..n_rows)
            .map(|r| (8.0 * (p1[r] - m1[r]) - (p2[r] - m2[r])) / (12.0 * h))
            .collect();
        let size = fd.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        let err = fd
            .iter()
            .zip(&dense[l])
            .fold(0.0f64, |a, (f, j)| a.max((f - j).abs()));
        let jn = junction
            .iter()
            .flat_map(|&i| (0..3).map(move |c| 3 * i + c))
            .fold(0.0f64, |a, r| a.max(fd[r].abs()));
        let mut modifier_only = param::jacobian::column(&jp, l);
        modifier_only.resize(n_rows, 0.0);
        let old = fd
            .iter()
            .zip(&modifier_only)
            .fold(0.0f64, |a, (f, j)| a.max((f - j).abs()));
        eprintln!(
            "{}: |FD| {size:.3e}, error {:.2e} (modifiers' Jacobian alone {:.2e}), junction rows {jn:.3e}",
            var.name,
            err / size,
            old / size
        );
        assert!(size > 0.0, "{}: column zero", var.name);
        assert!(err <= 1e-6 * size, "{}: error {:.3e}", var.name, err / size);
        if jn > 1e-6 * size {
            junction_cols += 1;
        }
    }
    assert!(junction_cols > 0, "some variable moves the junction");
}

fn fd_check(prep: &Prepared, x: &[f64], what: &str) {
    let (_, j) = prep.apply_with_jacobian(x).unwrap();
    for l in 0..x.len() {
        let h = 1e-5 * x[l].abs().max(1.0);
        let (mut xp, mut xm) = (x.to_vec(), x.to_vec());
        xp[l] += h;
        xm[l] -= h;
        let (pp, pm) = (prep.apply(&xp).unwrap(), prep.apply(&xm).unwrap());
        let col = param::jacobian::column(&j, l);
        let (mut err, mut size) = (0.0f64, 0.0f64);
        for (k, (a, b)) in pp.iter().zip(&pm).enumerate() {
            for c in 0..3 {
                let fd = (a[c] - b[c]) / (2.0 * h);
                size = size.max(fd.abs());
                err = err.max((col[3 * k + c] - fd).abs());
            }
        }
        assert!(size > 0.0, "{what}: column {l} is zero");
        assert!(
            err <= 1e-6 * size,
            "{what}: column {l}: error {err:.3e} vs size {size:.3e}"
        );
    }
}

#[test]
fn jacobian_of_every_modifier_of_the_case_matches_central_differences() {
    let (case, db) = load();
    let dv = load_design_values(&dv_path()).unwrap();
    for m in &case.parametrisation.modifiers {
        let p = Parametrisation {
            modifiers: vec![m.clone()],
            constraints: vec![],
        };
        let prep = p.bind(&db, &MasterSources::new()).unwrap();
        let mut sub = param::DesignValues::new();
        for v in prep.registry().variables() {
            if let Some(&x) = dv.get(&v.name) {
                sub.insert(v.name.clone(), x);
            }
        }
        // the case's design vector, with every variable non-zero
        let mut x = prep.registry().vector_from_values(&sub).unwrap();
        for (xi, v) in x.iter_mut().zip(prep.registry().variables()) {
            if *xi == 0.0 {
                *xi = 0.3 * v.upper;
            }
        }
        fd_check(&prep, &x, m.name());
    }
    let prep = case
        .parametrisation
        .bind(&db, &MasterSources::new())
        .unwrap();
    let x = prep.registry().vector_from_values(&dv).unwrap();
    fd_check(&prep, &x, "composition");
}

#[test]
fn bounds_unknown_names_and_constraints_are_user_errors() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("g.ron");
    let run = |dv: &str, extra: &[&str]| {
        let p = dir.path().join("dv.ron");
        std::fs::write(&p, dv).unwrap();
        bin()
            .args(["param", "apply"])
            .arg(case_path())
            .arg("--dv")
            .arg(&p)
            .arg("-o")
            .arg(&out)
            .args(extra)
            .output()
            .unwrap()
    };
    let o = run("{\"tip_twist\": 0.5}", &[]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("tip_twist") && stderr(&o).contains("[-0.1, 0.1]"),
        "{}",
        stderr(&o)
    );
    let o = run("{\"wing_span\": 1.0}", &[]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("'wing_span'"), "{}", stderr(&o));
    let o = run("{\"tip_twist\": 0.06, \"m_twist\": 0.05}", &[]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("total tip twist <= 0.08"),
        "{}",
        stderr(&o)
    );
    assert!(!out.exists());
    let o = run(
        "{\"tip_twist\": 0.06, \"m_twist\": 0.05}",
        &["--allow-infeasible"],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("warning: constraint 'total tip twist <= 0.08'"));
    let o = run("{\"tip_twist\": }", &[]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("dv.ron:1:"), "{}", stderr(&o));
}

#[test]
fn refuses_to_overwrite_an_input_and_reports_case_errors() {
    let o = bin()
        .args(["param", "apply"])
        .arg(case_path())
        .arg("-o")
        .arg(root().join("fixtures/geom/wing_body.ron"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("overwrite an input"), "{}", stderr(&o));
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("case.ron");
    std::fs::write(&bad, "(format_version: 1,\n geometry: \"g.ron\",\n parametrisation: (modifiers: [Node(name: 1)]))").unwrap();
    let o = bin().args(["param", "list"]).arg(&bad).output().unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("case.ron:3:"), "{}", stderr(&o));
    // a link to a missing surface names the modifier and the entity
    std::fs::copy(
        root().join("fixtures/geom/wing_body.ron"),
        dir.path().join("g.ron"),
    )
    .unwrap();
    let text = std::fs::read_to_string(case_path())
        .unwrap()
        .replace("../geom/wing_body.ron", "g.ron")
        .replace(
            "surfaces: [0],\n        basis_u",
            "surfaces: [7],\n        basis_u",
        );
    std::fs::write(&bad, text).unwrap();
    let o = bin().args(["param", "list"]).arg(&bad).output().unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("'fuselage_bulge'") && stderr(&o).contains("surface 7"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn apply_reports_the_sampled_junction_distance_and_fails_above_tolerance() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("g.ron");
    let rep = dir.path().join("report.json");
    let o = bin()
        .args(["param", "apply"])
        .arg(case_path())
        .arg("--dv")
        .arg(dv_path())
        .arg("-o")
        .arg(&out)
        .arg("--report")
        .arg(&rep)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8(o.stdout).unwrap();
    assert!(text.contains("junctions: "), "{text}");
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&rep).unwrap()).unwrap();
    let m = &v["model"];
    let tol = m["junction_tolerance"].as_f64().unwrap();
    let js = m["junctions"].as_array().unwrap();
    assert!(!js.is_empty(), "{m}");
    for j in js {
        let arcs = j["degrees"].as_array().unwrap().len() as u64;
        assert!(j["samples"].as_u64().unwrap() >= 200 * arcs, "{j}");
        for k in 0..2 {
            assert!(j["max"][k].as_f64().unwrap() <= tol, "{j}");
        }
    }
    assert!(m["curve_deviation_rel"].as_f64().unwrap() <= 1e-8);
    assert!(v["update"]["curves"].is_array());
    // a tolerance no representation meets: an error naming the curve and the distance
    let o = bin()
        .args(["param", "apply"])
        .arg(case_path())
        .arg("--dv")
        .arg(dv_path())
        .arg("-o")
        .arg(dir.path().join("g2.ron"))
        .args(["--junction-tol", "1e-13"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert!(
        err.contains("junction is") && err.contains("away from surface"),
        "{err}"
    );
    // the error names one of the junctions the report listed
    assert!(
        js.iter()
            .any(|j| err.contains(j["curve"].as_str().unwrap())),
        "{err}"
    );
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(!dir.path().join("g2.ron").exists());
    // a tolerance that is not a positive number is a usage mistake named by its flag
    let o = bin()
        .args(["param", "apply"])
        .arg(case_path())
        .arg("-o")
        .arg(dir.path().join("g3.ron"))
        .args(["--junction-tol", "0"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("--junction-tol"), "{}", stderr(&o));
    assert!(!dir.path().join("g3.ron").exists());
}
