//! Whitespace tokenizer and fast number
//! parsing and formatting shared by the text readers and writers.

use crate::error::{Error, Location};

/// A syntax error at `line` of `file`.
pub(crate) fn syntax(file: &str, line: usize, msg: impl Into<String>) -> Error {
    Error::Syntax {
        file: file.to_string(),
        at: Location::Line(line),
        msg: msg.into(),
    }
}

/// Whitespace-separated tokens of a line.
pub(crate) struct Tokens<'a> {
    s: &'a [u8],
    pos: usize,
}

impl<'a> Tokens<'a> {
    pub fn new(s: &'a [u8]) -> Self {
        Tokens { s, pos: 0 }
    }
}

impl<'a> Iterator for Tokens<'a> {
    type Item = &'a [u8];
    #[inline]
    fn next(&mut self) -> Option<&'a [u8]> {
        let s = self.s;
        let mut i = self.pos;
        while i < s.len() && s[i].is_ascii_whitespace() {
            i += 1;
        }
        if i == s.len() {
            self.pos = i;
            return None;
        }
        let start = i;
        while i < s.len() && !s[i].is_ascii_whitespace() {
            i += 1;
        }
        self.pos = i;
        Some(&s[start..i])
    }
}

/// Reserves room for `n` more items, at most 512 MiB worth: counts come from the file and
/// may be corrupt, so the reservation is a hint that never fails or aborts.
pub(crate) fn reserve_capped<T>(v: &mut Vec<T>, n: usize) {
    let cap = (512usize << 20) / std::mem::size_of::<T>().max(1);
    let _ = v.try_reserve_exact(n.min(cap));
}

/// Parses an unsigned decimal integer.
#[inline]
pub(crate) fn parse_u64(t: &[u8]) -> Option<u64> {
    let t = t.strip_prefix(b"+").unwrap_or(t);
    if t.is_empty() || t.len() > 20 {
        return None;
    }
    let mut v: u64 = 0;
    for &c in t {
        let d = c.wrapping_sub(b'0');
        if d > 9 {
            return None;
        }
        v = v.checked_mul(10)?.checked_add(u64::from(d))?;
    }
    Some(v)
}

/// Parses a signed decimal integer.
#[inline]
pub(crate) fn parse_i64(t: &[u8]) -> Option<i64> {
    if let Some(r) = t.strip_prefix(b"-") {
        let v = parse_u64(r)?;
        if v <= i64::MAX as u64 + 1 {
            Some((v as i128).wrapping_neg() as i64)
        } else {
            None
        }
    } else {
        i64::try_from(parse_u64(t)?).ok()
    }
}

/// Parses a floating-point number (decimal or exponent notation; also Fortran `D`).
#[inline]
pub(crate) fn parse_f64(t: &[u8]) -> Option<f64> {
    let s = std::str::from_utf8(t).ok()?;
    match s.parse::<f64>() {
        Ok(v) => Some(v),
        Err(_) => {
            if t.iter().any(|&c| c == b'd' || c == b'D') {
                s.replace(['d', 'D'], "e").parse().ok()
            } else {
                None
            }
        }
    }
}

/// The two-digit strings "00" … "99".
const DIGIT_PAIRS: &[u8; 200] = b"\
0001020304050607080910111213141516171819\
2021222324252627282930313233343536373839\
4041424344454647484950515253545556575859\
6061626364656667686970717273747576777879\
8081828384858687888990919293949596979899";

/// Appends the decimal representation of `v` (two digits per division).
#[inline]
pub(crate) fn push_u64(out: &mut Vec<u8>, mut v: u64) {
    let mut tmp = [0u8; 20];
    let mut i = tmp.len();
    while v >= 100 {
        let d = (v % 100) as usize * 2;
        v /= 100;
        i -= 2;
        tmp[i..i + 2].copy_from_slice(&DIGIT_PAIRS[d..d + 2]);
    }
    if v >= 10 {
        let d = v as usize * 2;
        i -= 2;
        tmp[i..i + 2].copy_from_slice(&DIGIT_PAIRS[d..d + 2]);
    } else {
        i -= 1;
        tmp[i] = b'0' + v as u8;
    }
    out.extend_from_slice(&tmp[i..]);
}

/// Appends the shortest representation of `v` that parses back to the same bits.
#[inline]
pub(crate) fn push_f64(out: &mut Vec<u8>, v: f64) {
    use std::io::Write;
    // Debug prints the shortest round-trip representation ("1.0", "1e-7", "0.1").
    let _ = write!(out, "{v:?}");
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integers_parse_and_print() {
        assert_eq!(parse_u64(b"0"), Some(0));
        assert_eq!(parse_u64(b"18446744073709551615"), Some(u64::MAX));
        assert_eq!(parse_u64(b"18446744073709551616"), None);
        assert_eq!(parse_u64(b"12a"), None);
        assert_eq!(parse_u64(b""), None);
        assert_eq!(parse_i64(b"-5"), Some(-5));
        assert_eq!(parse_i64(b"-9223372036854775808"), Some(i64::MIN));
        let mut v = Vec::new();
        v.push(b'-');
        push_u64(&mut v, 1203);
        push_u64(&mut v, 0);
        assert_eq!(v, b"-12030");
        for x in [
            0,
            9,
            10,
            99,
            100,
            101,
            999,
            1000,
            4_294_967_295,
            10_000_000_000_000_000_000,
            u64::MAX,
        ]
        .into_iter()
        .chain((0..200_000).step_by(7))
        {
            let mut b = Vec::new();
            push_u64(&mut b, x);
            assert_eq!(b, x.to_string().as_bytes());
        }
    }

    #[test]
    fn floats_round_trip() {
        for x in [
            0.0,
            -0.0,
            1.0,
            0.1,
            1e-300,
            5.128205128205128e-02,
            -3.2e17,
            f64::MAX,
        ] {
            let mut v = Vec::new();
            push_f64(&mut v, x);
            assert_eq!(parse_f64(&v).unwrap().to_bits(), x.to_bits());
        }
        assert_eq!(parse_f64(b"1.5D+01"), Some(15.0));
        assert_eq!(parse_f64(b"abc"), None);
    }

    #[test]
    fn tokens_split_on_any_whitespace() {
        let t: Vec<&[u8]> = Tokens::new(b"\t 1\t2  3 \r").collect();
        assert_eq!(t, vec![&b"1"[..], b"2", b"3"]);
    }
}
