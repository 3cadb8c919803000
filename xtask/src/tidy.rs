//! `cargo xtask tidy`: the architecture invariants that a compiler does not check.
//!
//! * Crates depend only on crates above them in [`LAYERS`] (no upward edges, no cycles).
//! * Every `.rs` file starts with a `//!` module doc line.

use std::path::Path;

/// The workspace crates from top (depends on nothing of ours) to bottom. A crate may depend
/// on crates that come before it. `testkit` may be a dev-dependency of anyone.
pub const LAYERS: &[&str] = &[
    "sparse",
    "iges",
    "step",
    "geom-db",
    "mesh",
    "intersect",
    "param",
    "surfgrid",
    "deform",
    "wingmaster",
    "aeroshape",
    "aeroshape-cli",
    "aeroshape-py",
    "xtask",
];

/// Runs every check and reports all violations at once.
pub fn run(root: &Path) -> Result<(), String> {
    let mut problems = layering(root)?;
    problems.extend(file_headers(root));
    if problems.is_empty() {
        eprintln!("tidy: ok");
        Ok(())
    } else {
        Err(format!(
            "tidy found {} problem(s):\n  {}",
            problems.len(),
            problems.join("\n  ")
        ))
    }
}

fn layering(root: &Path) -> Result<Vec<String>, String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = std::process::Command::new(cargo)
        .args([
            "metadata",
            "--format-version",
            "1",
            "--no-deps",
            "--offline",
        ])
        .current_dir(root)
        .output()
        .map_err(|e| format!("cargo metadata: {e}"))?;
    if !out.status.success() {
        return Err(format!(
            "cargo metadata failed: {}",
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    let meta: serde_json::Value =
        serde_json::from_slice(&out.stdout).map_err(|e| format!("cargo metadata output: {e}"))?;
    let mut problems = Vec::new();
    let rank = |name: &str| LAYERS.iter().position(|l| *l == name);
    for pkg in meta["packages"].as_array().into_iter().flatten() {
        let name = pkg["name"].as_str().unwrap_or_default();
        if name == "testkit" {
            continue;
        }
        let Some(me) = rank(name) else {
            problems.push(format!("crate `{name}` is not in xtask/src/tidy.rs LAYERS"));
            continue;
        };
        for dep in pkg["dependencies"].as_array().into_iter().flatten() {
            let dname = dep["name"].as_str().unwrap_or_default();
            let dev = dep["kind"].as_str() == Some("dev");
            if dname == "testkit" {
                if !dev {
                    problems.push(format!(
                        "`{name}` depends on testkit outside dev-dependencies"
                    ));
                }
                continue;
            }
            if let Some(them) = rank(dname)
                && them >= me
            {
                problems.push(format!(
                    "`{name}` depends on `{dname}`, which is not above it"
                ));
            }
        }
    }
    Ok(problems)
}

fn file_headers(root: &Path) -> Vec<String> {
    let mut problems = Vec::new();
    let mut stack = vec![root.join("crates"), root.join("xtask"), root.join("tests")];
    while let Some(dir) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        for entry in entries.flatten() {
            let path = entry.path();
            if path.is_dir() {
                if path.file_name().is_some_and(|n| n != "target") {
                    stack.push(path);
                }
            } else if path.extension().is_some_and(|e| e == "rs") {
                let text = std::fs::read_to_string(&path).unwrap_or_default();
                if !text.trim_start().starts_with("//!") {
                    let rel = path.strip_prefix(root).unwrap_or(&path);
                    problems.push(format!(
                        "{}: does not start with a `//!` doc line",
                        rel.display()
                    ));
                }
            }
        }
    }
    problems.sort();
    problems
}

#[cfg(test)]
mod tests {
    #[test]
    fn workspace_is_tidy() {
        super::run(&crate::root()).unwrap();
    }
}
