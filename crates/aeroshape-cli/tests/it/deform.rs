//! `aeroshape deform` end to end: exit codes, outputs, report, refusals.

use std::path::{Path, PathBuf};
use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_aeroshape"))
}

fn naca() -> PathBuf {
    Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/su2/mesh_NACA0012_inv.su2"
    ))
    .to_path_buf()
}

fn read(p: &Path) -> mesh::Mesh {
    mesh::io::read_path(p).unwrap()
}

#[test]
fn pitch_naca_writes_grid_and_report() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.su2");
    let rep = dir.path().join("rep.json");
    let o = bin()
        .args(["deform"])
        .arg(naca())
        .arg("-o")
        .arg(&out)
        .args([
            "--rigid",
            "airfoil",
            "--rotate-deg",
            "-5",
            "--axis-point",
            "0.25,0,0",
        ])
        .arg("--report")
        .arg(&rep)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let a = read(&naca());
    let b = read(&out);
    assert_eq!(a.n_nodes(), b.n_nodes());
    assert_eq!(a.cells, b.cells);
    // Airfoil nodes rotated by -5° about (0.25, 0): check one against Eq. 34 by hand.
    let v = a.marker("airfoil").unwrap().elements.node_set()[3] as usize;
    let (s, c) = (-5f64).to_radians().sin_cos();
    let (dx, dy) = (a.coords[v][0] - 0.25, a.coords[v][1]);
    testkit::assert_close!(b.coords[v][0], 0.25 + c * dx - s * dy, abs = 1e-12);
    testkit::assert_close!(b.coords[v][1], s * dx + c * dy, abs = 1e-12);
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&rep).unwrap()).unwrap();
    for k in [
        "nodes",
        "cells",
        "iterations",
        "residual",
        "seconds",
        "quality_before",
        "quality_after",
    ] {
        assert!(r.get(k).is_some(), "report lacks {k}");
    }
    for k in ["read", "assemble", "solve", "write"] {
        assert!(r["seconds"][k].as_f64().unwrap() >= 0.0);
    }
    assert_eq!(r["quality_after"]["n_nonpositive"], 0);
    assert_eq!(r["nodes"], a.n_nodes());
}

#[test]
fn zero_motion_and_displacement_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("same.su2");
    let o = bin()
        .arg("deform")
        .arg(naca())
        .arg("-o")
        .arg(&out)
        .args(["--rigid", "airfoil"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let a = read(&naca());
    assert_eq!(read(&out).coords, a.coords);
    // A CSV moving one airfoil node.
    let v = a.marker("airfoil").unwrap().elements.node_set()[10];
    let csv = dir.path().join("d.csv");
    std::fs::write(&csv, format!("node,dx,dy,dz\n{v},0.0,0.001,0\n")).unwrap();
    let out2 = dir.path().join("moved.vtu");
    let o = bin()
        .arg("deform")
        .arg(naca())
        .arg("-o")
        .arg(&out2)
        .arg("--displacements")
        .arg(&csv)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let b = read(&out2);
    testkit::assert_close!(
        b.coords[v as usize][1],
        a.coords[v as usize][1] + 0.001,
        abs = 1e-15
    );
}

#[test]
fn errors_are_one_line_with_exit_1_or_usage_2() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o.su2");
    let o = bin()
        .arg("deform")
        .arg(naca())
        .arg("-o")
        .arg(&out)
        .args(["--rigid", "wing"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("wing") && err.trim().lines().count() == 1,
        "{err}"
    );
    assert!(!out.exists());
    // Bad CSV line named.
    let csv = dir.path().join("bad.csv");
    std::fs::write(&csv, "node,dx,dy,dz\n1,0,0,0\n2,0,x,0\n").unwrap();
    let o = bin()
        .arg("deform")
        .arg(naca())
        .arg("-o")
        .arg(&out)
        .arg("--displacements")
        .arg(&csv)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("line 3"));
    // Output naming the input is refused.
    let copy = dir.path().join("in.su2");
    std::fs::copy(naca(), &copy).unwrap();
    let o = bin()
        .arg("deform")
        .arg(&copy)
        .arg("-o")
        .arg(&copy)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    // Usage error.
    let o = bin()
        .args(["deform", "--solver", "magic"])
        .arg(naca())
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    // deform's own message names the choices.
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("unknown solver \"magic\" (expected pcg, jacobi or pcg-jacobi)"),
        "{err}"
    );
    let o = bin().args(["deform", "--help"]).output().unwrap();
    let help = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success() && help.contains("--slide"));
    // --help lists deform's names of the solvers and stiffnesses, and their defaults.
    assert!(
        help.contains("[default: pcg] [possible values: pcg, jacobi, pcg-jacobi]"),
        "{help}"
    );
    assert!(
        help.contains("[default: inverse-length2] [possible values: inverse-length, inverse-length2, volume, wall-distance]"),
        "{help}"
    );
}

