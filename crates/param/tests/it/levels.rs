//! The four levels: zero perturbation is the identity bit for bit, analytic values, the
//! rotation convention and θ then −θ.

use geom_db::eval::ParamSurface;
use geom_db::prelude::{Point3, Vector3};
use geom_db::{SurfaceId, control};
use param::*;
use testkit::assert_close;

use crate::common::*;

fn bits(p: &[Point3]) -> Vec<u64> {
    p.iter()
        .flat_map(|q| q.coords.iter().map(|c| c.to_bits()).collect::<Vec<_>>())
        .collect()
}

#[test]
fn zero_design_vector_is_identity_for_every_modifier_and_the_composition() {
    let (db, all) = wing_body_all();
    // each modifier alone
    for m in &all.modifiers {
        let p = Parametrisation {
            modifiers: vec![m.clone()],
            constraints: vec![],
        };
        let prep = p.bind(&db, &MasterSources::new()).unwrap();
        let x0 = prep.registry().initial();
        let out = prep.apply(&x0).unwrap();
        assert_eq!(bits(&out), bits(db.control_points()), "{}", m.name());
        let (out, _) = prep.apply_with_jacobian(&x0).unwrap();
        assert_eq!(bits(&out), bits(db.control_points()), "{}", m.name());
    }
    // the composition
    let prep = all.bind(&db, &MasterSources::new()).unwrap();
    let out = prep.apply(&prep.registry().initial()).unwrap();
    assert_eq!(bits(&out), bits(db.control_points()));
    // and a non-trivial vector moves something
    let x = some_x(prep.registry(), 0.01, 3);
    let moved = prep.apply(&x).unwrap();
    assert_ne!(bits(&moved), bits(db.control_points()));
}

#[test]
fn every_modifier_moves_its_nodes_only() {
    let (db, all) = wing_body_all();
    for (m, (_, _, count)) in all
        .modifiers
        .iter()
        .zip(all.bind(&db, &MasterSources::new()).unwrap().summary())
    {
        assert!(*count > 0, "{} moves no node", m.name());
    }
}

fn cylinder_side_line(basis: Basis, decay: Decay, n: usize) -> Parametrisation {
    Parametrisation {
        modifiers: vec![Modifier::Line(LineModifier {
            name: "l".into(),
            line: LineSupport::Iso(IsoLine {
                surface: SurfaceId(0),
                fixed: Param::V,
                at: 1.0,
            }),
            links: Links::default(),
            range: None,
            basis,
            active: None,
            direction: Direction::Normal,
            decay,
            variables: vars("q", n),
        })],
        constraints: vec![],
    }
}

/// Radial unit vector of the cylinder at a point.
fn radial(p: &Point3) -> Vector3 {
    Vector3::new(p.x, p.y, 0.0).normalize()
}

#[test]
fn line_on_cylinder_matches_eq36() {
    let db = fixture("cylinder");
    let p = cylinder_side_line(
        Basis::Bernstein { degree: 3 },
        Decay::Cosine { width: 1.0 },
        4,
    );
    let prep = p.bind(&db, &MasterSources::new()).unwrap();
    let x = [0.01, -0.02, 0.03, 0.015];
    let out = prep.apply(&x).unwrap();
    let side = db.surface(SurfaceId(0));
    let xu = control::nodes(8);
    let mut seen = std::collections::BTreeSet::new();
    for (pi, ids) in side.control.nodes.iter().enumerate() {
        for (a, &xa) in xu.iter().enumerate() {
            for (b, &v) in [0.0, 1.0].iter().enumerate() {
                let id = ids[a * 2 + b].index();
                if !seen.insert(id) {
                    continue; // the seam node takes its first occurrence's parameters
                }
                let s = (pi as f64 + xa) / 4.0;
                let q: f64 = (0..4)
                    .map(|i| x[i] * geom_db::bspline::bernstein(3, i, s))
                    .sum();
                let w = if v == 1.0 { 1.0 } else { 0.0 }; // cosine decay, width 1
                let p0 = db.control_points()[id];
                let want = p0 + radial(&p0) * (q * w);
                assert_close!(
                    out[id].coords.as_slice(),
                    want.coords.as_slice(),
                    rel = 0.0,
                    abs = 1e-8
                );
            }
        }
    }
}

