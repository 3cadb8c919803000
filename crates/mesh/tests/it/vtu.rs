//! VTK XML unstructured grids: round trips through our reader, a hand-written ASCII file.

use mesh::vtu::{VtuEncoding, VtuOptions};
use mesh::{ElementKind, Error};

use crate::common::{assert_same_grid, read_su2, shared_su2};

#[test]
fn vtu_round_trip_in_both_encodings() {
    for name in ["mesh_brick_tets_ffd.su2", "mesh_NACA0012_inv.su2"] {
        let a = read_su2(&shared_su2(name));
        let disp = vec![[0.5, -0.25, 1e-300]; a.n_nodes()];
        for enc in [VtuEncoding::AppendedRaw, VtuEncoding::Base64] {
            let mut buf = Vec::new();
            let opts = VtuOptions::default()
                .with_encoding(enc)
                .with_displacement(&disp);
            mesh::vtu::write(&a, &opts, &mut buf).unwrap();
            let b = mesh::vtu::read(&buf[..], "mem.vtu".as_ref()).unwrap();
            assert_same_grid(&a, &b);
            assert!(b.warnings.is_empty(), "{:?}", b.warnings);
        }
    }
}

#[test]
fn displacement_of_the_wrong_length_is_refused() {
    let m = mesh::generate::box_tets(1, 1, 1, [0.0; 3], [1.0; 3]);
    let d = vec![[0.0; 3]; 3];
    let opts = VtuOptions::default().with_displacement(&d);
    let e = mesh::vtu::write(&m, &opts, &mut Vec::new()).unwrap_err();
    assert!(e.to_string().contains("3 entries for 8 nodes"));
}

#[test]
fn ascii_vtu_as_other_tools_write_it() {
    let txt = r#"<?xml version="1.0"?>
<VTKFile type="UnstructuredGrid" version="0.1" byte_order="LittleEndian">
  <UnstructuredGrid>
    <Piece NumberOfPoints="4" NumberOfCells="2">
      <Points>
        <DataArray type="Float32" NumberOfComponents="3" format="ascii">
          0 0 0  1 0 0  0 1 0  0 0 1
        </DataArray>
      </Points>
      <Cells>
        <DataArray type="Int32" Name="connectivity" format="ascii">0 1 2 3 0 2 1</DataArray>
        <DataArray type="Int32" Name="offsets" format="ascii">4 7</DataArray>
        <DataArray type="UInt8" Name="types" format="ascii">10 5</DataArray>
      </Cells>
    </Piece>
  </UnstructuredGrid>
</VTKFile>
"#;
    let m = mesh::vtu::read(txt.as_bytes(), "t.vtu".as_ref()).unwrap();
    assert_eq!(m.tets(), &[[0, 1, 2, 3]]);
    assert_eq!(m.coords[3], [0.0, 0.0, 1.0]);
    assert_eq!(m.markers.len(), 1);
    assert_eq!(m.markers[0].elements.count(ElementKind::Triangle), 1);
    let bad = txt.replace("10 5", "10 42");
    let e = mesh::vtu::read(bad.as_bytes(), "t.vtu".as_ref()).unwrap_err();
    assert!(
        matches!(e, Error::UnknownElementType { code: 42, .. }),
        "{e}"
    );
    let bad = txt.replace("0 2 1</", "0 2 9</");
    let e = mesh::vtu::read(bad.as_bytes(), "t.vtu".as_ref()).unwrap_err();
    assert!(matches!(e, Error::NodeOutOfRange { node: 9, .. }), "{e}");
    let bad = txt.replace("4 7", "4 6");
    let e = mesh::vtu::read(bad.as_bytes(), "t.vtu".as_ref()).unwrap_err();
    assert!(e.to_string().starts_with("t.vtu: byte "), "{e}");
}

