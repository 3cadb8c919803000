//! The MPI part of `cargo xtask regress` (docs/mpi.md): skipped with a message when
//! `mpirun` is absent.
//!
//! 1. Builds `aeroshape` and the examples `distributed` of `deform` and `distributed_study`
//!    of `aeroshape` with the feature `mpi`, and runs the unit tests of `deform::distributed`
//!    (the partitioners, the parts, the coarse space: built only with the feature `mpi`,
//!    which `cargo test --workspace` leaves out), all in the release profile.
//! 2. On the ~100k-node Gmsh wing-body grid (`target/grids/wing_body.su2`, made by
//!    `fixtures/grids/make_grids.py --size 100k` when absent): the serial `aeroshape deform`
//!    and `mpirun -n 2` and `-n 3 --oversubscribe` of the same command (the partition made
//!    on rank 0 by METIS, which the report must name); every node of the gathered grid
//!    within 1e-8 of the serial one, relative to the largest displacement, no cell with
//!    q ≤ 0, and the Eq. 21 solver the constrained block multigrid (`…-held`: the symmetry
//!    plane slides); rank 0 made the partition with as many threads as the ranks (on the
//!    cores of the ranks waiting for it), up to the machine's CPUs. The `.pvtu` run (-n 3) cuts by coordinate bisection (`--partition rcb`).
//! 3. `mpirun aeroshape run` on the default case against the serial run
//!    (`regress_mpi_study`); sliding on geometry supports and the volume and wall-distance
//!    stiffnesses against the serial runs (`regress_mpi_slide`).
//! 4. The partition given by the caller (`distributed` example, 3 ranks) against the serial
//!    result, and two bad partitions (a missing ghost, a global id owned twice): exit status
//!    1 with the error on every rank, within a time limit (a hang fails).
//! 5. A set-up reused for a second design (`distributed CELLS reuse`, 2 and 3 ranks): the
//!    same result as a new set-up, bit for bit, on a made and a given partition; a third
//!    design warm started from the second's solutions within 1e-8 of its cold start, in
//!    fewer iterations; and the distributed study's reuse of its set-up
//!    (`regress_mpi_study`).

use std::path::Path;
use std::process::{Command, Output};

/// The motion of the wing-body test: the whole body pitched 2° about a spanwise axis,
/// the symmetry plane sliding, solved to 1e-11.
pub(crate) const FLAGS: &[&str] = &[
    "--rigid",
    "wing",
    "--rigid",
    "fuselage",
    "--rotate-deg",
    "2",
    "--axis-point",
    "5,0,0",
    "--axis-dir",
    "0,1,0",
    "--slide",
    "symmetry",
    "--tolerance",
    "1e-11",
];

/// Relative deviation allowed from the serial result.
pub(crate) const REL: f64 = 1e-8;

fn have(cmd: &str) -> bool {
    Command::new(cmd)
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success())
}

/// `mpirun` with the flags CI needs (root, more ranks than cores), under a time limit.
pub(crate) fn mpirun(n: usize, prog: &Path, args: &[&str]) -> Result<Output, String> {
    let mut c = Command::new("timeout");
    c.arg("600").arg("mpirun");
    if std::env::var("USER").is_ok_and(|u| u == "root") || is_root() {
        c.arg("--allow-run-as-root");
    }
    c.arg("--oversubscribe")
        .args(["-n", &n.to_string()])
        .arg(prog)
        .args(args);
    eprintln!("$ mpirun -n {n} {} {}", prog.display(), args.join(" "));
    c.output().map_err(|e| format!("cannot run mpirun: {e}"))
}

pub(crate) fn is_root() -> bool {
    Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
}

/// Node coordinates of an SU2 grid (the `NPOIN` section).
pub(crate) fn su2_points(path: &Path) -> Result<Vec<[f64; 3]>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut lines = text.lines();
    let bad = || format!("{}: malformed NPOIN section", path.display());
    let head = lines
        .by_ref()
        .find(|l| l.trim_start().starts_with("NPOIN"))
        .ok_or_else(bad)?;
    let n: usize = head
        .split('=')
        .nth(1)
        .and_then(|s| s.split_whitespace().next())
        .and_then(|s| s.parse().ok())
        .ok_or_else(bad)?;
    let mut out = Vec::with_capacity(n);
    for l in lines.take(n) {
        let v: Vec<f64> = l
            .split_whitespace()
            .take(3)
            .filter_map(|s| s.parse().ok())
            .collect();
        if v.len() < 2 {
            return Err(bad());
        }
        out.push([v[0], v[1], v.get(2).copied().unwrap_or(0.0)]);
    }
    if out.len() != n {
        return Err(bad());
    }
    Ok(out)
}

