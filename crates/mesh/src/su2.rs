//! SU2 native ASCII grids (2D and 3D): `NDIME`, `NELEM`, `NPOIN`, `NMARK` with
//! `MARKER_TAG` / `MARKER_ELEMS`. Trailing sections that SU2 tools append (periodic
//! information, FFD boxes) are kept verbatim in [`Mesh::su2_extra`] and written back.
//!
//! The reader streams the input line by line. The element and point sections are read in
//! batches of lines (each batch parsed in parallel while the next one is read) and written in
//! parallel blocks: the same grid, errors and bytes as a sequential reader and writer, for
//! any thread count. Element codes are VTK cell types (3 line, 5 triangle, 9 quad, 10 tetra,
//! 12 hexa, 13 prism, 14 pyramid).

use std::io::{BufRead, Write};
use std::path::Path;

use rayon::prelude::*;

use crate::error::{Error, Location, Result};
use crate::grid::{ElementKind, Elements, Marker, Mesh};
use crate::text::{
    LineReader, Tokens, parse_f64, parse_i64, parse_u64, push_f64, push_u64, reserve_capped, syntax,
};

/// Splits `KEY= value` (value trimmed); `None` when the line has no `=`.
fn keyword(line: &[u8]) -> Option<(&[u8], &[u8])> {
    let eq = line.iter().position(|&c| c == b'=')?;
    Some((line[..eq].trim_ascii(), line[eq + 1..].trim_ascii()))
}

fn is_skippable(line: &[u8]) -> bool {
    let t = line.trim_ascii();
    t.is_empty() || t[0] == b'%'
}

/// Largest node index seen in a section, and the line where it was seen.
#[derive(Default, Clone, Copy)]
struct MaxRef {
    node: u64,
    line: usize,
}

impl MaxRef {
    #[inline]
    fn see(&mut self, node: u64, line: usize) {
        if node >= self.node {
            self.node = node;
            self.line = line;
        }
    }
}

/// Reading context: the file name for errors.
struct Ctx<'a> {
    file: &'a str,
}

impl Ctx<'_> {
    fn err(&self, line: usize, msg: impl Into<String>) -> Error {
        syntax(self.file, line, msg)
    }
}

/// Scans a line of unsigned integers separated by spaces or tabs into `out`; `None` if the
/// line holds anything else, more than `out.len()` numbers or a number above `u32::MAX`
/// (the caller then re-reads it with full error reporting).
#[inline]
fn scan_uints(line: &[u8], out: &mut [u64; 10]) -> Option<usize> {
    let mut n = 0;
    let mut acc: u64 = 0;
    let mut digits = 0u32;
    for &c in line {
        let d = c.wrapping_sub(b'0');
        if d <= 9 {
            acc = acc * 10 + u64::from(d);
            digits += 1;
            if digits > 10 {
                return None;
            }
        } else if c == b' ' || c == b'\t' || c == b'\r' {
            if digits > 0 {
                *out.get_mut(n)? = acc;
                n += 1;
                acc = 0;
                digits = 0;
            }
        } else {
            return None;
        }
    }
    if digits > 0 {
        *out.get_mut(n)? = acc;
        n += 1;
    }
    Some(n)
}

