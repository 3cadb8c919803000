//! Integration tests of the `deform` public API.

mod cases;
mod identities;
mod props;
mod reuse;
mod supports;
