//! Free-format parameters: splitting parameter text at the delimiters, Hollerith strings,
//! numbers with `E` or `D` exponents, and formatting them back.

/// One free-format parameter as written in the Global or Parameter Data section.
///
/// Integers and pointers are both written as integers; the entity decoders interpret them.
#[derive(Debug, Clone, PartialEq)]
pub enum Param {
    /// Nothing between two delimiters: the field's default value.
    Empty,
    /// An integer (also used for pointers, flags and counts).
    Int(i64),
    /// A real number (written with a decimal point and optional `E`/`D` exponent).
    Real(f64),
    /// A Hollerith string `nHxxx`.
    Str(String),
}

impl Param {
    /// The parameter as it would appear in an error message.
    pub fn describe(&self) -> String {
        match self {
            Param::Empty => "<empty>".to_string(),
            Param::Int(i) => i.to_string(),
            Param::Real(x) => format_real(*x),
            Param::Str(s) => format!("{}H{}", s.len(), s),
        }
    }
}

/// Why a parameter text could not be split into parameters.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct SplitError {
    /// 1-based index of the parameter at fault (0 for the first one, e.g. the entity type).
    pub index: usize,
    /// What is wrong.
    pub reason: String,
    /// For a token that is not a number: the token.
    pub bad_token: Option<String>,
}

/// Splits free-format text into parameters, up to the record delimiter.
///
/// `first_index` is the index given to the first parameter (0 in the Parameter Data
/// section, whose first parameter is the entity type; 1 in the Global section). Text after
/// the record delimiter is ignored (it may hold comments). Returns an error when the record
/// delimiter is missing (a truncated record), a Hollerith count runs past the text, or a
/// token is neither empty, a number nor a string.
pub(crate) fn split(
    text: &[u8],
    pd: u8,
    rd: u8,
    first_index: usize,
) -> Result<Vec<Param>, SplitError> {
    let mut out = Vec::new();
    let mut i = 0usize;
    loop {
        let index = first_index + out.len();
        while i < text.len() && text[i] == b' ' {
            i += 1;
        }
        if i >= text.len() {
            return Err(SplitError {
                index,
                reason: format!(
                    "the record ends without the record delimiter '{}' (truncated?)",
                    rd as char
                ),
                bad_token: None,
            });
        }
        // Hollerith string: digits then 'H'.
        let mut j = i;
        while j < text.len() && text[j].is_ascii_digit() {
            j += 1;
        }
        if j > i && j < text.len() && (text[j] == b'H' || text[j] == b'h') {
            let n: usize = std::str::from_utf8(&text[i..j])
                .ok()
                .and_then(|s| s.parse().ok())
                .ok_or_else(|| SplitError {
                    index,
                    reason: "Hollerith count is too large".into(),
                    bad_token: None,
                })?;
            let start = j + 1;
            let end = start
                .checked_add(n)
                .filter(|&e| e <= text.len())
                .ok_or_else(|| SplitError {
                    index,
                    reason: format!(
                        "Hollerith string of {n} characters runs past the end of the record"
                    ),
                    bad_token: None,
                })?;
            out.push(Param::Str(
                String::from_utf8_lossy(&text[start..end]).into_owned(),
            ));
            i = end;
            while i < text.len() && text[i] == b' ' {
                i += 1;
            }
            if i >= text.len() {
                return Err(SplitError {
                    index,
                    reason: format!(
                        "the record ends without the record delimiter '{}' (truncated?)",
                        rd as char
                    ),
                    bad_token: None,
                });
            }
            let c = text[i];
            i += 1;
            if c == rd {
                return Ok(out);
            }
            if c != pd {
                return Err(SplitError {
                    index,
                    reason: format!(
                        "expected a delimiter after the string, found '{}'",
                        c as char
                    ),
                    bad_token: None,
                });
            }
            continue;
        }
        // Plain token up to the next delimiter.
        let mut j = i;
        while j < text.len() && text[j] != pd && text[j] != rd {
            j += 1;
        }
        if j >= text.len() {
            return Err(SplitError {
                index,
                reason: format!(
                    "the record ends without the record delimiter '{}' (truncated?)",
                    rd as char
                ),
                bad_token: None,
            });
        }
        let token = String::from_utf8_lossy(&text[i..j]);
        out.push(parse_token(token.trim()).map_err(|reason| SplitError {
            index,
            reason,
            bad_token: Some(token.trim().to_string()),
        })?);
        i = j + 1;
        if text[j] == rd {
            return Ok(out);
        }
    }
}

