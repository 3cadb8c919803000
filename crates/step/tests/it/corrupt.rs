//! Corrupted files: an error naming the file (and line or instance), never a panic.

use proptest::prelude::*;

fn files() -> Vec<(String, Vec<u8>)> {
    ["box_ap214.stp", "cylinder_ap203.stp", "nurbs_ap242.stp"]
        .iter()
        .map(|n| (n.to_string(), std::fs::read(crate::data(n)).unwrap()))
        .collect()
}

/// Parses, and checks that a failure is a one-line message naming the file and a line or
/// an instance; then asks for the units of every context (the other consumer of references).
fn check(bytes: &[u8]) {
    match step::parse(bytes, "bad.stp") {
        Err(e) => {
            let m = e.to_string();
            assert!(m.starts_with("bad.stp: "), "{m}");
            assert!(!m.contains('\n'), "{m}");
            assert!(m.contains("line "), "{m}");
        }
        Ok(f) => {
            for (inst, e) in f.iter() {
                if let step::Entity::Context(_) = e {
                    let _ = f.units(inst.id);
                }
            }
        }
    }
}

#[test]
fn truncations_are_reported() {
    for (_, b) in files() {
        for cut in [0, 10, 100, b.len() / 3, b.len() / 2, b.len() - 30] {
            let e = step::parse(&b[..cut], "cut.stp").unwrap_err().to_string();
            assert!(e.starts_with("cut.stp: line "), "{e}");
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    #[test]
    fn byte_changes_never_panic(
        which in 0usize..3,
        edits in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>(), 0u8..3), 1..6),
    ) {
        let (_, mut b) = files().swap_remove(which);
        for (at, byte, op) in edits {
            let i = at.index(b.len().max(1));
            match op {
                0 => b[i] = byte,
                1 => b.insert(i, byte),
                _ => { b.remove(i); }
            }
        }
        check(&b);
    }

    #[test]
    fn token_changes_never_panic(
        which in 0usize..3,
        edits in prop::collection::vec(
            (any::<prop::sample::Index>(), prop::sample::select(vec![
                "#99999", "$", "*", "(", ")", ",", ";", "'", ".T.", "1.E400", "-", "#1",
                "(#1,#1)", "()", "((1.,2.),(3.))", "/*", "ENDSEC;", "=",
            ])),
            1..4,
        ),
    ) {
        let (_, b) = files().swap_remove(which);
        let mut s = String::from_utf8(b).unwrap();
        for (at, tok) in edits {
            let mut i = at.index(s.len().max(1));
            while !s.is_char_boundary(i) {
                i -= 1;
            }
            s.insert_str(i, tok);
        }
        check(s.as_bytes());
    }
}
