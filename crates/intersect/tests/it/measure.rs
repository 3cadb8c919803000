//! `intersect::measure` on the cube sphere (fixtures/geom/sphere.ron, six patches of
//! polynomial surfaces on control nodes): the derivatives of thickness, volume and area for
//! a control-node perturbation against central differences of the model re-solved from its
//! nodes (Eq. 9), and the cotangents against the tangents (dot-product test).

use geom_db::linearise::ModelTangent;
use geom_db::prelude::{Point3, Vector3};
use geom_db::{GeomDb, SurfaceId};
use intersect::measure::{Measured, thickness};

fn sphere() -> GeomDb {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../fixtures/geom/sphere.ron"
    );
    GeomDb::from_ron_str(&std::fs::read_to_string(path).unwrap(), path).unwrap()
}

/// A smooth perturbation of the control nodes: dp = (0.3 x y, 0.2 y − 0.2 z², 0.5 x + 0.1)
/// (divergence 0.3 y + 0.2: the volume grows).
fn perturbation(db: &GeomDb) -> Vec<Vector3> {
    db.control_nodes
        .iter()
        .map(|p| {
            Vector3::new(
                0.3 * p.x * p.y,
                0.2 * p.y - 0.2 * p.z * p.z,
                0.5 * p.x + 0.1,
            )
        })
        .collect()
}

fn measures(db: &GeomDb) -> Vec<Measured> {
    let all: Vec<SurfaceId> = (0..db.surfaces.len() as u32).map(SurfaceId).collect();
    let signs: Vec<(SurfaceId, f64)> = all
        .iter()
        .map(|&s| {
            let c = db
                .surface_components
                .iter()
                .find(|c| c.surface == s)
                .unwrap();
            (s, c.inward.sign())
        })
        .collect();
    vec![
        Measured::Thickness(
            thickness(db, &all, &[0.1, 0.2, 0.0], &[0.0, 0.6, 0.8]).expect("thickness"),
        ),
        Measured::volume(db, signs, [0.0, 0.0, 1.0]),
        Measured::area(db, &all),
    ]
}

#[test]
fn measure_derivatives_match_central_differences_of_the_model() {
    let db = sphere();
    let dp = perturbation(&db);
    let mut t = ModelTangent::zeros(&db);
    t.nodes.copy_from_slice(&dp);
    let m0 = measures(&db);
    let at = |h: f64| {
        let pts: Vec<Point3> = db
            .control_nodes
            .iter()
            .zip(&dp)
            .map(|(p, d)| p + d * h)
            .collect();
        let moved = db.with_control_points(&pts).unwrap();
        measures(&moved)
            .iter()
            .map(Measured::value)
            .collect::<Vec<f64>>()
    };
    let h = 1e-3;
    let (p1, m1, p2, m2) = (at(h), at(-h), at(2.0 * h), at(-2.0 * h));
    for (k, m) in m0.iter().enumerate() {
        let fd = (8.0 * (p1[k] - m1[k]) - (p2[k] - m2[k])) / (12.0 * h);
        let an = m.tangent(&db, &t);
        assert!(fd.abs() > 1e-2, "measure {k} moves: {fd}");
        assert!(
            (an - fd).abs() <= 1e-7 * fd.abs(),
            "measure {k}: {an} vs {fd}"
        );
    }
}

#[test]
fn measure_cotangent_is_the_transpose_of_the_tangent() {
    let db = sphere();
    let mut t = ModelTangent::zeros(&db);
    t.nodes.copy_from_slice(&perturbation(&db));
    for (k, m) in measures(&db).iter().enumerate() {
        let mut w = ModelTangent::zeros(&db);
        m.add_cotangent(&db, 0.7, &mut w);
        let (a, b) = (0.7 * m.tangent(&db, &t), w.dot(&t));
        assert!(
            (a - b).abs() <= 1e-12 * a.abs().max(1.0),
            "measure {k}: {a} vs {b}"
        );
    }
}
