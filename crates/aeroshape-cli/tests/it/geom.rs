//! `aeroshape geom info|check|import` end to end: exit codes, messages naming the entity, JSON.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_aeroshape"))
}

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/geom")
        .join(name)
}

fn run(args: &[&str], file: &Path) -> Output {
    bin().args(args).arg(file).output().unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// Writes `text` into a temporary folder and returns (folder guard, path).
fn temp_file(text: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("bad.ron");
    std::fs::write(&p, text).unwrap();
    (dir, p)
}

fn assert_one_line_error(o: &Output, needle: &str) {
    assert_eq!(o.status.code(), Some(1), "stderr: {}", stderr(o));
    let e = stderr(o);
    assert_eq!(e.trim_end().lines().count(), 1, "not one line: {e}");
    assert!(e.contains(needle), "{e:?} does not contain {needle:?}");
}

#[test]
fn every_fixture_is_valid() {
    for name in ["sphere.ron", "cylinder.ron", "wing_body.ron"] {
        let o = run(&["geom", "check"], &fixture(name));
        assert_eq!(o.status.code(), Some(0), "{name}: {}", stderr(&o));
        assert!(stdout(&o).contains("valid"), "{name}: {}", stdout(&o));
        let o = run(&["geom", "info"], &fixture(name));
        assert_eq!(o.status.code(), Some(0), "{name}: {}", stderr(&o));
        assert!(stdout(&o).contains("support surfaces"));
    }
}

#[test]
fn info_json_counts() {
    let o = run(&["geom", "info", "--json"], &fixture("wing_body.ron"));
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["counts"]["surfaces"], 3);
    assert_eq!(v["counts"]["surface_components"], 3);
    assert_eq!(v["topology"]["closed"], false);
    assert_eq!(v["topology"]["free_edges"].as_array().unwrap().len(), 2);
    let comps = v["surface_components"].as_array().unwrap();
    let names: Vec<&str> = comps.iter().map(|c| c["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["fuselage", "wing", "wing tip"]);
}

#[test]
fn check_json_reports_closed_sphere() {
    let o = run(&["geom", "check", "--json"], &fixture("sphere.ron"));
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["ok"], true);
    assert_eq!(v["topology"]["closed"], true);
    assert_eq!(v["counts"]["curve_components"], 12);
    assert!(v["max_gap"].as_f64().unwrap() < 1e-9);
}

#[test]
fn nan_coefficient_is_named() {
    let text = std::fs::read_to_string(fixture("wing_body.ron")).unwrap();
    // the first surface's first coefficient: the fuselage nose point (0, 0, 0)
    let at = text.find("\n surfaces: [").unwrap();
    let c = at + text[at..].find("coeffs: [(").unwrap() + "coeffs: [(".len();
    let end = c + text[c..].find(',').unwrap();
    let bad = format!("{}NaN{}", &text[..c], &text[end..]);
    let (_d, p) = temp_file(&bad);
    let o = run(&["geom", "check"], &p);
    assert_one_line_error(&o, "surface 0 patch 0: coefficient a[0,0] x is NaN");
    assert!(stderr(&o).contains("bad.ron"));
}

#[test]
fn dangling_surface_id_is_named() {
    let text = std::fs::read_to_string(fixture("wing_body.ron")).unwrap();
    let bad = text.replacen("surface: 1,", "surface: 7,", 1);
    assert_ne!(bad, text);
    let (_d, p) = temp_file(&bad);
    let o = run(&["geom", "info"], &p);
    assert_one_line_error(&o, "surface component 1: surface 7 does not exist");
}

#[test]
fn open_loop_is_named() {
    // replace the 4th edge of the first sphere face's loop by the first: the loop breaks
    let text = std::fs::read_to_string(fixture("sphere.ron")).unwrap();
    let db = geom_db::GeomDb::from_ron_str(&text, "sphere.ron").unwrap();
    let mut broken = db.clone();
    let first = broken.surface_components[0].loops[0][0];
    broken.surface_components[0].loops[0][3] = first;
    let (_d, p) = temp_file(&broken.to_ron_string());
    let o = run(&["geom", "check"], &p);
    assert_one_line_error(&o, "surface component 0 loop 0: not closed");
}

#[test]
fn wrong_orientation_fails_check() {
    let text = std::fs::read_to_string(fixture("sphere.ron")).unwrap();
    let bad = text.replacen("inward: Positive", "inward: Negative", 1);
    let (_d, p) = temp_file(&bad);
    let o = run(&["geom", "check"], &p);
    assert_one_line_error(&o, "surface component 0 loop 0 runs against the convention");
    // info does not judge orientation
    let o = run(&["geom", "info"], &p);
    assert_eq!(o.status.code(), Some(0));
}

#[test]
fn syntax_error_gives_line_and_column() {
    let (_d, p) = temp_file(
        "(\n format_version: 1,\n name: \"x\",\n corners: [(point: (0, 0, 0) name: \"a\")],\n)",
    );
    let o = run(&["geom", "info"], &p);
    assert_one_line_error(&o, "bad.ron:4:");
}

#[test]
fn missing_file_and_usage_errors() {
    let o = run(&["geom", "check"], Path::new("/nonexistent/geom.ron"));
    assert_one_line_error(&o, "/nonexistent/geom.ron");
    let o = bin().args(["geom", "check"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    let o = bin().args(["geom", "--help"]).output().unwrap();
    assert_eq!(o.status.code(), Some(0));
    assert!(stdout(&o).contains("info") && stdout(&o).contains("check"));
}

/// The "done when": import the real M6 file, check it, read the report.
#[test]
fn import_m6_then_check() {
    let igs = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/iges/geom_oneram6.igs");
    let dir = tempfile::tempdir().unwrap();
    let ron = dir.path().join("m6.ron");
    let json = dir.path().join("m6.json");
    let o = bin()
        .args(["geom", "import"])
        .arg(&igs)
        .arg("-o")
        .arg(&ron)
        .arg("--report")
        .arg(&json)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(
        stdout(&o).contains("faces: 2 farfield, 1 symmetry, 2 wing, 2 wing_tip"),
        "{}",
        stdout(&o)
    );
    let r: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert!(r["max_error"].as_f64().unwrap() <= r["tolerance"].as_f64().unwrap());
    let o = run(&["geom", "check"], &ron);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(stdout(&o).contains("closed"), "{}", stdout(&o));
    // Nothing but the two outputs was left in the folder.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
}

#[test]
fn truncated_iges_is_one_line_error() {
    let igs = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/iges/geom_oneram6.igs");
    let text = std::fs::read(&igs).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("cut.igs");
    std::fs::write(&bad, &text[..text.len() / 2]).unwrap();
    let out = dir.path().join("cut.ron");
    let o = bin()
        .args(["geom", "import"])
        .arg(&bad)
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    assert_one_line_error(&o, "cut.igs");
    assert!(!out.exists());
}
