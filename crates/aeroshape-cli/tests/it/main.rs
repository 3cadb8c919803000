//! The `aeroshape` program end to end, one module per subcommand family (one integration
//! binary for the crate, to keep link time down).

mod cad_param;
mod case;
mod constraints;
mod deform;
mod fuselage;
mod geom;
mod gradient;
mod mesh;
mod param;
mod pipe;
mod reach;
mod section;
mod surfgrid;
