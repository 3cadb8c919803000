//! Shared helpers: fixture loading.

use geom_db::GeomDb;

/// Loads `fixtures/geom/<name>.ron` of the workspace.
pub fn fixture(name: &str) -> GeomDb {
    let path = format!(
        "{}/../../fixtures/geom/{name}.ron",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(&path).unwrap();
    GeomDb::from_ron_str(&text, &path).unwrap()
}
