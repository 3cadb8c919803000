//! Writing an SU2 grid: lines formatted in parallel blocks, written in order.

use std::io::Write;

use rayon::prelude::*;

use crate::grid::{Elements, Mesh};
use crate::text::{push_f64, push_u64};

/// Lines per block of the parallel writer (each block formatted by one task into its own
/// buffer; the blocks are written in order, so the output does not depend on the thread
/// count).
pub(super) const WRITE_BLOCK: usize = 8192;

/// Blocks formatted at once before they are written (bounds the buffered text).
pub(super) const WRITE_BATCH: usize = 16;

/// Formats `n` lines by `line(i, out)` in parallel blocks of [`WRITE_BLOCK`] lines and writes
/// them to `w` in order.
pub(super) fn write_lines<W, F>(n: usize, w: &mut W, line: F) -> std::io::Result<()>
where
    W: Write + ?Sized,
    F: Fn(usize, &mut Vec<u8>) + Sync,
{
    let blocks = n.div_ceil(WRITE_BLOCK);
    // Formats blocks `first..` of one batch into `texts` (its buffers reused).
    let format = |first: usize, texts: &mut Vec<Vec<u8>>| {
        let last = (first + WRITE_BATCH).min(blocks);
        texts.resize_with(last - first, Vec::new);
        texts.par_iter_mut().enumerate().for_each(|(k, out)| {
            let lo = (first + k) * WRITE_BLOCK;
            let hi = (lo + WRITE_BLOCK).min(n);
            out.clear();
            out.reserve((hi - lo) * 48);
            for i in lo..hi {
                line(i, out);
            }
        });
    };
    let (mut cur, mut next): (Vec<Vec<u8>>, Vec<Vec<u8>>) = (Vec::new(), Vec::new());
    if blocks == 0 {
        return Ok(());
    }
    format(0, &mut cur);
    let mut first = 0;
    loop {
        first += WRITE_BATCH;
        // Write this batch on this thread while the next one is formatted on the others.
        // (`in_place_scope`: the writer stays on this thread, so it need not be `Send`.)
        let written = if first < blocks {
            rayon::in_place_scope(|s| {
                s.spawn(|_| format(first, &mut next));
                cur.iter().try_for_each(|t| w.write_all(t))
            })
        } else {
            cur.iter().try_for_each(|t| w.write_all(t))
        };
        written?;
        if first >= blocks {
            return Ok(());
        }
        std::mem::swap(&mut cur, &mut next);
    }
}

/// Writes the element lines of `set` (code, nodes, and with `ids` the element's index).
pub(super) fn write_elements<W: Write + ?Sized>(
    set: &Elements,
    ids: bool,
    w: &mut W,
) -> std::io::Result<()> {
    let mut first_id = 0usize;
    for g in set.groups() {
        let nn = g.kind.n_nodes();
        let code = u64::from(g.kind.vtk_code());
        write_lines(g.len(), w, |e, b| {
            push_u64(b, code);
            for &v in &g.nodes[e * nn..(e + 1) * nn] {
                b.push(b'\t');
                push_u64(b, u64::from(v));
            }
            if ids {
                b.push(b'\t');
                push_u64(b, (first_id + e) as u64);
            }
            b.push(b'\n');
        })?;
        first_id += g.len();
    }
    Ok(())
}

/// Writes `mesh` in SU2 native ASCII. Coordinates are written in their shortest
/// round-trip form, so reading back gives the same bits. Element ids follow the canonical
/// kind order of [`Elements`]. [`Mesh::su2_extra`] is appended verbatim.
///
/// The lines are formatted in parallel by blocks and written in order, a batch of blocks
/// being written on the calling thread while the next is formatted (the same bytes for any
/// thread count).
///
/// A 2-D grid whose nodes do not all have z = 0 is refused (SU2 2-D files carry x and y
/// only), rather than silently flattened.
pub fn write<W: Write + ?Sized>(mesh: &Mesh, w: &mut W) -> std::io::Result<()> {
    if mesh.dim == 2
        && let Some(i) = mesh.coords.iter().position(|p| p[2] != 0.0)
    {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!(
                "2-D grid: node {i} has z = {} (SU2 2-D files carry x and y only)",
                mesh.coords[i][2]
            ),
        ));
    }
    let mut b: Vec<u8> = Vec::with_capacity(256);
    writeln!(b, "NDIME= {}", mesh.dim)?;
    writeln!(b, "NELEM= {}", mesh.cells.len())?;
    w.write_all(&b)?;
    write_elements(&mesh.cells, true, w)?;
    writeln!(w, "NPOIN= {}", mesh.coords.len())?;
    let dim = mesh.dim as usize;
    write_lines(mesh.coords.len(), w, |i, b| {
        for x in &mesh.coords[i][..dim] {
            push_f64(b, *x);
            b.push(b'\t');
        }
        push_u64(b, i as u64);
        b.push(b'\n');
    })?;
    writeln!(w, "NMARK= {}", mesh.markers.len())?;
    for m in &mesh.markers {
        writeln!(w, "MARKER_TAG= {}", m.name)?;
        writeln!(w, "MARKER_ELEMS= {}", m.elements.len())?;
        write_elements(&m.elements, false, w)?;
    }
    w.write_all(mesh.su2_extra.as_bytes())
}
