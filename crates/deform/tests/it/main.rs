//! Integration tests of the `deform` public API.

mod cases;
mod identities;
mod kinds;
mod linearise;
mod linearise_grids;
mod props;
mod reach;
mod reuse;
mod supports;
