//! `aeroshape gradient` on the default case with sensitivity files in SU2's own layouts
//! (RESTART_ASCII volume CSV, surface CSV; `CSU2FileWriter` / `CCSVFileWriter`): the
//! gradient of J(X) = Σ w_i·X_i against central differences of the chain, the surface
//! layout against the wall product, and the errors for a file that does not fit the grid.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use aeroshape::case::load_design_values;
use aeroshape::study::Study;

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

fn weights(n: usize) -> Vec<[f64; 3]> {
    (0..n)
        .map(|i| {
            let t = i as f64;
            [
                (0.37 * t).sin(),
                (0.11 * t + 0.5).cos(),
                (0.23 * t + 1.0).sin(),
            ]
        })
        .collect()
}

/// A volume file as SU2 writes it: quoted header, "PointID" first, ", " separators,
/// scientific with 15 digits.
fn su2_volume(coords: &[[f64; 3]], w: &[[f64; 3]]) -> String {
    let mut s = String::from(
        "\"PointID\",\"x\",\"y\",\"z\",\"Adjoint_Density\",\"Sensitivity_x\",\"Sensitivity_y\",\"Sensitivity_z\"\n",
    );
    for (i, (p, g)) in coords.iter().zip(w).enumerate() {
        writeln!(
            s,
            "{i}, {:.15e}, {:.15e}, {:.15e}, {:.15e}, {:.15e}, {:.15e}, {:.15e}",
            p[0], p[1], p[2], 0.0, g[0], g[1], g[2]
        )
        .unwrap();
    }
    s
}

fn run(args: &[&std::ffi::OsStr]) -> Output {
    bin().arg("gradient").args(args).output().unwrap()
}

fn gradient_of(out: &Path) -> Vec<(String, f64)> {
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out).unwrap()).unwrap();
    v["gradient"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| (e[0].as_str().unwrap().to_string(), e[1].as_f64().unwrap()))
        .collect()
}

/// The default case with its deformation solved to 1e-12 (the default 1e-8 leaves FD noise
/// of about 1e-5 relative on J), written into `dir` with absolute paths.
fn tight_case(dir: &Path) -> PathBuf {
    use aeroshape::case::Case;
    let src = case_dir().join("case.ron");
    let mut c = Case::load(&src).unwrap();
    c.geometry = case_dir().join(&c.geometry).display().to_string();
    c.grid = c.grid.map(|g| case_dir().join(g).display().to_string());
    c.deform.rel_tol = 1e-12;
    c.deform.warm_start = false;
    let p = dir.join("case.ron");
    std::fs::write(&p, param::ron_to_string(&c)).unwrap();
    p
}

