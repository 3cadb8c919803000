//! `cargo xtask regress [--bless] [--skip-ignored-tests]`: the regression suite.
//!
//! 1. Runs the chain cases (`fixtures/cases/default`, `fixtures/cases/sphere`) into
//!    `target/regress/<case>/` and compares figures of their `report.json` with
//!    `fixtures/reference/<case>.json`, each within its own tolerance
//!    (|value − reference| ≤ abs + rel·|reference|, or an upper bound); `--bless` rewrites the
//!    references from this run instead.
//! 2. Runs the ignored (heavy) tests: `cargo test --workspace -- --ignored`.
//! 3. Round trips through other tools when they are installed (skipped with a note
//!    otherwise): meshio reads `deformed.vtu` and `deformed.su2` with the same node count
//!    and coordinates (its MSH reader has no parametric nodes); Gmsh opens `deformed.msh`
//!    with the node count of `deformed.su2`.
//! 4. The default case's checked box (`fixtures/cases/default/case_box.ron`, written by
//!    `aeroshape case check`): 40 design vectors drawn uniformly in it, each through
//!    `aeroshape run`, every cell of every deformed grid checked by corner Jacobians in
//!    numpy (`fixtures/cases/box_sample.py`, not aeroshape's quality code); skipped with a
//!    note without meshio.
//! 5. The distributed deformation under `mpirun` (`regress_mpi`; skipped without MPI).
//!
//! Fails with one line per drifted quantity: case, name, value, reference, tolerance.

use std::path::Path;
use std::process::Command;

use serde_json::{Map, Value, json};

use crate::chain;

/// Cases compared against references.
const CASES: &[&str] = &["default", "sphere"];

/// How a quantity is compared with its reference.
#[derive(Clone, Copy)]
enum Tol {
    /// |v − ref| ≤ abs + rel·|ref|.
    Close { rel: f64, abs: f64 },
    /// v ≤ bound (the reference is recorded but not compared).
    AtMost(f64),
}

/// The compared quantities: name, JSON path in report.json, tolerance.
const QUANTITIES: &[(&str, &[&str], Tol)] = &[
    (
        "grid nodes",
        &["setup", "nodes"],
        Tol::Close { rel: 0.0, abs: 0.0 },
    ),
    (
        "grid cells",
        &["setup", "cells"],
        Tol::Close { rel: 0.0, abs: 0.0 },
    ),
    (
        "wall nodes",
        &["setup", "wall_nodes"],
        Tol::Close { rel: 0.0, abs: 0.0 },
    ),
    (
        "control nodes moved",
        &["evaluation", "param", "nodes_moved"],
        Tol::Close { rel: 0.0, abs: 0.0 },
    ),
    (
        "max control-node move",
        &["evaluation", "param", "max_move"],
        Tol::Close {
            rel: 1e-9,
            abs: 1e-12,
        },
    ),
    (
        "curves re-intersected",
        &["evaluation", "model", "curves_reintersected"],
        Tol::Close { rel: 0.0, abs: 0.0 },
    ),
    (
        "junction residual (relative)",
        &["evaluation", "model", "junction_residual_rel"],
        Tol::AtMost(1e-8),
    ),
    (
        "wall nodes moved",
        &["evaluation", "surface", "moved_nodes"],
        Tol::Close { rel: 0.0, abs: 0.0 },
    ),
    (
        "max wall displacement",
        &["evaluation", "surface", "max_displacement"],
        Tol::Close {
            rel: 1e-6,
            abs: 1e-12,
        },
    ),
    (
        "worst wall triangle",
        &["evaluation", "surface", "worst_triangle"],
        Tol::Close {
            rel: 1e-3,
            abs: 1e-6,
        },
    ),
    (
        "deform iterations",
        &["evaluation", "deform", "report", "iterations"],
        Tol::Close {
            rel: 0.25,
            abs: 2.0,
        },
    ),
    (
        "deform residual",
        &["evaluation", "deform", "report", "residual"],
        Tol::AtMost(1e-6),
    ),
    (
        "quality min after",
        &["evaluation", "quality_after", "min"],
        Tol::Close {
            rel: 0.0,
            abs: 2e-3,
        },
    ),
    (
        "quality mean after",
        &["evaluation", "quality_after", "mean"],
        Tol::Close {
            rel: 0.0,
            abs: 2e-4,
        },
    ),
    (
        "quality 1st percentile after",
        &["evaluation", "quality_after", "p1"],
        Tol::Close {
            rel: 0.0,
            abs: 2e-3,
        },
    ),
    (
        "inverted cells after",
        &["evaluation", "quality_after", "inverted"],
        Tol::AtMost(0.0),
    ),
    (
        "wall nodes off support (relative)",
        &["evaluation", "wall_support_rel"],
        Tol::AtMost(1e-10),
    ),
];

