//! OpenFOAM polyMesh: the committed gmshToFoam fixture against the SU2 file of the same grid,
//! write-back byte for byte, binary and 64-bit labels, and refused inputs.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use mesh::{ElementKind, Mesh};

fn fixture() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/openfoam/m6_coarse")
}

fn read_su2(p: &Path) -> Mesh {
    mesh::io::read_path(p).unwrap()
}

/// The elements of a set as sorted node lists, per kind.
fn as_sets(e: &mesh::Elements) -> BTreeSet<(ElementKind, Vec<u32>)> {
    e.iter()
        .map(|(k, n)| {
            let mut v = n.to_vec();
            v.sort_unstable();
            (k, v)
        })
        .collect()
}

/// Every corner tetrahedron of every cell positive (VTK node orders).
fn all_corners_positive(m: &Mesh) -> Result<(), String> {
    use mesh::quality::tet_volume;
    let x = &m.coords;
    let corners: fn(ElementKind) -> &'static [[usize; 4]] = |k| match k {
        ElementKind::Tetra => &[[0, 1, 2, 3]],
        ElementKind::Pyramid => &[[0, 1, 3, 4], [1, 2, 0, 4], [2, 3, 1, 4], [3, 0, 2, 4]],
        // VTK prism: triangle 0 1 2 with its normal away from 3 4 5
        ElementKind::Prism => &[[0, 2, 1, 3], [3, 4, 5, 0]],
        ElementKind::Hexa => &[
            [0, 1, 3, 4],
            [1, 2, 0, 5],
            [2, 3, 1, 6],
            [3, 0, 2, 7],
            [4, 7, 5, 0],
            [5, 4, 6, 1],
            [6, 5, 7, 2],
            [7, 6, 4, 3],
        ],
        _ => &[],
    };
    for (i, (k, n)) in m.cells.iter().enumerate() {
        for c in corners(k) {
            let v = tet_volume(c.map(|j| x[n[j] as usize]));
            if v <= 0.0 {
                return Err(format!(
                    "{} cell {i} {n:?}: corner {c:?} volume {v}",
                    k.name()
                ));
            }
        }
    }
    Ok(())
}

#[test]
fn gmsh_to_foam_fixture_equals_the_su2_grid() {
    let dir = fixture();
    let m = mesh::io::read_path(&dir).unwrap();
    let s = read_su2(&dir.join("m6_coarse.su2"));
    assert_eq!(m.coords.len(), 5541);
    assert_eq!(m.coords.len(), s.coords.len());
    let h = s.bbox_diagonal();
    for (a, b) in m.coords.iter().zip(&s.coords) {
        for k in 0..3 {
            assert!((a[k] - b[k]).abs() <= 1e-14 * h, "{a:?} {b:?}");
        }
    }
    assert_eq!(m.cells.count(ElementKind::Prism), 4518);
    assert_eq!(m.cells.count(ElementKind::Tetra), 15998);
    assert_eq!(as_sets(&m.cells), as_sets(&s.cells));
    all_corners_positive(&m).unwrap();
    // each prism in SU2's (VTK) order, up to the 6 rotations that keep its orientation
    let su2_prisms: BTreeSet<Vec<u32>> = s
        .cells
        .group(ElementKind::Prism)
        .unwrap()
        .iter()
        .flat_map(|p| {
            let flip = [p[3], p[5], p[4], p[0], p[2], p[1]];
            [p.to_vec(), flip.to_vec()].into_iter().flat_map(|q| {
                (0..3).map(move |r| {
                    let mut v: Vec<u32> = (0..3).map(|i| q[(i + r) % 3]).collect();
                    v.extend((0..3).map(|i| q[3 + (i + r) % 3]));
                    v
                })
            })
        })
        .collect();
    for p in m.cells.group(ElementKind::Prism).unwrap().iter() {
        assert!(su2_prisms.contains(p), "prism {p:?} not in SU2's order");
    }
    let names: Vec<&str> = m.markers.iter().map(|k| k.name.as_str()).collect();
    assert_eq!(names, ["wing", "symmetry", "farfield"]);
    for mk in &m.markers {
        let sm = s.marker(&mk.name).unwrap();
        assert_eq!(as_sets(&mk.elements), as_sets(&sm.elements), "{}", mk.name);
    }
    // the same grid through the path of its polyMesh directory
    let p = mesh::io::read_path(&dir.join("constant/polyMesh")).unwrap();
    assert_eq!(p.coords, m.coords);
    assert_eq!(p.cells, m.cells);
}

