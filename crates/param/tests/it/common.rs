//! Shared geometry fixtures and parametrisations for the tests.

use std::path::PathBuf;

use geom_db::prelude::{Point3, Vector3};
use geom_db::{ControlNodeId, CurveId, GeomDb, SurfaceId};
use param::*;

pub fn fixture(name: &str) -> GeomDb {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../fixtures/geom")
        .join(format!("{name}.ron"));
    let text = std::fs::read_to_string(&p).unwrap();
    GeomDb::from_ron_str(&text, &p.display().to_string()).unwrap()
}

pub fn var(name: &str, lo: f64, hi: f64) -> DesignVariable {
    DesignVariable::new(name, lo, hi)
}

pub fn node_mod(name: &str, links: Links, axis: Axis, rot: bool, tr: [bool; 3]) -> Modifier {
    let t = |c: usize, n: &str| tr[c].then(|| var(&format!("{name}_{n}"), -1.0, 1.0));
    Modifier::Node(NodeModifier {
        name: name.into(),
        links,
        axis,
        rotation: rot.then(|| var(&format!("{name}_theta"), -3.0, 3.0)),
        translation: [t(0, "dx"), t(1, "dy"), t(2, "dz")],
    })
}

pub fn vars(prefix: &str, n: usize) -> Vec<DesignVariable> {
    (0..n)
        .map(|i| var(&format!("{prefix}{i}"), -1.0, 1.0))
        .collect()
}

/// One modifier of every kind (and both surface forms, the three line supports) on the
/// wing-body fixture.
pub fn wing_body_all() -> (GeomDb, Parametrisation) {
    let db = fixture("wing_body");
    let mods = vec![
        Modifier::Line(LineModifier {
            name: "bump".into(),
            line: LineSupport::Iso(IsoLine {
                surface: SurfaceId(1),
                fixed: Param::V,
                at: 1.0,
            }),
            links: Links::default(),
            range: Some([2.0, 4.0]),
            basis: Basis::HicksHenne {
                bumps: vec![
                    Bump {
                        peak: 0.3,
                        width: 2.0,
                    },
                    Bump {
                        peak: 0.6,
                        width: 3.0,
                    },
                ],
            },
            active: None,
            direction: Direction::Normal,
            decay: Decay::Cosine { width: 1.5 },
            variables: vars("hh", 2),
        }),
        Modifier::Line(LineModifier {
            name: "fus_top".into(),
            line: LineSupport::Curve(CurveId(2)),
            links: Links {
                surfaces: vec![SurfaceId(0)],
                ..Links::default()
            },
            range: None,
            basis: Basis::BSpline {
                degree: 3,
                n_basis: 6,
                knots: None,
            },
            active: Some(vec![1, 2, 3, 4]),
            direction: Direction::Axis(Vector3::z()),
            decay: Decay::Gaussian { width: 0.5 },
            variables: vars("ft", 4),
        }),
        Modifier::Surface(SurfaceModifier {
            name: "fus_tensor".into(),
            surfaces: vec![SurfaceId(0)],
            range_u: None,
            range_v: None,
            basis_u: Basis::BSpline {
                degree: 2,
                n_basis: 5,
                knots: Some(vec![0.0, 0.0, 0.0, 0.5, 2.0, 3.0, 3.0, 3.0]),
            },
            basis_v: Basis::Bernstein { degree: 2 },
            active_u: Some(vec![1, 2, 3]),
            active_v: None,
            direction: Direction::Normal,
            form: SurfaceForm::Tensor {
                variables: vars("tq", 9),
            },
        }),
        Modifier::Surface(SurfaceModifier {
            name: "wing_sep".into(),
            surfaces: vec![SurfaceId(1)],
            range_u: None,
            range_v: None,
            basis_u: Basis::Bernstein { degree: 4 },
            basis_v: Basis::BSpline {
                degree: 1,
                n_basis: 2,
                knots: None,
            },
            active_u: Some(vec![1, 2, 3]),
            active_v: Some(vec![1]),
            direction: Direction::Normal,
            form: SurfaceForm::Separable {
                variables_u: vars("su", 3),
                variables_v: vars("sv", 1),
            },
        }),
        node_mod(
            "tip",
            Links {
                surfaces: vec![SurfaceId(2)],
                iso_lines: vec![IsoLine {
                    surface: SurfaceId(1),
                    fixed: Param::V,
                    at: 1.0,
                }],
                ..Links::default()
            },
            Axis {
                point: Point3::new(5.53, 5.0, 0.15),
                direction: Vector3::y(),
            },
            true,
            [false, false, true],
        ),
        Modifier::Master(MasterModifier {
            name: "planform".into(),
            links: Links {
                surfaces: vec![SurfaceId(1), SurfaceId(2)],
                ..Links::default()
            },
            source: MasterSpec::Stations(StationsMaster {
                surface: SurfaceId(1),
                spanwise: Param::V,
                n_s: 41,
                n_t: 6,
                axis: Vector3::y(),
                reference: [Point3::new(3.5, 0.0, -0.1), Point3::new(5.53, 5.0, 0.15)],
                stations: vec![
                    Station {
                        t: 0.0,
                        ..Station::default()
                    },
                    Station {
                        t: 1.0,
                        twist: Some("m_twist".into()),
                        scale: Some("m_scale".into()),
                        shift: [Some("m_sweep".into()), None, Some("m_dihedral".into())],
                    },
                ],
            }),
            variables: vec![
                var("m_twist", -0.2, 0.2),
                var("m_scale", -0.5, 0.5),
                var("m_sweep", -1.0, 1.0),
                var("m_dihedral", -1.0, 1.0),
            ],
        }),
        // a displacement field along an axis (Figs. 10 and 12): the fuselage ahead of
        // x = 2 bent down and stretched forward, growing towards the nose
        Modifier::Line(LineModifier {
            name: "nose".into(),
            line: LineSupport::Axis(Axis {
                point: Point3::new(2.0, 0.0, 0.0),
                direction: Vector3::new(-2.0, 0.0, 0.0),
            }),
            links: Links {
                surfaces: vec![SurfaceId(0)],
                ..Links::default()
            },
            range: Some([0.0, 2.0]),
            basis: Basis::Bernstein { degree: 2 },
            active: Some(vec![1, 2]),
            direction: Direction::Axis(Vector3::new(0.0, 0.0, -1.0)),
            decay: Decay::Cosine { width: 3.0 },
            variables: vars("nd", 2),
        }),
    ];
    let _ = ControlNodeId(0);
    (
        db,
        Parametrisation {
            modifiers: mods,
            constraints: vec![],
        },
    )
}

