//! Master modifier with analytic masters supplied by the caller.

use std::sync::Arc;

use geom_db::SurfaceId;
use geom_db::prelude::{Point3, Vector3};
use param::*;
use testkit::assert_close;

use crate::common::*;

/// The cylinder's side as a master grid: s around (n_s points, closed), t along z; the
/// variables scale the height (`dz`: z → z (1 + dz)) and the radius (`dr`).
struct CylMaster {
    exact: bool,
}

impl CylMaster {
    fn point(i: usize, j: usize, x: &[f64]) -> Point3 {
        let th = i as f64 / 40.0 * std::f64::consts::TAU;
        let z = j as f64 / 4.0 * 2.0;
        Point3::new(
            (1.0 + x[1]) * th.cos(),
            (1.0 + x[1]) * th.sin(),
            z * (1.0 + x[0]),
        )
    }
}

impl MasterSource for CylMaster {
    fn variable_names(&self) -> Vec<String> {
        vec!["dz".into(), "dr".into()]
    }
    fn generate(&self, x: &[f64]) -> Result<MasterGrid, param::MasterError> {
        let mut points = Vec::new();
        for j in 0..5 {
            for i in 0..41 {
                points.push(Self::point(i, j, x));
            }
        }
        Ok(MasterGrid {
            n_s: 41,
            n_t: 5,
            points,
        })
    }
    fn jacobian(&self, _x: &[f64]) -> Option<Result<Vec<Vec<Vector3>>, param::MasterError>> {
        if !self.exact {
            return None;
        }
        let mut out = Vec::new();
        for j in 0..5 {
            for i in 0..41 {
                let th = i as f64 / 40.0 * std::f64::consts::TAU;
                let z = j as f64 / 4.0 * 2.0;
                out.push(vec![
                    Vector3::new(0.0, 0.0, z),
                    Vector3::new(th.cos(), th.sin(), 0.0),
                ]);
            }
        }
        Some(Ok(out))
    }
}

fn master_param(source: &str) -> Parametrisation {
    Parametrisation {
        modifiers: vec![Modifier::Master(MasterModifier {
            name: "m".into(),
            links: Links {
                surfaces: vec![SurfaceId(0)],
                ..Links::default()
            },
            source: MasterSpec::External(source.into()),
            variables: vec![var("dz", -0.5, 0.5), var("dr", -0.5, 0.5)],
        })],
        constraints: vec![],
    }
}

fn sources(exact: bool) -> MasterSources {
    let mut m = MasterSources::new();
    m.insert(
        "cyl".into(),
        Arc::new(CylMaster { exact }) as Arc<dyn MasterSource>,
    );
    m
}

#[test]
fn master_deviation_is_interpolated_to_the_nodes() {
    let db = fixture("cylinder");
    let prep = master_param("cyl").bind(&db, &sources(true)).unwrap();
    let out = prep.apply(&[0.1, 0.0]).unwrap();
    // the height scaling is linear in t: bilinear interpolation is exact, dz·z along z
    for ids in &db.surface(SurfaceId(0)).control.nodes {
        for id in ids {
            let p0 = db.control_points()[id.index()];
            let want = p0 + Vector3::new(0.0, 0.0, 0.1 * p0.z);
            assert_close!(
                out[id.index()].coords.as_slice(),
                want.coords.as_slice(),
                abs = 1e-12
            );
        }
    }
    // radius change: every side node moves radially by dr (interpolated on the chords)
    let out = prep.apply(&[0.0, 0.05]).unwrap();
    for ids in &db.surface(SurfaceId(0)).control.nodes {
        for id in ids {
            let p0 = db.control_points()[id.index()];
            let d = out[id.index()] - p0;
            let radial = Vector3::new(p0.x, p0.y, 0.0).normalize();
            assert_close!(d.dot(&radial), 0.05, rel = 4e-3);
            assert_close!(d.z, 0.0, abs = 1e-14);
        }
    }
}

#[test]
fn master_jacobian_exact_and_by_differences() {
    let db = fixture("cylinder");
    for exact in [true, false] {
        let prep = master_param("cyl").bind(&db, &sources(exact)).unwrap();
        check_jacobian(&prep, &[0.07, -0.03], 1e-6);
    }
}

#[test]
fn master_errors_name_the_modifier() {
    let db = fixture("cylinder");
    let e = master_param("nope")
        .bind(&db, &sources(true))
        .err()
        .unwrap();
    assert!(matches!(e, Error::MissingMasterSource { .. }));
    assert!(e.to_string().contains("'nope'"), "{e}");
    let mut p = master_param("cyl");
    if let Modifier::Master(m) = &mut p.modifiers[0] {
        m.variables.swap(0, 1);
    }
    let e = p.bind(&db, &sources(true)).err().unwrap();
    assert!(e.to_string().contains("modifier 'm'"), "{e}");
}

/// A master source whose generator fails beyond a height change of 0.2 with its own typed
/// error (an `std::io::Error` of a known kind).
struct FailingMaster;

impl MasterSource for FailingMaster {
    fn variable_names(&self) -> Vec<String> {
        vec!["dz".into(), "dr".into()]
    }
    fn generate(&self, x: &[f64]) -> Result<MasterGrid, MasterError> {
        if x[0] > 0.2 {
            return Err(Box::new(std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                "height change beyond 0.2",
            )));
        }
        CylMaster { exact: true }.generate(x)
    }
}

#[test]
fn a_failing_master_source_keeps_its_typed_error() {
    let db = fixture("cylinder");
    let mut m = MasterSources::new();
    m.insert(
        "cyl".into(),
        Arc::new(FailingMaster) as Arc<dyn MasterSource>,
    );
    let prep = master_param("cyl").bind(&db, &m).unwrap();
    assert!(prep.apply(&[0.1, 0.0]).is_ok());
    let e = prep.apply(&[0.3, 0.0]).unwrap_err();
    let Error::MasterSource { modifier, source } = &e else {
        panic!("{e:?}");
    };
    assert_eq!(modifier, "m");
    let io = source
        .downcast_ref::<std::io::Error>()
        .expect("the source's own error type");
    assert_eq!(io.kind(), std::io::ErrorKind::InvalidData);
    // the chain reaches it through `Error::source` too
    let via_chain = std::error::Error::source(&e).and_then(|s| s.downcast_ref::<std::io::Error>());
    assert!(via_chain.is_some());
    assert!(e.to_string().contains("height change beyond 0.2"), "{e}");
}