/// A cylindrical shell (r ∈ [1, 1.6], θ ∈ [20°, 70°], z ∈ [0.4, 1.6]) around the side of
/// `fixtures/geom/cylinder.ron`, written as MSH 4.1 with parametric nodes: the inner face's
/// nodes are classified on the side's surface component (tag = id + 1) with their (u, v).
#[test]
fn slide_on_geometry_supports_from_parametric_msh() {
    let geom = Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/geom/cylinder.ron"
    ));
    let db = geom_db::GeomDb::from_ron_str(&std::fs::read_to_string(geom).unwrap(), "cyl").unwrap();
    let comp = db
        .surface_components
        .iter()
        .position(|c| db.surface(c.surface).name == "side")
        .expect("side component");
    let side = db.surface(db.surface_components[comp].surface);
    let mut m = mesh::generate::box_tets(5, 8, 6, [0.0; 3], [1.0; 3]);
    for p in m.coords.iter_mut() {
        let (r, th, z) = (
            1.0 + 0.6 * p[0],
            (20.0 + 50.0 * p[1]).to_radians(),
            0.4 + 1.2 * p[2],
        );
        *p = [r * th.cos(), r * th.sin(), z];
    }
    let inner = m.marker("x_m").unwrap().elements.node_set();
    let mut classes = vec![
        mesh::NodeClass {
            dim: 3,
            entity: 1,
            param: [0.0; 2],
        };
        m.n_nodes()
    ];
    for &v in &inner {
        let x = geom_db::prelude::Vector3::from(m.coords[v as usize]);
        let inv = geom_db::invert::SurfaceInverter::new(
            "side",
            side,
            &geom_db::invert::InvertOptions::for_model(&db),
        )
        .unwrap();
        let f = inv.project(&geom_db::prelude::Point3::from(x)).unwrap();
        let (uv, dist) = (f.uv, f.distance);
        assert!(dist < 1e-9);
        let q = geom_db::eval::ParamSurface::point(side, uv[0], uv[1]);
        m.coords[v as usize] = [q.x, q.y, q.z];
        classes[v as usize] = mesh::NodeClass {
            dim: 2,
            entity: comp as i32 + 1,
            param: uv,
        };
    }
    m.classes = Some(classes);
    m.parametric = true;
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("shell.msh");
    let mut f = std::fs::File::create(&input).unwrap();
    mesh::io::write(&m, mesh::io::Format::from_path(&input).unwrap(), &mut f).unwrap();
    drop(f);
    let m = read(&input);
    assert!(m.parametric && m.classes.is_some());
    let out = dir.path().join("turned.msh");
    let rep = dir.path().join("rep.json");
    let o = bin()
        .arg("deform")
        .arg(&input)
        .arg("-o")
        .arg(&out)
        .args(["--rigid", "x_p", "--rotate-deg", "4", "--slide", "x_m"])
        .arg("--geometry")
        .arg(geom)
        .arg("--report")
        .arg(&rep)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let b = read(&out);
    let classes = b.classes.as_ref().unwrap();
    let mut turned = 0.0f64;
    for &v in &inner {
        let p = b.coords[v as usize];
        let c = classes[v as usize];
        // On the support at the written parameters, and on the cylinder r = 1.
        let q = geom_db::eval::ParamSurface::point(side, c.param[0], c.param[1]);
        let dev = ((p[0] - q.x).powi(2) + (p[1] - q.y).powi(2) + (p[2] - q.z).powi(2)).sqrt();
        assert!(dev <= 1e-12 * 3.0, "node {v}: {dev:e}");
        assert!(((p[0] * p[0] + p[1] * p[1]).sqrt() - 1.0).abs() < 1e-9);
        let p0 = m.coords[v as usize];
        turned = turned.max((p[1].atan2(p[0]) - p0[1].atan2(p0[0])).abs().to_degrees());
    }
    assert!(turned > 0.5, "{turned}");
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&rep).unwrap()).unwrap();
    assert!(
        r["deform"]["sliding_on_supports"].as_u64().unwrap() > 10,
        "{r}"
    );
    assert_eq!(r["quality_after"]["n_nonpositive"].as_u64(), Some(0));
    // Without --geometry the curved marker is refused as not planar.
    let o = bin()
        .arg("deform")
        .arg(&input)
        .arg("-o")
        .arg(&out)
        .args(["--rigid", "x_p", "--rotate-deg", "4", "--slide", "x_m"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("not planar"));
}