#[test]
fn surface_tensor_on_cylinder_matches_eq38_and_separable_eq37() {
    let db = fixture("cylinder");
    let mk = |form| Parametrisation {
        modifiers: vec![Modifier::Surface(SurfaceModifier {
            name: "s".into(),
            surfaces: vec![SurfaceId(0)],
            range_u: None,
            range_v: None,
            basis_u: Basis::BSpline {
                degree: 2,
                n_basis: 4,
                knots: None,
            },
            basis_v: Basis::Bernstein { degree: 1 },
            active_u: None,
            active_v: None,
            direction: Direction::Normal,
            form,
        })],
        constraints: vec![],
    };
    let kv = geom_db::bspline::KnotVector::clamped_uniform(2, 4).unwrap();
    let tensor = mk(SurfaceForm::Tensor {
        variables: vars("t", 8),
    });
    let x: Vec<f64> = (0..8).map(|i| 0.01 * (i as f64 - 3.5)).collect();
    let out = tensor
        .bind(&db, &MasterSources::new())
        .unwrap()
        .apply(&x)
        .unwrap();
    let sep = mk(SurfaceForm::Separable {
        variables_u: vars("a", 4),
        variables_v: vars("b", 2),
    });
    let xs = [0.1, -0.2, 0.3, 0.05, 0.4, -0.3];
    let outs = sep
        .bind(&db, &MasterSources::new())
        .unwrap()
        .apply(&xs)
        .unwrap();
    let side = db.surface(SurfaceId(0));
    let xu = control::nodes(8);
    let mut seen = std::collections::BTreeSet::new();
    for (pi, ids) in side.control.nodes.iter().enumerate() {
        for (a, &xa) in xu.iter().enumerate() {
            for (b, &v) in [0.0f64, 1.0].iter().enumerate() {
                let id = ids[a * 2 + b].index();
                if !seen.insert(id) {
                    continue;
                }
                let hu = kv.eval_all((pi as f64 + xa) / 4.0);
                let hv = [1.0 - v, v];
                let mut q = 0.0;
                for i in 0..4 {
                    for j in 0..2 {
                        q += x[i * 2 + j] * hu[i] * hv[j];
                    }
                }
                let p0 = db.control_points()[id];
                let want = p0 + radial(&p0) * q;
                assert_close!(
                    out[id].coords.as_slice(),
                    want.coords.as_slice(),
                    abs = 1e-8
                );
                let qu: f64 = (0..4).map(|i| xs[i] * hu[i]).sum();
                let qv: f64 = (0..2).map(|j| xs[4 + j] * hv[j]).sum();
                let want = p0 + radial(&p0) * (qu * qv);
                assert_close!(
                    outs[id].coords.as_slice(),
                    want.coords.as_slice(),
                    abs = 1e-8
                );
            }
        }
    }
}

fn z_rotation(theta_var: bool) -> Parametrisation {
    Parametrisation {
        modifiers: vec![node_mod(
            "n",
            Links {
                surfaces: vec![SurfaceId(0)],
                ..Links::default()
            },
            Axis {
                point: Point3::new(0.0, 0.0, 5.0),
                direction: Vector3::new(0.0, 0.0, 2.0),
            },
            theta_var,
            [true, true, true],
        )],
        constraints: vec![],
    }
}