#[test]
fn volume_gradient_matches_central_differences_of_the_chain() {
    let dir = tempfile::tempdir().unwrap();
    let case = tight_case(dir.path());
    let dv = case_dir().join("dv.ron");
    let study = Study::load(&case).unwrap();
    let x = study
        .vector_from_values(&load_design_values(&dv).unwrap())
        .unwrap();
    let n = study.baseline().n_nodes();
    let w = weights(n);
    let sens = dir.path().join("restart_adj.csv");
    std::fs::write(&sens, su2_volume(&study.baseline().coords, &w)).unwrap();
    let out = dir.path().join("grad.json");
    let o = run(&[
        case.as_os_str(),
        "--dv".as_ref(),
        dv.as_os_str(),
        "--sensitivity".as_ref(),
        sens.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let g = gradient_of(&out);
    assert_eq!(g.len(), x.len());
    // J(x) = Σ w·X(x), fourth-order central differences of the chain
    let j = |y: &[f64]| -> f64 {
        study.forget_warm_start();
        let c = study.evaluate(y).unwrap().grid.coords;
        c.iter()
            .zip(&w)
            .map(|(p, q)| p[0] * q[0] + p[1] * q[1] + p[2] * q[2])
            .sum()
    };
    for name in ["twist", "waist_top", "thick_upper"] {
        let l = g.iter().position(|(n, _)| n == name).unwrap();
        let h = 1e-3;
        let at = |s: f64| {
            let mut y = x.clone();
            y[l] += s * h;
            j(&y)
        };
        let fd = (8.0 * (at(1.0) - at(-1.0)) - (at(2.0) - at(-2.0))) / (12.0 * h);
        let rel = (fd - g[l].1).abs() / fd.abs();
        eprintln!(
            "{name}: gradient {:.12e}, FD {fd:.12e}, relative {rel:.2e}",
            g[l].1
        );
        assert!(rel < 1e-6, "{name}: relative {rel:.3e}");
    }
    // the CSV output holds the same numbers
    let out_csv = dir.path().join("grad.csv");
    let o = run(&[
        case.as_os_str(),
        "--dv".as_ref(),
        dv.as_os_str(),
        "--sensitivity".as_ref(),
        sens.as_os_str(),
        "-o".as_ref(),
        out_csv.as_os_str(),
    ]);
    assert!(o.status.success());
    let text = std::fs::read_to_string(&out_csv).unwrap();
    let rows: Vec<&str> = text.lines().collect();
    assert_eq!(rows[0], "variable,gradient");
    for ((n, v), r) in g.iter().zip(&rows[1..]) {
        let (a, b) = r.split_once(',').unwrap();
        assert_eq!(a, n);
        // serde_json's default float parsing may be one unit in the last place off
        let c: f64 = b.parse().unwrap();
        assert!(
            (c - v).abs() <= 4.0 * f64::EPSILON * v.abs(),
            "{n}: {c} vs {v}"
        );
    }
}

#[test]
fn surface_layout_gives_the_wall_product_and_bad_files_name_their_line() {
    let dir = tempfile::tempdir().unwrap();
    let case = case_dir().join("case.ron");
    let study = Study::load(&case).unwrap();
    let x = study.initial();
    let n = study.baseline().n_nodes();
    let w = weights(n);
    let wall = study.wall_nodes();
    let mut s = String::from(
        "\"Point\",\"x\",\"y\",\"z\",\"Pressure_Coefficient\",\"Sensitivity_x\",\"Sensitivity_y\",\"Sensitivity_z\",\"Surface_Sensitivity\"\n",
    );
    for i in (0..n).filter(|&i| wall[i]) {
        writeln!(
            s,
            "{i}, 0.0, 0.0, 0.0, 0.0, {:.15e}, {:.15e}, {:.15e}, 0.0",
            w[i][0], w[i][1], w[i][2]
        )
        .unwrap();
    }
    let sens = dir.path().join("surface_sens.csv");
    std::fs::write(&sens, &s).unwrap();
    let out = dir.path().join("grad.json");
    let o = run(&[
        case.as_os_str(),
        "--sensitivity".as_ref(),
        sens.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let g = gradient_of(&out);
    let want = study.linearise(&x).unwrap().vjp_wall(&w).unwrap();
    for ((n, v), r) in g.iter().zip(&want) {
        assert!(
            (v - r).abs() <= 1e-12 * r.abs().max(1e-12),
            "{n}: {v} vs {r}"
        );
    }
    // a wall node missing: exit 1, the file and its last line named
    let cut: Vec<&str> = s.lines().collect();
    let short = dir.path().join("short.csv");
    std::fs::write(&short, cut[..cut.len() - 1].join("\n")).unwrap();
    let o = run(&[
        case.as_os_str(),
        "--sensitivity".as_ref(),
        short.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    let nw = wall.iter().filter(|b| **b).count();
    assert!(
        err.contains(&format!(
            "short.csv:{}: {} points for {nw} wall nodes",
            cut.len() - 1,
            nw - 1
        )),
        "{err}"
    );
    // a volume file with one node too many: the first bad row is named
    let mut coords = study.baseline().coords.clone();
    coords.push([0.0; 3]);
    let big = dir.path().join("big.csv");
    std::fs::write(&big, su2_volume(&coords, &weights(n + 1))).unwrap();
    let o = run(&[
        case.as_os_str(),
        "--sensitivity".as_ref(),
        big.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains(&format!(
            "big.csv:{}: point {n} is not a node of the grid ({n} nodes)",
            n + 2
        )),
        "{err}"
    );
}

fn python_has_meshio() -> bool {
    Command::new("python3")
        .args(["-c", "import meshio"])
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false)
}

/// meshio (the independent writer) turns our VTU of the grid at x into one with the
/// point-data vector "Sensitivity" = the test's weights; `keep` drops the last node (and
/// its cells), `reverse` reverses the node order (cells renumbered).
const MESHIO_SENS: &str = r#"
import sys, meshio, numpy as np
m = meshio.read(sys.argv[1])
mode = sys.argv[3]
pts = m.points
i = np.arange(len(pts), dtype=float)
w = np.column_stack([np.sin(0.37 * i), np.cos(0.11 * i + 0.5), np.sin(0.23 * i + 1.0)])
cells = [(c.type, c.data) for c in m.cells]
if mode == "short":
    n = len(pts) - 1
    cells = [(t, d[(d < n).all(axis=1)]) for t, d in cells]
    pts, w = pts[:n], w[:n]
elif mode == "reverse":
    n = len(pts)
    cells = [(t, n - 1 - d) for t, d in cells]
    pts, w = pts[::-1], w[::-1]
meshio.write(sys.argv[2], meshio.Mesh(pts, cells, point_data={"Sensitivity": w}))
"#;

/// A `.vtu` with a point-data vector "Sensitivity", written by meshio: the same gradient
/// as the SU2 volume CSV of the same values (itself checked against central differences
/// above); a file with a node missing, or in another node order, is exit 1 naming the file
/// and the first bad point.
#[test]
fn vtu_sensitivity_written_by_meshio_gives_the_csv_gradient() {
    if !python_has_meshio() {
        eprintln!("SKIPPED: python3 module meshio not available");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let case = tight_case(dir.path());
    let dv = case_dir().join("dv.ron");
    let study = Study::load(&case).unwrap();
    let x = study
        .vector_from_values(&load_design_values(&dv).unwrap())
        .unwrap();
    let n = study.baseline().n_nodes();
    let grid = study.evaluate(&x).unwrap().grid;
    let ours = dir.path().join("grid_at_x.vtu");
    let mut buf = Vec::new();
    mesh::vtu::write(&grid, &mesh::vtu::VtuOptions::default(), &mut buf).unwrap();
    std::fs::write(&ours, buf).unwrap();
    let meshio = |name: &str, mode: &str| -> PathBuf {
        let p = dir.path().join(name);
        let o = Command::new("python3")
            .args(["-c", MESHIO_SENS])
            .arg(&ours)
            .arg(&p)
            .arg(mode)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        p
    };
    let gradient = |sens: &Path, out: &str| -> (Output, PathBuf) {
        let out = dir.path().join(out);
        let o = run(&[
            case.as_os_str(),
            "--dv".as_ref(),
            dv.as_os_str(),
            "--sensitivity".as_ref(),
            sens.as_os_str(),
            "-o".as_ref(),
            out.as_os_str(),
        ]);
        (o, out)
    };
    let vtu = meshio("sens.vtu", "full");
    let (o, out) = gradient(&vtu, "grad_vtu.json");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let gv = gradient_of(&out);
    let csv = dir.path().join("restart_adj.csv");
    std::fs::write(&csv, su2_volume(&grid.coords, &weights(n))).unwrap();
    let (o, out) = gradient(&csv, "grad_csv.json");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let gc = gradient_of(&out);
    let size = gc.iter().fold(0.0f64, |a, (_, v)| a.max(v.abs()));
    for ((n1, a), (n2, b)) in gv.iter().zip(&gc) {
        assert_eq!(n1, n2);
        // numpy's and Rust's sin/cos may differ in the last place
        assert!((a - b).abs() <= 1e-12 * size, "{n1}: vtu {a} vs csv {b}");
    }
    // one node missing: exit 1, the file and the first missing point named
    let short = meshio("short.vtu", "short");
    let (o, _) = gradient(&short, "g_short.json");
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    let want = format!(
        "{}: {} points for {n} grid nodes; first missing: point {}",
        short.display(),
        n - 1,
        n - 1
    );
    assert!(err.contains(&want), "{err}");
    // the node order reversed: the first point off its node is named
    let rev = meshio("reversed.vtu", "reverse");
    let (o, _) = gradient(&rev, "g_rev.json");
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains(&format!("{}: point 0 at (", rev.display()))
            && err.contains("not in its node order"),
        "{err}"
    );
}
