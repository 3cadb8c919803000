//! SU2 native ASCII grids (2D and 3D): `NDIME`, `NELEM`, `NPOIN`, `NMARK` with
//! `MARKER_TAG` / `MARKER_ELEMS`. Trailing sections that SU2 tools append (periodic
//! information, FFD boxes) are kept verbatim in [`Mesh::su2_extra`] and written back.
//!
//! The reader reads the input 33 MiB at a time straight from the reader (no per-line
//! copy) and takes it by blocks of whole lines (4 MiB); the element and point sections are parsed by pieces of a block
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

/// The value of eight decimal digits given as byte values 0–9, the first (most
/// significant) in the lowest byte: three multiplications combine pairs, quads, octets
/// (exact integer arithmetic: the largest intermediate, 99 999 999 · 2^32, fits in 64 bits).
#[inline]
fn eight_digits(v: u64) -> u64 {
    const MASK: u64 = 0x0000_00FF_0000_00FF;
    const MUL1: u64 = 100 + (1_000_000 << 32);
    const MUL2: u64 = 1 + (10_000 << 32);
    // Byte pairs: 10 · d[2k] + d[2k + 1] in the even bytes.
    let v = v.wrapping_mul(10).wrapping_add(v >> 8);
    ((v & MASK)
        .wrapping_mul(MUL1)
        .wrapping_add(((v >> 16) & MASK).wrapping_mul(MUL2)))
        >> 32
}

/// Scans unsigned integers separated by spaces, tabs or `\r` from the start of `s` to the
/// first `\n` (or the end) into `out`: the count of numbers and the position of that line
/// end. `None` if the line holds anything else, more than `out.len()` numbers or a number of
/// more than 10 digits (the caller then re-reads it with full error reporting). Up to eight
/// digits of a number are taken at once when eight bytes are left ([`eight_digits`]).
#[inline]
fn scan_uints(s: &[u8], out: &mut [u64; 10]) -> Option<(usize, usize)> {
    const LOW7: u64 = 0x7F7F_7F7F_7F7F_7F7F;
    const HIGH: u64 = 0x8080_8080_8080_8080;
    const ZEROS: u64 = 0x3030_3030_3030_3030;
    let is_sep = |c: u8| c == b'\t' || c == b' ' || c == b'\r';
    let (len, mut i, mut n) = (s.len(), 0, 0);
    loop {
        while i < len && is_sep(s[i]) {
            i += 1;
        }
        if i == len || s[i] == b'\n' {
            return Some((n, i));
        }
        let start = i;
        let mut acc: u64 = 0;
        if let Some(chunk) = s.get(i..i + 8).and_then(|c| <[u8; 8]>::try_from(c).ok()) {
            // Byte j of t is d_j = s[i + j] - '0' for a digit; the high bit of byte j of
            // `non` is set iff s[i + j] is not a digit (no carry crosses a byte: 0x7F +
            // 0x76 < 0x100).
            let t = u64::from_le_bytes(chunk) ^ ZEROS;
            let non = (((t & LOW7) + 0x7676_7676_7676_7676) | t) & HIGH;
            let run = (non.trailing_zeros() / 8) as usize;
            if run > 0 {
                // Keep the run's bytes, shifted up: the bytes below are leading zeros.
                acc = eight_digits(t << (8 * (8 - run)));
                i += run;
            }
        }
        while i < len {
            let d = s[i].wrapping_sub(b'0');
            if d > 9 {
                break;
            }
            // (Wrapping: a number of more than 10 digits is refused below.)
            acc = acc.wrapping_mul(10).wrapping_add(u64::from(d));
            i += 1;
        }
        if i == start || i - start > 10 || (i < len && !is_sep(s[i]) && s[i] != b'\n') {
            return None;
        }
        *out.get_mut(n)? = acc;
        n += 1;
    }
}

