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

fn su2_fixture(name: &str) -> std::path::PathBuf {
    std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/su2")
        .join(name)
}

/// SU2's own 2-D RANS grids (`fixtures/su2`): the RAE2822 grid's points carry a z column
/// (`x y 0 index`) and come before the elements; every cell is valid and the smallest
/// quadrilateral scaled Jacobian is the independent script's (`check_2d.py`).
#[test]
fn su2_two_dimensional_rans_grids_read_with_real_quality() {
    for (name, nodes, tri, quad, qmin, markers) in [
        (
            "mesh_RAE2822_turb.su2",
            13937,
            18042,
            4800,
            0.97110120647508,
            [("AIRFOIL", 192), ("FARFIELD", 40)],
        ),
        (
            "n0012_113-33.su2",
            3704,
            0,
            3584,
            0.80756756265483,
            [("airfoil", 64), ("farfield", 176)],
        ),
    ] {
        let m = read_su2(&su2_fixture(name));
        m.validate().unwrap();
        assert_eq!(m.dim, 2, "{name}");
        assert_eq!(m.n_nodes(), nodes, "{name}");
        assert_eq!(m.cells.count(ElementKind::Triangle), tri, "{name}");
        assert_eq!(m.cells.count(ElementKind::Quad), quad, "{name}");
        assert!(m.warnings.is_empty(), "{name}: {:?}", m.warnings);
        for (mk, n) in markers {
            assert_eq!(m.marker(mk).unwrap().elements.len(), n, "{name} {mk}");
        }
        let q = mesh::quality::cell_quality(&m);
        let s = mesh::quality::summary(&q);
        assert_eq!((s.measured, s.n_nonpositive), (m.cells.len(), 0), "{name}");
        let by = mesh::quality::summary_by_kind(&m.cells, &q);
        let (_, sq) = by.iter().find(|(k, _)| *k == ElementKind::Quad).unwrap();
        testkit::assert_close!(sq.min, qmin, rel = 1e-12);
        // Written back (2-D: x y index) and read again: the same grid.
        let mut buf = Vec::new();
        mesh::su2::write(&m, &mut buf).unwrap();
        let b = mesh::su2::read(&buf[..], "back.su2".as_ref()).unwrap();
        assert_same_grid(&m, &b);
    }
    // The first RAE2822 node as printed: "0.999999523162842\t0.000158801834913902\t0\t0".
    let m = read_su2(&su2_fixture("mesh_RAE2822_turb.su2"));
    assert_eq!(m.coords[0], [0.999999523162842, 0.000158801834913902, 0.0]);
}

/// The layouts of a 2-D point line: `x y`, `x y index`, `x y z`, `x y z index`; a nonzero z
/// is dropped with a warning (SU2 ignores it), a bad z or a fifth token is an error.
#[test]
fn su2_two_dimensional_point_layouts() {
    let grid = |pts: &str| {
        format!(
            "NDIME= 2\nNELEM= 1\n5 0 1 2 0\nNPOIN= 3\n{pts}NMARK= 1\nMARKER_TAG= w\nMARKER_ELEMS= 1\n3 0 1\n"
        )
    };
    let want = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    for pts in [
        "0 0\n1 0\n0 1\n",
        "0 0 0\n1 0 1\n0 1 2\n",
        "0 0 0.0\n1 0 0.0\n0 1 0.0\n",
        "0 0 0 0\n1 0 0 1\n0 1 0 2\n",
        "0\t0\t0\t0\n1\t0\t0\t1\n0\t1\t0\t2\n",
    ] {
        let m = mesh::su2::read(grid(pts).as_bytes(), "p.su2".as_ref()).unwrap();
        assert_eq!(m.coords, want, "{pts:?}");
        assert!(m.warnings.is_empty(), "{pts:?}: {:?}", m.warnings);
    }
    let m = mesh::su2::read(
        grid("0 0 0.5 0\n1 0 0 1\n0 1 1e-3\n").as_bytes(),
        "p.su2".as_ref(),
    )
    .unwrap();
    assert_eq!(m.coords, want);
    assert_eq!(m.warnings.len(), 1);
    assert!(m.warnings[0].contains("2 nodes"), "{:?}", m.warnings);
    let e = mesh::su2::read(grid("0 0 x 0\n1 0\n0 1\n").as_bytes(), "p.su2".as_ref()).unwrap_err();
    assert_eq!(
        e.to_string(),
        "p.su2: line 5: node 0: coordinate 2 must be a finite number, found 'x'"
    );
    let e =
        mesh::su2::read(grid("0 0 0 0 7\n1 0\n0 1\n").as_bytes(), "p.su2".as_ref()).unwrap_err();
    assert!(e.to_string().contains("unexpected token '7'"), "{e}");
}
