//! The exact Jacobian against central differences, for every modifier type alone and for
//! the composition, at non-zero design vectors (the rotation is nonlinear in θ).

use param::*;

use crate::common::*;

#[test]
fn jacobian_matches_central_differences_for_every_modifier() {
    let (db, all) = wing_body_all();
    for m in &all.modifiers {
        let p = Parametrisation {
            modifiers: vec![m.clone()],
            constraints: vec![],
        };
        let prep = p.bind(&db, &MasterSources::new()).unwrap();
        for seed in [1, 2] {
            let x = some_x(prep.registry(), 0.15, seed);
            check_jacobian(&prep, &x, 1e-6);
        }
    }
}

#[test]
fn jacobian_of_the_composition() {
    let (db, all) = wing_body_all();
    let prep = all.bind(&db, &MasterSources::new()).unwrap();
    let x = some_x(prep.registry(), 0.1, 7);
    check_jacobian(&prep, &x, 1e-6);
}

#[test]
fn jacobian_is_sparse_for_local_modifiers() {
    let (db, all) = wing_body_all();
    let prep = all.bind(&db, &MasterSources::new()).unwrap();
    let x = some_x(prep.registry(), 0.1, 9);
    let (_, j) = prep.apply_with_jacobian(&x).unwrap();
    assert_eq!(j.rows(), 3 * db.control_points().len());
    assert!(j.nnz() < j.rows() * j.cols() / 2, "nnz {}", j.nnz());
    // the JSON export carries the CSR arrays
    let mut buf = Vec::new();
    param::jacobian::write_json(&j, &prep.registry().names(), &mut buf).unwrap();
    let v: serde_json::Value = serde_json::from_slice(&buf).unwrap();
    assert_eq!(v["values"].as_array().unwrap().len(), j.nnz());
    assert_eq!(v["variables"].as_array().unwrap().len(), j.cols());
    // dense and sparse agree
    let d = j.to_dense();
    for r in (0..j.rows()).step_by(7) {
        for c in 0..j.cols() {
            assert_eq!(d[[r, c]], j.get(r, c).copied().unwrap_or(0.0));
        }
    }
}