fn cavity(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/openfoam")
        .join(name)
}

#[test]
fn block_mesh_cavity_in_ascii_binary_and_gzip_reads_the_same() {
    let a = mesh::io::read_path(&cavity("cavity")).unwrap();
    assert_eq!(a.coords.len(), 882);
    assert_eq!(a.cells.count(ElementKind::Hexa), 400);
    assert_eq!(a.cells.len(), 400);
    all_corners_positive(&a).unwrap();
    let names: Vec<(&str, usize)> = a
        .markers
        .iter()
        .map(|k| (k.name.as_str(), k.elements.count(ElementKind::Quad)))
        .collect();
    assert_eq!(
        names,
        [
            ("movingWall", 20),
            ("fixedWalls", 60),
            ("frontAndBack", 800)
        ]
    );
    let src = a.foam.as_deref().unwrap();
    assert!(!src.points_layout.binary);
    assert_eq!(src.patches[2].kind, "empty");
    for name in ["cavity_binary", "cavity_gz"] {
        let b = mesh::io::read_path(&cavity(name)).unwrap();
        assert_eq!(b.coords, a.coords, "{name}");
        assert_eq!(b.cells, a.cells, "{name}");
        assert_eq!(b.markers, a.markers, "{name}");
        let l = b.foam.as_deref().unwrap().points_layout;
        assert_eq!(
            (l.binary, l.label_bytes, l.scalar_bytes),
            (name == "cavity_binary", 4, 8)
        );
    }
}

#[test]
fn a_polyhedral_cell_is_refused_by_name() {
    let err = mesh::io::read_path(&cavity("cavity_dual"))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("faces: cell ") && err.contains("is a polyhedron"),
        "{err}"
    );
}

/// Every file under `dir`, relative, with its bytes.
fn tree(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.push((
                    p.strip_prefix(dir).unwrap().to_path_buf(),
                    std::fs::read(&p).unwrap(),
                ));
            }
        }
    }
    out.sort();
    out
}

/// A smooth displacement, small against the cavity's cells (0.005 m).
fn bend(m: &mut Mesh) {
    for p in &mut m.coords {
        p[0] += 1e-3 * (30.0 * p[1]).sin() * p[0] * (0.1 - p[0]) * 100.0;
    }
}

#[test]
fn write_back_changes_points_only_and_reads_back_exactly() {
    for name in ["cavity", "cavity_binary", "cavity_gz"] {
        let src = cavity(name);
        let mut m = mesh::io::read_path(&src).unwrap();
        let before = m.coords.clone();
        bend(&mut m);
        assert_ne!(m.coords, before);
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path().join("bent");
        mesh::io::write_path(&m, mesh::io::Format::Foam, &out).unwrap();
        let (a, b) = (tree(&src), tree(&out));
        let names = |t: &[(PathBuf, Vec<u8>)]| t.iter().map(|(p, _)| p.clone()).collect::<Vec<_>>();
        assert_eq!(names(&a), names(&b), "{name}: the same files");
        for ((p, x), (_, y)) in a.iter().zip(&b) {
            let is_points = p
                .file_name()
                .unwrap()
                .to_string_lossy()
                .starts_with("points");
            assert_eq!(
                x == y,
                !is_points,
                "{name}: {} changed: {}",
                p.display(),
                x != y
            );
        }
        let r = mesh::io::read_path(&out).unwrap();
        assert_eq!(
            r.coords, m.coords,
            "{name}: the points read back bit for bit"
        );
        assert_eq!(r.cells, m.cells);
        // the same layout and header
        let (sa, sb) = (m.foam.as_deref().unwrap(), r.foam.as_deref().unwrap());
        assert_eq!(sa.points_layout, sb.points_layout);
        assert_eq!(sa.points_head, sb.points_head);
        assert_eq!(sa.points_tail, sb.points_tail);
        // writing the grid unchanged gives the input's points back: byte for byte in binary
        let same = tmp.path().join("same/constant/polyMesh");
        let m0 = mesh::io::read_path(&src).unwrap();
        mesh::io::write_path(&m0, mesh::io::Format::Foam, &same).unwrap();
        let r0 = mesh::io::read_path(&same).unwrap();
        assert_eq!(r0.coords, m0.coords);
        if name == "cavity_binary" {
            assert_eq!(
                std::fs::read(same.join("points")).unwrap(),
                std::fs::read(src.join("constant/polyMesh/points")).unwrap()
            );
        }
        // only the polyMesh when a polyMesh directory is named
        assert!(!tmp.path().join("same/system").exists());
    }
}