fn get(v: &Value, path: &[&str]) -> Option<f64> {
    let mut x = v;
    for k in path {
        x = x.get(*k)?;
    }
    x.as_f64()
}

/// Runs the regression suite.
pub fn run(root: &Path, args: &[String]) -> Result<(), String> {
    let bless = args.iter().any(|a| a == "--bless");
    let mut drift = Vec::new();
    let refdir = root.join("fixtures").join("reference");
    for case in CASES {
        let dir = format!("fixtures/cases/{case}");
        if !root.join(&dir).join("case.ron").exists() {
            drift.push(format!("{case}: {dir}/case.ron is missing"));
            continue;
        }
        let out = root.join("target").join("regress").join(case);
        chain::run_case(root, &dir, &out)?;
        let report = chain::read_report(&out)?;
        chain::print_summary(&report, &out);
        let refpath = refdir.join(format!("{case}.json"));
        if bless {
            let mut m = Map::new();
            for (name, path, _) in QUANTITIES {
                let v = get(&report, path)
                    .ok_or_else(|| format!("{case}: report.json has no {}", path.join(".")))?;
                m.insert(name.to_string(), json!(v));
            }
            std::fs::create_dir_all(&refdir).map_err(|e| format!("{}: {e}", refdir.display()))?;
            let text =
                serde_json::to_string_pretty(&Value::Object(m)).map_err(|e| e.to_string())?;
            crate::fixtures::write_atomic(&refpath, (text + "\n").as_bytes())?;
            eprintln!("blessed {}", refpath.display());
        } else {
            let text = std::fs::read_to_string(&refpath).map_err(|e| {
                format!(
                    "{}: {e} (run `cargo xtask regress --bless`)",
                    refpath.display()
                )
            })?;
            let reference: Value =
                serde_json::from_str(&text).map_err(|e| format!("{}: {e}", refpath.display()))?;
            for (name, path, tol) in QUANTITIES {
                let v = get(&report, path).unwrap_or(f64::NAN);
                let ok = match *tol {
                    Tol::AtMost(b) => v <= b,
                    Tol::Close { rel, abs } => match reference.get(*name).and_then(Value::as_f64) {
                        Some(r) => (v - r).abs() <= abs + rel * r.abs(),
                        None => false,
                    },
                };
                if !ok {
                    let r = reference.get(*name).cloned().unwrap_or(Value::Null);
                    let t = match *tol {
                        Tol::AtMost(b) => format!("at most {b:e}"),
                        Tol::Close { rel, abs } => format!("abs {abs:e} + rel {rel:e}"),
                    };
                    drift.push(format!(
                        "{case}: {name}: {v} (reference {r}, tolerance {t})"
                    ));
                }
            }
        }
        round_trips(&out, case, &mut drift);
    }
    checked_box(root, &mut drift);
    if args.iter().any(|a| a == "--skip-ignored-tests") {
        println!("regress: ignored tests skipped (--skip-ignored-tests)");
    } else {
        crate::cargo(&["test", "--workspace", "--", "--ignored"])?;
    }
    crate::regress_mpi::run(root, &mut drift)?;
    if drift.is_empty() {
        println!("regress: all quantities within tolerance");
        Ok(())
    } else {
        for d in &drift {
            eprintln!("drift: {d}");
        }
        Err(format!("{} quantities drifted", drift.len()))
    }
}

