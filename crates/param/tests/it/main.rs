//! Integration tests of the `param` public API.

mod common;
mod constraints;
mod jacobian;
mod levels;
mod master;
mod props;
mod registry;