/// The element of a line scanned by [`scan_uints`] (`k` numbers in `v`) if it is a
/// well-formed `want_dim`-D element line: code, nodes below `u32::MAX`, optionally an index.
#[inline]
fn plain_element(v: &[u64; 10], k: usize, want_dim: u8) -> Option<(ElementKind, [u32; 8])> {
    if k == 0 {
        return None;
    }
    let kind = ElementKind::from_vtk_code(i64::try_from(v[0]).ok()?)?;
    let nn = kind.n_nodes();
    if kind.dim() != want_dim || !(k == nn + 1 || k == nn + 2) {
        return None;
    }
    let mut nodes = [0u32; 8];
    for (o, &x) in nodes.iter_mut().zip(&v[1..=nn]) {
        if x >= u64::from(u32::MAX) {
            return None;
        }
        *o = x as u32;
    }
    Some((kind, nodes))
}

/// The fast path of the element reader: a well-formed element line at the start of `s`,
/// and the position of its line end.
#[inline]
fn fast_element(s: &[u8], want_dim: u8) -> Option<((ElementKind, [u32; 8]), usize)> {
    let mut v = [0u64; 10];
    let (k, end) = scan_uints(s, &mut v)?;
    Some((plain_element(&v, k, want_dim)?, end))
}

/// Parses one element line: the code, `n_nodes` node indices, optionally the element index
/// (ignored). Returns the kind and the nodes (first `n_nodes` entries used).
fn parse_element(
    cx: &Ctx<'_>,
    ln: usize,
    line: &[u8],
    want_dim: u8,
) -> Result<(ElementKind, [u32; 8])> {
    // Fast path for well-formed lines; anything unusual falls through to the checked parse.
    if let Some((e, _)) = fast_element(line, want_dim) {
        return Ok(e);
    }
    let mut nodes = [0u32; 8];
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

/// Bytes read from the input at once, and the least capacity of the input's buffers. Above
/// 32 MiB on purpose: glibc's malloc raises its mmap threshold to the size of a freed
/// mmap'ed chunk of at most 32 MiB, after which allocations below that size come from the
/// heap, where freed memory is not given back; freeing 4 MiB read buffers raised the peak
/// resident memory of a whole 1M-node deformation run by ~40 MB (Linux, glibc).
const READ_BYTES: usize = 33 << 20;

/// Blocks of a section (parsed while the next is read) are about `READ_BYTES / TAKES`
/// bytes: 4 MiB; the elements or points parsed from a block are held until it is applied.
const TAKES: usize = 8;

/// Pieces per block (each piece, of whole lines, parsed by one task): 64 KiB each.
const PIECES: usize = 64;

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
    /// Bytes read from `inner` per call when the buffer is empty ([`READ_BYTES`]; smaller
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
    /// front, makes room for more (64 KiB at first, doubling up to `block`, so that a small
    /// file needs no large buffer; the growth is by `realloc`, which glibc does by `mremap`
    /// for large buffers, without the free of the note at [`READ_BYTES`]) and reads into it.
    fn read_more(&mut self, file: &str) -> Result<()> {
        if self.pos > 0 {
            self.buf.copy_within(self.pos..self.end, 0);
            self.end -= self.pos;
            self.pos = 0;
        }
        let room = self.buf.len().max(1 << 16).min(self.block.max(1));
        if self.buf.len() < self.end + room {
            self.buf.resize(self.end + room, 0);
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
            if let Some(k) = find_nl(&self.buf[self.pos + scanned..self.end]) {
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

    /// Takes the next block of whole lines: about `want` bytes (at most
    /// [`Input::block`] / [`TAKES`], more to end the last line; less at the end of the input; empty at the end). The
    /// smaller of the block and the rest of the buffer is copied: the block into `spare`, or
    /// the rest into `spare`, which then becomes the buffer. Lines are not counted here: the
    /// caller adds the lines it uses to [`Input::line`] and gives back the rest with
    /// [`Input::unread`].
    fn take_block(&mut self, file: &str, mut spare: Vec<u8>, want: usize) -> Result<Block> {
        let want = want.clamp(1, (self.block / TAKES).max(1));
        let mut from = self.pos + want - 1;
        let cut = loop {
            if self.end - self.pos >= want || self.eof {
                let at = from.min(self.end);
                if let Some(k) = find_nl(&self.buf[at..self.end]) {
                    break at + k + 1;
                }
                if self.eof {
                    break self.end;
                }
                // A line longer than the rest of the buffer: read on until its end.
                from = self.end;
            }
            let before = self.pos;
            self.read_more(file)?;
            from -= before;
        };
        let (len, tail) = (cut - self.pos, self.end - cut);
        if len <= tail {
            // (Capacity of a read at least, so that no buffer of the size range of the
            // malloc note at READ_BYTES is freed.)
            if spare.capacity() < self.block {
                spare.reserve_exact(self.block - spare.len());
            }
            if spare.len() < len {
                spare.resize(len, 0);
            }
            spare[..len].copy_from_slice(&self.buf[self.pos..cut]);
            self.pos = cut;
            return Ok(Block {
                text: spare,
                range: 0..len,
            });
        }
        let text = std::mem::replace(&mut self.buf, spare);
        if self.buf.len() < tail {
            self.buf.resize(tail, 0);
        }
        self.buf[..tail].copy_from_slice(&text[cut..self.end]);
        let range = self.pos..cut;
        self.end = tail;
        self.pos = 0;
        Ok(Block { text, range })
    }

    /// Puts `first` and then `second` back in front of the unread input.
    fn unread(&mut self, first: &[u8], second: &[u8]) {
        let n = first.len() + second.len();
        if n == 0 {
            return;
        }
        if n <= self.pos {
            // Room in front of the unread bytes.
            self.pos -= n;
            self.buf[self.pos..self.pos + first.len()].copy_from_slice(first);
            self.buf[self.pos + first.len()..self.pos + n].copy_from_slice(second);
            return;
        }
        let mut b = Vec::with_capacity(n + self.end - self.pos + self.block);
        b.extend_from_slice(first);
        b.extend_from_slice(second);
        b.extend_from_slice(&self.buf[self.pos..self.end]);
        self.end = b.len();
        self.pos = 0;
        self.buf = b;
    }
}

/// Position of the first `\n` in `s` (by the standard library's word-at-a-time `memchr`,
/// through `BufRead::skip_until` on a slice).
#[inline]
fn find_nl(s: &[u8]) -> Option<usize> {
    let mut r = s;
    let k = BufRead::skip_until(&mut r, b'\n').unwrap_or(0);
    (k > 0 && s[k - 1] == b'\n').then(|| k - 1)
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

/// Parses the lines of `text[a..b]` (whole lines) by `fast` (a line at the start of a
/// slice: the item and the position of the line end, `None` to leave the line to the rest)
/// or else by `parse` (with dummy line and item numbers) and `push`es the items into a new collection (`new(bytes)`), up to `limit`
/// items or the first error.
fn parse_piece<T, C, F, P, U>(
    text: &[u8],
    (a, b): (usize, usize),
    limit: usize,
    (fast, parse): (&F, &P),
    items: C,
    push: &U,
) -> Piece<C>
where
    F: Fn(&[u8]) -> Option<(T, usize)>,
    P: Fn(usize, &[u8], usize) -> Result<T>,
    U: Fn(&mut C, T, usize),
{
    let mut p = Piece {
        items,
        n_items: 0,
        skipped: Vec::new(),
        lines: 0,
        failed: None,
    };
    let mut s = a;
    while s < b && p.n_items < limit {
        if let Some((t, end)) = fast(&text[s..b]) {
            push(&mut p.items, t, p.n_items);
            p.n_items += 1;
            p.lines += 1;
            s += end + 1;
            continue;
        }
        let e = find_nl(&text[s..b]).map_or(b, |k| s + k);
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
            b = find_nl(&text[b..range.end]).map_or(range.end, |k| b + k + 1);
        }
        out.push((a, b));
        a = b;
    }
    out
}

/// Reads the `n` item lines of a section, skipping comment and blank lines: the input is
/// taken by blocks of whole lines, each block cut into pieces parsed in parallel
/// (a line by `fast` if it takes it, else by `parse(line number, text, item index)`; the
/// result must be the same), each item `push`ed into its piece's collection
/// made by `new(piece bytes)`) while the next block is read (rayon::join); the pieces are
/// then applied in line order (`apply(collection, items before it, line number of its k-th
/// item)`), and the lines after the section's last item are given back to the input. The
/// result and the first error reported are those of a sequential line-by-line read, for any
/// thread count: a piece stops at its first failing line (or at the number of items still
/// wanted), and that line is parsed again with its line and item numbers once the pieces
/// before it are applied.
#[allow(clippy::too_many_arguments)]
fn read_section<R, T, C, F, P, N, U, A>(
    cx: &Ctx<'_>,
    inp: &mut Input<R>,
    n: usize,
    what: &str,
    (fast, parse): (F, P),
    new: N,
    push: U,
    mut apply: A,
) -> Result<()>
where
    R: std::io::Read + Send,
    C: Send,
    F: Fn(&[u8]) -> Option<(T, usize)> + Sync,
    P: Fn(usize, &[u8], usize) -> Result<T> + Sync,
    N: Fn(usize) -> C + Sync,
    U: Fn(&mut C, T, usize) + Sync,
    A: FnMut(C, usize, &dyn Fn(usize) -> usize),
{
    if n == 0 {
        return Ok(());
    }
    let piece_bytes = (inp.block / TAKES / PIECES).max(1);
    let mut done = 0;
    // Bytes wanted for the items still to read (at most a block): 64 per line, so that a
    // short section (a marker) takes little more than its lines.
    let want = |items: usize| items.saturating_mul(64);
    let mut block = inp.take_block(cx.file, Vec::new(), want(n))?;
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
        // The pieces' collections are made here, on the calling thread: allocations by the
        // pool's threads (glibc gives each its own arena) left the allocator in a state that
        // raised the peak resident memory of the later deformation by ~40 MB.
        let outs: Vec<C> = pieces_at.iter().map(|&(a, b)| new(b - a)).collect();
        let parse_block = || {
            outs.into_par_iter()
                .zip(&pieces_at)
                .map(|(items, &ab)| {
                    parse_piece(&block.text, ab, limit, (&fast, &parse), items, &push)
                })
                .collect::<Vec<_>>()
        };
        let (next, pieces) = if ahead {
            let buf = std::mem::take(&mut spare);
            let more = want(limit.saturating_sub(block.range.len() / 64));
            let (next, pieces) = rayon::join(|| inp.take_block(cx.file, buf, more), parse_block);
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
                    s += find_nl(&block.text[s..block.range.end])
                        .map_or(block.range.end - s, |k| k + 1);
                }
                inp.line += used;
                let rest = &block.text[s..block.range.end];
                match next {
                    Some(Ok(nb)) => inp.unread(rest, &nb.text[nb.range]),
                    Some(Err(_)) | None => inp.unread(rest, &[]),
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
                None => inp.take_block(cx.file, spare, want(n - done))?,
            },
        )
        .text;
    }
}

/// The elements of one piece of a section and its largest node (node, local item index).
struct ElementPiece {
    /// The nodes of the elements in line order.
    nodes: Vec<u32>,
    /// Runs of elements of one kind: (kind, number of elements).
    runs: Vec<(ElementKind, usize)>,
    max: Option<(u32, usize)>,
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
        assert_eq!(scan_uints(b"10\t1 2  3 4\t5\r", &mut v), Some((6, 14)));
        assert_eq!(&v[..6], &[10, 1, 2, 3, 4, 5]);
        assert_eq!(scan_uints(b"", &mut v), Some((0, 0)));
        assert_eq!(scan_uints(b"5 -1 2", &mut v), None);
        assert_eq!(scan_uints(b"5 1.0 2", &mut v), None);
        assert_eq!(scan_uints(b"5 12345678901 2", &mut v), None);
        assert_eq!(scan_uints(b"5 1234567890 2", &mut v), Some((3, 14)));
        assert_eq!(v[1], 1_234_567_890);
        assert_eq!(scan_uints(b"5 99999999999999999999999", &mut v), None);
        assert_eq!(scan_uints(b"1 2 3 4 5 6 7 8 9 10 11", &mut v), None);
        // Stops at the line end.
        assert_eq!(
            scan_uints(b"10 123456789 7\r\n5 x\n", &mut v),
            Some((3, 15))
        );
        assert_eq!(&v[..3], &[10, 123_456_789, 7]);
    }

    proptest::proptest! {
        /// The scan equals splitting on separators and `str::parse::<u64>` for lines of
        /// numbers (any lengths, so any alignment of the eight-byte steps) and refuses lines
        /// with any other character.
        #[test]
        fn integer_scan_equals_str_parse(
            nums in proptest::collection::vec((0u64..=9_999_999_999, 0usize..11, 0usize..3), 0..11),
            junk in proptest::option::of((0usize..200, proptest::sample::select(b"x-+.e,;\x00\xff:/".to_vec()))),
            tail in proptest::sample::select(vec!["", "\n", "\r\n", "\n7 7"]),
        ) {
            let mut line = String::new();
            for &(x, zeros, sep) in &nums {
                line.push_str(["\t", " ", "  \t"][sep]);
                line.push_str(&"0".repeat(zeros));
                line.push_str(&x.to_string());
            }
            let mut b = line.clone().into_bytes();
            let junk_at = junk.map(|(at, c)| {
                let at = at % (b.len() + 1);
                b.insert(at, c);
                at
            });
            b.extend_from_slice(tail.as_bytes());
            let end = b.iter().position(|&c| c == b'\n').unwrap_or(b.len());
            let mut v = [0u64; 10];
            let got = scan_uints(&b, &mut v);
            let want: Option<Vec<u64>> = std::str::from_utf8(&b[..end])
                .ok()
                .and_then(|t| {
                    t.split(['\t', ' ', '\r'])
                        .filter(|w| !w.is_empty())
                        .map(|w| {
                            (w.len() <= 10 && w.bytes().all(|c| c.is_ascii_digit()))
                                .then(|| w.parse::<u64>().ok())
                                .flatten()
                        })
                        .collect()
                });
            // (Every junk character is neither a digit nor a separator.)
            proptest::prop_assert!(junk_at.is_none() || want.is_none());
            match want {
                Some(w) => {
                    proptest::prop_assert_eq!(got, Some((w.len(), end)));
                    proptest::prop_assert_eq!(&v[..w.len()], &w[..]);
                }
                _ => proptest::prop_assert_eq!(got, None),
            }
        }

        /// Eight digits at once equal the decimal value.
        #[test]
        fn eight_digits_equal_str_parse(x in 0u64..100_000_000, run in 1usize..9) {
            let x = x % 10u64.pow(run as u32);
            let txt = format!("{x:0run$}");
            let mut t = 0u64;
            for (j, c) in txt.bytes().enumerate() {
                t |= u64::from(c - b'0') << (8 * j);
            }
            proptest::prop_assert_eq!(eight_digits(t << (8 * (8 - run))), x);
        }
    }

    #[test]
    fn parallel_write_and_read_span_several_blocks_and_batches() {
        // 162 000 tetrahedra (more than WRITE_BLOCK × WRITE_BATCH lines), 29 791 points
        // (the whole file is more than one block of a section), irrational coordinates.
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
