//! Unstructured CFD grids: types, readers and writers (SU2, Gmsh MSH 4.1, VTK XML, OpenFOAM
//! polyMesh), node classification, node adjacency and quality measures.
//!
//! Layer: directly under `intersect` in the workspace order; knows nothing of `geom-db`.
//! A node is classified by entity dimension, entity id and parametric coordinates, as Gmsh
//! does ([`NodeClass`]), which is how later layers tie boundary nodes to the geometry.
//!
//! - [`Mesh`]: nodes as a structure of arrays, cells per element kind ([`Elements`]),
//!   boundary [`Marker`]s, optional classification and Gmsh entities.
//! - [`Adjacency`]: node-to-node edges in CSR form, built once in parallel.
//! - [`su2`]: SU2 native ASCII reader and writer.
//! - [`vtu`]: VTK XML unstructured grid writer and reader (ParaView).
//! - [`msh`]: Gmsh MSH 4.1 reader and writer (ASCII and binary, entities, parametric nodes).
//! - [`foam`]: OpenFOAM polyMesh reader, and writer back into the case it came from.
//! - [`io`]: reading and writing by file extension.
//! - [`generate`]: structured tetrahedral boxes for tests and benchmarks.
//! - [`quality`]: validity and quality of every kind (signed mean ratio of tetrahedra and
//!   triangles, scaled Jacobian of the others), minimum angles, summaries, grid comparison.
//!
//! No paper equation is implemented here; the quality measure is the project's (DESIGN.md):
//! mean ratio `q = 12 (3|V|)^(2/3) / Σ l²` over the six edges of a tetrahedron, signed by `V`;
//! for pyramids, prisms, hexahedra and quadrilaterals the smallest scaled corner Jacobian.
//! Node orders are VTK's (and SU2's) for every kind; the MSH reader and writer convert
//! Gmsh's prism ([`ElementKind::gmsh_order`]).

pub mod adjacency;
pub mod error;
pub mod foam;
pub mod generate;
pub mod grid;
pub mod io;
pub mod msh;
pub mod pvtu;
pub mod quality;
pub mod su2;
mod text;
pub mod vtu;

pub use adjacency::Adjacency;
pub use error::{Error, Location, Result};
pub use grid::{
    ALL_KINDS, ElementGroup, ElementKind, Elements, Entity, Marker, Mesh, NodeClass, PhysicalName,
};
