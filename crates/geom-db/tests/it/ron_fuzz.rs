//! The RON loader on mangled files: errors, never panics.

use geom_db::GeomDb;
use proptest::prelude::*;

use crate::fixture_text;

fn load_bytes(bytes: &[u8]) -> Result<GeomDb, geom_db::Error> {
    GeomDb::read_ron(bytes, "mangled.ron")
}

/// Byte ranges of the numbers (after a '(' '[' or ' ', outside strings) in the text.
fn number_spans(text: &str) -> Vec<(usize, usize)> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    let mut in_string = false;
    while i < b.len() {
        if b[i] == b'"' {
            in_string = !in_string;
        }
        let starts = !in_string
            && (b[i].is_ascii_digit() || b[i] == b'-')
            && i > 0
            && matches!(b[i - 1], b'(' | b' ' | b'[');
        if starts {
            let j = i + b[i..]
                .iter()
                .position(|c| !(c.is_ascii_digit() || matches!(c, b'.' | b'-' | b'e' | b'+')))
                .unwrap_or(b.len() - i);
            out.push((i, j));
            i = j;
        } else {
            i += 1;
        }
    }
    out
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn truncated_files_are_errors(which in 0usize..3, frac in 0.0..0.995f64) {
        let text = fixture_text(["sphere.ron", "cylinder.ron", "wing_body.ron"][which]);
        let cut = (text.len() as f64 * frac) as usize;
        let r = load_bytes(&text.as_bytes()[..cut]);
        prop_assert!(r.is_err());
    }

    #[test]
    fn byte_flips_never_panic(which in 0usize..3, flips in proptest::collection::vec((0.0..1.0f64, any::<u8>()), 1..6)) {
        let text = fixture_text(["sphere.ron", "cylinder.ron", "wing_body.ron"][which]);
        let mut b = text.into_bytes();
        for (f, byte) in flips {
            let i = ((b.len() as f64 * f) as usize).min(b.len() - 1);
            b[i] = byte;
        }
        // Ok (a flip inside a name or a digit) or Err: never a panic
        let _ = load_bytes(&b);
    }

    #[test]
    fn bad_numbers_are_errors(which in 0usize..3, pick in 0.0..1.0f64, bad in 0usize..4) {
        let text = fixture_text(["sphere.ron", "cylinder.ron", "wing_body.ron"][which]);
        let spans = number_spans(&text);
        let (a, b) = spans[((spans.len() as f64 * pick) as usize).min(spans.len() - 1)];
        let repl = ["NaN", "inf", "-inf", "1e400"][bad];
        let mangled = format!("{}{}{}", &text[..a], repl, &text[b..]);
        let r = load_bytes(mangled.as_bytes());
        prop_assert!(r.is_err(), "{repl} at byte {a} accepted");
        let msg = r.unwrap_err().to_string();
        prop_assert!(msg.starts_with("mangled.ron"), "{msg}");
    }
}

#[test]
fn nan_injection_names_the_entity() {
    let text = fixture_text("cylinder.ron");
    let spans = number_spans(&text);
    // the first number is format_version; the second the first corner's x
    let (a, b) = spans[1];
    let mangled = format!("{}NaN{}", &text[..a], &text[b..]);
    let e = load_bytes(mangled.as_bytes()).unwrap_err();
    assert_eq!(e.to_string(), "mangled.ron: corner 0: coordinate x is NaN");
}

#[test]
fn garbage_and_empty_input() {
    assert!(load_bytes(b"").is_err());
    assert!(load_bytes(&[0xff, 0xfe, 0x00]).is_err());
    assert!(load_bytes("((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((((".as_bytes()).is_err());
    let deep = "[".repeat(100_000);
    assert!(load_bytes(deep.as_bytes()).is_err());
}