/// A deterministic pseudo-random design vector within ±amp of the initial values.
pub fn some_x(reg: &Registry, amp: f64, seed: u64) -> Vec<f64> {
    let mut s = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    reg.variables()
        .iter()
        .map(|v| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let r = ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0;
            v.value + amp * r
        })
        .collect()
}

/// Checks every Jacobian column against central differences: max |J − FD| ≤ rel × max|FD|
/// of the column (+ 1e-9 for columns that are zero).
pub fn check_jacobian(p: &Prepared, x: &[f64], rel: f64) {
    let (_, j) = p.apply_with_jacobian(x).unwrap();
    let names = p.registry().names();
    for l in 0..x.len() {
        let h = 1e-5 * x[l].abs().max(1.0);
        let mut xp = x.to_vec();
        let mut xm = x.to_vec();
        xp[l] += h;
        xm[l] -= h;
        let (pp, pm) = (p.apply(&xp).unwrap(), p.apply(&xm).unwrap());
        let col = param::jacobian::column(&j, l);
        let mut scale: f64 = 0.0;
        let mut err: f64 = 0.0;
        for (k, (a, b)) in pp.iter().zip(&pm).enumerate() {
            for c in 0..3 {
                let fd = (a[c] - b[c]) / (2.0 * h);
                scale = scale.max(fd.abs());
                err = err.max((col[3 * k + c] - fd).abs());
            }
        }
        assert!(
            err <= rel * scale + 1e-9,
            "column {l} ({}): max error {err:.3e}, column size {scale:.3e}",
            names[l]
        );
    }
}
