//! The dependency rules: layering, and "only surfgrid knows both the geometry and the grid"
//! (which crates may depend on both `geom-db` and `mesh`, and what they may name).

use std::path::Path;

use super::paths::{allowed, named_paths};
use super::{Knows, LAYERS, Package, rel, rs_files};

/// Upward or unknown edges: a crate may depend only on crates before it in [`LAYERS`];
/// `testkit` only as a dev-dependency.
pub fn layering(pkgs: &[Package]) -> Vec<String> {
    let mut problems = Vec::new();
    let rank = |name: &str| LAYERS.iter().position(|l| *l == name);
    for pkg in pkgs {
        if pkg.name == "testkit" {
            continue;
        }
        let Some(me) = rank(&pkg.name) else {
            problems.push(format!(
                "crate `{}` is not in xtask/src/tidy/mod.rs LAYERS",
                pkg.name
            ));
            continue;
        };
        for (dep, kind) in &pkg.deps {
            if dep == "testkit" {
                if kind != "dev" {
                    problems.push(format!(
                        "`{}` depends on testkit outside dev-dependencies",
                        pkg.name
                    ));
                }
                continue;
            }
            if let Some(them) = rank(dep)
                && them >= me
            {
                problems.push(format!(
                    "`{}` depends on `{dep}`, which is not above it",
                    pkg.name
                ));
            }
        }
    }
    problems
}

/// Only `cli` may depend (directly, outside dev-dependencies) on the crates in `front`
/// (e.g. the command line and the pictures): the library an MDO framework embeds compiles
/// none of them.
pub fn front_end_only_in(pkgs: &[Package], cli: &str, front: &[&str]) -> Vec<String> {
    let mut problems = Vec::new();
    for pkg in pkgs.iter().filter(|p| p.name != cli) {
        for (dep, kind) in &pkg.deps {
            if kind != "dev" && front.contains(&dep.as_str()) {
                problems.push(format!(
                    "`{}` depends on `{dep}`: only `{cli}` may (FRONT_END, \
                     xtask/src/tidy/mod.rs)",
                    pkg.name
                ));
            }
        }
    }
    problems
}

/// True when `pkg` is, or depends (outside dev-dependencies) on, `krate`.
fn knows(pkg: &Package, krate: &str) -> bool {
    pkg.name == krate || pkg.deps.iter().any(|(d, k)| d == krate && k != "dev")
}

/// The rule "only surfgrid knows both the geometry and the grid": a crate that knows both
/// `geom-db` and `mesh` must be in `list`, and the paths its `src/` names under `geom_db::`
/// and `intersect::` must be among the listed ones.
pub fn geometry_and_grid(root: &Path, pkgs: &[Package], list: &[Knows]) -> Vec<String> {
    let mut problems = Vec::new();
    for pkg in pkgs {
        if !(knows(pkg, "geom-db") && knows(pkg, "mesh")) {
            continue;
        }
        let Some(entry) = list.iter().find(|k| k.krate == pkg.name) else {
            problems.push(format!(
                "`{}` depends on both geom-db and mesh; only surfgrid relates grid nodes to \
                 the geometry (list it in GEOMETRY_AND_GRID, xtask/src/tidy/mod.rs, only with \
                 a reason and the items it needs)",
                pkg.name
            ));
            continue;
        };
        for file in rs_files(&pkg.dir.join("src")) {
            let text = std::fs::read_to_string(&file).unwrap_or_default();
            problems.extend(named_outside(&pkg.name, &rel(root, &file), &text, entry));
        }
    }
    for k in list {
        if !pkgs.iter().any(|p| p.name == k.krate) {
            problems.push(format!(
                "GEOMETRY_AND_GRID lists `{}`, which is not a workspace crate",
                k.krate
            ));
        }
    }
    problems
}

/// The paths of `text` under `geom_db::` and `intersect::` that `entry` does not allow.
fn named_outside(krate: &str, file: &str, text: &str, entry: &Knows) -> Vec<String> {
    let mut problems = Vec::new();
    for (root, allow) in [("geom_db", entry.geom_db), ("intersect", entry.intersect)] {
        for path in named_paths(text, root) {
            if !allowed(&path, allow) {
                problems.push(format!(
                    "{file}: `{krate}` knows both geometry and grid ({}) and names \
                     `{root}::{path}`, which GEOMETRY_AND_GRID does not allow it",
                    entry.why
                ));
            }
        }
    }
    problems
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pkg(name: &str, deps: &[(&str, &str)]) -> Package {
        Package {
            name: name.into(),
            dir: std::path::PathBuf::from("/nonexistent"),
            is_lib: true,
            deps: deps
                .iter()
                .map(|(d, k)| (d.to_string(), k.to_string()))
                .collect(),
        }
    }

    #[test]
    fn a_crate_that_takes_both_geometry_and_grid_must_be_listed() {
        let list = [Knows {
            krate: "surfgrid",
            geom_db: &["*"],
            intersect: &["*"],
            why: "",
        }];
        let pkgs = [
            pkg("surfgrid", &[("geom-db", "normal"), ("mesh", "normal")]),
            pkg("param", &[("geom-db", "normal"), ("mesh", "dev")]),
            pkg("intersect", &[("geom-db", "normal"), ("mesh", "normal")]),
            pkg("mesh", &[("geom-db", "normal")]),
        ];
        let p = geometry_and_grid(Path::new("/"), &pkgs, &list);
        assert_eq!(p.len(), 2, "{p:#?}");
        assert!(p[0].starts_with("`intersect` depends on both"), "{}", p[0]);
        assert!(p[1].starts_with("`mesh` depends on both"), "{}", p[1]);
    }

    #[test]
    fn a_listed_crate_may_name_only_its_items() {
        let entry = Knows {
            krate: "aeroshape",
            geom_db: &["GeomDb", "prelude"],
            intersect: &["update"],
            why: "drives the chain",
        };
        let ok = "use geom_db::{GeomDb, prelude::Point3};\nuse intersect::update::ModelBaseline;";
        assert!(named_outside("aeroshape", "a.rs", ok, &entry).is_empty());
        let bad = "use intersect::project::{ProjectOptions, SurfaceProjector};\n\
                   fn f() { geom_db::import::import(); }";
        let p = named_outside("aeroshape", "a.rs", bad, &entry);
        assert_eq!(p.len(), 3, "{p:#?}");
        assert!(p[0].contains("`geom_db::import::import`"), "{}", p[0]);
        assert!(
            p[1].contains("`intersect::project::ProjectOptions`"),
            "{}",
            p[1]
        );
    }

    #[test]
    fn only_the_program_takes_the_command_line_and_pictures() {
        let pkgs = [
            pkg(
                "aeroshape-cli",
                &[("clap", "normal"), ("plotters", "normal")],
            ),
            pkg(
                "aeroshape",
                &[("plotters", "normal"), ("tempfile", "normal")],
            ),
            pkg("mesh", &[("clap", "dev")]),
        ];
        let p = front_end_only_in(&pkgs, "aeroshape-cli", &["clap", "indicatif", "plotters"]);
        assert_eq!(p.len(), 1, "{p:#?}");
        assert!(p[0].starts_with("`aeroshape` depends on `plotters`"));
    }

    #[test]
    fn upward_edges_and_unknown_crates_are_reported() {
        let pkgs = [
            pkg("mesh", &[("deform", "normal")]),
            pkg("newcrate", &[]),
            pkg("deform", &[("testkit", "normal")]),
        ];
        let p = layering(&pkgs);
        assert_eq!(p.len(), 3, "{p:#?}");
    }
}
