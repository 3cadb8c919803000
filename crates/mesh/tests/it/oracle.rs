//! Independent readers as oracles (ignored by default; `cargo xtask regress` runs them):
//! Python's `meshio` reads our .vtu and .msh, and Gmsh itself reads our .msh. Skipped with a
//! message when Python or the module is missing (`pip install -r .ci/requirements.txt`).

use std::path::Path;
use std::process::Command;

use mesh::io::Format;
use mesh::msh::Encoding;
use mesh::vtu::VtuEncoding;

use crate::common::{read_su2, shared_su2};

fn python_has(module: &str) -> bool {
    Command::new("python3")
        .args(["-c", &format!("import {module}")])
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false)
}

fn run_python(script: &str, arg: &Path) -> String {
    let out = Command::new("python3")
        .args(["-c", script])
        .arg(arg)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "python failed on {}: {}",
        arg.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    text.trim().lines().last().unwrap_or("").to_string()
}

fn write(m: &mesh::Mesh, f: Format, path: &Path) {
    let mut buf = Vec::new();
    mesh::io::write(m, f, &mut buf).unwrap();
    std::fs::write(path, buf).unwrap();
}

const MESHIO: &str = r#"
import sys, meshio
m = meshio.read(sys.argv[1])
counts = {}
for c in m.cells:
    counts[c.type] = counts.get(c.type, 0) + len(c.data)
print(len(m.points), counts.get("tetra", 0), counts.get("triangle", 0))
"#;

const GMSH: &str = r#"
import sys, gmsh
gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
gmsh.open(sys.argv[1])
tags, _, _ = gmsh.model.mesh.getNodes()
tets = gmsh.model.mesh.getElementsByType(4)[0]
tris = gmsh.model.mesh.getElementsByType(2)[0]
names = sorted(gmsh.model.getPhysicalName(d, t) for d, t in gmsh.model.getPhysicalGroups(2))
print(len(tags), len(tets), len(tris), ",".join(names))
gmsh.finalize()
"#;

#[test]
#[ignore = "needs python3 with meshio; run by cargo xtask regress"]
fn meshio_reads_our_vtu_and_msh() {
    if !python_has("meshio") {
        eprintln!("SKIPPED: python3 module meshio not available");
        return;
    }
    let m = read_su2(&shared_su2("mesh_brick_tets_ffd.su2"));
    let dir = tempfile::tempdir().unwrap();
    let n_tri: usize = m.markers.iter().map(|k| k.elements.len()).sum();
    let want = format!("{} {} {}", m.n_nodes(), m.tets().len(), n_tri);
    for (name, f) in [
        ("raw.vtu", Format::Vtu(VtuEncoding::AppendedRaw)),
        ("b64.vtu", Format::Vtu(VtuEncoding::Base64)),
        ("ascii.msh", Format::Msh(Encoding::Ascii)),
        ("binary.msh", Format::Msh(Encoding::Binary)),
    ] {
        let p = dir.path().join(name);
        write(&m, f, &p);
        assert_eq!(run_python(MESHIO, &p), want, "{name}");
    }
}

#[test]
#[ignore = "needs python3 with gmsh; run by cargo xtask regress"]
fn gmsh_reads_our_msh() {
    if !python_has("gmsh") {
        eprintln!("SKIPPED: python3 module gmsh not available");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    // From SU2 (synthesised entities) and from a Gmsh file (entities kept), both encodings.
    let brick = read_su2(&shared_su2("mesh_brick_tets_ffd.su2"));
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/mesh/box_param.msh");
    let gbox = mesh::io::read_path(&fixture).unwrap();
    for (tag, m) in [("brick", &brick), ("box", &gbox)] {
        let n_tri: usize = m.markers.iter().map(|k| k.elements.len()).sum();
        let mut names: Vec<&str> = m.markers.iter().map(|k| k.name.as_str()).collect();
        names.sort_unstable();
        let want = format!(
            "{} {} {} {}",
            m.n_nodes(),
            m.tets().len(),
            n_tri,
            names.join(",")
        );
        for enc in [Encoding::Ascii, Encoding::Binary] {
            let p = dir.path().join(format!("{tag}-{enc:?}.msh"));
            write(m, Format::Msh(enc), &p);
            assert_eq!(run_python(GMSH, &p), want, "{tag} {enc:?}");
        }
    }
}
