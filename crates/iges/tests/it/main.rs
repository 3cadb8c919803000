//! Integration tests of the `iges` crate's public API.

// Values below are copied from IGES files, not meant as the constants they resemble.
#![allow(clippy::approx_constant, clippy::excessive_precision)]

mod corrupt;
mod real_file;
mod roundtrip;
mod snippets;

use std::path::PathBuf;

/// Path of a file in the workspace's `fixtures/iges/`.
pub fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/iges")
        .join(name)
}

/// One hand-written entity for [`build`]: type, form, transformation pointer and the
/// parameter data text (with the type number first and `;` at the end).
pub struct Snip<'a> {
    /// Entity type number.
    pub ty: i32,
    /// Form number.
    pub form: i32,
    /// Transformation matrix pointer (0 for none).
    pub transform: u32,
    /// Parameter data text.
    pub params: &'a str,
}

/// Lays out hand-written parameter texts as a fixed-format IGES file (columns, sequence
/// numbers, pointers and back-pointers), so that tests only write the parameters.
pub fn build(snips: &[Snip]) -> String {
    let line = |data: &str, letter: char, seq: usize| format!("{data:72}{letter}{seq:7}\n");
    let mut out = line("hand-written test file", 'S', 1);
    out += &line(
        "1H,,1H;,4Htest,8Htest.igs,4Higes,3H0.1,32,38,6,308,15,4Htest,1.,2,",
        'G',
        1,
    );
    out += &line(
        "2HMM,1,0.,13H260101.000000,1.E-6,100.,4Htest,4Htest,11,0;",
        'G',
        2,
    );
    let mut d = String::new();
    let mut p = String::new();
    let mut p_seq = 1;
    for (k, s) in snips.iter().enumerate() {
        let de = 2 * k + 1;
        let mut lines: Vec<String> = vec![String::new()];
        for tok in s.params.split_inclusive([',', ';']) {
            if lines.last().unwrap().len() + tok.len() > 64 {
                lines.push(String::new());
            }
            lines.last_mut().unwrap().push_str(tok);
        }
        d += &format!(
            "{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}D{:7}\n",
            s.ty, p_seq, 0, 0, 0, 0, s.transform, 0, "00000000", de
        );
        d += &format!(
            "{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}{:>8}D{:7}\n",
            s.ty,
            0,
            0,
            lines.len(),
            s.form,
            "",
            "",
            "",
            0,
            de + 1
        );
        for l in &lines {
            p += &format!("{l:64}{de:>8}P{p_seq:7}\n");
            p_seq += 1;
        }
    }
    out += &d;
    out += &p;
    out += &line(
        &format!("S{:7}G{:7}D{:7}P{:7}", 1, 2, 2 * snips.len(), p_seq - 1),
        'T',
        1,
    );
    out
}
