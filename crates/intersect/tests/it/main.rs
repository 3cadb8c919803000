//! Integration tests of `intersect`'s public API on analytic shapes with exact answers.

mod accuracy;
mod corner;
mod fixture;
mod linearise;
mod measure;
mod model;
mod project;
mod props;
mod shapes;
mod ssi;
