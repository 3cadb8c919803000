//! SU2 native ASCII grids (2D and 3D): `NDIME`, `NELEM`, `NPOIN`, `NMARK` with
//! `MARKER_TAG` / `MARKER_ELEMS`. Trailing sections that SU2 tools append (periodic
//! information, FFD boxes) are kept verbatim in [`Mesh::su2_extra`](crate::Mesh::su2_extra) and written back.
//!
//! The reader reads the input 33 MiB at a time straight from the reader (no per-line
//! copy) and takes it by blocks of whole lines (4 MiB); the element and point sections are parsed by pieces of a block
//! in parallel while the next block is read, each piece collecting its own elements or
//! points, which are then appended in line order. The writer formats parallel blocks of
//! lines while the previous ones are written. The same grid, errors and bytes as a
//! sequential reader and writer, for any thread count. Element codes are VTK cell types (3 line, 5 triangle, 9 quad, 10 tetra,
//! 12 hexa, 13 prism, 14 pyramid).
//!
//! Files: `lines.rs` (one line: keywords, counts, elements, points), `blocks.rs` (the
//! input by blocks of whole lines, parsed by pieces in parallel), `read.rs` (the sections
//! and the grid), `write.rs` (the parallel writer).

mod blocks;
mod lines;
mod read;
mod write;

pub use read::read;
pub use write::write;

#[cfg(test)]
mod tests;
