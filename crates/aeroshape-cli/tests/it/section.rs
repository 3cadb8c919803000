//! `aeroshape section fit|build` through the real binary: text and JSON output, Selig output,
//! plots, the build round trip and error exits.

use std::path::PathBuf;
use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_aeroshape"))
}

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/airfoils")
        .join(name)
}

fn read_selig(p: &std::path::Path) -> Vec<[f64; 2]> {
    std::fs::read_to_string(p)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| {
            let v: Vec<f64> = l.split_whitespace().map(|t| t.parse().unwrap()).collect();
            [v[0], v[1]]
        })
        .collect()
}

#[test]
fn fit_json_out_plot_and_build_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("fit.dat");
    let png = dir.path().join("fit.png");
    let ron = dir.path().join("params.ron");
    let o = bin()
        .args(["section", "fit"])
        .arg(fixture("naca2412.dat"))
        .args(["--json", "--camber-points", "6", "--thickness-extra", "1"])
        .arg("--out")
        .arg(&out)
        .arg("--plot")
        .arg(&png)
        .arg("--params")
        .arg(&ron)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let t = v["thickness"].as_object().unwrap();
    for k in [
        "r0", "z1", "z2", "xtmax", "tmax", "crv4", "x6", "z6", "phi_te", "d78",
    ] {
        assert!(t[k].is_f64(), "{k}");
    }
    assert_eq!(v["camber"].as_array().unwrap().len(), 6);
    assert_eq!(v["thickness_extra"].as_array().unwrap().len(), 1);
    let max = v["max_error"].as_f64().unwrap();
    let rms = v["rms_error"].as_f64().unwrap();
    assert!(max < 1e-3 && rms <= max && rms > 0.0, "{max} {rms}");
    // NACA 2412: 12 % thick, maximum near 30 % chord.
    assert!((t["tmax"].as_f64().unwrap() - 0.12).abs() < 2e-3);
    let pts = read_selig(&out);
    assert!(pts.len() >= 200);
    // Selig order: trailing edge, upper surface, leading edge, lower surface.
    assert!(pts[0][0] > 0.99 && pts[pts.len() - 1][0] > 0.99);
    assert!(pts[pts.len() / 2][0] < 1e-3);
    assert_eq!(&std::fs::read(&png).unwrap()[1..4], b"PNG");
    // build from the written parameters gives the same section (normalised frame; this file
    // is already normalised, so the coordinates agree to the frame's round-off).
    let rebuilt = dir.path().join("rebuilt.dat");
    let o = bin()
        .args(["section", "build"])
        .arg(&ron)
        .arg("-o")
        .arg(&rebuilt)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let b = read_selig(&rebuilt);
    assert_eq!(b.len(), pts.len());
    for (p, q) in b.iter().zip(&pts) {
        assert!(
            (p[0] - q[0]).abs() < 1e-4 && (p[1] - q[1]).abs() < 1e-4,
            "{p:?} {q:?}"
        );
    }
}

#[test]
fn text_output_lists_parameters_and_error() {
    let o = bin()
        .args(["section", "fit"])
        .arg(fixture("naca2412-lednicer.dat"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = String::from_utf8(o.stdout).unwrap();
    for k in [
        "r0",
        "xtmax",
        "phi_te",
        "d78",
        "camber control points",
        "max",
        "rms",
    ] {
        assert!(s.contains(k), "{k} missing in\n{s}");
    }
}

#[test]
fn errors_exit_1_with_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.dat");
    std::fs::write(&bad, "foil\n1 0\n0.5 oops\n").unwrap();
    let o = bin().args(["section", "fit"]).arg(&bad).output().unwrap();
    assert_eq!(o.status.code(), Some(1));
    let e = String::from_utf8(o.stderr).unwrap();
    assert!(e.contains("bad.dat:3"), "{e}");
    assert_eq!(e.trim().lines().count(), 1);
    // Refuses to overwrite its input.
    let copy = dir.path().join("in.dat");
    std::fs::copy(fixture("naca0012.dat"), &copy).unwrap();
    let o = bin()
        .args(["section", "fit"])
        .arg(&copy)
        .arg("--out")
        .arg(&copy)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    // Invalid parameters in a RON file name the parameter.
    let ron = dir.path().join("p.ron");
    std::fs::write(
        &ron,
        "(thickness: (r0: -0.01, z1: 0.03, z2: 0.05, xtmax: 0.3, tmax: 0.12, crv4: -0.45, \
         x6: 0.65, z6: 0.04, phi_te: 0.3, d78: 0.15), camber: [(0.0, 0.0), (1.0, 0.0)])",
    )
    .unwrap();
    let o = bin()
        .args(["section", "build"])
        .arg(&ron)
        .arg("-o")
        .arg(dir.path().join("o.dat"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let e = String::from_utf8(o.stderr).unwrap();
    assert!(e.contains("r0"), "{e}");
    assert!(!dir.path().join("o.dat").exists());
    // Usage error: exit 2.
    let o = bin().args(["section", "fit"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
}