/// Parses one element line: the code, `n_nodes` node indices, optionally the element index
/// (ignored). Returns the kind and the nodes (first `n_nodes` entries used).
fn parse_element(
    cx: &Ctx<'_>,
    ln: usize,
    line: &[u8],
    want_dim: u8,
) -> Result<(ElementKind, [u32; 8])> {
    let mut nodes = [0u32; 8];
    // Fast path for well-formed lines; anything unusual falls through to the checked parse.
    let mut v = [0u64; 10];
    if let Some(k) = scan_uints(line, &mut v)
        && k >= 1
        && let Some(kind) = ElementKind::from_vtk_code(v[0] as i64)
        && kind.dim() == want_dim
        && (k == kind.n_nodes() + 1 || k == kind.n_nodes() + 2)
        && v[1..=kind.n_nodes()]
            .iter()
            .all(|&x| x < u64::from(u32::MAX))
    {
        for (o, &x) in nodes.iter_mut().zip(&v[1..=kind.n_nodes()]) {
            *o = x as u32;
        }
        return Ok((kind, nodes));
    }
    let mut tok = Tokens::new(line);
    let code_tok = tok.next().ok_or_else(|| cx.err(ln, "empty element line"))?;
    let code = parse_i64(code_tok).ok_or_else(|| {
        cx.err(
            ln,
            format!("element type '{}' is not an integer", lossy(code_tok)),
        )
    })?;
    let kind = ElementKind::from_vtk_code(code).ok_or_else(|| Error::UnknownElementType {
        file: cx.file.to_string(),
        at: Location::Line(ln),
        code,
    })?;
    if kind.dim() != want_dim {
        return Err(cx.err(
            ln,
            format!(
                "{} element where {want_dim}-D elements are expected",
                kind.name()
            ),
        ));
    }
    for k in 0..kind.n_nodes() {
        let t = tok.next().ok_or_else(|| {
            cx.err(
                ln,
                format!("{} needs {} nodes, found {k}", kind.name(), kind.n_nodes()),
            )
        })?;
        let v = parse_u64(t).ok_or_else(|| {
            cx.err(
                ln,
                format!("node index '{}' is not a non-negative integer", lossy(t)),
            )
        })?;
        if v >= u64::from(u32::MAX) {
            return Err(Error::NodeOutOfRange {
                file: cx.file.to_string(),
                at: Location::Line(ln),
                node: v,
                n_nodes: u32::MAX as usize,
            });
        }
        nodes[k] = v as u32;
    }
    if let Some(t) = tok.next()
        && (parse_u64(t).is_none() || tok.next().is_some())
    {
        return Err(cx.err(
            ln,
            format!(
                "unexpected token '{}' after the {} nodes of a {}",
                lossy(t),
                kind.n_nodes(),
                kind.name()
            ),
        ));
    }
    Ok((kind, nodes))
}

fn lossy(t: &[u8]) -> String {
    String::from_utf8_lossy(&t[..t.len().min(60)]).into_owned()
}

/// Parses a count value such as `59156` or (for `NPOIN`) `11703 11703`.
fn count(cx: &Ctx<'_>, ln: usize, key: &str, val: &[u8]) -> Result<usize> {
    let t = Tokens::new(val).next().unwrap_or(b"");
    parse_u64(t)
        .and_then(|v| usize::try_from(v).ok())
        .filter(|&v| v < u32::MAX as usize)
        .ok_or_else(|| {
            cx.err(
                ln,
                format!("{key}= expects a count, found '{}'", lossy(val)),
            )
        })
}

/// Lines per batch of the element reader.
const BATCH: usize = 1 << 14;

/// One batch of lines of a section: their text, and per line (line number, start, end).
#[derive(Default)]
struct Batch {
    text: Vec<u8>,
    spans: Vec<(usize, usize, usize)>,
    /// Index (within the section) of the batch's first item.
    first: usize,
    /// The read error that ended the batch early, if any.
    err: Option<Error>,
}

impl Batch {
    /// Reads the next lines of the section (items `first..`, at most [`BATCH`], fewer at the
    /// section's end `n` or at a read error), skipping comments and blank lines.
    fn fill<R: BufRead>(
        &mut self,
        rd: &mut LineReader<R>,
        file: &str,
        what: &str,
        first: usize,
        n: usize,
    ) {
        self.text.clear();
        self.spans.clear();
        self.first = first;
        self.err = None;
        while self.spans.len() < BATCH && first + self.spans.len() < n {
            match rd.expect_line(file, what) {
                Ok((ln, line)) => {
                    if is_skippable(line) {
                        continue;
                    }
                    let a = self.text.len();
                    self.text.extend_from_slice(line);
                    self.spans.push((ln, a, self.text.len()));
                }
                Err(e) => {
                    self.err = Some(e);
                    break;
                }
            }
        }
    }
}

/// Reads the `n` item lines of a section: lines are read sequentially by batches, each batch
/// parsed in parallel (`parse(line number, text, item index)`) while the next batch is read
/// (rayon::join), and the results applied in line order (`apply(item, line number)`), so the
/// result and the first error reported are those of a sequential read.
fn read_section<R, T, P, A>(
    cx: &Ctx<'_>,
    rd: &mut LineReader<R>,
    n: usize,
    what: &str,
    parse: P,
    mut apply: A,
) -> Result<()>
where
    R: BufRead + Send,
    T: Send,
    P: Fn(usize, &[u8], usize) -> Result<T> + Sync,
    A: FnMut(T, usize),
{
    let (mut cur, mut next) = (Batch::default(), Batch::default());
    let mut parsed: Vec<Result<T>> = Vec::new();
    cur.fill(rd, cx.file, what, 0, n);
    loop {
        let read = cur.first + cur.spans.len();
        let more = cur.err.is_none() && read < n;
        let parse_cur = |out: &mut Vec<Result<T>>| {
            cur.spans
                .par_iter()
                .enumerate()
                .map(|(k, &(ln, a, b))| parse(ln, &cur.text[a..b], cur.first + k))
                .collect_into_vec(out);
        };
        if more {
            rayon::join(
                || next.fill(rd, cx.file, what, read, n),
                || parse_cur(&mut parsed),
            );
        } else {
            parse_cur(&mut parsed);
        }
        for (r, &(ln, _, _)) in parsed.drain(..).zip(&cur.spans) {
            apply(r?, ln);
        }
        if let Some(e) = cur.err.take() {
            return Err(e);
        }
        if !more {
            return Ok(());
        }
        std::mem::swap(&mut cur, &mut next);
    }
}

