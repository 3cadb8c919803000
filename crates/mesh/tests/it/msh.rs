//! Gmsh MSH 4.1: files written by Gmsh itself, round trips in both encodings.

use std::path::PathBuf;

use mesh::msh::Encoding;
use mesh::{ElementKind, Error, Mesh};

use crate::common::{assert_same_grid, read_su2, shared_su2};

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/mesh")
        .join(name)
}

fn read_msh(path: &std::path::Path) -> Mesh {
    let f = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    mesh::msh::read(std::io::BufReader::new(f), path).unwrap()
}

fn round_trip(m: &Mesh, enc: Encoding) -> Mesh {
    let mut buf = Vec::new();
    mesh::msh::write(m, enc, &mut buf).unwrap();
    mesh::msh::read(&buf[..], "mem.msh".as_ref()).unwrap()
}

#[test]
fn gmsh_square_with_parametric_nodes() {
    let m = read_msh(&fixture("square_param.msh"));
    m.validate().unwrap();
    assert_eq!(m.dim, 2);
    assert_eq!(m.n_nodes(), 98);
    assert!(m.parametric);
    let names: Vec<&str> = m.markers.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["bottom", "right", "top", "left"]);
    assert_eq!(m.markers[0].tag, Some(1));
    assert!(m.warnings.is_empty(), "{:?}", m.warnings);
    let classes = m.classes.as_ref().unwrap();
    // Every boundary line lies on a curve whose nodes carry u; on the unit square's
    // sides u is the arc length from the side's first corner, so u equals x or y (or
    // 1 - x, 1 - y) there. Check the bottom side (curve 1, from (0,0) to (1,0)).
    let mut n_curve = 0;
    let mut shift: Option<[f64; 2]> = None;
    for (i, c) in classes.iter().enumerate() {
        let p = m.coords[i];
        match c.dim {
            1 if c.entity == 1 => {
                testkit::assert_close!(c.param[0], p[0], abs = 1e-12);
                testkit::assert_close!(p[1], 0.0, abs = 1e-12);
                n_curve += 1;
            }
            2 => {
                // The plane surface of the square: (u, v) = (x, y) + a constant shift.
                let d = [c.param[0] - p[0], c.param[1] - p[1]];
                let s = *shift.get_or_insert(d);
                testkit::assert_close!(d, s, abs = 1e-12);
            }
            0 => assert!(p[0] == 0.0 || p[0] == 1.0),
            _ => {}
        }
    }
    assert_eq!(n_curve, 7);
    assert!(shift.is_some());
    // Positive quality: Gmsh orients 2-D triangles counter-clockwise.
    let q = mesh::quality::summary(&mesh::quality::cell_quality(&m));
    assert!(q.min > 0.3 && q.n_nonpositive == 0, "{q:?}");
}

#[test]
fn gmsh_ascii_and_binary_files_give_the_same_grid() {
    let a = read_msh(&fixture("box_param.msh"));
    let b = read_msh(&fixture("box_param_bin.msh"));
    a.validate().unwrap();
    assert_eq!(a.dim, 3);
    assert!(!a.tets().is_empty());
    // Gmsh prints 16 significant digits in ASCII, so coordinates agree to the last bit
    // or so; connectivity, markers and classification entities agree exactly.
    assert_eq!(a.n_nodes(), b.n_nodes());
    for (p, q) in a.coords.iter().zip(&b.coords) {
        testkit::assert_close!(&p[..], &q[..], rel = 1e-15, abs = 1e-300);
    }
    assert_eq!(a.cells, b.cells);
    assert_eq!(a.markers, b.markers);
    let (ca, cb) = (a.classes.as_ref().unwrap(), b.classes.as_ref().unwrap());
    for (c, d) in ca.iter().zip(cb) {
        assert_eq!((c.dim, c.entity), (d.dim, d.entity));
        testkit::assert_close!(&c.param[..], &d.param[..], rel = 1e-15, abs = 1e-300);
    }
    assert_eq!(a.entities.len(), b.entities.len());
    assert_eq!(a.physical_names, b.physical_names);
    let names: Vec<&str> = a.markers.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["ends", "side0", "side1", "side2", "side3"]);
    // "ends" groups two faces: its elements come from two entities.
    let ends = &a.markers[0]
        .elements
        .group(ElementKind::Triangle)
        .unwrap()
        .entity;
    let mut ents = ends.clone();
    ents.dedup();
    assert_eq!(ents.len(), 2);
    // The six faces of a 2 x 1 x 0.5 box: total boundary area 2(2 + 1 + 0.5) = 7.
    let mut area = 0.0;
    for mk in &a.markers {
        for (_, t) in mk.elements.iter() {
            let p: Vec<[f64; 3]> = t.iter().map(|&v| a.coords[v as usize]).collect();
            let u = [p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2]];
            let w = [p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2]];
            let c = [
                u[1] * w[2] - u[2] * w[1],
                u[2] * w[0] - u[0] * w[2],
                u[0] * w[1] - u[1] * w[0],
            ];
            area += 0.5 * (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
        }
    }
    testkit::assert_close!(area, 7.0, rel = 1e-12);
    let q = mesh::quality::summary(&mesh::quality::cell_quality(&a));
    assert_eq!(q.n_nonpositive, 0);
}

#[test]
fn msh_round_trip_keeps_entities_and_parametric_coordinates() {
    for name in ["box_param.msh", "square_param.msh"] {
        let a = read_msh(&fixture(name));
        for enc in [Encoding::Ascii, Encoding::Binary] {
            let b = round_trip(&a, enc);
            assert_same_grid(&a, &b);
            assert_eq!(a.classes, b.classes, "{name} {enc:?}");
            assert!(b.parametric);
            assert_eq!(a.entities, b.entities);
            assert_eq!(a.physical_names, b.physical_names);
            for (m, n) in a.markers.iter().zip(&b.markers) {
                assert_eq!(m.tag, n.tag);
                assert_eq!(m.elements, n.elements);
            }
            assert_eq!(a.cells, b.cells);
        }
    }
}

