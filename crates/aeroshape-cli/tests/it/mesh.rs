//! `aeroshape mesh info|convert` end to end: counts on the real grids, conversions that
//! read back identical, refusals and exit codes.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_aeroshape"))
}

fn shared(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/su2")
        .join(name)
}

fn run(args: &[&std::ffi::OsStr]) -> Output {
    bin().args(args).output().unwrap()
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

#[test]
fn info_prints_the_brick_counts_and_markers() {
    let brick = shared("mesh_brick_tets_ffd.su2");
    let o = run(&["mesh".as_ref(), "info".as_ref(), brick.as_os_str()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = stdout(&o);
    assert!(s.contains("nodes: 11703\n"), "{s}");
    assert!(s.contains("tetra: 59156\n"), "{s}");
    for m in ["x_m", "x_p", "y_m", "y_p", "z_m", "z_p"] {
        assert!(s.contains(&format!("  {m}: ")), "{s}");
    }
    assert!(s.contains(", 0 invalid (q <= 0)"), "{s}");
}

#[test]
fn info_json_is_machine_readable() {
    let naca = shared("mesh_NACA0012_inv.su2");
    let o = run(&[
        "mesh".as_ref(),
        "info".as_ref(),
        naca.as_os_str(),
        "--json".as_ref(),
    ]);
    assert!(o.status.success());
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["dim"], 2);
    assert_eq!(v["nodes"], 5233);
    assert_eq!(v["cell_kinds"]["triangle"], 10216);
    assert_eq!(v["markers"][0]["name"], "airfoil");
    assert_eq!(v["markers"][0]["elements"], 200);
    assert_eq!(v["markers"][1]["name"], "farfield");
    assert_eq!(v["quality"]["n_nonpositive"], 0);
    let q = &v["quality"];
    assert!(q["min"].as_f64().unwrap() <= q["p1"].as_f64().unwrap());
    assert!(q["p1"].as_f64().unwrap() <= q["mean"].as_f64().unwrap());
}

fn conn(set: &mesh::Elements) -> Vec<(mesh::ElementKind, Vec<u32>)> {
    set.groups()
        .iter()
        .map(|g| (g.kind, g.nodes.clone()))
        .collect()
}

#[test]
fn convert_chain_reads_back_identical() {
    let dir = tempfile::tempdir().unwrap();
    let brick = shared("mesh_brick_tets_ffd.su2");
    let a = mesh::io::read_path(&brick).unwrap();
    let steps: [(&str, &[&str]); 4] = [
        ("a.msh", &["--binary"]),
        ("b.vtu", &[]),
        ("c.vtu", &["--base64"]),
        ("d.su2", &[]),
    ];
    let mut prev = brick.clone();
    for (name, flags) in steps {
        let out = dir.path().join(name);
        let mut args: Vec<&std::ffi::OsStr> = vec![
            "mesh".as_ref(),
            "convert".as_ref(),
            prev.as_os_str(),
            out.as_os_str(),
        ];
        args.extend(flags.iter().map(|f| std::ffi::OsStr::new(*f)));
        let o = run(&args);
        assert!(
            o.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let b = mesh::io::read_path(&out).unwrap();
        assert_eq!(a.coords, b.coords, "{name}");
        // Connectivity (entity tags picked up in .msh are not compared).
        assert_eq!(conn(&a.cells), conn(&b.cells), "{name}");
        let markers = |m: &mesh::Mesh| {
            m.markers
                .iter()
                .map(|k| (k.name.clone(), conn(&k.elements)))
                .collect::<Vec<_>>()
        };
        assert_eq!(markers(&a), markers(&b), "{name}");
        prev = out;
    }
    // The final SU2 has no FFD section (it went through .msh and .vtu): stderr said so.
}

#[test]
fn msh_to_msh_keeps_classification() {
    let dir = tempfile::tempdir().unwrap();
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/mesh/box_param.msh");
    let out = dir.path().join("copy.msh");
    let o = run(&[
        "mesh".as_ref(),
        "convert".as_ref(),
        src.as_os_str(),
        out.as_os_str(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let a = mesh::io::read_path(&src).unwrap();
    let b = mesh::io::read_path(&out).unwrap();
    assert_eq!(a.classes, b.classes);
    assert_eq!(a.entities, b.entities);
    assert!(b.parametric);
}

#[test]
fn refusals_and_errors_exit_1_with_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let copy = dir.path().join("g.su2");
    std::fs::copy(shared("mesh_NACA0012_inv.su2"), &copy).unwrap();
    // Output equal to the input.
    let o = run(&[
        "mesh".as_ref(),
        "convert".as_ref(),
        copy.as_os_str(),
        copy.as_os_str(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("overwrite an input"));
    // Unknown output extension; nothing written.
    let bad = dir.path().join("g.cgns");
    let o = run(&[
        "mesh".as_ref(),
        "convert".as_ref(),
        copy.as_os_str(),
        bad.as_os_str(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(!bad.exists());
    // A malformed input names file and line; the output is not created.
    let broken = dir.path().join("broken.su2");
    std::fs::write(&broken, "NDIME= 2\nNELEM= 1\n5 0 1 x\n").unwrap();
    let out = dir.path().join("o.vtu");
    let o = run(&[
        "mesh".as_ref(),
        "convert".as_ref(),
        broken.as_os_str(),
        out.as_os_str(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("broken.su2: line 3:"), "{err}");
    assert!(!out.exists());
    let o = run(&["mesh".as_ref(), "info".as_ref(), broken.as_os_str()]);
    assert_eq!(o.status.code(), Some(1));
    // Usage error: exit 2; --help: exit 0.
    let o = run(&["mesh".as_ref(), "info".as_ref()]);
    assert_eq!(o.status.code(), Some(2));
    let o = run(&["mesh".as_ref(), "convert".as_ref(), "--help".as_ref()]);
    assert_eq!(o.status.code(), Some(0));
    assert!(stdout(&o).contains("--binary"));
}