fn gmsh_grid(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/grids")
        .join(name)
}

/// Precedence on a Gmsh-made grid (split wing in a half sphere): the far field meets the
/// symmetry plane along a half circle. Pitching the wing with `--slide symmetry --fixed
/// farfield`, every far-field node stays where it was, bit for bit (those on the symmetry
/// plane included), and the symmetry nodes stay in their plane; the summary is printed.
#[test]
fn fixed_marker_wins_over_sliding_and_summary_printed() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.su2");
    let input = gmsh_grid("split_wing.su2");
    let o = bin()
        .arg("deform")
        .arg(&input)
        .arg("-o")
        .arg(&out)
        .args([
            "--rigid",
            "wing",
            "--rotate-deg",
            "3",
            "--axis-dir",
            "0,1,0",
        ])
        .args(["--slide", "symmetry", "--fixed", "farfield"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains(" nodes, ") && stdout.contains(" iterations"),
        "{stdout}"
    );
    assert!(stdout.contains("inverted 0 → 0"), "{stdout}");
    let (a, b) = (read(&input), read(&out));
    let far = a.marker("farfield").unwrap().elements.node_set();
    let sym = a.marker("symmetry").unwrap().elements.node_set();
    let seam: Vec<u32> = far.iter().copied().filter(|v| sym.contains(v)).collect();
    assert!(
        seam.len() > 10,
        "the grid has far-field nodes on the symmetry plane"
    );
    for &v in &far {
        assert_eq!(
            b.coords[v as usize], a.coords[v as usize],
            "far-field node {v}"
        );
    }
    let mut moved = 0;
    for &v in &sym {
        assert!(b.coords[v as usize][1].abs() <= 1e-12, "symmetry node {v}");
        moved += usize::from(b.coords[v as usize] != a.coords[v as usize]);
    }
    assert!(moved > 100, "symmetry nodes slide ({moved} moved)");
}

