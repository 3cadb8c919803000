//! `cargo xtask tidy`: the architecture invariants that a compiler does not check
//! (ARCHITECTURE.md lists them), also run as a `#[test]` of xtask. Every rule reports all
//! its violations at once, one line each, naming the crate, file or commit.
//!
//! * **Layering** ([`deps`]): crates depend only on crates above them in [`LAYERS`] (no
//!   upward edges, no cycles); `testkit` only as a dev-dependency.
//! * **Only surfgrid knows both the geometry and the grid** ([`deps`]): a crate that
//!   depends on both `geom-db` and `mesh` must be listed in [`GEOMETRY_AND_GRID`], and in
//!   its `src/` it may name under `geom_db::` and `intersect::` only the paths listed there
//!   (surfgrid: anything; the others: no point inversion of grid nodes of their own).
//! * **The top crates are thin** ([`deps`]): only `aeroshape-cli` depends on clap,
//!   indicatif and plotters, only `aeroshape-py` on PyO3 and numpy ([`FRONT_END`]).
//! * **No environment or /proc in library code** ([`files`]): the `src/` of a library
//!   crate does not read environment variables (`std::env::var…`) or `/proc`; benchmarks
//!   and traces take options. Exceptions: [`ENV_EXCEPTIONS`].
//! * **One idea per file** ([`files`]): no `.rs` file of a library crate's `src/` is over
//!   [`MAX_LINES`] lines unless its `//!` doc says why it is one idea (the words "one idea"
//!   in its leading doc block). Exceptions: [`LONG_FILE_EXCEPTIONS`].
//! * **File headers** ([`files`]): every `.rs` file starts with a `//!` doc line.
//! * **Commit subjects** ([`commits`]): every commit since [`COMMITS_SINCE`] has a subject
//!   of at most [`MAX_SUBJECT`] characters, except the landed ones in
//!   [`LONG_SUBJECT_EXCEPTIONS`].
//!
//! An exception that no longer applies is itself a problem, so the lists only shrink.

use std::path::{Path, PathBuf};

mod commits;
mod deps;
mod files;
mod paths;

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

/// A crate allowed to depend on both the geometry (`geom-db`) and the grid (`mesh`), with
/// the paths it may name in its `src/` under `geom_db::` and `intersect::` (an entry `X`
/// allows `X` and everything under it; `*` allows everything).
#[derive(Debug, Clone, Copy)]
pub struct Knows {
    /// The crate.
    pub krate: &'static str,
    /// Allowed paths under `geom_db::`.
    pub geom_db: &'static [&'static str],
    /// Allowed paths under `intersect::`.
    pub intersect: &'static [&'static str],
    /// Why it holds both.
    pub why: &'static str,
}

/// The crates that depend on both `geom-db` and `mesh`. Only `surfgrid` relates grid nodes
/// to geometric entities (classification by point inversion, update at frozen
/// parameters); the others hold both to evaluate supports or to drive the chain, and name
/// no projection (`intersect::project`) of their own.
pub const GEOMETRY_AND_GRID: &[Knows] = &[
    Knows {
        krate: "surfgrid",
        geom_db: &["*"],
        intersect: &["*"],
        why: "ties grid nodes to geometric entities: classification, update",
    },
    Knows {
        krate: "deform",
        geom_db: &[
            "GeomDb",
            "CornerId",
            "CurveId",
            "CurveCompId",
            "SurfaceId",
            "SurfCompId",
            "SupportCurve",
            "SupportSurface",
            "eval",
            "invert",
            "newton",
            "prelude",
        ],
        intersect: &[],
        why: "evaluates the support a sliding node lies on (Eqs. 27-33) and puts the node back \
              on it by geom-db's foot of the normal (Eq. 11) on that one known support",
    },
    Knows {
        krate: "aeroshape",
        geom_db: &[
            "GeomDb",
            "Error",
            "prelude",
            "SurfaceId",
            "CurveCompId",
            "eval",
            "import",
            "linearise",
        ],
        intersect: &["Error", "update", "measure"],
        why: "drives the chain; ties the wall to the geometry through surfgrid; `case init` \
              imports the CAD and samples its surfaces and curves (never grid nodes) for the \
              default design space; the constraints measure the model (intersect's measures) \
              and differentiate them along model tangents",
    },
    Knows {
        krate: "aeroshape-py",
        geom_db: &["GeomDb", "Error", "prelude"],
        intersect: &[],
        why: "the Python package: wraps Study and the deformation",
    },
    Knows {
        krate: "aeroshape-cli",
        geom_db: &["*"],
        intersect: &["Error", "update", "check"],
        why: "the program: geometry subcommands and pictures, the chain via the library",
    },
];

