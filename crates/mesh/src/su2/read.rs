//! Reading an SU2 grid: the element and point sections, markers and the grid.

use std::io::BufRead;
use std::path::Path;

use crate::error::{Error, Location, Result};
use crate::grid::{ElementKind, Elements, Marker, Mesh};
use crate::text::reserve_capped;

use super::blocks::{Input, READ_BYTES, read_section};
use super::lines::{
    Ctx, MaxRef, count, fast_element, is_skippable, keyword, lossy, parse_element, parse_point,
};

/// The elements of one piece of a section and its largest node (node, local item index).
pub(super) struct ElementPiece {
    /// The nodes of the elements in line order.
    pub(super) nodes: Vec<u32>,
    /// Runs of elements of one kind: (kind, number of elements).
    pub(super) runs: Vec<(ElementKind, usize)>,
    pub(super) max: Option<(u32, usize)>,
}

/// Reads `n` element lines into `set` ([`read_section`]).
pub(super) fn read_elements<R: std::io::Read + Send>(
    cx: &Ctx<'_>,
    rd: &mut Input<R>,
    n: usize,
    dim: u8,
    set: &mut Elements,
    max: &mut MaxRef,
    section: &str,
) -> Result<()> {
    read_section(
        cx,
        rd,
        n,
        section,
        (
            |s: &[u8]| fast_element(s, dim),
            |ln, line, _| parse_element(cx, ln, line, dim),
        ),
        // About 8 bytes per number on a line.
        |bytes| ElementPiece {
            nodes: Vec::with_capacity(bytes / 8),
            runs: Vec::with_capacity(4),
            max: None,
        },
        |piece, (kind, nodes), k| {
            let nn = kind.n_nodes();
            match piece.runs.last_mut() {
                Some((last, count)) if *last == kind => *count += 1,
                _ => piece.runs.push((kind, 1)),
            }
            extend_nodes(&mut piece.nodes, &nodes, nn);
            let top = nodes[..nn].iter().copied().max().unwrap_or(0);
            if piece.max.is_none_or(|(m, _)| top >= m) {
                piece.max = Some((top, k));
            }
        },
        |piece, mut done, line_of| {
            let mut at = 0;
            for &(kind, count) in &piece.runs {
                let g = set.group_mut(kind);
                if g.nodes.capacity() == 0 {
                    reserve_capped(&mut g.nodes, (n - done).saturating_mul(kind.n_nodes()));
                }
                let len = count * kind.n_nodes();
                g.nodes.extend_from_slice(&piece.nodes[at..at + len]);
                at += len;
                done += count;
            }
            if let Some((node, k)) = piece.max {
                max.see(u64::from(node), line_of(k));
            }
        },
    )
}

/// Appends the first `nn` of `nodes` (copies of a size known at compile time for the
/// element kinds).
#[inline]
pub(super) fn extend_nodes(v: &mut Vec<u32>, nodes: &[u32; 8], nn: usize) {
    match nn {
        2 => v.extend_from_slice(&nodes[..2]),
        3 => v.extend_from_slice(&nodes[..3]),
        4 => v.extend_from_slice(&nodes[..4]),
        5 => v.extend_from_slice(&nodes[..5]),
        6 => v.extend_from_slice(&nodes[..6]),
        8 => v.extend_from_slice(nodes),
        _ => v.extend_from_slice(&nodes[..nn]),
    }
}

/// Reads `n` point lines into `coords` ([`read_section`]).
pub(super) fn read_points<R: std::io::Read + Send>(
    cx: &Ctx<'_>,
    rd: &mut Input<R>,
    n: usize,
    dim: u8,
    coords: &mut Vec<[f64; 3]>,
) -> Result<()> {
    reserve_capped(coords, n);
    read_section(
        cx,
        rd,
        n,
        "NPOIN",
        (
            |_: &[u8]| None,
            |ln, line, node| parse_point(cx, ln, line, dim, node),
        ),
        // About 32 bytes per line at least (3 coordinates in full precision take ~60).
        |bytes| Vec::with_capacity(bytes / 32),
        |piece: &mut Vec<[f64; 3]>, p, _| piece.push(p),
        |piece, _, _| coords.extend_from_slice(&piece),
    )
}

/// Reads an SU2 grid from `r`; `file` names the input in errors (`Send`: the next block of
/// lines is read on one thread while the last one is parsed on the others). The input is
/// read in slices of 33 MiB (a `BufReader` passes such reads straight through).
///
/// ```
/// let txt = "NDIME= 2\nNELEM= 1\n5 0 1 2 0\nNPOIN= 3\n0 0 0\n1 0 1\n0 1 2\n\
///            NMARK= 1\nMARKER_TAG= wall\nMARKER_ELEMS= 1\n3 0 1\n";
/// let m = mesh::su2::read(txt.as_bytes(), "t.su2".as_ref()).unwrap();
/// assert_eq!((m.dim, m.n_nodes(), m.triangles().len()), (2, 3, 1));
/// assert_eq!(m.markers[0].name, "wall");
/// ```
pub fn read<R: BufRead + Send>(r: R, file: &Path) -> Result<Mesh> {
    read_by_blocks(r, file, READ_BYTES)
}

