//! Tests of the SU2 reader and writer: the integer scan, block boundaries, round trips.

use super::lines::{eight_digits, scan_uints};
use super::read::read_by_blocks;
use super::write::{WRITE_BATCH, WRITE_BLOCK};
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
        seq.extend_from_slice(format!("{}\t{}\t{id}\n", kind.vtk_code(), ns.join("\t")).as_bytes());
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