#[test]
fn node_rotation_is_right_handed_and_translates() {
    let db = fixture("cylinder");
    let prep = z_rotation(true).bind(&db, &MasterSources::new()).unwrap();
    let th = 0.3;
    let t = [0.1, -0.2, 0.05];
    let out = prep.apply(&[th, t[0], t[1], t[2]]).unwrap();
    for (id, p0) in db.control_points().iter().enumerate() {
        let on_side = db
            .surface(SurfaceId(0))
            .control
            .nodes
            .iter()
            .flatten()
            .any(|n| n.index() == id);
        let want = if on_side {
            // right-handed rotation about +z by θ: (x, y) → (x cos θ − y sin θ, x sin θ + y cos θ)
            Point3::new(
                p0.x * th.cos() - p0.y * th.sin() + t[0],
                p0.x * th.sin() + p0.y * th.cos() + t[1],
                p0.z + t[2],
            )
        } else {
            *p0
        };
        assert_close!(
            out[id].coords.as_slice(),
            want.coords.as_slice(),
            abs = 1e-14
        );
    }
}

#[test]
fn rotation_then_inverse_rotation_is_identity() {
    let db = fixture("wing_body");
    let p = Parametrisation {
        modifiers: vec![node_mod(
            "n",
            Links {
                surfaces: vec![SurfaceId(1), SurfaceId(2)],
                ..Links::default()
            },
            Axis {
                point: Point3::new(3.5, 0.3, -0.1),
                direction: Vector3::new(0.1, 1.0, 0.2),
            },
            true,
            [false, false, false],
        )],
        constraints: vec![],
    };
    for th in [0.05, -0.4, 1.3] {
        let p1 = p
            .bind(&db, &MasterSources::new())
            .unwrap()
            .apply(&[th])
            .unwrap();
        let db1 = db.with_control_points(&p1).unwrap();
        let p2 = p
            .bind(&db1, &MasterSources::new())
            .unwrap()
            .apply(&[-th])
            .unwrap();
        let a: Vec<f64> = p2
            .iter()
            .flat_map(|q| q.coords.iter().copied().collect::<Vec<_>>())
            .collect();
        let b: Vec<f64> = db
            .control_points()
            .iter()
            .flat_map(|q| q.coords.iter().copied().collect::<Vec<_>>())
            .collect();
        assert_close!(a, b, rel = 0.0, abs = 1e-13 * db.reference_length());
    }
}

#[test]
fn node_composition_carries_earlier_perturbations() {
    // bump then rotation: the bumped shape is rotated rigidly; rotation then bump: the bump
    // is added along the initial normal after the rotation.
    let db = fixture("cylinder");
    let line = cylinder_side_line(Basis::Bernstein { degree: 2 }, Decay::Uniform, 3).modifiers;
    let rot = z_rotation(true).modifiers;
    let a = Parametrisation {
        modifiers: vec![line[0].clone(), rot[0].clone()],
        constraints: vec![],
    };
    let xa = [0.02, 0.03, -0.01, 0.4, 0.0, 0.0, 0.0];
    let out = a
        .bind(&db, &MasterSources::new())
        .unwrap()
        .apply(&xa)
        .unwrap();
    let bump = Parametrisation {
        modifiers: line.clone(),
        constraints: vec![],
    }
    .bind(&db, &MasterSources::new())
    .unwrap()
    .apply(&xa[..3])
    .unwrap();
    let th: f64 = 0.4;
    for (id, q) in bump.iter().enumerate() {
        let want = Point3::new(
            q.x * th.cos() - q.y * th.sin(),
            q.x * th.sin() + q.y * th.cos(),
            q.z,
        );
        let on_side = db
            .surface(SurfaceId(0))
            .control
            .nodes
            .iter()
            .flatten()
            .any(|n| n.index() == id);
        if on_side {
            assert_close!(
                out[id].coords.as_slice(),
                want.coords.as_slice(),
                abs = 1e-14
            );
        }
    }
}

