//! SU2 native ASCII grids (2D and 3D): `NDIME`, `NELEM`, `NPOIN`, `NMARK` with
//! `MARKER_TAG` / `MARKER_ELEMS`. Trailing sections that SU2 tools append (periodic
//! information, FFD boxes) are kept verbatim in [`Mesh::su2_extra`] and written back.
//!
//! The reader takes the input in large blocks of whole lines (4 MiB read straight from the
//! reader, no per-line copy); the element and point sections are parsed by pieces of a block
//! in parallel while the next block is read, each piece collecting its own elements or
//! points, which are then appended in line order. The writer formats parallel blocks of
//! lines while the previous ones are written. The same grid, errors and bytes as a
//! sequential reader and writer, for any thread count. Element codes are VTK cell types (3 line, 5 triangle, 9 quad, 10 tetra,
//! 12 hexa, 13 prism, 14 pyramid).

use std::io::{BufRead, Write};
use std::path::Path;

use rayon::prelude::*;

use crate::error::{Error, Location, Result};
use crate::grid::{ElementKind, Elements, Marker, Mesh};
use crate::text::{
    Tokens, parse_f64, parse_i64, parse_u64, push_f64, push_u64, reserve_capped, syntax,
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

/// Bytes per block of the section reader (a block holds whole lines).
const BLOCK_BYTES: usize = 1 << 22;

/// Bytes per piece of a block (each piece parsed by one task; a piece holds whole lines).
const PIECE_BYTES: usize = 1 << 16;

/// Buffered input that hands out single lines (headers, marker tags) and blocks of whole
/// lines (sections), reading from the inner reader in large slices. Lines end at `\n`; the
/// `\r`s before it are dropped; a last line without `\n` counts.
struct Input<R> {
    inner: R,
    /// Bytes read and not yet handed out: `buf[pos..end]`.
    buf: Vec<u8>,
    pos: usize,
    end: usize,
    eof: bool,
    /// Lines handed out so far (the number of the last one).
    line: usize,
    /// Bytes read from `inner` per call when the buffer is empty ([`BLOCK_BYTES`]; smaller
    /// in tests so that small inputs span many blocks).
    block: usize,
}

/// Whole lines taken out of an [`Input`]: `text[range]`, ending with a line end unless the
/// input ended without one.
struct Block {
    text: Vec<u8>,
    range: std::ops::Range<usize>,
}

impl<R: std::io::Read> Input<R> {
    fn new(inner: R, block: usize) -> Self {
        Input {
            inner,
            buf: Vec::new(),
            pos: 0,
            end: 0,
            eof: false,
            line: 0,
            block,
        }
    }

    /// Reads more bytes (at least one unless at the end): moves the unread bytes to the
    /// front, makes room for `block` more and reads into it.
    fn read_more(&mut self, file: &str) -> Result<()> {
        if self.pos > 0 {
            self.buf.copy_within(self.pos..self.end, 0);
            self.end -= self.pos;
            self.pos = 0;
        }
        if self.buf.len() < self.end + self.block {
            self.buf.resize(self.end + self.block, 0);
        }
        loop {
            match self.inner.read(&mut self.buf[self.end..]) {
                Ok(0) => {
                    self.eof = true;
                    return Ok(());
                }
                Ok(k) => {
                    self.end += k;
                    return Ok(());
                }
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(error) => {
                    return Err(Error::Io {
                        file: file.to_string(),
                        error,
                    });
                }
            }
        }
    }

    /// The next line (number, text without the line end), or `None` at the end.
    fn next_line(&mut self, file: &str) -> Result<Option<(usize, &[u8])>> {
        let mut scanned = 0;
        let (a, b) = loop {
            if let Some(k) = self.buf[self.pos + scanned..self.end]
                .iter()
                .position(|&c| c == b'\n')
            {
                let nl = self.pos + scanned + k;
                let a = self.pos;
                self.pos = nl + 1;
                break (a, nl);
            }
            if self.eof {
                if self.pos == self.end {
                    return Ok(None);
                }
                let a = self.pos;
                self.pos = self.end;
                break (a, self.end);
            }
            scanned = self.end - self.pos;
            self.read_more(file)?;
        };
        self.line += 1;
        Ok(Some((self.line, trim_line_end(&self.buf[a..b]))))
    }

    /// The next line, or a [`Error::Truncated`] naming `what`.
    fn expect_line(&mut self, file: &str, what: &str) -> Result<(usize, &[u8])> {
        let at = Location::Line(self.line + 1);
        self.next_line(file)?.ok_or_else(|| Error::Truncated {
            file: file.to_string(),
            at,
            what: what.to_string(),
        })
    }

    /// Takes the next block of whole lines (at least `block` bytes unless the input ends
    /// first; empty at the end), leaving `spare` as the buffer. Lines are not counted here:
    /// the caller adds the lines it uses to [`Input::line`] and gives back the rest with
    /// [`Input::unread`].
    fn take_block(&mut self, file: &str, spare: Vec<u8>) -> Result<Block> {
        let mut searched = self.pos;
        let cut = loop {
            if self.end - self.pos >= self.block || self.eof {
                if let Some(k) = self.buf[searched..self.end]
                    .iter()
                    .rposition(|&c| c == b'\n')
                {
                    break searched + k + 1;
                }
                if self.eof {
                    break self.end;
                }
                // A line longer than a block: read on until its end.
                searched = self.end;
            }
            let before = self.pos;
            self.read_more(file)?;
            searched -= before;
        };
        let text = std::mem::replace(&mut self.buf, spare);
        let tail = self.end - cut;
        if self.buf.len() < tail {
            self.buf.resize(tail, 0);
        }
        self.buf[..tail].copy_from_slice(&text[cut..self.end]);
        let range = self.pos..cut;
        self.end = tail;
        self.pos = 0;
        Ok(Block { text, range })
    }

    /// Puts `bytes` back in front of the unread input.
    fn unread(&mut self, bytes: &[u8]) {
        if bytes.is_empty() {
            return;
        }
        let mut b = Vec::with_capacity(bytes.len() + self.end - self.pos + self.block);
        b.extend_from_slice(bytes);
        b.extend_from_slice(&self.buf[self.pos..self.end]);
        self.end = b.len();
        self.pos = 0;
        self.buf = b;
    }
}

/// A line without its `\n` and the `\r`s before it.
#[inline]
fn trim_line_end(mut l: &[u8]) -> &[u8] {
    while let [rest @ .., b'\n' | b'\r'] = l {
        l = rest;
    }
    l
}

/// What one task made of one piece of a block.
struct Piece<C> {
    /// The items parsed, in line order, up to the first error or the item limit.
    items: C,
    /// Number of items in `items`.
    n_items: usize,
    /// Local indices (0-based, within the piece) of the comment and blank lines skipped.
    skipped: Vec<usize>,
    /// Lines in the piece (all of them when it was parsed to its end).
    lines: usize,
    /// The first line that failed: its local index and its text (`text[a..b]` of the block).
    failed: Option<(usize, usize, usize)>,
}

/// Local line index of the `k`-th item of a piece whose skipped lines are `skipped`.
fn item_line(skipped: &[usize], k: usize) -> usize {
    let mut l = k;
    for &s in skipped {
        if s > l {
            break;
        }
        l += 1;
    }
    l
}

/// Parses the lines of `text[a..b]` (whole lines) by `parse` (with dummy line and item
/// numbers) and `push`es the items into a new collection (`new(bytes)`), up to `limit`
/// items or the first error.
fn parse_piece<T, C, P, N, U>(
    text: &[u8],
    (a, b): (usize, usize),
    limit: usize,
    parse: &P,
    new: &N,
    push: &U,
) -> Piece<C>
where
    P: Fn(usize, &[u8], usize) -> Result<T>,
    N: Fn(usize) -> C,
    U: Fn(&mut C, T, usize),
{
    let mut p = Piece {
        items: new(b - a),
        n_items: 0,
        skipped: Vec::new(),
        lines: 0,
        failed: None,
    };
    let mut s = a;
    while s < b && p.n_items < limit {
        let e = text[s..b]
            .iter()
            .position(|&c| c == b'\n')
            .map_or(b, |k| s + k);
        let line = trim_line_end(&text[s..e]);
        if is_skippable(line) {
            p.skipped.push(p.lines);
        } else {
            match parse(0, line, 0) {
                Ok(t) => {
                    push(&mut p.items, t, p.n_items);
                    p.n_items += 1;
                }
                Err(_) => {
                    p.failed = Some((p.lines, s, e));
                    return p;
                }
            }
        }
        p.lines += 1;
        s = e + 1;
    }
    p
}

/// Splits `range` of `text` into pieces of about `piece` bytes ending at line ends.
fn split_pieces(text: &[u8], range: std::ops::Range<usize>, piece: usize) -> Vec<(usize, usize)> {
    let mut out = Vec::with_capacity(range.len() / piece.max(1) + 1);
    let mut a = range.start;
    while a < range.end {
        let mut b = (a + piece).min(range.end);
        if b < range.end {
            b = text[b..range.end]
                .iter()
                .position(|&c| c == b'\n')
                .map_or(range.end, |k| b + k + 1);
        }
        out.push((a, b));
        a = b;
    }
    out
}

/// Reads the `n` item lines of a section, skipping comment and blank lines: the input is
/// taken by blocks of whole lines, each block cut into pieces parsed in parallel
/// (`parse(line number, text, item index)`, each item `push`ed into its piece's collection
/// made by `new(piece bytes)`) while the next block is read (rayon::join); the pieces are
/// then applied in line order (`apply(collection, items before it, line number of its k-th
/// item)`), and the lines after the section's last item are given back to the input. The
/// result and the first error reported are those of a sequential line-by-line read, for any
/// thread count: a piece stops at its first failing line (or at the number of items still
/// wanted), and that line is parsed again with its line and item numbers once the pieces
/// before it are applied.
#[allow(clippy::too_many_arguments)]
fn read_section<R, T, C, P, N, U, A>(
    cx: &Ctx<'_>,
    inp: &mut Input<R>,
    n: usize,
    what: &str,
    parse: P,
    new: N,
    push: U,
    mut apply: A,
) -> Result<()>
where
    R: std::io::Read + Send,
    C: Send,
    P: Fn(usize, &[u8], usize) -> Result<T> + Sync,
    N: Fn(usize) -> C + Sync,
    U: Fn(&mut C, T, usize) + Sync,
    A: FnMut(C, usize, &dyn Fn(usize) -> usize),
{
    if n == 0 {
        return Ok(());
    }
    let piece_bytes = inp.block.div_ceil(BLOCK_BYTES / PIECE_BYTES).max(1);
    let mut done = 0;
    let mut block = inp.take_block(cx.file, Vec::new())?;
    let mut spare = Vec::new();
    loop {
        if block.range.is_empty() {
            return Err(Error::Truncated {
                file: cx.file.to_string(),
                at: Location::Line(inp.line + 1),
                what: what.to_string(),
            });
        }
        let limit = n - done;
        // Read the next block alongside unless this one may well end the section (fewer
        // than 16 bytes per remaining line).
        let ahead = limit.saturating_mul(16) > block.range.len() && !inp.eof;
        let pieces_at = split_pieces(&block.text, block.range.clone(), piece_bytes);
        let parse_block = || {
            pieces_at
                .par_iter()
                .map(|&ab| parse_piece(&block.text, ab, limit, &parse, &new, &push))
                .collect::<Vec<_>>()
        };
        let (next, pieces) = if ahead {
            let buf = std::mem::take(&mut spare);
            let (next, pieces) = rayon::join(|| inp.take_block(cx.file, buf), parse_block);
            (Some(next), pieces)
        } else {
            (None, parse_block())
        };
        for (p, &(a, _)) in pieces.into_iter().zip(&pieces_at) {
            let base = inp.line + 1;
            let n_items = p.n_items;
            apply(p.items, done, &|k| base + item_line(&p.skipped, k));
            done += n_items;
            if done == n {
                // Give back what follows the last item's line (and the block read ahead).
                let used = item_line(&p.skipped, n_items - 1) + 1;
                let mut s = a;
                for _ in 0..used {
                    s += block.text[s..block.range.end]
                        .iter()
                        .position(|&c| c == b'\n')
                        .map_or(block.range.end - s, |k| k + 1);
                }
                inp.line += used;
                let rest = &block.text[s..block.range.end];
                match next {
                    Some(Ok(nb)) => {
                        let mut r = rest.to_vec();
                        r.extend_from_slice(&nb.text[nb.range]);
                        inp.unread(&r);
                    }
                    Some(Err(_)) | None => inp.unread(rest),
                }
                return Ok(());
            }
            if let Some((k, a, b)) = p.failed {
                let ln = base + k;
                let line = trim_line_end(&block.text[a..b]);
                return Err(match parse(ln, line, done) {
                    Err(e) => e,
                    Ok(_) => cx.err(ln, format!("{what}: line parsed differently on a retry")),
                });
            }
            inp.line += p.lines;
        }
        spare = std::mem::replace(
            &mut block,
            match next {
                Some(r) => r?,
                None => inp.take_block(cx.file, spare)?,
            },
        )
        .text;
    }
}

/// The elements of one piece of a section and its largest node (node, local item index).
struct ElementPiece {
    set: Elements,
    max: Option<(u32, usize)>,
    /// Bytes of the piece (a hint for the first reservation).
    bytes: usize,
}

/// Reads `n` element lines into `set` ([`read_section`]).
fn read_elements<R: std::io::Read + Send>(
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
        |ln, line, _| parse_element(cx, ln, line, dim),
        |bytes| ElementPiece {
            set: Elements::new(),
            max: None,
            bytes,
        },
        |piece, (kind, nodes), k| {
            let nn = kind.n_nodes();
            let g = piece.set.group_mut(kind);
            if g.nodes.capacity() == 0 {
                // About 4 bytes per number on a line.
                g.nodes.reserve(piece.bytes / (4 * (nn + 1)) * nn);
            }
            extend_nodes(&mut g.nodes, &nodes, nn);
            let top = nodes[..nn].iter().copied().max().unwrap_or(0);
            if piece.max.is_none_or(|(m, _)| top >= m) {
                piece.max = Some((top, k));
            }
        },
        |piece, done, line_of| {
            for g in piece.set.groups() {
                let all = set.group_mut(g.kind);
                if all.nodes.capacity() == 0 {
                    reserve_capped(&mut all.nodes, (n - done).saturating_mul(g.kind.n_nodes()));
                }
                all.nodes.extend_from_slice(&g.nodes);
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
fn extend_nodes(v: &mut Vec<u32>, nodes: &[u32; 8], nn: usize) {
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
fn read_points<R: std::io::Read + Send>(
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
        |ln, line, node| parse_point(cx, ln, line, dim, node),
        // About 32 bytes per line at least (3 coordinates in full precision take ~60).
        |bytes| Vec::with_capacity(bytes / 32),
        |piece: &mut Vec<[f64; 3]>, p, _| piece.push(p),
        |piece, _, _| coords.extend_from_slice(&piece),
    )
}

/// Reads an SU2 grid from `r`; `file` names the input in errors (`Send`: the next block of
/// lines is read on one thread while the last one is parsed on the others). The input is
/// read in slices of 4 MiB (a `BufReader` passes such reads straight through).
///
/// ```
/// let txt = "NDIME= 2\nNELEM= 1\n5 0 1 2 0\nNPOIN= 3\n0 0 0\n1 0 1\n0 1 2\n\
///            NMARK= 1\nMARKER_TAG= wall\nMARKER_ELEMS= 1\n3 0 1\n";
/// let m = mesh::su2::read(txt.as_bytes(), "t.su2".as_ref()).unwrap();
/// assert_eq!((m.dim, m.n_nodes(), m.triangles().len()), (2, 3, 1));
/// assert_eq!(m.markers[0].name, "wall");
/// ```
pub fn read<R: BufRead + Send>(r: R, file: &Path) -> Result<Mesh> {
    read_by_blocks(r, file, BLOCK_BYTES)
}

/// [`read`] taking the input by blocks of about `block` bytes.
fn read_by_blocks<R: std::io::Read + Send>(r: R, file: &Path, block: usize) -> Result<Mesh> {
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
        // (the whole file is more than one read block), irrational coordinates.
        let mut m = crate::generate::box_tets(30, 30, 30, [0.0; 3], [1.0, 0.7, 1.3]);
        for (i, p) in m.coords.iter_mut().enumerate() {
            p[0] += 1e-3 * (i as f64).sin();
        }
        assert!(m.cells.len() > WRITE_BLOCK * WRITE_BATCH);
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
        assert!(one.len() > BLOCK_BYTES);
        let back = read(&one[..], "t.su2".as_ref()).unwrap();
        assert_eq!(back.coords, m.coords);
        assert_eq!(back.cells, m.cells);
        // Small blocks (many pieces and blocks per section), any thread count.
        for threads in [1, 3] {
            let small = testkit::with_threads(threads, || {
                read_by_blocks(&one[..], "t.su2".as_ref(), 1000).unwrap()
            });
            assert_eq!(small, back);
        }
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

    /// A small grid's SU2 text with comment and blank lines inserted after the lines in
    /// `at` (indices modulo the line count), optionally with CRLF line ends.
    fn text_with_noise(at: &[usize], crlf: bool) -> Vec<u8> {
        let mut m = crate::generate::box_tets(3, 2, 2, [0.0; 3], [1.0, 0.3, 0.7]);
        m.su2_extra = "FFD_NBOX= 0\nFFD_NLEVEL= 0\n".into();
        let mut t = Vec::new();
        write(&m, &mut t).unwrap();
        let lines: Vec<&[u8]> = t.split(|&c| c == b'\n').collect();
        let n = lines.len() - 1;
        let mut out = Vec::new();
        for (k, l) in lines[..n].iter().enumerate() {
            out.extend_from_slice(l);
            out.extend_from_slice(if crlf { b"\r\n" } else { b"\n" });
            for (j, &a) in at.iter().enumerate() {
                if a % n == k {
                    out.extend_from_slice(if j % 2 == 0 { b"% note\n" } else { b" \t \n" });
                }
            }
        }
        out
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(48))]

        /// Reading by tiny blocks (many blocks and pieces per section, sections ending
        /// inside blocks, lines given back) gives the grid, or the first error, of a read in
        /// one block and one piece (line by line), for any thread count.
        #[test]
        fn tiny_blocks_read_like_one_block(
            at in proptest::collection::vec(0usize..400, 0..6),
            crlf: bool,
            block in 1usize..400,
            threads in 1usize..4,
            bad in proptest::option::of((0usize..400, 0usize..40, 0usize..4)),
        ) {
            let mut text = text_with_noise(&at, crlf);
            if let Some((line, col, what)) = bad {
                // Damage one character of one line.
                let starts: Vec<usize> = std::iter::once(0)
                    .chain(text.iter().enumerate().filter(|(_, c)| **c == b'\n').map(|(i, _)| i + 1))
                    .filter(|&i| i < text.len())
                    .collect();
                let a = starts[line % starts.len()];
                let len = text[a..].iter().position(|&c| c == b'\n').unwrap_or(text.len() - a);
                if len > 0 {
                    text[a + col % len] = [b'x', b'-', b' ', b'9'][what];
                }
            }
            // (One block, one piece: the text is ~4 kB.)
            let whole = read_by_blocks(&text[..], "t.su2".as_ref(), 1 << 20);
            let small = testkit::with_threads(threads, || {
                read_by_blocks(&text[..], "t.su2".as_ref(), block)
            });
            match (whole, small) {
                (Ok(a), Ok(b)) => proptest::prop_assert_eq!(a, b),
                (Err(a), Err(b)) => proptest::prop_assert_eq!(a.to_string(), b.to_string()),
                (a, b) => proptest::prop_assert!(false, "{:?} vs {:?}", a.map(|_| ()), b.map(|_| ())),
            }
        }
    }

    #[test]
    fn noise_lines_and_crlf_keep_the_grid_and_line_numbers() {
        let clean = read(&text_with_noise(&[], false)[..], "t.su2".as_ref()).unwrap();
        let noisy = text_with_noise(&[0, 5, 40, 41, 100, 150], true);
        for block in [7, 64, 1 << 20] {
            let m = read_by_blocks(&noisy[..], "t.su2".as_ref(), block).unwrap();
            assert_eq!(m.coords, clean.coords);
            assert_eq!(m.cells, clean.cells);
            assert_eq!(m.markers, clean.markers);
            assert_eq!(m.su2_extra, clean.su2_extra);
        }
        // An error names the line counted here, comments and blank lines included.
        let mut bad = noisy.clone();
        let npoin = bad.windows(6).position(|w| w == b"NPOIN=").unwrap();
        let third = npoin
            + bad[npoin..]
                .iter()
                .enumerate()
                .filter(|(_, c)| **c == b'\n')
                .nth(2)
                .unwrap()
                .0
            + 1;
        bad[third] = b'#';
        let line_no = bad[..third].iter().filter(|&&c| c == b'\n').count() + 1;
        for block in [7, 64, 1 << 20] {
            let e = read_by_blocks(&bad[..], "t.su2".as_ref(), block)
                .unwrap_err()
                .to_string();
            assert!(
                e.starts_with(&format!("t.su2: line {line_no}: node ")),
                "{e}"
            );
        }
    }
}