/// meshio and Gmsh round trips of the outputs, if those Python packages are installed.
fn round_trips(out: &Path, case: &str, drift: &mut Vec<String>) {
    let dir = out.display().to_string();
    // meshio reads .vtu and .su2 (its MSH 4.1 reader does not implement parametric nodes:
    // the .msh is checked with Gmsh itself)
    let meshio = format!(
        r#"
import meshio, sys
import numpy as np
d = "{dir}"
m = {{f: meshio.read(d + "/deformed." + f) for f in ("vtu", "su2")}}
n = {{f: len(x.points) for f, x in m.items()}}
if len(set(n.values())) != 1:
    sys.exit("node counts differ: %r" % n)
err = float(np.abs(m["vtu"].points - m["su2"].points).max())
print("meshio: %d nodes in .vtu and .su2, max coordinate difference %.3e" % (n["vtu"], err))
if err > 1e-12 * max(1.0, float(np.abs(m["vtu"].points).max())):
    sys.exit("coordinates differ by %g" % err)
"#
    );
    let gmsh = format!(
        r#"
import gmsh, sys
gmsh.initialize(["-v", "0"])
gmsh.option.setNumber("General.Verbosity", 0)
gmsh.open("{dir}/deformed.msh")
tags, xyz, _ = gmsh.model.mesh.getNodes()
types, etags, _ = gmsh.model.mesh.getElements()
print("gmsh: deformed.msh opened, %d nodes, %d elements" % (len(tags), sum(len(t) for t in etags)))
gmsh.finalize()
ref = [l for l in open("{dir}/deformed.su2") if l.startswith("NPOIN")][0].split()[1]
if len(tags) != int(ref):
    sys.exit("gmsh reads %d nodes, deformed.su2 has %s" % (len(tags), ref))
"#
    );
    for (tool, script) in [("meshio", meshio), ("gmsh", gmsh)] {
        let have = Command::new("python3")
            .args(["-c", &format!("import {tool}")])
            .output()
            .map(|o| o.status.success())
            .unwrap_or(false);
        if !have {
            println!("{case}: {tool} round trip skipped ({tool} not installed)");
            continue;
        }
        match Command::new("python3").args(["-c", &script]).output() {
            Ok(o) if o.status.success() => {
                print!("{case}: {}", String::from_utf8_lossy(&o.stdout));
            }
            Ok(o) => drift.push(format!(
                "{case}: {tool} round trip: {}",
                String::from_utf8_lossy(&o.stderr).trim()
            )),
            Err(e) => drift.push(format!("{case}: {tool}: {e}")),
        }
    }
}

/// Step 4 of the module doc: the checked box of the default case by the independent check.
fn checked_box(root: &Path, drift: &mut Vec<String>) {
    let have = Command::new("python3")
        .args(["-c", "import meshio, numpy"])
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false);
    if !have {
        println!("default: checked box skipped (meshio not installed)");
        return;
    }
    let cli = root.join("target/release/aeroshape");
    let work = root.join("target/regress/box");
    let o = Command::new("python3")
        .arg(root.join("fixtures/cases/box_sample.py"))
        .arg(root.join("fixtures/cases/default/case_box.ron"))
        .args(["--n", "40", "--seed", "7", "--cli"])
        .arg(&cli)
        .arg("--work")
        .arg(&work)
        .output();
    match o {
        Ok(o) => {
            let text = String::from_utf8_lossy(&o.stdout);
            let last = text.lines().last().unwrap_or("?");
            if o.status.success() {
                println!("default: {last}");
            } else {
                drift.push(format!("default: checked box: {last}"));
            }
        }
        Err(e) => drift.push(format!("default: checked box: cannot run python3: {e}")),
    }
}
