//! `aeroshape constraints` on the default case with a `constraints` section: the table,
//! the Jacobian file (against `Study::constraints_jacobian`), the updated model as IGES, and
//! the one-line errors for a case without constraints and a station off the wing.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_aeroshape"))
}

fn case_dir() -> PathBuf {
    Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/cases/default"
    ))
    .to_path_buf()
}

/// The default case (geometry and grid by absolute path) with `constraints` appended, in
/// `dir`.
fn write_case(dir: &Path, constraints: &str) -> PathBuf {
    let src = std::fs::read_to_string(case_dir().join("case.ron")).unwrap();
    let abs = |f: &str| case_dir().join(f).display().to_string();
    let text = src
        .replace(
            "geometry: \"wing_body.ron\"",
            &format!("geometry: {:?}", abs("wing_body.ron")),
        )
        .replace(
            "grid: \"grid.msh\"",
            &format!("grid: {:?}", abs("grid.msh")),
        );
    let end = text.rfind(')').unwrap();
    let text = format!(
        "{}  constraints: [{constraints}],\n{}",
        &text[..end],
        &text[end..]
    );
    let path = dir.join("case.ron");
    std::fs::write(&path, text).unwrap();
    path
}

const WING: &str = r#"
    (name: "t", measure: Thickness(surfaces: [1], stations: Points([(4.6, 2.5, 0.0), (4.9, 2.5, 0.0)])),
     relative: true, lower: Some(1.0)),
    (name: "volume", measure: Volume(surfaces: [1, 2]), relative: true, lower: Some(0.99), upper: Some(1.01)),
    (name: "area", measure: Area(surfaces: [1])),
"#;

fn stderr_line(o: &Output) -> String {
    let e = String::from_utf8_lossy(&o.stderr).to_string();
    assert_eq!(e.trim_end().lines().count(), 1, "one line: {e}");
    e
}

#[test]
fn constraints_table_jacobian_and_updated_iges() {
    let tmp = tempfile::tempdir().unwrap();
    let case = write_case(tmp.path(), WING);
    let j = tmp.path().join("J.json");
    let igs = tmp.path().join("updated.igs");
    let o = bin()
        .arg("constraints")
        .arg(&case)
        .arg("--dv")
        .arg(case_dir().join("dv.ron"))
        .arg("--jacobian")
        .arg(&j)
        .arg("--iges")
        .arg(&igs)
        .output()
        .unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{out}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    for name in ["t[0]", "t[1]", "volume", "area"] {
        assert!(out.lines().any(|l| l.starts_with(name)), "{name}: {out}");
    }
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&j).unwrap()).unwrap();
    let rows = v["constraints"].as_array().unwrap();
    assert_eq!(rows.len(), 4);
    // the file's Jacobian is the library's
    let study = aeroshape::study::Study::load(&case).unwrap();
    let dv = aeroshape::case::load_design_values(&case_dir().join("dv.ron")).unwrap();
    let x = study.vector_from_values(&dv).unwrap();
    let lib = study.constraints_jacobian(&x).unwrap();
    for (k, row) in v["jacobian"].as_array().unwrap().iter().enumerate() {
        for (l, d) in row.as_array().unwrap().iter().enumerate() {
            // serde_json's parser may round the last digit (no float_roundtrip feature)
            let (a, b) = (d.as_f64().unwrap(), lib.jacobian[k][l]);
            assert!(
                (a - b).abs() <= 1e-14 * b.abs(),
                "row {k} column {l}: {a} vs {b}"
            );
        }
    }
    // thicker tip section: the ratio moved
    let ratio = rows[0]["ratio"].as_f64().unwrap();
    assert!((ratio - 1.0).abs() > 1e-4, "{ratio}");
    assert_eq!(v["surfaces"].as_array().unwrap().len(), 2);
    // the updated model as IGES: trimmed surfaces
    let text = std::fs::read_to_string(&igs).unwrap();
    assert!(
        text.lines()
            .any(|l| l.len() >= 73 && l.starts_with("     144")),
        "144 entities"
    );
}

#[test]
fn constraints_errors_are_one_line() {
    let tmp = tempfile::tempdir().unwrap();
    // no constraints section
    let case = write_case(tmp.path(), "");
    let o = bin().arg("constraints").arg(&case).output().unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr_line(&o).contains("no constraints"));
    // a station off the wing names the constraint and the station
    let case = write_case(
        tmp.path(),
        r#"(name: "off", measure: Thickness(surfaces: [1], stations: Points([(40.0, 2.5, 0.0)])))"#,
    );
    let o = bin().arg("constraints").arg(&case).output().unwrap();
    assert_eq!(o.status.code(), Some(1));
    let e = stderr_line(&o);
    assert!(e.contains("\"off\"") && e.contains("station 0"), "{e}");
    // an unknown surface
    let case = write_case(tmp.path(), r#"(name: "a", measure: Area(surfaces: [9]))"#);
    let o = bin().arg("constraints").arg(&case).output().unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr_line(&o).contains("surface 9"));
    // a Jacobian file that is not JSON
    let case = write_case(tmp.path(), WING);
    let o = bin()
        .arg("constraints")
        .arg(&case)
        .arg("--jacobian")
        .arg(tmp.path().join("J.txt"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr_line(&o).contains(".json"));
}
