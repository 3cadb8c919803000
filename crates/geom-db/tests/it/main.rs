//! Integration tests of the public API of `geom-db`.

mod aircraft;
mod analytic;
mod cad_import;
mod control;
mod convert;
mod corrupt;
mod fixtures;
mod high_degree;
mod ron_fuzz;
mod validate;

use std::path::PathBuf;

use geom_db::GeomDb;

/// Path of a committed geometry fixture.
pub fn fixture_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/geom")
        .join(name)
}

/// Text of a committed geometry fixture.
pub fn fixture_text(name: &str) -> String {
    std::fs::read_to_string(fixture_path(name)).unwrap()
}

/// A committed geometry fixture, loaded and validated.
pub fn fixture(name: &str) -> GeomDb {
    GeomDb::from_ron_str(&fixture_text(name), name).unwrap()
}
