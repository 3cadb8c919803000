//! `aeroshape deform` end to end: exit codes, outputs, report, refusals.

use std::path::{Path, PathBuf};
use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_aeroshape"))
}

fn naca() -> PathBuf {
    Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/su2/mesh_NACA0012_inv.su2"
    ))
    .to_path_buf()
}

fn read(p: &Path) -> mesh::Mesh {
    mesh::io::read_path(p).unwrap()
}

#[test]
fn pitch_naca_writes_grid_and_report() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.su2");
    let rep = dir.path().join("rep.json");
    let o = bin()
        .args(["deform"])
        .arg(naca())
        .arg("-o")
        .arg(&out)
        .args([
            "--rigid",
            "airfoil",
            "--rotate-deg",
            "-5",
            "--axis-point",
            "0.25,0,0",
        ])
        .arg("--report")
        .arg(&rep)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let a = read(&naca());
    let b = read(&out);
    assert_eq!(a.n_nodes(), b.n_nodes());
    assert_eq!(a.cells, b.cells);
    // Airfoil nodes rotated by -5° about (0.25, 0): check one against Eq. 34 by hand.
    let v = a.marker("airfoil").unwrap().elements.node_set()[3] as usize;
    let (s, c) = (-5f64).to_radians().sin_cos();
    let (dx, dy) = (a.coords[v][0] - 0.25, a.coords[v][1]);
    testkit::assert_close!(b.coords[v][0], 0.25 + c * dx - s * dy, abs = 1e-12);
    testkit::assert_close!(b.coords[v][1], s * dx + c * dy, abs = 1e-12);
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&rep).unwrap()).unwrap();
    for k in [
        "nodes",
        "cells",
        "iterations",
        "residual",
        "seconds",
        "quality_before",
        "quality_after",
    ] {
        assert!(r.get(k).is_some(), "report lacks {k}");
    }
    for k in ["read", "assemble", "solve", "write"] {
        assert!(r["seconds"][k].as_f64().unwrap() >= 0.0);
    }
    assert_eq!(r["quality_after"]["inverted"], 0);
    assert_eq!(r["nodes"], a.n_nodes());
}

#[test]
fn zero_motion_and_displacement_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("same.su2");
    let o = bin()
        .arg("deform")
        .arg(naca())
        .arg("-o")
        .arg(&out)
        .args(["--rigid", "airfoil"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let a = read(&naca());
    assert_eq!(read(&out).coords, a.coords);
    // A CSV moving one airfoil node.
    let v = a.marker("airfoil").unwrap().elements.node_set()[10];
    let csv = dir.path().join("d.csv");
    std::fs::write(&csv, format!("node,dx,dy,dz\n{v},0.0,0.001,0\n")).unwrap();
    let out2 = dir.path().join("moved.vtu");
    let o = bin()
        .arg("deform")
        .arg(naca())
        .arg("-o")
        .arg(&out2)
        .arg("--displacements")
        .arg(&csv)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let b = read(&out2);
    testkit::assert_close!(
        b.coords[v as usize][1],
        a.coords[v as usize][1] + 0.001,
        abs = 1e-15
    );
}

#[test]
fn errors_are_one_line_with_exit_1_or_usage_2() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o.su2");
    let o = bin()
        .arg("deform")
        .arg(naca())
        .arg("-o")
        .arg(&out)
        .args(["--rigid", "wing"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("wing") && err.trim().lines().count() == 1,
        "{err}"
    );
    assert!(!out.exists());
    // Bad CSV line named.
    let csv = dir.path().join("bad.csv");
    std::fs::write(&csv, "node,dx,dy,dz\n1,0,0,0\n2,0,x,0\n").unwrap();
    let o = bin()
        .arg("deform")
        .arg(naca())
        .arg("-o")
        .arg(&out)
        .arg("--displacements")
        .arg(&csv)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("line 3"));
    // Output naming the input is refused.
    let copy = dir.path().join("in.su2");
    std::fs::copy(naca(), &copy).unwrap();
    let o = bin()
        .arg("deform")
        .arg(&copy)
        .arg("-o")
        .arg(&copy)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    // Usage error.
    let o = bin()
        .args(["deform", "--solver", "magic"])
        .arg(naca())
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let o = bin().args(["deform", "--help"]).output().unwrap();
    assert!(o.status.success() && String::from_utf8_lossy(&o.stdout).contains("--slide"));
}