/// Largest node deviation of `a` from `b`, relative to the largest displacement of `b`
/// from `x0`.
pub(crate) fn deviation(x0: &[[f64; 3]], a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    let d = |p: &[f64; 3], q: &[f64; 3]| (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt();
    let dev = a.iter().zip(b).map(|(p, q)| d(p, q)).fold(0.0, f64::max);
    let disp = b.iter().zip(x0).map(|(p, q)| d(p, q)).fold(0.0, f64::max);
    dev / disp
}

/// The check of a grid written in pieces (`.pvtu`), read by VTK's own parallel reader: every
/// node of the grid in some piece with the serial result's position (within [`REL`]), every
/// cell and every boundary element of each marker (`MARKER_ELEMS` of the SU2 file, the
/// markers numbered from 1 in its order) in exactly one piece. Prints the counts.
const PVTU_CHECK: &str = r#"
import sys
import numpy as np
import vtk
from vtk.util.numpy_support import vtk_to_numpy
from scipy.spatial import cKDTree
pvtu, grid, serial = sys.argv[1:4]
def su2(path):
    lines = open(path).read().splitlines()
    at = next(i for i, l in enumerate(lines) if l.strip().startswith("NPOIN"))
    n = int(lines[at].split("=")[1].split()[0])
    x = np.array([[float(v) for v in l.split()[:3]] for l in lines[at + 1:at + 1 + n]])
    cells = next(int(l.split("=")[1].split()[0]) for l in lines if l.strip().startswith("NELEM"))
    marks = [int(l.split("=")[1]) for l in lines if l.strip().startswith("MARKER_ELEMS")]
    return x, cells, marks
x0, cells, marks = su2(grid)
xs = su2(serial)[0]
r = vtk.vtkXMLPUnstructuredGridReader()
r.SetFileName(pvtu)
r.Update()
g = r.GetOutput()
x = vtk_to_numpy(g.GetPoints().GetData())
d = vtk_to_numpy(g.GetPointData().GetArray("displacement"))
marker = vtk_to_numpy(g.GetCellData().GetArray("marker"))
size = np.linalg.norm(x0.max(0) - x0.min(0))
dist, idx = cKDTree(x0).query(x - d)
disp = np.linalg.norm(xs - x0, axis=1).max()
dev = np.linalg.norm(x - xs[idx], axis=1).max() / disp
nodes = len(np.unique(idx))
volume = int((marker == 0).sum())
faces = np.bincount(marker.astype(int), minlength=len(marks) + 1)[1:].tolist()
print("regress: mpi pvtu: %d pieces, %d points, %d of %d nodes, %d of %d cells, boundary elements %s of %s, deviation from serial %.3e" % (
    r.GetNumberOfPieces(), len(x), nodes, len(x0), volume, cells, faces, marks, dev))
if dist.max() > 1e-9 * size or nodes != len(x0) or volume != cells or faces != marks or not dev <= float(sys.argv[4]):
    sys.exit("pvtu pieces do not make up the deformed grid")
"#;

/// `mpirun -n 3 aeroshape deform ... -o ranks3.pvtu` checked by [`PVTU_CHECK`] (skipped
/// without Python's vtk).
fn pieces(
    bin: &Path,
    g: &str,
    grid: &Path,
    serial: &Path,
    out: &Path,
    drift: &mut Vec<String>,
) -> Result<(), String> {
    let have = Command::new("python3")
        .args(["-c", "import vtk, scipy"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !have {
        println!("regress: mpi pvtu check skipped (Python vtk or scipy not installed)");
        return Ok(());
    }
    let o = out.join("ranks3.pvtu");
    let os = o.display().to_string();
    let mut args = vec!["deform", g, "-o", os.as_str(), "--partition", "rcb"];
    args.extend(FLAGS);
    let res = mpirun(3, bin, &args)?;
    if !res.status.success() {
        drift.push(format!(
            "mpi: -n 3 .pvtu: aeroshape deform failed ({}): {}",
            res.status,
            String::from_utf8_lossy(&res.stderr)
                .lines()
                .next()
                .unwrap_or("")
        ));
        return Ok(());
    }
    let res = Command::new("python3")
        .args(["-c", PVTU_CHECK, &os])
        .arg(grid)
        .arg(serial)
        .arg(REL.to_string())
        .output()
        .map_err(|e| format!("cannot run python3: {e}"))?;
    print!("{}", String::from_utf8_lossy(&res.stdout));
    if !res.status.success() {
        drift.push(format!(
            "mpi: .pvtu: {}",
            String::from_utf8_lossy(&res.stderr).trim()
        ));
    }
    Ok(())
}

/// Runs the MPI checks; drifts are pushed on `drift`.
pub fn run(root: &Path, drift: &mut Vec<String>) -> Result<(), String> {
    if !have("mpirun") {
        println!("regress: MPI tests skipped (mpirun not found; see docs/mpi.md)");
        return Ok(());
    }
    let grid = root.join("target/grids/wing_body.su2");
    if !grid.exists() {
        let status = Command::new("python3")
            .args([
                "fixtures/grids/make_grids.py",
                "--size",
                "100k",
                "--out",
                "target/grids",
                "wing_body",
            ])
            .current_dir(root)
            .status()
            .map_err(|e| format!("cannot run python3: {e}"))?;
        if !status.success() {
            return Err("fixtures/grids/make_grids.py --size 100k failed".into());
        }
    }
    crate::cargo(&[
        "build",
        "--release",
        "-q",
        "-p",
        "aeroshape-cli",
        "--features",
        "mpi",
    ])?;
    crate::cargo(&[
        "build",
        "--release",
        "-q",
        "-p",
        "deform",
        "-p",
        "aeroshape",
        "--features",
        "deform/mpi,aeroshape/mpi",
        "--example",
        "distributed",
        "--example",
        "distributed_study",
    ])?;
    // In the release profile: its dependencies (rsmpi's bindings, the vendored METIS) are
    // those just built, not built again in the debug one.
    crate::cargo(&[
        "test",
        "--release",
        "-q",
        "-p",
        "deform",
        "--features",
        "mpi",
        "--lib",
        "distributed::",
    ])?;
    let bin = root.join("target/release/aeroshape");
    let out = root.join("target/regress/mpi");
    std::fs::create_dir_all(&out).map_err(|e| format!("{}: {e}", out.display()))?;
    let g = grid.display().to_string();
    let serial = out.join("serial.su2");
    let s = serial.display().to_string();
    let serial_report = out.join("serial.json");
    let sr = serial_report.display().to_string();
    let mut args = vec![
        "deform",
        g.as_str(),
        "-o",
        s.as_str(),
        "--report",
        sr.as_str(),
    ];
    args.extend(FLAGS);
    eprintln!("$ aeroshape {}", args.join(" "));
    let st = Command::new(&bin)
        .args(&args)
        .status()
        .map_err(|e| format!("{}: {e}", bin.display()))?;
    if !st.success() {
        return Err("serial aeroshape deform failed".into());
    }
    let x0 = su2_points(&grid)?;
    let xs = su2_points(&serial)?;
    let serial_far: serde_json::Value = std::fs::read_to_string(&serial_report)
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .map(|v| v["far_field"].clone())
        .ok_or_else(|| format!("{}: unreadable report", serial_report.display()))?;
    for n in [2usize, 3] {
        let o = out.join(format!("ranks{n}.su2"));
        let r = out.join(format!("ranks{n}.json"));
        let (os, rs) = (o.display().to_string(), r.display().to_string());
        let mut args = vec![
            "deform",
            g.as_str(),
            "-o",
            os.as_str(),
            "--report",
            rs.as_str(),
        ];
        args.extend(FLAGS);
        let res = mpirun(n, &bin, &args)?;
        if !res.status.success() {
            drift.push(format!(
                "mpi: -n {n}: aeroshape deform failed ({}): {}",
                res.status,
                String::from_utf8_lossy(&res.stderr)
                    .lines()
                    .next()
                    .unwrap_or("")
            ));
            continue;
        }
        let rel = deviation(&x0, &su2_points(&o)?, &xs);
        let report: serde_json::Value = std::fs::read_to_string(&r)
            .ok()
            .and_then(|t| serde_json::from_str(&t).ok())
            .ok_or_else(|| format!("{}: unreadable report", r.display()))?;
        let inverted = report["quality_after"]["n_nonpositive"].as_u64();
        let dist = &report["distributed"];
        println!(
            "regress: mpi -n {n}: deviation from serial {rel:.3e} relative, {} + {} iterations ({}, coarse aggregates {}), partition {}, {} ghost nodes, inverted cells {inverted:?}",
            dist["iterations"],
            dist["rotation_iterations"],
            dist["solver"],
            dist["coarse_aggregates"],
            dist["partitioner"],
            dist["ghost_nodes"]
        );
        // Rank 0 cut on a pool over the cores of the ranks of its node.
        let cpus = std::thread::available_parallelism().map_or(1, usize::from);
        let threads = dist["partition_threads"].as_u64().unwrap_or(0) as usize;
        println!("regress: mpi -n {n}: rank 0 made the partition on {threads} threads");
        if threads < n.min(cpus) {
            drift.push(format!(
                "mpi: -n {n}: rank 0 made the partition on {threads} threads, not {}",
                n.min(cpus)
            ));
        }
        if dist["partitioner"] != "metis" {
            drift.push(format!(
                "mpi: -n {n}: the grid was partitioned by {}, not METIS",
                dist["partitioner"]
            ));
        }
        if rel.is_nan() || rel > REL {
            drift.push(format!(
                "mpi: -n {n}: deviation {rel:e} from the serial result exceeds {REL:e}"
            ));
        }
        if inverted != Some(0) {
            drift.push(format!("mpi: -n {n}: inverted cells {inverted:?}"));
        }
        // The symmetry plane's nodes are held in y: Eq. 21's block multigrid is the
        // constrained one (`DistOperator::held`).
        held_solver(dist, &format!("mpi: -n {n}"), drift);
        far_field(&serial_far, &dist["far_field"], n, drift);
        quality_matches_file(&bin, &o, &report["quality_after"], n, drift)?;
    }
    pieces(&bin, &g, &grid, &serial, &out, drift)?;
    crate::regress_mpi_study::run(root, &bin, drift)?;
    crate::regress_mpi_slide::run(root, &bin, drift)?;
    let ex = root.join("target/release/examples/distributed");
    example(3, &ex, &["24", "ok"], "mpi: given partition", drift)?;
    for n in [2usize, 3] {
        example(n, &ex, &["16", "reuse"], "mpi: reused set-up", drift)?;
    }
    for (mode, text) in [
        ("missing-ghost", "missing ghost"),
        ("duplicate-id", "owned by ranks"),
    ] {
        let res = mpirun(2, &ex, &["12", mode])?;
        let what = format!("mpi bad partition ({mode})");
        every_rank_failed(&res, 2, &what, |l| l.contains(text), text, drift);
    }
    Ok(())
}

/// `mpirun -n ranks` of an example that checks itself (`prog args`): prints what it printed,
/// and records a drift named `what` with the first line of its error when it failed.
pub(crate) fn example(
    ranks: usize,
    prog: &Path,
    args: &[&str],
    what: &str,
    drift: &mut Vec<String>,
) -> Result<(), String> {
    let res = mpirun(ranks, prog, args)?;
    print!("{}", String::from_utf8_lossy(&res.stdout));
    if !res.status.success() {
        let err = String::from_utf8_lossy(&res.stderr);
        let line = err.lines().next().unwrap_or("failed");
        drift.push(format!("{what}, {ranks} ranks: {line}"));
    }
    Ok(())
}

/// Records a drift named `what` unless the distributed report `dist` names an Eq. 21
/// solver with the constrained block multigrid (`…-held`, docs/mpi.md, "Preconditioner"),
/// as a run with sliding nodes must.
/// The distributed report's far field against the serial one's: the same distance and
/// node count, the largest far displacement within [`REL`] of the moving markers' largest
/// displacement (the node may differ between near-equal displacements).
fn far_field(
    serial: &serde_json::Value,
    dist: &serde_json::Value,
    n: usize,
    drift: &mut Vec<String>,
) {
    let f = |v: &serde_json::Value, k: &str| v[k].as_f64().unwrap_or(f64::NAN);
    let (ds, dd) = (f(serial, "distance"), f(dist, "distance"));
    let (ns, nd) = (serial["nodes"].as_u64(), dist["nodes"].as_u64());
    let scale = f(serial, "wall_max_displacement");
    let gap = (f(serial, "max_displacement") - f(dist, "max_displacement")).abs() / scale;
    println!(
        "regress: mpi -n {n}: far field {nd:?} nodes at ≥ {dd:.6e} (serial {ns:?} at ≥ {ds:.6e}), largest displacement {:.6e} (serial {:.6e}, gap {gap:.2e} of the moving markers')",
        f(dist, "max_displacement"),
        f(serial, "max_displacement")
    );
    let same_distance = (ds - dd).abs() <= 1e-12 * ds.abs().max(1.0);
    if ns.is_none() || ns != nd || !same_distance || gap.is_nan() || gap > REL {
        drift.push(format!(
            "mpi: -n {n}: far field {dist} against the serial {serial}"
        ));
    }
}

pub(crate) fn held_solver(dist: &serde_json::Value, what: &str, drift: &mut Vec<String>) {
    let solver = dist["solver"].as_str().unwrap_or("");
    if !solver.ends_with("-held") {
        drift.push(format!(
            "{what}: Eq. 21 solver {solver:?}, not the constrained block multigrid (…-held)"
        ));
    }
}

/// Checks that the report's `quality_after`, summarised over the ranks, is the serial
/// summary of the written grid `o` (`aeroshape mesh info --json`): counts, minimum, 1st
/// percentile and maximum exactly, the mean (summed in another order) to 1e-12 relative.
fn quality_matches_file(
    bin: &Path,
    o: &Path,
    reported: &serde_json::Value,
    n: usize,
    drift: &mut Vec<String>,
) -> Result<(), String> {
    let info = Command::new(bin)
        .args(["mesh", "info", "--json"])
        .arg(o)
        .output()
        .map_err(|e| format!("{}: {e}", bin.display()))?;
    let info: serde_json::Value = serde_json::from_slice(&info.stdout)
        .map_err(|e| format!("{}: mesh info: {e}", o.display()))?;
    let file = &info["quality"];
    for key in ["count", "measured", "min", "p1", "max", "n_nonpositive"] {
        if file[key].is_null() || file[key] != reported[key] {
            drift.push(format!(
                "mpi: -n {n}: quality_after.{key} {} over the ranks, {} of the written grid",
                reported[key], file[key]
            ));
        }
    }
    let (a, b) = (reported["mean"].as_f64(), file["mean"].as_f64());
    if !matches!((a, b), (Some(a), Some(b)) if (a - b).abs() <= 1e-12 * b.abs()) {
        drift.push(format!(
            "mpi: -n {n}: quality_after.mean {a:?} over the ranks, {b:?} of the written grid"
        ));
    }
    Ok(())
}

/// Checks that an `mpirun` of `ranks` ranks exited 1 with one line of standard error per
/// rank that `reports` accepts (`text` names what those lines say); prints the figures
/// and records a drift otherwise. `timeout` exits 124 on a hang; mpirun exits 1 when its
/// ranks do.
pub(crate) fn every_rank_failed(
    res: &Output,
    ranks: usize,
    what: &str,
    reports: impl Fn(&str) -> bool,
    text: &str,
    drift: &mut Vec<String>,
) {
    let err = String::from_utf8_lossy(&res.stderr);
    let lines = err.lines().filter(|l| reports(l)).count();
    let code = res.status.code();
    println!("regress: {what}: exit {code:?}, {lines} rank(s) reported it");
    if code != Some(1) || lines != ranks {
        drift.push(format!(
            "{what}: exit {code:?}, {lines} of {ranks} ranks printed \"{text}\""
        ));
    }
}
