//! Integration tests of the surfgrid public API.

mod classify;
mod common;
mod curves;
mod generate;
mod linearise;
mod poles;
mod update;
mod wall;
