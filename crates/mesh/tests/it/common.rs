//! Shared helpers: paths to the real grids and grid comparison.

use std::path::PathBuf;

use mesh::Mesh;

/// A file of the shared data set (`<workspace>/../shared/data/su2/NAME`).
pub fn shared_su2(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/su2")
        .join(name)
}

/// Reads an SU2 file from disk.
pub fn read_su2(path: &std::path::Path) -> Mesh {
    let f = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    mesh::su2::read(std::io::BufReader::new(f), path).unwrap()
}

/// Asserts that two grids have the same nodes (bit for bit), cells and markers.
pub fn assert_same_grid(a: &Mesh, b: &Mesh) {
    assert_eq!(a.dim, b.dim);
    assert_eq!(a.coords.len(), b.coords.len());
    for (i, (p, q)) in a.coords.iter().zip(&b.coords).enumerate() {
        for k in 0..3 {
            assert_eq!(p[k].to_bits(), q[k].to_bits(), "node {i} coordinate {k}");
        }
    }
    assert_eq!(a.cells.groups().len(), b.cells.groups().len());
    for (g, h) in a.cells.groups().iter().zip(b.cells.groups()) {
        assert_eq!(g.kind, h.kind);
        assert_eq!(g.nodes, h.nodes);
    }
    assert_eq!(a.markers.len(), b.markers.len());
    for (m, n) in a.markers.iter().zip(&b.markers) {
        assert_eq!(m.name, n.name);
        assert_eq!(m.elements.groups().len(), n.elements.groups().len());
        for (g, h) in m.elements.groups().iter().zip(n.elements.groups()) {
            assert_eq!(g.kind, h.kind);
            assert_eq!(g.nodes, h.nodes, "marker {}", m.name);
        }
    }
}
