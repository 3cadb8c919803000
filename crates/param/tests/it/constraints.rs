//! Linear inequality constraints: violations reported by name, export.

use std::collections::BTreeMap;

use param::*;

use crate::common::*;

#[test]
fn violations_are_reported_by_name() {
    let (_, mut all) = wing_body_all();
    all.constraints = vec![
        LinearConstraint {
            name: "bumps below 0.05".into(),
            coefficients: BTreeMap::from([("hh0".into(), 1.0), ("hh1".into(), 1.0)]),
            rhs: 0.05,
        },
        LinearConstraint {
            name: "twist vs dihedral".into(),
            coefficients: BTreeMap::from([("tip_theta".into(), 1.0), ("tip_dz".into(), -2.0)]),
            rhs: 0.0,
        },
    ];
    let reg = all.registry().unwrap();
    let cm = all.constraint_matrix().unwrap();
    assert_eq!(cm.a.len(), 2);
    assert_eq!(cm.a[0].len(), reg.len());
    let mut x = reg.initial();
    assert!(cm.violations(&x).is_empty());
    x[reg.index_of("hh0").unwrap()] = 0.04;
    x[reg.index_of("hh1").unwrap()] = 0.02;
    let v = cm.violations(&x);
    assert_eq!(v.len(), 1);
    assert_eq!(v[0].name, "bumps below 0.05");
    assert!((v[0].lhs - 0.06).abs() < 1e-15);
    assert!(v[0].to_string().contains("bumps below 0.05"));
    x[reg.index_of("tip_theta").unwrap()] = 0.1;
    let names: Vec<String> = cm.violations(&x).into_iter().map(|v| v.name).collect();
    assert_eq!(names, ["bumps below 0.05", "twist vs dihedral"]);
    // JSON export
    let mut buf = Vec::new();
    cm.write_json(&mut buf).unwrap();
    let j: serde_json::Value = serde_json::from_slice(&buf).unwrap();
    assert_eq!(j["names"][1], "twist vs dihedral");
    assert_eq!(j["a"][1][reg.index_of("tip_dz").unwrap()], -2.0);
}

#[test]
fn unknown_variable_in_constraint_is_named() {
    let (_, mut all) = wing_body_all();
    all.constraints = vec![LinearConstraint {
        name: "c1".into(),
        coefficients: BTreeMap::from([("ghost".into(), 1.0)]),
        rhs: 0.0,
    }];
    let e = all.constraint_matrix().unwrap_err();
    assert!(
        e.to_string().contains("constraint 'c1'") && e.to_string().contains("'ghost'"),
        "{e}"
    );
}