#[test]
fn su2_to_msh_to_su2_is_exact() {
    for name in ["mesh_brick_tets_ffd.su2", "mesh_NACA0012_inv.su2"] {
        let a = read_su2(&shared_su2(name));
        for enc in [Encoding::Ascii, Encoding::Binary] {
            let b = round_trip(&a, enc);
            b.validate().unwrap();
            assert_same_grid(&a, &b);
            let mut buf = Vec::new();
            mesh::su2::write(&b, &mut buf).unwrap();
            let c = mesh::su2::read(&buf[..], "mem.su2".as_ref()).unwrap();
            assert_same_grid(&a, &c);
        }
    }
}

#[test]
fn malformed_msh_reports_file_and_place() {
    let good = std::fs::read(fixture("square_param.msh")).unwrap();
    let text = String::from_utf8(good).unwrap();
    let bad = text.replacen("$Nodes\n9 98 1 98", "$Nodes\n9 99 1 99", 1);
    let e = mesh::msh::read(bad.as_bytes(), "sq.msh".as_ref()).unwrap_err();
    assert!(e.to_string().starts_with("sq.msh: line"), "{e}");
    let bad = text.replacen("4.1 0 8", "2.2 0 8", 1);
    let e = mesh::msh::read(bad.as_bytes(), "sq.msh".as_ref()).unwrap_err();
    assert_eq!(
        e.to_string(),
        "sq.msh: line 2: unsupported format '2.2 0 8': only MSH 4.1 (ASCII or binary) is read"
    );
    // An element referring to a node tag that does not exist.
    let bad = text.replacen("\n1 1 5 \n", "\n1 1 500 \n", 1);
    let e = mesh::msh::read(bad.as_bytes(), "sq.msh".as_ref()).unwrap_err();
    assert!(matches!(e, Error::NodeOutOfRange { node: 500, .. }), "{e}");
    // Unknown (second-order) element type.
    let bad = text.replacen("\n2 1 2 162\n", "\n2 1 9 162\n", 1);
    let e = mesh::msh::read(bad.as_bytes(), "sq.msh".as_ref()).unwrap_err();
    assert!(
        matches!(e, Error::UnknownElementType { code: 9, .. }),
        "{e}"
    );
    // Truncated binary file: the error gives a byte offset.
    let bin = std::fs::read(fixture("box_param_bin.msh")).unwrap();
    let e = mesh::msh::read(&bin[..bin.len() / 2], "b.msh".as_ref()).unwrap_err();
    assert!(e.to_string().starts_with("b.msh: byte "), "{e}");
}

#[test]
fn mixed_elements_survive_every_format() {
    // A hexahedron, a prism on top of it, a pyramid beside it and a tetrahedron; quads and
    // triangles on the boundary.
    // Every cell valid in SU2's (VTK's) order: the prism's first triangle 4-6-5 turns
    // clockwise seen from its second, 9-8-10.
    let txt = "NDIME= 3\nNELEM= 4\n12 0 1 2 3 4 5 6 7\n13 4 6 5 9 8 10\n14 1 11 12 2 13\n10 4 5 7 14\n\
               NPOIN= 15\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n1 1 2\n\
               0 0 2\n1 0 2\n2 0 0\n2 1 0\n1.5 0.5 1\n0.2 0.2 1.5\n\
               NMARK= 2\nMARKER_TAG= bottom\nMARKER_ELEMS= 2\n9 0 3 2 1\n9 1 2 12 11\n\
               MARKER_TAG= top\nMARKER_ELEMS= 1\n5 8 9 10\n";
    let a = mesh::su2::read(txt.as_bytes(), "mixed.su2".as_ref()).unwrap();
    a.validate().unwrap();
    assert_eq!(a.cells.len(), 4);
    for enc in [Encoding::Ascii, Encoding::Binary] {
        let b = round_trip(&a, enc);
        assert_same_grid(&a, &b);
    }
    for enc in [
        mesh::vtu::VtuEncoding::AppendedRaw,
        mesh::vtu::VtuEncoding::Base64,
    ] {
        let mut buf = Vec::new();
        mesh::io::write(&a, mesh::io::Format::Vtu(enc), &mut buf).unwrap();
        let b = mesh::vtu::read(&buf[..], "mixed.vtu".as_ref()).unwrap();
        assert_same_grid(&a, &b);
    }
    // Every kind is measured, and every cell is valid.
    let s = mesh::quality::summary(&mesh::quality::cell_quality(&a));
    assert_eq!((s.count, s.measured, s.n_nonpositive), (4, 4, 0), "{s:?}");
    // The MSH file lists the prism in Gmsh's order (first triangle towards the second):
    // nodes 4 5 6 9 10 8, tags + 1.
    let mut buf = Vec::new();
    mesh::msh::write(&a, Encoding::Ascii, &mut buf).unwrap();
    let text = String::from_utf8(buf).unwrap();
    let block = text.split("\n3 1 6 1\n").nth(1).expect("the prism block");
    assert_eq!(block.lines().next().unwrap(), "3 5 6 7 10 11 9", "{text}");
    // A Gmsh-order prism read from MSH is valid here.
    let b = mesh::msh::read(text.as_bytes(), "mixed.msh".as_ref()).unwrap();
    assert_eq!(
        b.cells.group(ElementKind::Prism).unwrap().nodes,
        [4, 6, 5, 9, 8, 10]
    );
}
