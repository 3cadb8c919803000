//! Gmsh MSH 4.1, ASCII and binary: `$MeshFormat`, `$PhysicalNames`, `$Entities`, `$Nodes`
//! (with parametric blocks: curve nodes carry `u`, surface nodes `u v`) and `$Elements`.
//! Other sections are skipped with a warning.
//!
//! Reading: the grid's dimension is the largest element dimension present; elements of that
//! dimension are the cells; elements of dimension `dim - 1` become markers, one per physical
//! group of their entity (name from `$PhysicalNames`, else `physical_<tag>`), or one per
//! entity (`entity_<tag>`) when the entity has no physical group. Point elements and other
//! lower-dimensional elements are dropped with a warning. Every node gets a [`NodeClass`](crate::NodeClass)
//! from its block (entity dimension and tag, parametric coordinates).
//!
//! Writing: the stored entities and classification are written back when present (so a
//! `.msh` → `.msh` conversion keeps entities and parametric coordinates); otherwise one
//! volume (or surface, in 2D) entity holds all nodes and cells, and each marker becomes a
//! boundary entity with its own physical group, plus a physical group `domain` for the cells.
//! Node and element tags are written as 1-based consecutive numbers.
//!
//! The reader is in `read.rs`, the writer in `write.rs`.

mod read;
mod write;

pub use read::read;
pub use write::write;

/// MSH encoding.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Encoding {
    /// Text.
    Ascii,
    /// Little-endian binary (`4.1 1 8`).
    Binary,
}