/// [`read`] reading the input by `block` bytes at once (sections taken by an eighth of it).
pub(super) fn read_by_blocks<R: std::io::Read + Send>(
    r: R,
    file: &Path,
    block: usize,
) -> Result<Mesh> {
    let file = file.display().to_string();
    let cx = Ctx { file: &file };
    let mut rd = Input::new(r, block);
    let mut mesh = Mesh::new(0);
    let mut dim: Option<u8> = None;
    let (mut seen_elem, mut seen_poin, mut seen_mark) = (false, false, false);
    let mut max = MaxRef::default();
    let mut max_marker = MaxRef::default();
    while let Some((ln, line)) = rd.next_line(cx.file)? {
        if is_skippable(line) {
            continue;
        }
        let Some((key, val)) = keyword(line) else {
            return Err(cx.err(
                ln,
                format!("expected a 'KEYWORD= value' line, found '{}'", lossy(line)),
            ));
        };
        let key = String::from_utf8_lossy(key).into_owned();
        let val = val.to_vec();
        match key.as_str() {
            "NDIME" => {
                let d = count(&cx, ln, "NDIME", &val)?;
                if d != 2 && d != 3 {
                    return Err(cx.err(ln, format!("NDIME= {d}: only 2 and 3 are supported")));
                }
                dim = Some(d as u8);
                mesh.dim = d as u8;
            }
            "NZONE" | "IZONE" => {
                let n = count(&cx, ln, &key, &val)?;
                if n != 1 {
                    return Err(cx.err(
                        ln,
                        format!("{key}= {n}: multi-zone grids are not supported"),
                    ));
                }
            }
            "NELEM" => {
                let d = dim.ok_or_else(|| cx.err(ln, "NELEM= before NDIME="))?;
                let n = count(&cx, ln, "NELEM", &val)?;
                read_elements(&cx, &mut rd, n, d, &mut mesh.cells, &mut max, "NELEM")?;
                seen_elem = true;
            }
            "NPOIN" => {
                let d = dim.ok_or_else(|| cx.err(ln, "NPOIN= before NDIME="))?;
                let n = count(&cx, ln, "NPOIN", &val)?;
                read_points(&cx, &mut rd, n, d, &mut mesh.coords)?;
                if d == 2 {
                    // SU2's 2-D grids may carry a z column: SU2 ignores it, and so do we.
                    let off = mesh.coords.iter().filter(|p| p[2] != 0.0).count();
                    if off > 0 {
                        mesh.warnings.push(format!(
                            "{file}: line {ln}: {off} nodes of this 2-D grid (NDIME= 2) have a nonzero z, set to 0 (as SU2 reads them)"
                        ));
                    }
                    for p in &mut mesh.coords {
                        p[2] = 0.0;
                    }
                }
                seen_poin = true;
            }
            "NMARK" => {
                let d = dim.ok_or_else(|| cx.err(ln, "NMARK= before NDIME="))?;
                let n = count(&cx, ln, "NMARK", &val)?;
                seen_mark = true;
                for i in 0..n {
                    let name = loop {
                        let (ln, l) = rd.expect_line(cx.file, "NMARK")?;
                        if is_skippable(l) {
                            continue;
                        }
                        match keyword(l) {
                            Some((k, v)) if k == b"MARKER_TAG" && !v.is_empty() => {
                                break String::from_utf8_lossy(v).into_owned();
                            }
                            _ => {
                                return Err(cx.err(
                                    ln,
                                    format!(
                                        "expected MARKER_TAG= for marker {i} of {n}, found '{}'",
                                        lossy(l)
                                    ),
                                ));
                            }
                        }
                    };
                    let what = format!("marker {name}");
                    let k = loop {
                        let (ln, l) = rd.expect_line(cx.file, &what)?;
                        if is_skippable(l) {
                            continue;
                        }
                        match keyword(l) {
                            Some((k, v)) if k == b"MARKER_ELEMS" => {
                                break count(&cx, ln, "MARKER_ELEMS", v)?;
                            }
                            _ => {
                                return Err(
                                    cx.err(ln, format!("expected MARKER_ELEMS= for marker {name}"))
                                );
                            }
                        }
                    };
                    let mut elements = Elements::new();
                    read_elements(
                        &cx,
                        &mut rd,
                        k,
                        d - 1,
                        &mut elements,
                        &mut max_marker,
                        &what,
                    )?;
                    mesh.markers.push(Marker {
                        name,
                        tag: None,
                        elements,
                    });
                }
            }
            _ => {
                if !(seen_elem && seen_poin) {
                    return Err(cx.err(
                        ln,
                        format!("unknown keyword {key}= before the grid is complete"),
                    ));
                }
                let mut extra = Vec::new();
                extra.extend_from_slice(line);
                extra.push(b'\n');
                let mut n_lines = 1;
                while let Some((_, l)) = rd.next_line(cx.file)? {
                    extra.extend_from_slice(l);
                    extra.push(b'\n');
                    n_lines += 1;
                }
                mesh.su2_extra = String::from_utf8_lossy(&extra).into_owned();
                mesh.warnings.push(format!(
                    "{file}: line {ln}: {n_lines} trailing lines from {key}= on kept verbatim, not interpreted"
                ));
                break;
            }
        }
    }
    let end = Location::Line(rd.line + 1);
    let missing = if dim.is_none() {
        Some("the header (no NDIME=)")
    } else if !seen_elem {
        Some("the grid (no NELEM=)")
    } else if !seen_poin {
        Some("the grid (no NPOIN=)")
    } else if !seen_mark {
        Some("the grid (no NMARK=)")
    } else {
        None
    };
    if let Some(what) = missing {
        return Err(Error::Truncated {
            file: file.clone(),
            at: end,
            what: what.into(),
        });
    }
    let n = mesh.coords.len();
    for m in [max, max_marker] {
        if m.line > 0 && m.node as usize >= n {
            return Err(Error::NodeOutOfRange {
                file: file.clone(),
                at: Location::Line(m.line),
                node: m.node,
                n_nodes: n,
            });
        }
    }
    for g in mesh.cells.groups_mut() {
        g.nodes.shrink_to_fit();
    }
    Ok(mesh)
}
