//! How far R reaches (issue 20, item 7): `aeroshape deform --rotation-reach` on a Gmsh-made
//! wing grid (limits 0 and none), and the far-field displacement of `report.json` against an
//! independent maximum over the written grid.

use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::path::{Path, PathBuf};
use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_aeroshape"))
}

fn gmsh_grid(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/grids")
        .join(name)
}

/// The far field computed here from the grids alone: the nodes whose distance along the
/// tetrahedra's edges (textbook Dijkstra on an edge list built here) from the nodes of the
/// `wall` markers is at least the bounding-box diagonal of those nodes. Returns (that
/// diagonal, far-field node count, largest displacement from `base` to `moved` there).
pub(crate) fn far_field(
    base: &mesh::Mesh,
    moved: &mesh::Mesh,
    wall: &[String],
) -> (f64, usize, f64) {
    let n = base.n_nodes();
    let mut nb: Vec<Vec<usize>> = vec![Vec::new(); n];
    for t in base.tets() {
        for a in 0..4 {
            for b in 0..4 {
                if a != b {
                    nb[t[a] as usize].push(t[b] as usize);
                }
            }
        }
    }
    let mut d = vec![f64::INFINITY; n];
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    let mut heap = BinaryHeap::new();
    for w in wall {
        for v in base.marker(w).unwrap().elements.node_set() {
            let v = v as usize;
            d[v] = 0.0;
            heap.push(Reverse((0u64, v)));
            for k in 0..3 {
                lo[k] = lo[k].min(base.coords[v][k]);
                hi[k] = hi[k].max(base.coords[v][k]);
            }
        }
    }
    while let Some(Reverse((key, i))) = heap.pop() {
        if f64::from_bits(key) > d[i] {
            continue;
        }
        for &j in &nb[i] {
            let (p, q) = (base.coords[i], base.coords[j]);
            let l = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt();
            if d[i] + l < d[j] {
                d[j] = d[i] + l;
                heap.push(Reverse((d[j].to_bits(), j)));
            }
        }
    }
    let diag = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
    let far: Vec<usize> = (0..n).filter(|&i| d[i] >= diag).collect();
    let max = far
        .iter()
        .map(|&i| {
            let (p, q) = (base.coords[i], moved.coords[i]);
            (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt()
        })
        .fold(0.0, f64::max);
    (diag, far.len(), max)
}

/// `deform` of the split wing pitched 5° with `extra` options; returns the written grid and
/// the report.
fn pitch(dir: &Path, name: &str, extra: &[&str]) -> (mesh::Mesh, serde_json::Value, String) {
    let out = dir.join(format!("{name}.su2"));
    let rep = dir.join(format!("{name}.json"));
    let o = bin()
        .arg("deform")
        .arg(gmsh_grid("split_wing.su2"))
        .arg("-o")
        .arg(&out)
        .args([
            "--rigid",
            "wing",
            "--rotate-deg",
            "5",
            "--axis-dir",
            "0,1,0",
        ])
        .args(["--axis-point", "0.25,0,0"])
        .args(["--slide", "symmetry", "--fixed", "farfield"])
        .arg("--report")
        .arg(&rep)
        .args(extra)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r = serde_json::from_str(&std::fs::read_to_string(&rep).unwrap()).unwrap();
    (
        mesh::io::read_path(&out).unwrap(),
        r,
        String::from_utf8_lossy(&o.stdout).into_owned(),
    )
}

fn max_diff(a: &mesh::Mesh, b: &mesh::Mesh) -> f64 {
    a.coords
        .iter()
        .zip(&b.coords)
        .map(|(p, q)| (0..3).map(|k| (p[k] - q[k]).abs()).fold(0.0, f64::max))
        .fold(0.0, f64::max)
}

#[test]
fn deform_rotation_reach_limits_and_far_field_report() {
    let dir = tempfile::tempdir().unwrap();
    let base = mesh::io::read_path(&gmsh_grid("split_wing.su2")).unwrap();
    let (full, rf, stdout) = pitch(dir.path(), "full", &[]);
    assert!(stdout.contains("far field (≥ "), "{stdout}");
    // the report's far field against the independent one
    let (diag, nodes, max) = far_field(&base, &full, &["wing".to_string()]);
    let ff = &rf["far_field"];
    testkit::assert_close!(ff["distance"].as_f64().unwrap(), diag, rel = 1e-12);
    assert_eq!(ff["nodes"].as_u64().unwrap() as usize, nodes);
    assert!(nodes > 100, "{nodes}");
    testkit::assert_close!(ff["max_displacement"].as_f64().unwrap(), max, rel = 1e-9);
    assert!(max > 0.0);
    // reach 0 is the plain spring system; R changes the grid, so the check is not vacuous
    let (zero, _, _) = pitch(dir.path(), "zero", &["--rotation-reach", "0"]);
    let (plain, _, _) = pitch(dir.path(), "plain", &["--no-rotation"]);
    let wall = ff["wall_max_displacement"].as_f64().unwrap();
    assert!(max_diff(&zero, &plain) <= 1e-12 * wall);
    assert!(max_diff(&full, &plain) > 1e-3 * wall);
    // a reach of a quarter of the far-field distance: the far field moves less
    let l = format!("{}", 0.25 * diag);
    let (short, rs, _) = pitch(dir.path(), "short", &["--rotation-reach", &l]);
    let (_, _, max_short) = far_field(&base, &short, &["wing".to_string()]);
    testkit::assert_close!(
        rs["far_field"]["max_displacement"].as_f64().unwrap(),
        max_short,
        rel = 1e-9
    );
    assert!(max_short < max, "{max_short} vs {max}");
    // a negative reach is a usage error
    let o = bin()
        .arg("deform")
        .arg(gmsh_grid("split_wing.su2"))
        .arg("-o")
        .arg(dir.path().join("x.su2"))
        .args(["--rotation-reach", "-1"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
}
