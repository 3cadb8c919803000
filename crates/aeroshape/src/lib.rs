//! The aeroshape pipeline as a library (paper Figure 5): [`Study`] (built once from a case,
//! then evaluated for as many design vectors as an optimiser needs), the case file
//! ([`case`]), the design box checked as a whole ([`boxcheck`]), geometric constraints on
//! the updated model with their derivatives ([`constraints`]) and atomic output ([`fsio`]).
//!
//! Layer: the bottom; depends on every other crate. No command line or plotting
//! dependency: the `aeroshape` program and its pictures are the crate `aeroshape-cli`.

pub mod boxcheck;
pub mod case;
pub mod constraints;
pub mod fsio;
pub mod init;
pub mod precedence;
pub mod reach;
pub mod sensitivity;
pub mod study;

pub use study::{Evaluation, Study};