#[test]
fn basis_properties() {
    // B-spline partition of unity and local support (user knots)
    let knots = vec![0.0, 0.0, 0.0, 0.0, 0.2, 0.5, 0.7, 1.0, 1.0, 1.0, 1.0];
    let b = Basis::BSpline {
        degree: 3,
        n_basis: 0,
        knots: Some(knots.clone()),
    }
    .prepare("t")
    .unwrap();
    assert_eq!(b.len(), 7);
    for i in 0..=200 {
        let s = i as f64 / 200.0;
        let h = b.eval(s);
        assert_close!(h.iter().sum::<f64>(), 1.0, rel = 1e-14);
        for (k, v) in h.iter().enumerate() {
            assert!(*v >= 0.0);
            if s < knots[k] || s > knots[k + 4] {
                assert_eq!(*v, 0.0, "N_{k}({s}) outside its support");
            }
        }
    }
    // Bernstein end interpolation: B_0(0) = 1, B_n(1) = 1, others zero there
    let bern = Basis::Bernstein { degree: 5 }.prepare("t").unwrap();
    let (h0, h1) = (bern.eval(0.0), bern.eval(1.0));
    assert_eq!(h0[0], 1.0);
    assert_eq!(h1[5], 1.0);
    assert!(h0[1..].iter().all(|&v| v == 0.0) && h1[..5].iter().all(|&v| v == 0.0));
    // Hicks–Henne peak position
    for peak in [0.1, 0.35, 0.5, 0.8] {
        let hh = Basis::HicksHenne {
            bumps: vec![Bump { peak, width: 3.0 }],
        }
        .prepare("t")
        .unwrap();
        let (mut arg, mut best) = (0.0, -1.0);
        for i in 0..=10000 {
            let s = i as f64 / 10000.0;
            let v = hh.eval(s)[0];
            if v > best {
                best = v;
                arg = s;
            }
        }
        assert_close!(arg, peak, abs = 1e-4);
        assert_close!(hh.eval(peak)[0], 1.0, rel = 1e-13);
    }
}

#[test]
fn normal_direction_is_the_surface_normal() {
    let db = fixture("sphere");
    let p = Parametrisation {
        modifiers: vec![Modifier::Surface(SurfaceModifier {
            name: "s".into(),
            surfaces: vec![SurfaceId(0)],
            range_u: None,
            range_v: None,
            basis_u: Basis::Bernstein { degree: 0 },
            basis_v: Basis::Bernstein { degree: 0 },
            active_u: None,
            active_v: None,
            direction: Direction::Normal,
            form: SurfaceForm::Tensor {
                variables: vars("c", 1),
            },
        })],
        constraints: vec![],
    };
    let out = p
        .bind(&db, &MasterSources::new())
        .unwrap()
        .apply(&[0.1])
        .unwrap();
    let s = db.surface(SurfaceId(0));
    // every control node of face 0 moves by 0.1 along ±(its position) (unit sphere)
    let sign = s
        .normal(0.5, 0.5)
        .unwrap()
        .dot(&s.point(0.5, 0.5).coords)
        .signum();
    let x = control::nodes(s.patches[0].deg_u);
    let y = control::nodes(s.patches[0].deg_v);
    for (a, &u) in x.iter().enumerate() {
        for (b, &v) in y.iter().enumerate() {
            let id = s.control.nodes[0][a * y.len() + b].index();
            let p0 = db.control_points()[id];
            // exactly the database's unit normal r_u × r_v / |r_u × r_v| ...
            let want = p0 + s.normal(u, v).unwrap() * 0.1;
            assert_close!(
                out[id].coords.as_slice(),
                want.coords.as_slice(),
                abs = 1e-15
            );
            // ... which is the outward or inward radial direction of the sphere
            let radial = p0 + p0.coords.normalize() * (0.1 * sign);
            assert_close!(
                out[id].coords.as_slice(),
                radial.coords.as_slice(),
                abs = 1e-4
            );
        }
    }
}

