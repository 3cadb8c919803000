//! Sliding on geometry supports and the grid-wide stiffnesses under `mpirun` in `cargo xtask
//! regress` (docs/mpi.md): on the default case's Gmsh-made grid
//! (`fixtures/cases/default/grid.msh`), its wall nodes classified on the case's geometry
//! `wing_body.ron` with their parameters by `aeroshape surfgrid classify` (as a user ties
//! a grid of their own mesher to the geometry), the serial `aeroshape deform` and `mpirun
//! -n 2` and `-n 3 --oversubscribe` of the same command:
//! 1. `--geometry wing_body.ron --slide fuselage`: the wing moved along the fuselage, the
//!    fuselage's nodes sliding on its support surface. The sliding nodes must be as many as
//!    serially and not none, and must move (a check that passes when nothing slides would
//!    be no check).
//! 2. `--stiffness volume`, `--stiffness wall-distance` and `--rotation-reach 3` with the
//!    wing pitched, solved to 1e-13: the stiffer springs make the solution's error larger
//!    for a residual (the serial grid solved to 1e-11 is 1.1e-8 from the one solved to
//!    1e-13 with the wall-distance springs, docs/perf-log/2026-12-03-mpi-sliding.md).
//!
//! Every node of the gathered grid within 1e-8 of the serial one, relative to the largest
//! displacement, and no inverted cell; the Eq. 21 solver the constrained block multigrid
//! (`…-held`), and at most `SUPPORTS_ITERATIONS` Eq. 21 iterations in the supports case.
//! Then a geometry the grid's classification does not refer to: all three ranks of `-n 3`
//! must print the error and exit 1 (no hang).

use std::path::Path;
use std::process::Command;

use crate::regress_mpi::{REL, deviation, every_rank_failed, held_solver, mpirun, su2_points};

/// The most Eq. 21 iterations of the supports case on 2 and 3 ranks (summed over the six
/// outer iterations' solves): 126 and 126 measured with the constrained block multigrid,
/// 204 and 208 with the free one (docs/perf-log/2026-12-03-mpi-held.md).
const SUPPORTS_ITERATIONS: u64 = 145;

/// One comparison: its name and the flags after `deform GRID -o OUT`.
struct Case {
    name: &'static str,
    flags: Vec<String>,
}

fn cases(geometry: &str) -> Vec<Case> {
    let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
    let pitch = s(&[
        "--rigid",
        "wing",
        "--rotate-deg",
        "2",
        "--axis-point",
        "4.5,0,0",
        "--axis-dir",
        "0,1,0",
        "--slide",
        "symmetry",
        "--tolerance",
        "1e-13",
    ]);
    let mut slide = s(&[
        "--rigid",
        "wing",
        "--translate",
        "0.1,0,0",
        "--slide",
        "fuselage",
        "--slide",
        "symmetry",
        "--tolerance",
        "1e-11",
        "--geometry",
    ]);
    slide.push(geometry.to_string());
    let with = |k: &str| {
        let mut v = pitch.clone();
        v.extend(s(&["--stiffness", k]));
        v
    };
    vec![
        Case {
            name: "supports",
            flags: slide,
        },
        Case {
            name: "volume",
            flags: with("volume"),
        },
        Case {
            name: "wall-distance",
            flags: with("wall-distance"),
        },
        Case {
            name: "reach",
            flags: {
                let mut v = pitch.clone();
                v.extend(s(&["--rotation-reach", "3"]));
                v
            },
        },
    ]
}

fn report(path: &Path) -> Result<serde_json::Value, String> {
    std::fs::read_to_string(path)
        .ok()
        .and_then(|t| serde_json::from_str(&t).ok())
        .ok_or_else(|| format!("{}: unreadable report", path.display()))
}

/// The first line of a failed run's standard error.
fn first_line(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr)
        .lines()
        .next()
        .unwrap_or("")
        .to_string()
}

/// `aeroshape deform GRID -o OUT --report REPORT FLAGS…`'s arguments.
fn deform_args(grid: &str, out: &Path, report: &Path, flags: &[String]) -> Vec<String> {
    let mut args = vec!["deform".to_string(), grid.to_string(), "-o".into()];
    args.push(out.display().to_string());
    args.extend(["--report".into(), report.display().to_string()]);
    args.extend(flags.iter().cloned());
    args
}

/// Runs `bin` serially with `args` (printed first); an error naming `what` and the first
/// line of its standard error when it fails.
fn run_serial<S: AsRef<std::ffi::OsStr> + std::fmt::Display>(
    bin: &Path,
    args: &[S],
    what: &str,
) -> Result<(), String> {
    let shown: Vec<String> = args.iter().map(ToString::to_string).collect();
    eprintln!("$ aeroshape {}", shown.join(" "));
    let st = Command::new(bin)
        .args(args)
        .output()
        .map_err(|e| format!("{}: {e}", bin.display()))?;
    if st.status.success() {
        Ok(())
    } else {
        Err(format!("{what} failed: {}", first_line(&st)))
    }
}