/// Reads `n` element lines into `set` ([`read_section`]).
fn read_elements<R: BufRead + Send>(
    cx: &Ctx<'_>,
    rd: &mut LineReader<R>,
    n: usize,
    dim: u8,
    set: &mut Elements,
    max: &mut MaxRef,
    section: &str,
) -> Result<()> {
    let mut done = 0;
    read_section(
        cx,
        rd,
        n,
        section,
        |ln, line, _| parse_element(cx, ln, line, dim),
        |(kind, nodes), ln| {
            let g = set.group_mut(kind);
            if g.nodes.capacity() == 0 {
                reserve_capped(&mut g.nodes, (n - done).saturating_mul(kind.n_nodes()));
            }
            for &x in &nodes[..kind.n_nodes()] {
                max.see(u64::from(x), ln);
            }
            g.nodes.extend_from_slice(&nodes[..kind.n_nodes()]);
            done += 1;
        },
    )
}

/// Parses one point line of node `node`: `dim` finite coordinates, optionally the node's
/// index.
fn parse_point(cx: &Ctx<'_>, ln: usize, line: &[u8], dim: u8, node: usize) -> Result<[f64; 3]> {
    let mut tok = Tokens::new(line);
    let mut p = [0.0; 3];
    for (k, pk) in p.iter_mut().enumerate().take(dim as usize) {
        let t = tok.next();
        match t.and_then(parse_f64) {
            Some(x) if x.is_finite() => *pk = x,
            _ => {
                let found = t.map_or("nothing".to_string(), |t| format!("'{}'", lossy(t)));
                return Err(cx.err(
                    ln,
                    format!("node {node}: coordinate {k} must be a finite number, found {found}"),
                ));
            }
        }
    }
    if let Some(t) = tok.next()
        && (parse_u64(t).is_none() || tok.next().is_some())
    {
        return Err(cx.err(
            ln,
            format!(
                "node {node}: unexpected token '{}' after {dim} coordinates",
                lossy(t)
            ),
        ));
    }
    Ok(p)
}

/// Reads `n` point lines into `coords` ([`read_section`]).
fn read_points<R: BufRead + Send>(
    cx: &Ctx<'_>,
    rd: &mut LineReader<R>,
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
        |ln, line, node| parse_point(cx, ln, line, dim, node),
        |p, _| coords.push(p),
    )
}

