//! The input by blocks of whole lines: a section's lines are parsed by pieces of a block
//! in parallel while the next block is read, and applied in line order.

use rayon::prelude::*;

use std::io::BufRead;

use crate::error::{Error, Location, Result};

use super::lines::{Ctx, is_skippable};

/// Bytes read from the input at once, and the least capacity of the input's buffers. Above
/// 32 MiB on purpose: glibc's malloc raises its mmap threshold to the size of a freed
/// mmap'ed chunk of at most 32 MiB, after which allocations below that size come from the
/// heap, where freed memory is not given back; freeing 4 MiB read buffers raised the peak
/// resident memory of a whole 1M-node deformation run by ~40 MB (Linux, glibc).
pub(super) const READ_BYTES: usize = 33 << 20;

/// Blocks of a section (parsed while the next is read) are about `READ_BYTES / TAKES`
/// bytes: 4 MiB; the elements or points parsed from a block are held until it is applied.
pub(super) const TAKES: usize = 8;

/// Pieces per block (each piece, of whole lines, parsed by one task): 64 KiB each.
pub(super) const PIECES: usize = 64;

/// Buffered input that hands out single lines (headers, marker tags) and blocks of whole
/// lines (sections), reading from the inner reader in large slices. Lines end at `\n`; the
/// `\r`s before it are dropped; a last line without `\n` counts.
pub(super) struct Input<R> {
    pub(super) inner: R,
    /// Bytes read and not yet handed out: `buf[pos..end]`.
    pub(super) buf: Vec<u8>,
    pub(super) pos: usize,
    pub(super) end: usize,
    pub(super) eof: bool,
    /// Lines handed out so far (the number of the last one).
    pub(super) line: usize,
    /// Bytes read from `inner` per call when the buffer is empty ([`READ_BYTES`]; smaller
    /// in tests so that small inputs span many blocks).
    pub(super) block: usize,
}

/// Whole lines taken out of an [`Input`]: `text[range]`, ending with a line end unless the
/// input ended without one.
pub(super) struct Block {
    pub(super) text: Vec<u8>,
    pub(super) range: std::ops::Range<usize>,
}

impl<R: std::io::Read> Input<R> {
    pub(super) fn new(inner: R, block: usize) -> Self {
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
    pub(super) fn read_more(&mut self, file: &str) -> Result<()> {
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
    pub(super) fn next_line(&mut self, file: &str) -> Result<Option<(usize, &[u8])>> {
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
    pub(super) fn expect_line(&mut self, file: &str, what: &str) -> Result<(usize, &[u8])> {
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
    pub(super) fn take_block(
        &mut self,
        file: &str,
        mut spare: Vec<u8>,
        want: usize,
    ) -> Result<Block> {
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
    pub(super) fn unread(&mut self, first: &[u8], second: &[u8]) {
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
pub(super) fn find_nl(s: &[u8]) -> Option<usize> {
    let mut r = s;
    let k = BufRead::skip_until(&mut r, b'\n').unwrap_or(0);
    (k > 0 && s[k - 1] == b'\n').then(|| k - 1)
}

/// A line without its `\n` and the `\r`s before it.
#[inline]
pub(super) fn trim_line_end(mut l: &[u8]) -> &[u8] {
    while let [rest @ .., b'\n' | b'\r'] = l {
        l = rest;
    }
    l
}

/// What one task made of one piece of a block.
pub(super) struct Piece<C> {
    /// The items parsed, in line order, up to the first error or the item limit.
    pub(super) items: C,
    /// Number of items in `items`.
    pub(super) n_items: usize,
    /// Local indices (0-based, within the piece) of the comment and blank lines skipped.
    pub(super) skipped: Vec<usize>,
    /// Lines in the piece (all of them when it was parsed to its end).
    pub(super) lines: usize,
    /// The first line that failed: its local index and its text (`text[a..b]` of the block).
    pub(super) failed: Option<(usize, usize, usize)>,
}

/// Local line index of the `k`-th item of a piece whose skipped lines are `skipped`.
pub(super) fn item_line(skipped: &[usize], k: usize) -> usize {
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
pub(super) fn parse_piece<T, C, F, P, U>(
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
pub(super) fn split_pieces(
    text: &[u8],
    range: std::ops::Range<usize>,
    piece: usize,
) -> Vec<(usize, usize)> {
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
pub(super) fn read_section<R, T, C, F, P, N, U, A>(
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
