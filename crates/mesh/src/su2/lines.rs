//! One line of an SU2 file: `KEY= value`, counts, element lines (with a fast scan of
//! plain integer lines) and point lines.

use crate::error::{Error, Location, Result};
use crate::grid::ElementKind;
use crate::text::{Tokens, parse_f64, parse_i64, parse_u64, syntax};

/// Splits `KEY= value` (value trimmed); `None` when the line has no `=`.
pub(super) fn keyword(line: &[u8]) -> Option<(&[u8], &[u8])> {
    let eq = line.iter().position(|&c| c == b'=')?;
    Some((line[..eq].trim_ascii(), line[eq + 1..].trim_ascii()))
}

pub(super) fn is_skippable(line: &[u8]) -> bool {
    let t = line.trim_ascii();
    t.is_empty() || t[0] == b'%'
}

/// Largest node index seen in a section, and the line where it was seen.
#[derive(Default, Clone, Copy)]
pub(super) struct MaxRef {
    pub(super) node: u64,
    pub(super) line: usize,
}

impl MaxRef {
    #[inline]
    pub(super) fn see(&mut self, node: u64, line: usize) {
        if node >= self.node {
            self.node = node;
            self.line = line;
        }
    }
}

/// Reading context: the file name for errors.
pub(super) struct Ctx<'a> {
    pub(super) file: &'a str,
}

impl Ctx<'_> {
    pub(super) fn err(&self, line: usize, msg: impl Into<String>) -> Error {
        syntax(self.file, line, msg)
    }
}

/// The value of eight decimal digits given as byte values 0–9, the first (most
/// significant) in the lowest byte: three multiplications combine pairs, quads, octets
/// (exact integer arithmetic: the largest intermediate, 99 999 999 · 2^32, fits in 64 bits).
#[inline]
pub(super) fn eight_digits(v: u64) -> u64 {
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
pub(super) fn scan_uints(s: &[u8], out: &mut [u64; 10]) -> Option<(usize, usize)> {
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
pub(super) fn plain_element(
    v: &[u64; 10],
    k: usize,
    want_dim: u8,
) -> Option<(ElementKind, [u32; 8])> {
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
pub(super) fn fast_element(s: &[u8], want_dim: u8) -> Option<((ElementKind, [u32; 8]), usize)> {
    let mut v = [0u64; 10];
    let (k, end) = scan_uints(s, &mut v)?;
    Some((plain_element(&v, k, want_dim)?, end))
}

/// Parses one element line: the code, `n_nodes` node indices, optionally the element index
/// (ignored). Returns the kind and the nodes (first `n_nodes` entries used).
pub(super) fn parse_element(
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

pub(super) fn lossy(t: &[u8]) -> String {
    String::from_utf8_lossy(&t[..t.len().min(60)]).into_owned()
}

/// Parses a count value such as `59156` or (for `NPOIN`) `11703 11703`.
pub(super) fn count(cx: &Ctx<'_>, ln: usize, key: &str, val: &[u8]) -> Result<usize> {
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

/// Parses one point line of node `node`: `dim` finite coordinates, optionally the node's
/// index. With `dim` 2 a third coordinate may follow, as in SU2's own 2-D grids
/// (`x y z index`, z = 0): it is kept in `p[2]` (the reader then sets it to 0, as SU2
/// ignores it). Three tokens `x y t` read `t` as the index when it is an integer, else as z.
pub(super) fn parse_point(
    cx: &Ctx<'_>,
    ln: usize,
    line: &[u8],
    dim: u8,
    node: usize,
) -> Result<[f64; 3]> {
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
    let mut next = tok.next();
    if dim == 2
        && let Some(t) = next
    {
        let after = tok.next();
        // `x y z [index]`: a fourth token, or a third that is not an index.
        if after.is_some() || parse_u64(t).is_none() {
            match parse_f64(t) {
                Some(z) if z.is_finite() => p[2] = z,
                _ => {
                    return Err(cx.err(
                        ln,
                        format!(
                            "node {node}: coordinate 2 must be a finite number, found '{}'",
                            lossy(t)
                        ),
                    ));
                }
            }
            next = after;
        } else {
            // `x y index`: the index, nothing after.
            next = None;
        }
    }
    // The index, if any, must be the last token.
    let bad = match next {
        Some(t) if parse_u64(t).is_none() => Some(t),
        Some(_) => tok.next(),
        None => None,
    };
    if let Some(t) = bad {
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