/// The front-end crates and the one workspace crate that may depend on each group: the
/// command line and pictures (`aeroshape-cli`), Python (`aeroshape-py`).
pub const FRONT_END: &[(&str, &[&str])] = &[
    ("aeroshape-cli", &["clap", "indicatif", "plotters"]),
    ("aeroshape-py", &["pyo3", "numpy"]),
];

/// Library files that still read the environment or /proc, with the reason (none: issue 21,
/// item 6, moved the deform traces to options).
pub const ENV_EXCEPTIONS: &[(&str, &str)] = &[];

/// Largest number of lines of a library `.rs` file whose doc does not say why it is one
/// idea.
pub const MAX_LINES: usize = 900;

/// Library files over [`MAX_LINES`] lines whose split is pending, with the reason.
pub const LONG_FILE_EXCEPTIONS: &[(&str, &str)] = &[];

/// The commit from which commit subjects are checked (main when the rule was made).
pub const COMMITS_SINCE: &str = "e5cf37f37b5671af23084d85422db8815a4ea43f";

/// Longest commit subject, in characters.
pub const MAX_SUBJECT: usize = 72;

/// Commits on main since [`COMMITS_SINCE`] whose longer subject cannot be changed any more
/// (main's history is never rewritten). Nothing may be added here.
pub const LONG_SUBJECT_EXCEPTIONS: &[&str] = &[
    // "Python package aeroshape (PyO3, rust-numpy, maturin) and aeroshape.openmdao" (75)
    "b33685ae8ec0571b4083047d7a6b2c6939329512",
];

/// A workspace package as `cargo metadata` describes it.
#[derive(Debug, Clone)]
pub struct Package {
    /// Its name.
    pub name: String,
    /// The folder of its manifest.
    pub dir: PathBuf,
    /// True when it has a library target.
    pub is_lib: bool,
    /// Its dependencies: (name, kind), kind "normal", "dev" or "build".
    pub deps: Vec<(String, String)>,
}

/// The workspace's packages from `cargo metadata` (offline, no dependencies resolved).
pub fn packages(root: &Path) -> Result<Vec<Package>, String> {
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
    let mut pkgs = Vec::new();
    for p in meta["packages"].as_array().into_iter().flatten() {
        let manifest = PathBuf::from(p["manifest_path"].as_str().unwrap_or_default());
        pkgs.push(Package {
            name: p["name"].as_str().unwrap_or_default().to_string(),
            dir: manifest.parent().map(Path::to_path_buf).unwrap_or_default(),
            is_lib: p["targets"].as_array().into_iter().flatten().any(|t| {
                t["kind"]
                    .as_array()
                    .into_iter()
                    .flatten()
                    .any(|k| k == "lib")
            }),
            deps: p["dependencies"]
                .as_array()
                .into_iter()
                .flatten()
                .map(|d| {
                    (
                        d["name"].as_str().unwrap_or_default().to_string(),
                        d["kind"].as_str().unwrap_or("normal").to_string(),
                    )
                })
                .collect(),
        });
    }
    pkgs.sort_by(|a, b| a.name.cmp(&b.name));
    Ok(pkgs)
}

/// Every `.rs` file under `dir`, sorted.
pub(crate) fn rs_files(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                if p.file_name().is_some_and(|n| n != "target") {
                    stack.push(p);
                }
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// `path` relative to `root`, with `/` separators.
pub(crate) fn rel(root: &Path, path: &Path) -> String {
    path.strip_prefix(root)
        .unwrap_or(path)
        .to_string_lossy()
        .replace('\\', "/")
}

/// Runs every check and reports all violations at once.
pub fn run(root: &Path) -> Result<(), String> {
    let pkgs = packages(root)?;
    let mut problems = deps::layering(&pkgs);
    problems.extend(deps::geometry_and_grid(root, &pkgs, GEOMETRY_AND_GRID));
    for (krate, front) in FRONT_END {
        problems.extend(deps::front_end_only_in(&pkgs, krate, front));
    }
    problems.extend(files::file_headers(root));
    problems.extend(files::no_environment(root, &pkgs, ENV_EXCEPTIONS));
    problems.extend(files::long_files(
        root,
        &pkgs,
        MAX_LINES,
        LONG_FILE_EXCEPTIONS,
    ));
    problems.extend(commits::subjects(
        root,
        COMMITS_SINCE,
        MAX_SUBJECT,
        LONG_SUBJECT_EXCEPTIONS,
    ));
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

#[cfg(test)]
mod tests {
    #[test]
    fn workspace_is_tidy() {
        super::run(&crate::root()).unwrap();
    }
}