/// Classifies one trimmed token: empty, integer or real.
fn parse_token(t: &str) -> Result<Param, String> {
    if t.is_empty() {
        return Ok(Param::Empty);
    }
    let digits = t.strip_prefix(['+', '-']).unwrap_or(t);
    if !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit()) {
        return t
            .parse::<i64>()
            .map(Param::Int)
            .map_err(|_| format!("expected a number, found '{t}' (integer out of range)"));
    }
    parse_real(t)
        .map(Param::Real)
        .ok_or_else(|| format!("expected a number, found '{t}'"))
}

/// Parses an IGES real: optional sign, digits with a decimal point, optional exponent
/// introduced by `E` or `D` (any case). Internal blanks are not allowed.
fn parse_real(t: &str) -> Option<f64> {
    let ok = t
        .bytes()
        .all(|b| b.is_ascii_digit() || matches!(b, b'+' | b'-' | b'.' | b'e' | b'E' | b'd' | b'D'));
    if !ok {
        return None;
    }
    let s: String = t
        .chars()
        .map(|c| if c == 'd' || c == 'D' { 'E' } else { c })
        .collect();
    // Rust accepts "inf"/"nan" spellings, which the character filter above excludes.
    let x: f64 = s.parse().ok()?;
    x.is_finite().then_some(x)
}

/// Formats a real so that it reads back to the same `f64` and is valid IGES (always a
/// decimal point, exponent with `E`).
pub fn format_real(x: f64) -> String {
    if x == 0.0 {
        return if x.is_sign_negative() {
            "-0.".into()
        } else {
            "0.".into()
        };
    }
    let e = format!("{x:e}"); // shortest round-trip: "1.5e-8", "2e0"
    let (mant, exp) = e.split_once('e').unwrap_or((&e, "0"));
    let exp: i32 = exp.parse().unwrap_or(0);
    let mut m = mant.to_string();
    if !m.contains('.') {
        m.push('.');
    }
    if (-3..=6).contains(&exp) {
        // Plain notation is shorter and more readable in this range.
        let plain = format!("{x}");
        let plain = if plain.contains('.') {
            plain
        } else {
            plain + "."
        };
        if plain.parse::<f64>().ok() == Some(x) {
            return plain;
        }
    }
    format!("{m}E{exp}")
}

/// Formats a parameter for writing.
pub(crate) fn format_param(p: &Param) -> String {
    match p {
        Param::Empty => String::new(),
        Param::Int(i) => i.to_string(),
        Param::Real(x) => format_real(*x),
        Param::Str(s) => format!("{}H{}", s.len(), s),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splits_numbers_strings_and_empties() {
        let p = split(b"126,1, 2.5D-3,,5Hab,;c, -4.E2 ; junk", b',', b';', 0).unwrap();
        assert_eq!(
            p,
            vec![
                Param::Int(126),
                Param::Int(1),
                Param::Real(2.5e-3),
                Param::Empty,
                Param::Str("ab,;c".into()),
                Param::Real(-400.0),
            ]
        );
    }

    #[test]
    fn other_delimiters() {
        let p = split(b"1/2./3HA/B/ $", b'/', b'$', 1).unwrap();
        assert_eq!(
            p,
            vec![
                Param::Int(1),
                Param::Real(2.0),
                Param::Str("A/B".into()),
                Param::Empty
            ]
        );
    }

    #[test]
    fn errors_name_the_parameter() {
        let e = split(b"110,1.,x,3.;", b',', b';', 0).unwrap_err();
        assert_eq!(e.index, 2);
        assert!(e.reason.contains("'x'"), "{}", e.reason);
        let e = split(b"110,1.,2.", b',', b';', 0).unwrap_err();
        assert!(e.reason.contains("truncated"));
        let e = split(b"1,20Habc;", b',', b';', 0).unwrap_err();
        assert_eq!(e.index, 1);
        assert!(split(b"1,1.E999;", b',', b';', 0).is_err());
        assert!(split(b"99999999999999999999;", b',', b';', 0).is_err());
    }

    #[test]
    #[allow(clippy::approx_constant)]
    fn reals_round_trip_through_text() {
        for x in [
            0.0,
            -0.0,
            1.0,
            -1.5,
            1e-8,
            1.40285071361946e-14,
            123456789.125,
            1e300,
            -2.5e-300,
            0.1,
            1.0 / 3.0,
            6.283185307179586,
        ] {
            let s = format_real(x);
            assert!(s.contains('.'), "{s}");
            match split(format!("{s};").as_bytes(), b',', b';', 0).unwrap()[0] {
                Param::Real(y) => assert_eq!(y.to_bits(), x.to_bits(), "{s}"),
                ref other => panic!("{s} read as {other:?}"),
            }
        }
    }
}
