//! Every subcommand that prints a lot stops quietly when the reader of its output goes away
//! (`aeroshape param list CASE | head -1`): exit 0, nothing on stderr, no panic.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

fn root() -> PathBuf {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../..")).to_path_buf()
}

/// Runs the program with stdout on a pipe whose read end is already closed, so that its
/// first write fails with a broken pipe whatever the timing (a `| head -1` that has read its
/// line before the program writes the next).
fn run_into_closed_pipe(args: &[&str], file: &Path) -> std::process::Output {
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    Command::new(env!("CARGO_BIN_EXE_aeroshape"))
        .args(args)
        .arg(file)
        .stdout(writer)
        .stderr(Stdio::piped())
        .output()
        .unwrap()
}

#[test]
fn printing_into_a_closed_pipe_exits_quietly() {
    let r = root();
    let cases: [(&[&str], PathBuf); 8] = [
        (
            &["param", "list"],
            r.join("fixtures/cases/wing_body_param.ron"),
        ),
        (
            &["param", "list", "--json"],
            r.join("fixtures/cases/wing_body_param.ron"),
        ),
        (&["geom", "info"], r.join("fixtures/geom/wing_body.ron")),
        (
            &["geom", "info", "--json"],
            r.join("fixtures/geom/wing_body.ron"),
        ),
        (&["geom", "check"], r.join("fixtures/geom/sphere.ron")),
        (&["mesh", "info"], r.join("fixtures/grids/wing_body.su2")),
        (
            &["mesh", "info", "--json"],
            r.join("fixtures/grids/wing_body.su2"),
        ),
        (
            &["section", "fit"],
            r.join("fixtures/airfoils/naca2412.dat"),
        ),
    ];
    for (args, file) in &cases {
        let o = run_into_closed_pipe(args, file);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            o.status.success() && !err.contains("panicked") && !err.contains("error"),
            "aeroshape {} {}: {:?}\n{err}",
            args.join(" "),
            file.display(),
            o.status
        );
    }
}

/// The same commands with a reader print normally (the closed pipe is what the test above
/// changes).
#[test]
fn printing_into_an_open_pipe_prints() {
    let o = Command::new(env!("CARGO_BIN_EXE_aeroshape"))
        .args(["param", "list"])
        .arg(root().join("fixtures/cases/wing_body_param.ron"))
        .output()
        .unwrap();
    assert!(o.status.success());
    assert!(String::from_utf8_lossy(&o.stdout).lines().count() > 10);
}
