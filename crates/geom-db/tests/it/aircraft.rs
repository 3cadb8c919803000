//! The whole transport aircraft (`fixtures/cad/make_aircraft.py`, issue 42) in its B-rep
//! forms: each imports with the default options into a closed model that passes `check`,
//! whose volume is OpenCASCADE's (`aircraft_reference.json`) within 1e-6; the copy whose
//! header says inches over numbers in metres warns with the evidence and the option that
//! reads it right, and with that option is the metre file.

use std::path::PathBuf;

use geom_db::CheckOptions;
use geom_db::import::{ImportOptions, ImportReport, LengthUnit, import_bytes};
use serde_json::Value;

fn cad_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/cad")
}

fn reference() -> Value {
    let text = std::fs::read_to_string(cad_dir().join("aircraft_reference.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

fn import(name: &str, opts: &ImportOptions) -> (geom_db::GeomDb, ImportReport) {
    let bytes = std::fs::read(cad_dir().join(name)).unwrap();
    import_bytes(&bytes, name, opts).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn aircraft_breps_import_closed_with_occ_volume() {
    let r = reference();
    for name in [
        "aircraft_brep_m.igs",
        "aircraft_faces_m.igs",
        "aircraft_ap214_m.stp",
    ] {
        let (db, rep) = import(name, &ImportOptions::default());
        let occ = &r["files"][name];
        assert_eq!(rep.shells.len(), 1, "{name}: {:?}", rep.shells);
        assert!(rep.shells[0].closed, "{name}");
        assert!(rep.non_manifold_edges.is_empty(), "{name}");
        assert_eq!(
            db.surface_components.len(),
            occ["faces"].as_array().unwrap().len(),
            "{name}"
        );
        let (v, v_occ) = (rep.shells[0].volume, occ["volume"].as_f64().unwrap());
        assert!(
            ((v - v_occ) / v_occ).abs() <= 1e-6,
            "{name}: volume {v}, OpenCASCADE's {v_occ}"
        );
        let check = db.check(&CheckOptions::default());
        assert!(check.is_ok(), "{name}: {:?}", check.problems);
        assert!(
            rep.warnings.iter().all(|w| !w.contains("--file-units")),
            "{name}"
        );
    }
}

#[test]
fn an_inch_header_over_metres_warns_and_file_units_reads_it() {
    let (_, rep) = import("aircraft_inch_header.igs", &ImportOptions::default());
    assert_eq!(rep.file_units.as_deref(), Some("in"));
    let w = rep
        .warnings
        .iter()
        .find(|w| w.contains("--file-units m"))
        .unwrap_or_else(|| panic!("no units warning: {:?}", rep.warnings));
    // the evidence: 36 inches = 0.9144 m, and 36 m when read as metres
    assert!(w.contains("36.0000 in = 0.9144 m"), "{w}");
    assert!(w.contains("36.0000 m"), "{w}");
    let opts = ImportOptions {
        file_units: LengthUnit::named("m"),
        ..ImportOptions::default()
    };
    let (_, fixed) = import("aircraft_inch_header.igs", &opts);
    let (_, metres) = import("aircraft_brep_m.igs", &ImportOptions::default());
    assert_eq!(fixed.file_units.as_deref(), Some("m"));
    assert_eq!(fixed.shells[0].volume, metres.shells[0].volume);
    assert!(fixed.warnings.iter().all(|w| !w.contains("--file-units")));
    // converting to millimetres on the way keeps the evidence in the file's numbers
    let opts = ImportOptions {
        file_units: LengthUnit::named("m"),
        units: LengthUnit::named("mm"),
        ..ImportOptions::default()
    };
    let (_, mm) = import("aircraft_inch_header.igs", &opts);
    assert!(mm.warnings.iter().all(|w| !w.contains("--file-units")));
    let v = mm.shells[0].volume * 1e-9;
    assert!((v / metres.shells[0].volume - 1.0).abs() < 1e-12, "{v}");
}