/// Runs the checks with the program `bin` (built with the feature `mpi`); drifts are pushed
/// on `drift`.
pub fn run(root: &Path, bin: &Path, drift: &mut Vec<String>) -> Result<(), String> {
    let out = root.join("target/regress/mpi-slide");
    std::fs::create_dir_all(&out).map_err(|e| format!("{}: {e}", out.display()))?;
    let dir = root.join("fixtures/cases/default");
    let geometry = dir.join("wing_body.ron").display().to_string();
    let classified = out.join("classified.msh");
    let grid = classified.display().to_string();
    let base = out.join("baseline.su2");
    let gmsh = dir.join("grid.msh").display().to_string();
    for args in [
        vec![
            "surfgrid", "classify", &geometry, &gmsh, "-o", &grid, "--wall", "wing", "--wall",
            "fuselage",
        ],
        vec!["mesh", "convert", &grid, base.to_str().unwrap_or("")],
    ] {
        run_serial(bin, &args, &format!("aeroshape {} {}", args[0], args[1]))?;
    }
    let x0 = su2_points(&base)?;
    for case in cases(&geometry) {
        let serial = out.join(format!("{}-serial.su2", case.name));
        let srep = out.join(format!("{}-serial.json", case.name));
        let args = deform_args(&grid, &serial, &srep, &case.flags);
        run_serial(
            bin,
            &args,
            &format!("serial aeroshape deform ({})", case.name),
        )?;
        let xs = su2_points(&serial)?;
        let sr = report(&srep)?;
        let sliding = sr["deform"]["sliding_on_supports"].as_u64().unwrap_or(0);
        for n in [2usize, 3] {
            let o = out.join(format!("{}-ranks{n}.su2", case.name));
            let r = out.join(format!("{}-ranks{n}.json", case.name));
            let args = deform_args(&grid, &o, &r, &case.flags);
            let a: Vec<&str> = args.iter().map(String::as_str).collect();
            let res = mpirun(n, bin, &a)?;
            if !res.status.success() {
                drift.push(format!(
                    "mpi {}: -n {n}: aeroshape deform failed ({}): {}",
                    case.name,
                    res.status,
                    first_line(&res)
                ));
                continue;
            }
            let rel = deviation(&x0, &su2_points(&o)?, &xs);
            let rep = report(&r)?;
            let inverted = rep["quality_after"]["n_nonpositive"].as_u64();
            let d = &rep["distributed"];
            let (count, moved) = (
                d["sliding_on_supports"].as_u64().unwrap_or(0),
                d["slide_max_move"].as_f64().unwrap_or(0.0),
            );
            println!(
                "regress: mpi {} -n {n}: deviation from serial {rel:.3e} relative, {} + {} iterations ({}), sliding on supports {count} nodes (serial {sliding}), {} outer iterations, largest slide {moved:.3e}, inverted cells {inverted:?}",
                case.name,
                d["iterations"],
                d["rotation_iterations"],
                d["solver"],
                d["slide_iterations"]
            );
            // Every case slides on the symmetry plane.
            held_solver(d, &format!("mpi {}: -n {n}", case.name), drift);
            if rel.is_nan() || rel > REL {
                drift.push(format!(
                    "mpi {}: -n {n}: deviation {rel:e} from the serial result exceeds {REL:e}",
                    case.name
                ));
            }
            if inverted != Some(0) {
                drift.push(format!(
                    "mpi {}: -n {n}: inverted cells {inverted:?}",
                    case.name
                ));
            }
            // The wing moves by 0.1: the fuselage's nodes beside it must slide with it.
            if case.name == "supports"
                && (count == 0 || count != sliding || moved.is_nan() || moved <= 1e-3)
            {
                drift.push(format!(
                    "mpi supports: -n {n}: {count} sliding nodes (serial {sliding}), largest slide {moved:e}: nothing slid"
                ));
            }
            // The outer iterations re-solve Eq. 21 on the fuselage's tangent planes: the
            // constrained block multigrid keeps them well below the free one's ~200.
            let its = d["iterations"].as_u64();
            if case.name == "supports" && its.is_none_or(|k| k > SUPPORTS_ITERATIONS) {
                drift.push(format!(
                    "mpi supports: -n {n}: {its:?} Eq. 21 iterations, more than {SUPPORTS_ITERATIONS}"
                ));
            }
        }
    }
    // A geometry whose components the grid's classification does not name: every rank
    // prints the error and exits 1.
    let cyl = root
        .join("fixtures/geom/cylinder.ron")
        .display()
        .to_string();
    let o = out.join("bad.su2").display().to_string();
    let a = [
        "deform",
        grid.as_str(),
        "-o",
        o.as_str(),
        "--rigid",
        "wing",
        "--translate",
        "0.1,0,0",
        "--slide",
        "fuselage",
        "--geometry",
        cyl.as_str(),
    ];
    let res = mpirun(3, bin, &a)?;
    // The cylinder's curve 0 is far from the grid's nodes classified on the case's curve 0:
    // rank 0's classification refuses them, and every rank names the node.
    let text = "away from its support";
    let reports = |l: &str| l.starts_with("error:") && l.contains(text);
    every_rank_failed(
        &res,
        3,
        "mpi supports, wrong geometry",
        reports,
        text,
        drift,
    );
    Ok(())
}
