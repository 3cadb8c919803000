//! Corrupted files (real and hand-written): an error naming the place, never a panic.

use proptest::prelude::*;

use crate::{Snip, build};

fn hand_written() -> Vec<u8> {
    let s = |ty, params| Snip {
        ty,
        form: 0,
        transform: 0,
        params,
    };
    build(&[
        s(128, "128,1,1,1,1,0,0,1,0,0,0.,0.,1.,1.,0.,0.,1.,1.,1.,1.,1.,1.,0.,0.,0.,1.,0.,0.,0.,1.,0.,1.,1.,0.,0.,1.,0.,1.;"),
        s(126, "126,1,1,1,0,1,0,0.,0.,1.,1.,1.,1.,0.,0.,0.,1.,0.,0.,0.,1.,0.,0.,1.;"),
        s(110, "110,0.,0.,0.,1.,0.,0.;"),
        s(102, "102,1,3;"),
        s(142, "142,0,1,7,5,1;"),
        s(144, "144,1,1,0,9;"),
        s(124, "124,1.,0.,0.,1.,0.,1.,0.,2.,0.,0.,1.,3.;"),
        s(112, "112,3,2,3,1,0.,1.,2.,1.,2.,0.,0.,0.,1.,0.,-1.,5.,0.,0.,5.,5.,2.,0.,1.,2.,1.,0.,4.,5.,0.,0.;"),
        s(508, "508,1,0,19,1,1,0;"),
        s(504, "504,1,5,21,1,21,1;"),
        s(502, "502,1,0.,0.,0.;"),
    ])
    .into_bytes()
}

fn real() -> Vec<u8> {
    std::fs::read(crate::fixture("geom_oneram6.igs")).unwrap()
}

/// Reads, and checks that a failure is a one-line message naming the file.
fn check(bytes: &[u8]) {
    if let Err(e) = iges::read(bytes, "bad.igs") {
        let m = e.to_string();
        assert!(m.starts_with("bad.igs: "), "{m}");
        assert!(!m.contains('\n'), "{m}");
    }
}

#[test]
fn the_unmodified_files_read() {
    iges::read(&hand_written()[..], "h.igs").unwrap();
    iges::read(&real()[..], "m6.igs").unwrap();
}

#[test]
fn truncation_is_reported() {
    let h = hand_written();
    for cut in [10, 81, 300, h.len() / 2, h.len() - 82] {
        let e = iges::read(&h[..cut], "cut.igs").unwrap_err().to_string();
        assert!(e.starts_with("cut.igs: "), "{e}");
    }
    let r = real();
    let last_line = r[..r.len() - 1].iter().rposition(|&b| b == b'\n').unwrap() + 1;
    let e = iges::read(&r[..last_line], "m6.igs")
        .unwrap_err()
        .to_string();
    assert!(e.contains("Terminate"), "{e}");
}

#[test]
fn compressed_form_is_rejected() {
    let mut h = hand_written();
    h[72] = b'C';
    let e = iges::read(&h[..], "c.igs").unwrap_err().to_string();
    assert!(e.contains("compressed ASCII IGES is not supported"), "{e}");
}

#[test]
fn bad_back_pointer_names_the_entity() {
    let text = String::from_utf8(hand_written()).unwrap();
    // Point the first P line of the 110 (D5) back at D7.
    let mut done = false;
    let bad: String = text
        .lines()
        .map(|l| {
            if !done && &l[72..73] == "P" && l[64..72].trim() == "5" {
                done = true;
                format!("{}{:>8}{}\n", &l[..64], 7, &l[72..])
            } else {
                format!("{l}\n")
            }
        })
        .collect();
    assert!(done);
    let e = iges::read(bad.as_bytes(), "b.igs").unwrap_err().to_string();
    assert!(e.starts_with("b.igs: entity at D line 5 (type 110)"), "{e}");
    assert!(e.contains("back-pointer"), "{e}");
}

fn corrupt(bytes: &[u8], ops: &[(usize, u8, u8)]) -> Vec<u8> {
    let mut b = bytes.to_vec();
    for &(pos, kind, byte) in ops {
        if b.is_empty() {
            break;
        }
        let i = pos % b.len();
        let c = b" 0123456789.,;-+EDHx\n"[byte as usize % 21];
        match kind % 4 {
            0 => b[i] = c,
            1 => {
                b.remove(i);
            }
            2 => b.insert(i, c),
            _ => b.truncate(i),
        }
    }
    b
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    #[test]
    fn corrupt_hand_written_never_panics(
        ops in proptest::collection::vec((any::<usize>(), any::<u8>(), any::<u8>()), 1..6)
    ) {
        check(&corrupt(&hand_written(), &ops));
    }

    #[test]
    fn digit_changes_in_hand_written_never_panic(pos in any::<usize>(), d in 0u8..10) {
        let mut b = hand_written();
        let digits: Vec<usize> =
            (0..b.len()).filter(|&i| b[i].is_ascii_digit()).collect();
        let i = digits[pos % digits.len()];
        b[i] = b'0' + d;
        check(&b);
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    #[test]
    fn corrupt_real_file_never_panics(
        ops in proptest::collection::vec((any::<usize>(), any::<u8>(), any::<u8>()), 1..4)
    ) {
        check(&corrupt(&real(), &ops));
    }
}