/// A node on two sliding planes slides on their intersection: the default case's far-field
/// box split into its faces, the bottom face z = z_min sliding as well as the symmetry plane
/// y = 0; their common edge's nodes keep both y and z and may move along x only.
#[test]
fn node_on_two_sliding_planes_keeps_to_their_line() {
    let case = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/cases/default");
    let mut g = read(&case.join("grid.msh"));
    let far = g.marker("farfield").unwrap().elements.clone();
    let (lo, _) = g.bbox();
    let mut bottom = mesh::Elements::new();
    let mut rest = mesh::Elements::new();
    for grp in far.groups() {
        for t in grp.iter() {
            let flat = t.iter().all(|&v| g.coords[v as usize][2] == lo[2]);
            let e = if flat { &mut bottom } else { &mut rest };
            e.push(grp.kind, t, None);
        }
    }
    g.markers.retain(|m| m.name != "farfield");
    for (name, elements) in [("bottom", bottom), ("farfield", rest)] {
        g.markers.push(mesh::Marker {
            name: name.into(),
            tag: None,
            elements,
        });
    }
    g.classes = None;
    g.parametric = false;
    g.entities.clear();
    g.physical_names.clear();
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("split.su2");
    let mut f = std::fs::File::create(&input).unwrap();
    mesh::io::write(&g, mesh::io::Format::Su2, &mut f).unwrap();
    drop(f);
    let g = read(&input);
    let out = dir.path().join("out.su2");
    let o = bin()
        .arg("deform")
        .arg(&input)
        .arg("-o")
        .arg(&out)
        .args([
            "--rigid",
            "wing",
            "--rigid",
            "fuselage",
            "--translate",
            "0.2,0,-0.1",
        ])
        .args([
            "--slide", "symmetry", "--slide", "bottom", "--fixed", "farfield",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let b = read(&out);
    let sym = g.marker("symmetry").unwrap().elements.node_set();
    let bot = g.marker("bottom").unwrap().elements.node_set();
    let far = g.marker("farfield").unwrap().elements.node_set();
    let line: Vec<u32> = sym
        .iter()
        .copied()
        .filter(|v| bot.contains(v) && !far.contains(v))
        .collect();
    assert!(line.len() > 3, "the grid has nodes on both sliding planes");
    let mut along = 0.0f64;
    for &v in &line {
        let (p, q) = (g.coords[v as usize], b.coords[v as usize]);
        assert!(
            q[1].abs() <= 1e-12 && (q[2] - p[2]).abs() <= 1e-12,
            "node {v}: {p:?} → {q:?}"
        );
        along = along.max((q[0] - p[0]).abs());
    }
    assert!(along > 1e-4, "the edge nodes slide along x ({along:e})");
    for &v in &far {
        assert_eq!(
            b.coords[v as usize], g.coords[v as usize],
            "far-field node {v}"
        );
    }
}

/// `deform` of an OpenFOAM case (the gmshToFoam M6 fixture) into a new case: the wing pitched,
/// the symmetry plane sliding; only `constant/polyMesh/points` differs from the input's files.
#[test]
fn openfoam_case_in_openfoam_case_out_with_points_only_changed() {
    let src = Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/openfoam/m6_coarse"
    ));
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("pitched");
    let o = bin()
        .arg("deform")
        .arg(src)
        .arg("-o")
        .arg(&out)
        .args([
            "--rigid",
            "wing",
            "--rotate-deg",
            "2",
            "--axis-point",
            "0.2,0,0",
        ])
        .args(["--axis-dir", "0,1,0", "--slide", "symmetry"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let poly = |c: &Path, f: &str| std::fs::read(c.join("constant/polyMesh").join(f)).unwrap();
    for f in ["faces", "owner", "neighbour", "boundary"] {
        assert!(poly(src, f) == poly(&out, f), "{f} changed");
    }
    assert!(poly(src, "points") != poly(&out, "points"));
    for f in ["m6_coarse.su2", "drag/pointSensVecadjESI"] {
        assert!(std::fs::read(src.join(f)).unwrap() == std::fs::read(out.join(f)).unwrap());
    }
    let (a, b) = (read(src), read(&out));
    assert_eq!(a.cells, b.cells);
    assert_eq!(a.markers, b.markers);
    // a wing node rotated by 2° about the y axis through (0.2, 0, 0) (Eq. 34)
    let v = a.marker("wing").unwrap().elements.node_set()[7] as usize;
    let (s, c) = 2f64.to_radians().sin_cos();
    let (dx, dz) = (a.coords[v][0] - 0.2, a.coords[v][2]);
    testkit::assert_close!(b.coords[v][0], 0.2 + c * dx + s * dz, abs = 1e-12);
    testkit::assert_close!(b.coords[v][2], -s * dx + c * dz, abs = 1e-12);
    // the input case is never the output
    let o = bin()
        .arg("deform")
        .arg(src)
        .arg("-o")
        .arg(src)
        .args(["--rigid", "wing"])
        .output()
        .unwrap();
    assert!(!o.status.success());
}

/// With `--find-planes` a symmetry plane not named is found by its shape and slides (issue
/// 43): a 2° pitch of the default case's wing and fuselage keeps every cell valid, with a
/// note naming the marker, and the symmetry nodes stay in their plane while some of them
/// move; without it the same motion inverts cells at the root and is refused, exit 1.
#[test]
fn a_symmetry_plane_found_by_shape_slides() {
    let dir = tempfile::tempdir().unwrap();
    let grid = crate::case::root().join("fixtures/cases/default/grid.msh");
    let out = dir.path().join("pitched.su2");
    let args = [
        "--rigid",
        "wing",
        "--rigid",
        "fuselage",
        "--rotate-deg",
        "2",
        "--axis-point",
        "4,0,0",
        "--axis-dir",
        "0,1,0",
    ];
    let o = bin()
        .arg("deform")
        .arg(&grid)
        .arg("-o")
        .arg(&out)
        .args(args)
        .arg("--find-planes")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("note: marker symmetry slides on its plane"),
        "{err}"
    );
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("inverted 0 → 0"), "{stdout}");
    let (a, b) = (
        mesh::io::read_path(&grid).unwrap(),
        mesh::io::read_path(&out).unwrap(),
    );
    let sym = a.marker("symmetry").unwrap().elements.node_set();
    let moved = sym
        .iter()
        .filter(|&&v| a.coords[v as usize] != b.coords[v as usize])
        .count();
    assert!(moved > 100, "{moved} symmetry nodes moved");
    for &v in &sym {
        let y = (b.coords[v as usize][1], a.coords[v as usize][1]);
        assert!(
            (y.0 - y.1).abs() <= 1e-12 * a.bbox_diagonal(),
            "node {v} left its plane: {y:?}"
        );
    }
    let o = bin()
        .arg("deform")
        .arg(&grid)
        .arg("-o")
        .arg(dir.path().join("fixed.su2"))
        .args(args)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("inverted cells"));
    assert!(!dir.path().join("fixed.su2").exists());
}