/// Reads an SU2 grid from `r`; `file` names the input in errors (`Send`: the next batch of
/// lines is read on one thread while the last one is parsed on the others).
///
/// ```
/// let txt = "NDIME= 2\nNELEM= 1\n5 0 1 2 0\nNPOIN= 3\n0 0 0\n1 0 1\n0 1 2\n\
///            NMARK= 1\nMARKER_TAG= wall\nMARKER_ELEMS= 1\n3 0 1\n";
/// let m = mesh::su2::read(txt.as_bytes(), "t.su2".as_ref()).unwrap();
/// assert_eq!((m.dim, m.n_nodes(), m.triangles().len()), (2, 3, 1));
/// assert_eq!(m.markers[0].name, "wall");
/// ```
pub fn read<R: BufRead + Send>(r: R, file: &Path) -> Result<Mesh> {
    let file = file.display().to_string();
    let cx = Ctx { file: &file };
    let mut rd = LineReader::new(r);
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

/// Lines per block of the parallel writer (each block formatted by one task into its own
/// buffer; the blocks are written in order, so the output does not depend on the thread
/// count).
const WRITE_BLOCK: usize = 8192;

/// Blocks formatted at once before they are written (bounds the buffered text).
const WRITE_BATCH: usize = 16;

/// Formats `n` lines by `line(i, out)` in parallel blocks of [`WRITE_BLOCK`] lines and writes
/// them to `w` in order.
fn write_lines<W, F>(n: usize, w: &mut W, line: F) -> std::io::Result<()>
where
    W: Write + ?Sized,
    F: Fn(usize, &mut Vec<u8>) + Sync,
{
    let blocks = n.div_ceil(WRITE_BLOCK);
    let mut texts: Vec<Vec<u8>> = Vec::new();
    for first in (0..blocks).step_by(WRITE_BATCH) {
        let last = (first + WRITE_BATCH).min(blocks);
        (first..last)
            .into_par_iter()
            .map(|b| {
                let lo = b * WRITE_BLOCK;
                let hi = (lo + WRITE_BLOCK).min(n);
                let mut out = Vec::with_capacity((hi - lo) * 48);
                for i in lo..hi {
                    line(i, &mut out);
                }
                out
            })
            .collect_into_vec(&mut texts);
        for t in &texts {
            w.write_all(t)?;
        }
    }
    Ok(())
}

/// Writes the element lines of `set` (code, nodes, and with `ids` the element's index).
fn write_elements<W: Write + ?Sized>(set: &Elements, ids: bool, w: &mut W) -> std::io::Result<()> {
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
/// The lines are formatted in parallel by blocks and written in order (the same bytes for
/// any thread count).
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_integer_scan_accepts_only_plain_lines() {
        let mut v = [0u64; 10];
        assert_eq!(scan_uints(b"10\t1 2  3 4\t5\r", &mut v), Some(6));
        assert_eq!(&v[..6], &[10, 1, 2, 3, 4, 5]);
        assert_eq!(scan_uints(b"", &mut v), Some(0));
        assert_eq!(scan_uints(b"5 -1 2", &mut v), None);
        assert_eq!(scan_uints(b"5 1.0 2", &mut v), None);
        assert_eq!(scan_uints(b"5 12345678901 2", &mut v), None);
        assert_eq!(scan_uints(b"1 2 3 4 5 6 7 8 9 10 11", &mut v), None);
    }

    #[test]
    fn parallel_write_and_read_span_several_blocks_and_batches() {
        // 162 000 tetrahedra (more than WRITE_BLOCK × WRITE_BATCH lines), 29 791 points
        // (more than one read batch), irrational coordinates.
        let mut m = crate::generate::box_tets(30, 30, 30, [0.0; 3], [1.0, 0.7, 1.3]);
        for (i, p) in m.coords.iter_mut().enumerate() {
            p[0] += 1e-3 * (i as f64).sin();
        }
        assert!(m.cells.len() > WRITE_BLOCK * WRITE_BATCH && m.n_nodes() > BATCH);
        let text = |threads: usize| {
            testkit::with_threads(threads, || {
                let mut out = Vec::new();
                write(&m, &mut out).unwrap();
                out
            })
        };
        let one = text(1);
        assert_eq!(one, text(3));
        // The same bytes as a line-by-line formatting of the element and point sections.
        let mut seq = Vec::new();
        for (id, (kind, nodes)) in m.cells.iter().enumerate() {
            let ns: Vec<String> = nodes.iter().map(|v| v.to_string()).collect();
            seq.extend_from_slice(
                format!("{}\t{}\t{id}\n", kind.vtk_code(), ns.join("\t")).as_bytes(),
            );
        }
        seq.extend_from_slice(format!("NPOIN= {}\n", m.n_nodes()).as_bytes());
        for (i, p) in m.coords.iter().enumerate() {
            seq.extend_from_slice(format!("{:?}\t{:?}\t{:?}\t{i}\n", p[0], p[1], p[2]).as_bytes());
        }
        let head = format!("NDIME= 3\nNELEM= {}\n", m.cells.len());
        assert_eq!(&one[head.len()..head.len() + seq.len()], &seq[..]);
        let back = read(&one[..], "t.su2".as_ref()).unwrap();
        assert_eq!(back.coords, m.coords);
        assert_eq!(back.cells, m.cells);
        // An error in a later read batch names the node and line of a sequential read.
        let mut bad = String::from_utf8(one).unwrap();
        let target = format!("\t{}\n", 20_000);
        let points = bad.find("NPOIN=").unwrap();
        let at = points + bad[points..].find(&target).unwrap();
        let line_start = bad[..at].rfind('\n').unwrap() + 1;
        bad.replace_range(line_start..line_start + 1, "x");
        let line_no = bad[..line_start].matches('\n').count() + 1;
        let e = read(bad.as_bytes(), "t.su2".as_ref())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(&format!("line {line_no}")) && e.contains("node 20000"),
            "{e}"
        );
    }
}