/// A line modifier along an axis (Eq. 36 with s the coordinate along a straight line): on
/// the wing-body fuselage, a linear ramp from x = 2 to the nose along −x stretches the nose
/// (x ↦ x − δ (2 − x) / 2, an affine map: the tip moves by δ), a quadratic one along −z bends
/// it down by δ (2 − x)² / 4; every node behind x = 2, and every node of the wing, keeps its
/// bits. Read from RON as a user writes it.
#[test]
fn axis_line_stretches_and_bends_the_nose_and_leaves_the_rest_bit_for_bit() {
    let db = fixture("wing_body");
    let text = r#"(modifiers: [
        Line(name: "stretch", line: Axis(point: (2.0, 0.0, 0.0), direction: (-1.0, 0.0, 0.0)),
             links: (surfaces: [0]), range: (0.0, 2.0), basis: Bernstein(degree: 1),
             active: [1], direction: Axis(-1.0, 0.0, 0.0),
             variables: [(name: "stretch", lower: -1.0, upper: 1.0)]),
        Line(name: "droop", line: Axis(point: (2.0, 0.5, 0.5), direction: (-3.0, 0.0, 0.0)),
             links: (surfaces: [0]), range: (0.0, 2.0), basis: Bernstein(degree: 2),
             active: [2], direction: Axis(0.0, 0.0, -1.0),
             variables: [(name: "droop", lower: -1.0, upper: 1.0)]),
    ])"#;
    let p = Parametrisation::from_ron_str(text, "p.ron").unwrap();
    let prep = p.bind(&db, &MasterSources::new()).unwrap();
    let fuselage: std::collections::BTreeSet<usize> = db
        .surface(SurfaceId(0))
        .control
        .nodes
        .iter()
        .flatten()
        .map(|i| i.index())
        .collect();
    let r0 = db.control_points();
    let tip = (0..r0.len())
        .filter(|k| fuselage.contains(k))
        .min_by(|&a, &b| r0[a].x.total_cmp(&r0[b].x))
        .unwrap();
    assert_eq!(r0[tip].x, 0.0, "the nose tip");
    for (x, which) in [([0.3, 0.0], 0), ([0.0, 0.2], 1), ([-0.25, -0.1], 2)] {
        let out = prep.apply(&x).unwrap();
        let mut ahead = 0;
        for k in 0..r0.len() {
            let p0 = r0[k];
            if !fuselage.contains(&k) || p0.x >= 2.0 {
                assert_eq!(bits(&[out[k]]), bits(&[p0]), "node {k} ({which}) moved");
                continue;
            }
            ahead += 1;
            let s = (2.0 - p0.x) / 2.0;
            let want = Point3::new(p0.x - x[0] * s, p0.y, p0.z - x[1] * s * s);
            assert_close!(
                out[k].coords.as_slice(),
                want.coords.as_slice(),
                rel = 0.0,
                abs = 1e-14
            );
        }
        assert!(ahead > 50, "{ahead} nodes ahead of x = 2");
        // the tip moves by exactly the variables
        assert_eq!(out[tip].x, -x[0]);
        assert_eq!(out[tip].z, r0[tip].z - x[1]);
    }
    // a zero axis and a line without links are errors naming the modifier
    let mut bad = p.clone();
    if let Modifier::Line(l) = &mut bad.modifiers[0] {
        l.line = LineSupport::Axis(Axis {
            point: Point3::origin(),
            direction: Vector3::zeros(),
        });
    }
    let e = bad
        .bind(&db, &MasterSources::new())
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("'stretch'") && e.contains("non-zero"), "{e}");
    let mut bad = p.clone();
    if let Modifier::Line(l) = &mut bad.modifiers[1] {
        l.links = Links::default();
    }
    let e = bad
        .bind(&db, &MasterSources::new())
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("'droop'") && e.contains("links no control node"),
        "{e}"
    );
}