#[test]
fn a_grid_from_another_format_or_of_another_size_is_not_written_as_openfoam() {
    let tmp = tempfile::tempdir().unwrap();
    let b = mesh::generate::box_tets(1, 1, 1, [0.0; 3], [1.0; 3]);
    let err = mesh::io::write_path(&b, mesh::io::Format::Foam, &tmp.path().join("c")).unwrap_err();
    assert!(
        err.to_string()
            .contains("written back from a grid read from one"),
        "{err}"
    );
    let mut m = mesh::io::read_path(&cavity("cavity")).unwrap();
    m.coords.pop();
    let err = mesh::io::write_path(&m, mesh::io::Format::Foam, &tmp.path().join("c")).unwrap_err();
    assert!(err.to_string().contains("881 nodes"), "{err}");
}

/// The binary cavity with its labels rewritten as 64-bit (`arch "LSB;label=64;scalar=64"`),
/// as a 64-bit-label build of OpenFOAM writes them.
fn widen_labels(src: &Path, dst: &Path) {
    std::fs::create_dir_all(dst).unwrap();
    for name in ["points", "faces", "owner", "neighbour", "boundary"] {
        let bytes = std::fs::read(src.join(name)).unwrap();
        let text_end =
            |b: &[u8], from: usize| b[from..].iter().position(|&c| c == b'(').unwrap() + from;
        let out = if name == "points" || name == "boundary" {
            bytes.clone()
        } else {
            // header then one (faces: two) binary label lists "N\n(" … ")"
            let mut out = Vec::new();
            let mut pos = 0;
            let lists = if name == "faces" { 2 } else { 1 };
            let hdr_end = bytes.windows(2).position(|w| w == b"\n}").unwrap();
            for _ in 0..lists {
                let open = text_end(&bytes, if pos == 0 { hdr_end } else { pos });
                let count_start = bytes[..open]
                    .iter()
                    .rposition(|c| !c.is_ascii_digit() && *c != b'\n')
                    .unwrap()
                    + 1;
                let n: usize = String::from_utf8_lossy(&bytes[count_start..open])
                    .trim()
                    .parse()
                    .unwrap();
                out.extend_from_slice(&bytes[pos..=open]);
                for c in bytes[open + 1..open + 1 + 4 * n].chunks_exact(4) {
                    let v = i32::from_le_bytes(c.try_into().unwrap());
                    out.extend_from_slice(&i64::from(v).to_le_bytes());
                }
                pos = open + 1 + 4 * n;
            }
            out.extend_from_slice(&bytes[pos..]);
            out
        };
        let mut out = out;
        if let Some(at) = out.windows(8).position(|w| w == b"label=32") {
            out[at + 6..at + 8].copy_from_slice(b"64");
        }
        std::fs::write(dst.join(name), out).unwrap();
    }
}

#[test]
fn labels_of_64_bits_as_the_header_says() {
    let tmp = tempfile::tempdir().unwrap();
    let dst = tmp.path().join("constant/polyMesh");
    widen_labels(&cavity("cavity_binary").join("constant/polyMesh"), &dst);
    let a = mesh::io::read_path(&cavity("cavity")).unwrap();
    let w = mesh::io::read_path(&dst).unwrap();
    assert_eq!(w.foam.as_deref().unwrap().points_layout.label_bytes, 8);
    assert_eq!(w.coords, a.coords);
    assert_eq!(w.cells, a.cells);
    assert_eq!(w.markers, a.markers);
    // read as 32-bit labels, the same bytes are garbage that the reader refuses
    let owner = std::fs::read(dst.join("owner")).unwrap();
    let at = owner.windows(8).position(|x| x == b"label=64").unwrap();
    let mut o32 = owner.clone();
    o32[at + 6..at + 8].copy_from_slice(b"32");
    std::fs::write(dst.join("owner"), o32).unwrap();
    assert!(mesh::io::read_path(&dst).is_err());
}

