//! The aeroshape pipeline as a library (paper Figure 5) and the support code of the
//! `aeroshape` command-line program.
//!
//! Layer: the bottom; depends on every other crate.

pub mod case;
pub mod fsio;
pub mod plot;
pub mod study;

pub use study::{Evaluation, Study};
