//! Corrupt IGES and STEP files (issue 19): the OpenCASCADE fixtures mutated byte by byte
//! (replaced, deleted, duplicated, truncated) either still import or give a one-line error
//! that names the file and the place (line, entity or instance), never a panic.

use std::path::PathBuf;

use geom_db::import::{ImportOptions, import_bytes};
use proptest::prelude::*;

/// Small fixtures of both formats and of both IGES modes.
const FILES: [&str; 4] = [
    "body_revolved_faces_m.igs",
    "body_nurbs_ap242_m.stp",
    "split_wing_brep_m.igs",
    "split_wing_ap214_m.stp",
];

fn bytes(name: &str) -> Vec<u8> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/cad")
        .join(name);
    std::fs::read(path).unwrap()
}

/// One mutation: at a position (fraction of the length), what to do.
#[derive(Debug, Clone)]
enum Mutation {
    Replace(f64, u8),
    Delete(f64, usize),
    Duplicate(f64, usize),
    Truncate(f64),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    let nasty = prop::sample::select(b"0123456789-+.eE,;()#'=*$HX \n/".to_vec());
    prop_oneof![
        4 => (0.0..1.0f64, nasty).prop_map(|(p, c)| Mutation::Replace(p, c)),
        2 => (0.0..1.0f64, 1..40usize).prop_map(|(p, n)| Mutation::Delete(p, n)),
        1 => (0.0..1.0f64, 1..40usize).prop_map(|(p, n)| Mutation::Duplicate(p, n)),
        1 => (0.0..1.0f64).prop_map(Mutation::Truncate),
    ]
}

fn apply(mut b: Vec<u8>, m: &Mutation) -> Vec<u8> {
    let at = |p: f64, len: usize| ((p * len as f64) as usize).min(len.saturating_sub(1));
    match *m {
        Mutation::Replace(p, c) => {
            // (an earlier truncation may have left nothing to replace)
            if !b.is_empty() {
                let i = at(p, b.len());
                b[i] = c;
            }
        }
        Mutation::Delete(p, n) => {
            let i = at(p, b.len());
            let j = (i + n).min(b.len());
            b.drain(i..j);
        }
        Mutation::Duplicate(p, n) => {
            let i = at(p, b.len());
            let j = (i + n).min(b.len());
            let piece = b[i..j].to_vec();
            b.splice(j..j, piece);
        }
        Mutation::Truncate(p) => b.truncate(at(p, b.len())),
    }
    b
}

/// The error names the file first, then where: a line, a directory entry or parameter of
/// an IGES entity, a STEP instance or the section or structure at fault.
fn names_a_place(msg: &str, file: &str) -> bool {
    let Some(rest) = msg.strip_prefix(&format!("{file}: ")) else {
        return false;
    };
    [
        "line ",
        "entity",
        "#",
        "parameter",
        "section",
        "Terminate",
        "directory",
        "unit",
        "no surface",
        "ends",
        "header",
        "HEADER",
        "DATA",
        "empty",
    ]
    .iter()
    .any(|w| rest.contains(w))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn mutated_fixtures_import_or_name_the_place(
        file in 0..FILES.len(),
        muts in prop::collection::vec(mutation(), 1..4),
    ) {
        let name = FILES[file];
        let mut b = bytes(name);
        for m in &muts {
            b = apply(b, m);
        }
        match import_bytes(&b, name, &ImportOptions::default()) {
            Ok((db, _)) => prop_assert!(db.validate().is_ok()),
            Err(e) => {
                let msg = e.to_string();
                prop_assert!(!msg.contains('\n'), "two lines: {msg}");
                prop_assert!(names_a_place(&msg, name), "names no place: {msg}");
            }
        }
    }
}

#[test]
fn a_corrupt_face_pointer_names_the_entity() {
    // The STEP wing's ADVANCED_FACE points at a surface instance that does not exist.
    let name = "split_wing_ap214_m.stp";
    let text = String::from_utf8(bytes(name)).unwrap();
    let line = text
        .lines()
        .find(|l| l.contains("ADVANCED_FACE"))
        .expect("a face")
        .to_string();
    let open = line.find('(').unwrap();
    let args = &line[open..];
    let last_ref = args.rfind('#').unwrap();
    let end = args[last_ref..].find(',').unwrap() + last_ref;
    let bad = format!(
        "{}{}#999999{}",
        &line[..open],
        &args[..last_ref],
        &args[end..]
    );
    let corrupt = text.replacen(&line, &bad, 1);
    let err = import_bytes(corrupt.as_bytes(), name, &ImportOptions::default())
        .unwrap_err()
        .to_string();
    let id = line.split('=').next().unwrap().trim();
    assert!(err.starts_with(name), "{err}");
    assert!(err.contains(id) || err.contains("#999999"), "{err}");
}
