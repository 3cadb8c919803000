//! The distributed study in `cargo xtask regress` (docs/mpi.md, "aeroshape run"): the
//! default case (`fixtures/cases/default`, its design vector `dv.ron`, the solves to 1e-11)
//! by the serial `aeroshape run` and by `mpirun -n 2` and `-n 3 --oversubscribe` of the same
//! command: every node of the deformed grid within 1e-8 of the serial one, relative to the
//! largest displacement, and no inverted cell; then a design vector naming no variable of the
//! case, which every rank must refuse alike (exit status 1, no hang). Last, the example
//! `distributed_study` at 2 and 3 ranks: a second design on the study's kept set-up, warm
//! started, within 100 × the solves' tolerance of a new study's result, and cold (after
//! `forget_warm_start`) equal to it bit for bit; the same design again, warm, in no
//! iteration.

use std::path::Path;
use std::process::Command;

use crate::regress_mpi::{REL, deviation, mpirun, su2_points};

/// The default case with absolute paths and the solves to 1e-11, written into `out`.
fn case(root: &Path, out: &Path) -> Result<std::path::PathBuf, String> {
    let dir = root.join("fixtures/cases/default");
    let text = std::fs::read_to_string(dir.join("case.ron")).map_err(|e| e.to_string())?;
    let abs = |name: &str| dir.join(name).display().to_string();
    let mut text = text
        .replacen(
            "geometry: \"wing_body.ron\"",
            &format!("geometry: {:?}", abs("wing_body.ron")),
            1,
        )
        .replacen(
            "grid: \"grid.msh\"",
            &format!("grid: {:?}", abs("grid.msh")),
            1,
        );
    if text.contains("\n  deform:") {
        return Err("fixtures/cases/default/case.ron: a deform field; update the test".into());
    }
    text = text.replacen("\n  wall:", "\n  deform: (rel_tol: 1e-11),\n  wall:", 1);
    let p = out.join("case.ron");
    std::fs::write(&p, text).map_err(|e| format!("{}: {e}", p.display()))?;
    Ok(p)
}

/// Runs the checks with the program `bin` (built with the feature `mpi`); drifts are pushed
/// on `drift`.
pub fn run(root: &Path, bin: &Path, drift: &mut Vec<String>) -> Result<(), String> {
    let out = root.join("target/regress/mpi-study");
    std::fs::create_dir_all(&out).map_err(|e| format!("{}: {e}", out.display()))?;
    let case = case(root, &out)?;
    let c = case.display().to_string();
    let dv = root.join("fixtures/cases/default/dv.ron");
    let dv = dv.display().to_string();
    let serial = out.join("serial");
    let s = serial.display().to_string();
    let args = ["run", &c, "--dv", &dv, "-o", &s, "--no-pictures"];
    eprintln!("$ aeroshape {}", args.join(" "));
    let st = Command::new(bin)
        .args(args)
        .output()
        .map_err(|e| format!("{}: {e}", bin.display()))?;
    if !st.status.success() {
        return Err(format!(
            "serial aeroshape run failed: {}",
            String::from_utf8_lossy(&st.stderr).trim()
        ));
    }
    let x0 = su2_points(&serial.join("baseline.su2"))?;
    let xs = su2_points(&serial.join("deformed.su2"))?;
    for n in [2usize, 3] {
        let o = out.join(format!("ranks{n}"));
        let os = o.display().to_string();
        let res = mpirun(
            n,
            bin,
            &["run", &c, "--dv", &dv, "-o", &os, "--no-pictures"],
        )?;
        if !res.status.success() {
            drift.push(format!(
                "mpi study: -n {n}: aeroshape run failed ({}): {}",
                res.status,
                String::from_utf8_lossy(&res.stderr)
                    .lines()
                    .next()
                    .unwrap_or("")
            ));
            continue;
        }
        let rel = deviation(&x0, &su2_points(&o.join("deformed.su2"))?, &xs);
        let r = o.join("report.json");
        let report: serde_json::Value = std::fs::read_to_string(&r)
            .ok()
            .and_then(|t| serde_json::from_str(&t).ok())
            .ok_or_else(|| format!("{}: unreadable report", r.display()))?;
        let inverted = report["evaluation"]["quality_after"]["inverted"].as_u64();
        let dist = &report["distributed"];
        println!(
            "regress: mpi study -n {n}: deviation from serial {rel:.3e} relative, {} + {} iterations, {} ghost nodes, inverted cells {inverted:?}",
            dist["iterations"], dist["rotation_iterations"], dist["ghost_nodes"]
        );
        if rel.is_nan() || rel > REL {
            drift.push(format!(
                "mpi study: -n {n}: deviation {rel:e} from the serial result exceeds {REL:e}"
            ));
        }
        if inverted != Some(0) || dist["ranks"].as_u64() != Some(n as u64) {
            drift.push(format!(
                "mpi study: -n {n}: inverted cells {inverted:?}, ranks {}",
                dist["ranks"]
            ));
        }
    }
    // A design vector naming a variable the case does not have: every rank refuses it.
    let bad = out.join("bad_dv.ron");
    std::fs::write(&bad, "{\"no_such_variable\": 0.1}").map_err(|e| e.to_string())?;
    let b = bad.display().to_string();
    let o = out.join("bad").display().to_string();
    let res = mpirun(2, bin, &["run", &c, "--dv", &b, "-o", &o, "--no-pictures"])?;
    let err = String::from_utf8_lossy(&res.stderr);
    let lines = err
        .lines()
        .filter(|l| l.contains("no_such_variable"))
        .count();
    let code = res.status.code();
    println!("regress: mpi study bad design vector: exit {code:?}, {lines} rank(s) reported it");
    if code != Some(1) || lines < 2 {
        drift.push(format!(
            "mpi study: bad design vector: exit {code:?}, {lines} of 2 ranks named the variable"
        ));
    }
    // A second design on the kept set-up against a new study (the example checks and
    // prints the gap, 0 to pass).
    let ex = root.join("target/release/examples/distributed_study");
    for n in [2usize, 3] {
        crate::regress_mpi::example(n, &ex, &[&c, &dv], "mpi study: kept set-up", drift)?;
    }
    Ok(())
}
