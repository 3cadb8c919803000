//! Integration tests of the `mesh` crate's public API.

mod adjacency;
mod common;
mod corrupt;
mod foam;
mod kinds;
mod msh;
mod oracle;
mod quality;
mod su2;
mod vtu;