#[test]
fn zlib_compressed_vtu_written_by_meshio() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/mesh");
    let v = mesh::io::read_path(&dir.join("box_meshio_zlib.vtu")).unwrap();
    let g = mesh::io::read_path(&dir.join("box_param_bin.msh")).unwrap();
    // Same nodes and tetrahedra as the Gmsh file it was made from (Gmsh node order).
    assert_eq!(v.n_nodes(), g.n_nodes());
    assert_eq!(v.coords, g.coords);
    assert_eq!(v.tets(), g.tets());
    // Boundary triangles of all markers together.
    let n_tri: usize = g.markers.iter().map(|m| m.elements.len()).sum();
    assert_eq!(v.markers.len(), 1);
    assert_eq!(v.markers[0].elements.len(), n_tri);
}

/// The point data of VTU files written by meshio (`fixtures/mesh/make_sensitivity_vtu.py`:
/// zlib-compressed binary and ASCII): every `<PointData>` array with its components, the
/// "Sensitivity" vector equal to the field the script evaluated at the points read.
#[test]
fn point_data_written_by_meshio() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/mesh");
    // binary: the f64 values exact (libm's last digit aside); ASCII: meshio prints 12
    // significant digits, of the coordinates too
    for (name, tol) in [
        ("box_sensitivity_zlib.vtu", 4.0 * f64::EPSILON),
        ("box_sensitivity_ascii.vtu", 1e-10),
    ] {
        let f = std::fs::File::open(dir.join(name)).unwrap();
        let (m, data) = mesh::vtu::read_with_point_data(f, name.as_ref()).unwrap();
        assert_eq!(m.n_nodes(), 228, "{name}");
        let names: Vec<(&str, usize)> = data
            .iter()
            .map(|a| (a.name.as_str(), a.components))
            .collect();
        assert_eq!(names, [("Pressure", 1), ("Sensitivity", 3)], "{name}");
        let s = &data[1];
        for (i, p) in m.coords.iter().enumerate() {
            let [x, y, z] = *p;
            let want = [(3.0 * x).sin() + y, (2.0 * y).cos() * z, x * y * z - 0.5];
            for c in 0..3 {
                assert!(
                    (s.at(i)[c] - want[c]).abs() <= tol,
                    "{name}: point {i}: {:?} vs {want:?}",
                    s.at(i)
                );
            }
            assert!((data[0].at(i)[0] - (x + 2.0 * y + 3.0 * z)).abs() <= 4.0 * tol);
        }
        // `read` gives the same grid without the arrays
        let f = std::fs::File::open(dir.join(name)).unwrap();
        assert_eq!(mesh::vtu::read(f, name.as_ref()).unwrap().coords, m.coords);
    }
}

/// Our own writer's point data read back, and a point array of the wrong length named.
#[test]
fn point_data_round_trip_and_wrong_length() {
    let a = read_su2(&shared_su2("mesh_brick_tets_ffd.su2"));
    let disp: Vec<[f64; 3]> = (0..a.n_nodes())
        .map(|i| [i as f64, -0.5 * i as f64, 1e-300])
        .collect();
    for enc in [VtuEncoding::AppendedRaw, VtuEncoding::Base64] {
        let mut buf = Vec::new();
        let opts = VtuOptions::default()
            .with_encoding(enc)
            .with_displacement(&disp);
        mesh::vtu::write(&a, &opts, &mut buf).unwrap();
        let (_, data) = mesh::vtu::read_with_point_data(&buf[..], "mem.vtu".as_ref()).unwrap();
        let d = data.iter().find(|d| d.name == "displacement").unwrap();
        assert_eq!(d.components, 3);
        for (i, v) in disp.iter().enumerate() {
            assert_eq!(d.at(i), v);
        }
    }
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/mesh");
    let txt = std::fs::read_to_string(dir.join("box_sensitivity_ascii.vtu")).unwrap();
    let bad = txt.replace(
        "Name=\"Sensitivity\" NumberOfComponents=\"3\"",
        "Name=\"Sensitivity\" NumberOfComponents=\"4\"",
    );
    let e = mesh::vtu::read_with_point_data(bad.as_bytes(), "s.vtu".as_ref()).unwrap_err();
    assert!(
        e.to_string()
            .contains("PointData Sensitivity: 684 values for 228 points of 4 components"),
        "{e}"
    );
}
