//! SU2 reader and writer on the real grids and on generated ones.

use mesh::{ElementKind, Error};

use crate::common::{assert_same_grid, read_su2, shared_su2};

#[test]
fn brick_has_the_published_counts_and_keeps_ffd_section() {
    let m = read_su2(&shared_su2("mesh_brick_tets_ffd.su2"));
    assert_eq!(m.dim, 3);
    assert_eq!(m.n_nodes(), 11703);
    assert_eq!(m.tets().len(), 59156);
    assert_eq!(m.cells.len(), 59156);
    let names: Vec<&str> = m.markers.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["x_m", "x_p", "y_m", "y_p", "z_m", "z_p"]);
    let counts: Vec<usize> = m.markers.iter().map(|m| m.elements.len()).collect();
    assert_eq!(counts, [722, 722, 1482, 1482, 1482, 1482]);
    assert!(m.su2_extra.starts_with("NPERIODIC= 1\n"));
    assert!(m.su2_extra.contains("FFD_CONTROL_POINTS= 50"));
    assert_eq!(m.warnings.len(), 1);
    m.validate().unwrap();
}

#[test]
fn naca0012_has_the_published_counts() {
    let m = read_su2(&shared_su2("mesh_NACA0012_inv.su2"));
    assert_eq!(m.dim, 2);
    assert_eq!(m.n_nodes(), 5233);
    assert_eq!(m.triangles().len(), 10216);
    let airfoil = m.marker("airfoil").unwrap();
    assert_eq!(airfoil.elements.count(ElementKind::Line), 200);
    assert_eq!(m.marker("farfield").unwrap().elements.len(), 50);
    assert!(m.su2_extra.is_empty());
    // The first node as printed in the file.
    assert_eq!(m.coords[0], [9.9975001812e-1, -3.632896519016437e-05, 0.0]);
    m.validate().unwrap();
}

#[test]
fn su2_round_trip_is_bit_exact_on_real_grids() {
    for name in ["mesh_brick_tets_ffd.su2", "mesh_NACA0012_inv.su2"] {
        let a = read_su2(&shared_su2(name));
        let mut buf = Vec::new();
        mesh::su2::write(&a, &mut buf).unwrap();
        let b = mesh::su2::read(&buf[..], "mem.su2".as_ref()).unwrap();
        assert_same_grid(&a, &b);
        assert_eq!(a.su2_extra, b.su2_extra);
    }
}

#[test]
fn mixed_elements_and_header_variants() {
    let txt = "% comment\nNDIME= 3\nNELEM= 3\n12 0 1 2 3 4 5 6 7 0\n10 0 1 2 4\n13 0 1 2 4 5 6\n\
               NPOIN= 8 8\n0 0 0 0\n1 0 0 1\n1 1 0 2\n0 1 0 3\n0 0 1 4\n1 0 1 5\n1 1 1 6\n0 1 1\n\
               NMARK= 1\nMARKER_TAG= bottom\nMARKER_ELEMS= 2\n9 0 1 2 3\n5 0 1 2\n";
    let m = mesh::su2::read(txt.as_bytes(), "mixed.su2".as_ref()).unwrap();
    assert_eq!(m.cells.count(ElementKind::Hexa), 1);
    assert_eq!(m.cells.count(ElementKind::Tetra), 1);
    assert_eq!(m.cells.count(ElementKind::Prism), 1);
    let b = &m.markers[0].elements;
    assert_eq!(
        (b.count(ElementKind::Quad), b.count(ElementKind::Triangle)),
        (1, 1)
    );
    // Canonical order: tetra, prism, hexa.
    let kinds: Vec<ElementKind> = m.cells.iter().map(|(k, _)| k).collect();
    assert_eq!(
        kinds,
        [ElementKind::Tetra, ElementKind::Prism, ElementKind::Hexa]
    );
}

fn err(txt: &str) -> Error {
    mesh::su2::read(txt.as_bytes(), "bad.su2".as_ref()).unwrap_err()
}

#[test]
fn malformed_inputs_name_file_and_line() {
    let e = err("NDIME= 2\nNELEM= 1\n5 0 1 x\n");
    assert_eq!(
        e.to_string(),
        "bad.su2: line 3: node index 'x' is not a non-negative integer"
    );
    // A bad line before a truncation: the first problem in file order is reported.
    let e = err("NDIME= 2\nNELEM= 4\n5 0 1 2\n5 0 1 y\n5 0 1 2\n");
    assert_eq!(
        e.to_string(),
        "bad.su2: line 4: node index 'y' is not a non-negative integer"
    );
    let e = err("NDIME= 2\nNELEM= 1\n5 0 1 2\nNPOIN= 3\n0 0\n1 zero\n");
    assert!(
        e.to_string()
            .starts_with("bad.su2: line 6: node 1: coordinate 1"),
        "{e}"
    );
    let e = err("NDIME= 2\nNELEM= 1\n5 0 1 2\nNPOIN= 3\n0 0\n1 0\n");
    assert!(matches!(e, Error::Truncated { .. }), "{e}");
    assert!(
        e.to_string()
            .starts_with("bad.su2: line 7: file ends inside NPOIN"),
        "{e}"
    );
    let e = err("NDIME= 2\nNELEM= 1\n7 0 1 2\n");
    assert_eq!(
        e.to_string(),
        "bad.su2: line 3: unknown or unsupported element type 7"
    );
    let e = err("NDIME= 2\nNELEM= 2\n5 0 1 2\n5 0 1 9\nNPOIN= 3\n0 0\n1 0\n0 1\nNMARK= 0\n");
    assert_eq!(
        e.to_string(),
        "bad.su2: line 4: node 9 out of range (the grid has 3 nodes)"
    );
    let e = err("NDIME= 2\nNELEM= 1\n10 0 1 2 3\n");
    assert!(
        e.to_string().contains("line 3: tetra element where 2-D"),
        "{e}"
    );
    let e = err("NDIME= 2\nNELEM= 1\n5 0 1\n");
    assert!(
        e.to_string().contains("triangle needs 3 nodes, found 2"),
        "{e}"
    );
    let e = err("NDIME= 2\nNELEM= 1\n5 0 1 2\nNPOIN= 3\n0 0\n1 0\n0 1\nNMARK= 1\nMARKER_TAG= a\n");
    assert!(matches!(e, Error::Truncated { .. }), "{e}");
    let e = err("NDIME= 2\nFOO= 1\n");
    assert!(
        e.to_string().contains("line 2: unknown keyword FOO="),
        "{e}"
    );
    let e = err("");
    assert!(matches!(e, Error::Truncated { .. }), "{e}");
}
