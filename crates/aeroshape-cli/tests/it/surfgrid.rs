//! `aeroshape surfgrid generate|classify` end to end on the whole wing-body fixture (with its
//! poles): the written grid reads back with its classification, its SU2 version classifies
//! back to the same supports, bad arguments are refused.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_aeroshape"))
}

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/geom")
        .join(name)
}

fn run(args: &[&std::ffi::OsStr]) -> Output {
    bin().args(args).output().unwrap()
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("aeroshape-cli-surfgrid-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

/// The line source along the fixture's leading edge (corners "junction leading edge" and
/// "tip leading edge").
fn le_source() -> String {
    let text = std::fs::read_to_string(fixture("wing_body.ron")).unwrap();
    let db = geom_db::GeomDb::from_ron_str(&text, "wing_body.ron").unwrap();
    let c = |n: &str| db.corners.iter().find(|c| c.name == n).unwrap().point;
    let (a, b) = (c("junction leading edge"), c("tip leading edge"));
    format!(
        "{},{},{},{},{},{},0.02,0.02,0.4",
        a.x, a.y, a.z, b.x, b.y, b.z
    )
}

#[test]
fn wing_body_generated_written_and_classified_back() {
    let geom = fixture("wing_body.ron");
    let msh = tmp("wb.msh");
    let su2 = tmp("wb.su2");
    let le = le_source();
    for out in [&msh, &su2] {
        let o = run(&[
            "surfgrid".as_ref(),
            "generate".as_ref(),
            geom.as_os_str(),
            "-o".as_ref(),
            out.as_os_str(),
            "--size".as_ref(),
            "0.2".as_ref(),
            "--line-source".as_ref(),
            le.as_ref(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert!(String::from_utf8_lossy(&o.stdout).contains(" triangles; min angle "));
    }
    // the MSH grid carries the classification: the poles (nose, tail, tip cap ends) are
    // corners (dimension 0)
    let m = mesh::io::read_path(&msh).unwrap();
    assert!(m.parametric);
    // one SU2 marker per surface component (fuselage, wing, tip cap)
    assert_eq!(mesh::io::read_path(&su2).unwrap().markers.len(), 3);
    let classes = m.classes.as_ref().unwrap();
    for name in ["nose", "tail"] {
        let text = std::fs::read_to_string(&geom).unwrap();
        let db = geom_db::GeomDb::from_ron_str(&text, "wing_body.ron").unwrap();
        let (k, c) = db
            .corners
            .iter()
            .enumerate()
            .find(|(_, c)| c.name == name)
            .unwrap();
        let i = m
            .coords
            .iter()
            .position(|p| {
                (c.point - geom_db::prelude::Point3::new(p[0], p[1], p[2])).norm() < 1e-12
            })
            .unwrap();
        assert_eq!(
            (classes[i].dim, classes[i].entity),
            (0, k as i32 + 1),
            "{name}"
        );
    }
    // the SU2 grid (no parameters) classifies back
    let out = tmp("wb_classified.msh");
    let o = run(&[
        "surfgrid".as_ref(),
        "classify".as_ref(),
        geom.as_os_str(),
        su2.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let c = mesh::io::read_path(&out).unwrap();
    assert_eq!(c.n_nodes(), m.n_nodes());
    let _ = std::fs::remove_dir_all(msh.parent().unwrap());
}

#[test]
fn a_bad_line_source_is_refused() {
    let geom = fixture("wing_body.ron");
    let out = tmp("bad.msh");
    let o = run(&[
        "surfgrid".as_ref(),
        "generate".as_ref(),
        geom.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
        "--size".as_ref(),
        "0.2".as_ref(),
        "--line-source".as_ref(),
        "1,2,3".as_ref(),
    ]);
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("expected 9 numbers"), "{e}");
    assert!(!out.exists());
}

/// A volume grid classified whole: the default case's grid as SU2 (no parameters, markers
/// renamed as another mesher might) classified on its geometry gives back the volume cells,
/// the markers with their names and, on the wall (found by geometry), the classification
/// aeroshape wrote in `grid.msh`.
#[test]
fn volume_grid_classified_keeps_cells_and_markers() {
    let case = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/cases/default");
    let orig = mesh::io::read_path(&case.join("grid.msh")).unwrap();
    let mut g = orig.clone();
    for m in &mut g.markers {
        m.name = format!("BC_{}", m.name.to_uppercase());
    }
    g.classes = None;
    g.parametric = false;
    g.entities.clear();
    g.physical_names.clear();
    for grp in g.cells.groups_mut() {
        grp.entity.clear();
    }
    for m in &mut g.markers {
        for grp in m.elements.groups_mut() {
            grp.entity.clear();
        }
    }
    let su2 = tmp("volume.su2");
    let mut f = std::fs::File::create(&su2).unwrap();
    mesh::io::write(&g, mesh::io::Format::Su2, &mut f).unwrap();
    drop(f);
    let out = tmp("volume_classified.msh");
    let o = run(&[
        "surfgrid".as_ref(),
        "classify".as_ref(),
        case.join("wing_body.ron").as_os_str(),
        su2.as_os_str(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    let line = stdout
        .lines()
        .find(|l| l.starts_with("wall markers: "))
        .unwrap();
    let mut found: Vec<&str> = line["wall markers: ".len()..].split(", ").collect();
    found.sort_unstable();
    assert_eq!(found, ["BC_FUSELAGE", "BC_WING"], "{stdout}");
    let c = mesh::io::read_path(&out).unwrap();
    assert_eq!(c.cells, orig.cells);
    let names = |m: &mesh::Mesh| m.markers.iter().map(|k| k.name.clone()).collect::<Vec<_>>();
    assert_eq!(names(&c), names(&g));
    for (a, b) in c.markers.iter().zip(&orig.markers) {
        assert_eq!(
            a.elements.node_set(),
            b.elements.node_set(),
            "marker {}",
            a.name
        );
    }
    let (cc, oc) = (c.classes.as_ref().unwrap(), orig.classes.as_ref().unwrap());
    let wall: std::collections::BTreeSet<u32> = ["wing", "fuselage"]
        .iter()
        .flat_map(|n| orig.marker(n).unwrap().elements.node_set())
        .collect();
    for v in 0..orig.n_nodes() {
        let (a, b) = (cc[v], oc[v]);
        if wall.contains(&(v as u32)) {
            assert_eq!((a.dim, a.entity), (b.dim, b.entity), "wall node {v}");
            assert!(
                (a.param[0] - b.param[0]).abs() <= 1e-9 && (a.param[1] - b.param[1]).abs() <= 1e-9,
                "wall node {v}: {:?} vs {:?}",
                a.param,
                b.param
            );
        } else {
            assert_eq!(a.dim, 3, "node {v} off the wall");
        }
    }
}