/// checkMesh of OpenFOAM (Debian's `openfoam`, ESI v1912) on the case `case`: its output,
/// or `None` when OpenFOAM is not installed.
fn check_mesh(case: &Path) -> Option<(bool, String)> {
    let bashrc = Path::new("/usr/share/openfoam/etc/bashrc");
    if !bashrc.exists() {
        eprintln!("skipped: no OpenFOAM (/usr/share/openfoam/etc/bashrc; apt install openfoam)");
        return None;
    }
    let out = std::process::Command::new("bash")
        .arg("-c")
        .arg(format!(
            "source {} >/dev/null 2>&1; checkMesh -case '{}'",
            bashrc.display(),
            case.display()
        ))
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    Some((out.status.success() && text.contains("\nMesh OK."), text))
}

/// The cavity's system/ (controlDict, fvSchemes, fvSolution), for a bare polyMesh.
fn add_system(case: &Path) {
    let sys = case.join("system");
    std::fs::create_dir_all(&sys).unwrap();
    for f in ["controlDict", "fvSchemes", "fvSolution"] {
        std::fs::copy(cavity("cavity/system").join(f), sys.join(f)).unwrap();
    }
}

#[test]
#[ignore = "runs OpenFOAM's checkMesh (cargo xtask regress)"]
fn check_mesh_accepts_the_written_cases_and_refuses_an_inverted_one() {
    let tmp = tempfile::tempdir().unwrap();
    // the M6 half wing: bend the grid by a smooth twist about the y axis near the wing
    let mut m = mesh::io::read_path(&fixture()).unwrap();
    for p in &mut m.coords {
        let r2 = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
        let a = 0.02 * (-r2).exp();
        let (x, z) = (p[0], p[2]);
        p[0] = x * a.cos() + z * a.sin();
        p[2] = -x * a.sin() + z * a.cos();
    }
    let out = tmp.path().join("m6_twisted");
    mesh::io::write_path(&m, mesh::io::Format::Foam, &out.join("constant/polyMesh")).unwrap();
    add_system(&out);
    let Some((ok, log)) = check_mesh(&out) else {
        return;
    };
    assert!(ok, "checkMesh refused the twisted M6 grid:\n{log}");
    let words: Vec<&str> = log.split_whitespace().collect();
    assert!(words.windows(2).any(|w| w == ["prisms:", "4518"]), "{log}");
    // the binary cavity, bent
    let mut c = mesh::io::read_path(&cavity("cavity_binary")).unwrap();
    bend(&mut c);
    let out = tmp.path().join("cavity_bent");
    mesh::io::write_path(&c, mesh::io::Format::Foam, &out).unwrap();
    let (ok, log) = check_mesh(&out).unwrap();
    assert!(ok, "checkMesh refused the bent cavity:\n{log}");
    // a point pushed through its neighbours: checkMesh must refuse what the writer wrote
    let mut c = mesh::io::read_path(&cavity("cavity")).unwrap();
    let i = c
        .coords
        .iter()
        .position(|p| (p[0] - 0.05).abs() < 1e-9 && (p[1] - 0.05).abs() < 1e-9)
        .unwrap();
    c.coords[i][0] += 0.02;
    let out = tmp.path().join("cavity_broken");
    mesh::io::write_path(&c, mesh::io::Format::Foam, &out).unwrap();
    let (ok, log) = check_mesh(&out).unwrap();
    assert!(!ok, "checkMesh accepted a folded cavity:\n{log}");
}

#[test]
fn the_input_case_is_never_overwritten() {
    let tmp = tempfile::tempdir().unwrap();
    let case = tmp.path().join("c");
    let m = mesh::io::read_path(&cavity("cavity")).unwrap();
    mesh::io::write_path(&m, mesh::io::Format::Foam, &case).unwrap();
    let mut c = mesh::io::read_path(&case).unwrap();
    bend(&mut c);
    let before = std::fs::read(case.join("constant/polyMesh/points")).unwrap();
    for out in [case.clone(), case.join("constant/polyMesh")] {
        let err = mesh::io::write_path(&c, mesh::io::Format::Foam, &out).unwrap_err();
        assert!(err.to_string().contains("never overwritten"), "{err}");
    }
    assert_eq!(
        std::fs::read(case.join("constant/polyMesh/points")).unwrap(),
        before
    );
    // a case inside the input case is written without copying itself into itself
    let inner = case.join("deformed");
    mesh::io::write_path(&c, mesh::io::Format::Foam, &inner).unwrap();
    assert!(!inner.join("deformed").exists());
    assert_eq!(mesh::io::read_path(&inner).unwrap().coords, c.coords);
}
