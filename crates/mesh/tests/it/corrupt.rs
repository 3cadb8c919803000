//! Readers on truncated and corrupted files: an error (naming the file) or a valid grid,
//! never a panic.

use mesh::io::Format;
use mesh::msh::Encoding;
use mesh::vtu::VtuEncoding;
use proptest::prelude::*;

fn sample(f: Format) -> Vec<u8> {
    let mut m = mesh::generate::box_tets(2, 2, 1, [0.0; 3], [1.0; 3]);
    if let Format::Msh(_) = f {
        // Exercise the parametric and entity paths too.
        m = mesh::msh::read(&write(&m, f)[..], "a.msh".as_ref()).unwrap();
    }
    write(&m, f)
}

fn write(m: &mesh::Mesh, f: Format) -> Vec<u8> {
    let mut buf = Vec::new();
    mesh::io::write(m, f, &mut buf).unwrap();
    buf
}

fn read(f: Format, data: &[u8]) -> mesh::Result<mesh::Mesh> {
    let name = std::path::Path::new("corrupt.grid");
    match f {
        Format::Su2 => mesh::su2::read(data, name),
        Format::Msh(_) => mesh::msh::read(data, name),
        Format::Vtu(_) => mesh::vtu::read(data, name),
        Format::Foam => unreachable!("OpenFOAM cases are directories: tests/it/foam.rs"),
    }
}

const FORMATS: [Format; 5] = [
    Format::Su2,
    Format::Msh(Encoding::Ascii),
    Format::Msh(Encoding::Binary),
    Format::Vtu(VtuEncoding::AppendedRaw),
    Format::Vtu(VtuEncoding::Base64),
];

proptest! {
    #![proptest_config(ProptestConfig {
        cases: std::env::var("MESH_FUZZ_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(48),
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x5eed_3e54),
        ..ProptestConfig::default()
    })]

    #[test]
    fn truncated_files_give_errors(which in 0usize..5, frac in 0.0f64..1.0) {
        let f = FORMATS[which];
        let data = sample(f);
        let cut = ((data.len() as f64) * frac) as usize;
        let kept = &data[..cut];
        match read(f, kept) {
            Err(e) => prop_assert!(e.to_string().starts_with("corrupt.grid: "), "{}", e),
            // Only whitespace (or nothing the grid needs) may have been cut.
            Ok(m) => {
                // A number cut in the last line of a text file without a terminator cannot be
                // told from a shorter number: SU2 accepts it (as SU2 itself does).
                let last_line = !data[cut..data.len() - 1].contains(&b'\n');
                prop_assert!(data[cut..].iter().all(|c| c.is_ascii_whitespace())
                    || (f == Format::Su2 && last_line),
                    "{:?}: cut at {} of {} accepted", f, cut, data.len());
                m.validate().unwrap();
            }
        }
    }

    #[test]
    fn corrupted_bytes_never_panic(which in 0usize..5, pos in 0.0f64..1.0, byte in any::<u8>(), n in 1usize..4) {
        let f = FORMATS[which];
        let mut data = sample(f);
        let len = data.len();
        for k in 0..n {
            let p = ((len as f64 * pos) as usize + 37 * k) % len;
            data[p] = byte.wrapping_add(k as u8);
        }
        match read(f, &data) {
            Err(e) => prop_assert!(e.to_string().starts_with("corrupt.grid: ") || matches!(e, mesh::Error::Invalid { .. }), "{}", e),
            Ok(m) => m.validate().unwrap(),
        }
    }
}

#[test]
fn huge_counts_in_headers_do_not_allocate_or_panic() {
    let msh = String::from_utf8(sample(Format::Msh(Encoding::Ascii))).unwrap();
    // Announce four billion nodes with tags up to 4e9: a wrong count, not an allocation.
    let i = msh.find("$Nodes\n").unwrap() + 7;
    let j = i + msh[i..].find('\n').unwrap();
    let fields: Vec<&str> = msh[i..j].split(' ').collect();
    let bad = format!(
        "{}{} 4000000000 1 4000000000{}",
        &msh[..i],
        fields[0],
        &msh[j..]
    );
    let e = mesh::msh::read(bad.as_bytes(), "big.msh".as_ref()).unwrap_err();
    assert!(e.to_string().starts_with("big.msh: line "), "{e}");
    let su2 = "NDIME= 3\nNELEM= 4000000000\n10 0 1 2 3\n";
    let e = mesh::su2::read(su2.as_bytes(), "big.su2".as_ref()).unwrap_err();
    assert!(e.to_string().starts_with("big.su2: line "), "{e}");
    let vtu = String::from_utf8(sample(Format::Vtu(VtuEncoding::Base64))).unwrap();
    let bad = vtu.replacen(
        "NumberOfPoints=\"",
        "NumberOfPoints=\"9999999999999999999",
        1,
    );
    let e = mesh::vtu::read(bad.as_bytes(), "big.vtu".as_ref()).unwrap_err();
    assert!(e.to_string().starts_with("big.vtu: "), "{e}");
}
