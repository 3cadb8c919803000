//! Reading real coordinate files: Selig, Lednicer, blunt trailing edges, stray headers.

use testkit::assert_close;
use wingmaster::Airfoil;

use crate::load;

#[test]
fn lednicer_equals_selig() {
    let s = load("naca2412.dat");
    let l = load("naca2412-lednicer.dat");
    assert_eq!(s.points.len(), 69);
    assert_eq!(l.points, s.points);
}

#[test]
fn blunt_trailing_edge_thickness() {
    let a = load("sc20714.dat").normalise().unwrap();
    // Upper TE at z = −0.0095, lower at −0.0165 (chord 1): gap 0.007.
    assert_close!(a.te_thickness, 0.007, rel = 1e-2);
    let b = load("naca0012.dat").normalise().unwrap();
    assert_close!(b.te_thickness, 2.0 * 0.00126, rel = 1e-3);
    assert_eq!(b.points[b.le_index], [0.0, 0.0]);
    // The trailing-edge midpoint maps to (1, 0).
    let n = b.points.len();
    assert_close!(
        0.5 * (b.points[0][0] + b.points[n - 1][0]),
        1.0,
        rel = 1e-12
    );
}

#[test]
fn stray_header_trailer_and_blank_lines() {
    let t = load("tasopt-c110.dat");
    assert_eq!(t.name, "NC110");
    assert_eq!(t.points[0], [1.0, -0.1406310E-15]);
    let h = load("hn276sa.dat");
    assert!(h.warnings.iter().any(|w| w.contains("ignored")));
    assert_eq!(*h.points.last().unwrap(), [1.0, 0.0]);
    let b = load("hs1430.dat");
    assert_eq!(b.points.len(), 123);
}

#[test]
fn truncated_surface_is_normalised_on_the_complete_one() {
    let a = load("mh112.dat").normalise().unwrap();
    assert_eq!(a.te_thickness, 0.0);
    assert_close!(a.frame.chord, 1.0, rel = 1e-4);
}

#[test]
fn duplicated_leading_edge_point_is_merged() {
    let s = "foil\n1 0\n0.5 0.06\n0.1 0.04\n0 0\n0 0\n0.1 -0.03\n0.5 -0.04\n1 0\n0.7 0.05\n";
    let a = Airfoil::parse(s.as_bytes(), "dup.dat").unwrap();
    assert_eq!(a.points.len(), 8);
}

#[test]
fn errors_name_file_and_line() {
    let e = Airfoil::parse("foil\n1 0\n0.5 x\n".as_bytes(), "bad.dat").unwrap_err();
    assert!(e.to_string().starts_with("bad.dat:"), "{e}");
    let e = Airfoil::parse("foil\n2. 3.\n0 0\n1 0\n".as_bytes(), "led.dat").unwrap_err();
    assert!(e.to_string().contains("led.dat:2"), "{e}");
    let e = Airfoil::parse("just a name\n".as_bytes(), "empty.dat").unwrap_err();
    assert!(e.to_string().contains("no coordinate"), "{e}");
}

#[test]
fn all_shared_airfoils_load_and_normalise() {
    // The whole UIUC-derived set when present (it is outside the repository).
    let dir = std::path::Path::new("/work/shared/data/airfoils");
    let Ok(rd) = std::fs::read_dir(dir) else {
        return;
    };
    let mut n = 0;
    for e in rd {
        let p = e.unwrap().path();
        let f = std::fs::File::open(&p).unwrap();
        let a = Airfoil::parse(std::io::BufReader::new(f), &p.display().to_string())
            .unwrap_or_else(|e| panic!("{e}"));
        let na = a
            .normalise()
            .unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        assert!(na.le_index > 3 && na.le_index + 4 < na.points.len());
        n += 1;
    }
    assert!(n >= 60);
}
