//! The model update on the wing–body fixture (`fixtures/geom/wing_body.ron`, written by
//! `cargo xtask fixtures`): fuselage radius ±5 %, wing root up by 2 % of the root chord.

use geom_db::GeomDb;
use geom_db::prelude::Point3;
use intersect::update::{ModelBaseline, UpdateOptions};

pub fn load(name: &str) -> GeomDb {
    let path = format!("{}/../../fixtures/geom/{name}", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap();
    GeomDb::from_ron_str(&text, &path).unwrap()
}

fn surface_id(db: &GeomDb, name: &str) -> usize {
    db.surfaces.iter().position(|s| s.name == name).unwrap()
}

/// Control nodes of support surface `s` moved by `f`.
fn move_surface_nodes(db: &GeomDb, s: usize, f: impl Fn(&Point3) -> Point3) -> Vec<Point3> {
    db.control_points_with_surface_moved(geom_db::SurfaceId::from_index(s), f)
}

/// The fixture's own junction against its surfaces at 200 samples per arc.
fn initial_deviation(db: &GeomDb) -> [f64; 2] {
    use intersect::check::curve_surface_deviation;
    use intersect::project::{ProjectOptions, SurfaceProjector};
    let c = &db.curves[0];
    let po = ProjectOptions::default().with_length_scale(db.reference_length());
    let s1 = &db.surfaces[c.defining_surfaces[0].index()];
    let s2 = &db.surfaces[c.defining_surfaces[1].index()];
    let p1 = SurfaceProjector::new("wing", s1, &po).unwrap();
    let p2 = SurfaceProjector::new("fuselage", s2, &po).unwrap();
    curve_surface_deviation("junction", c, &p1, &p2, 200)
        .unwrap()
        .max_distance
}

#[test]
fn zero_change_is_bit_for_bit() {
    let db = load("wing_body.ron");
    let base = ModelBaseline::new(&db, &UpdateOptions::default()).unwrap();
    let (new, rep) = base.update(db.control_points()).unwrap();
    assert_eq!(new.to_ron_string(), db.to_ron_string());
    assert!(rep.curves.iter().all(|c| !c.reintersected));
}

#[test]
fn fuselage_radius_and_wing_root_moves() {
    let db = load("wing_body.ron");
    let scale = db.reference_length();
    let base =
        ModelBaseline::new(&db, &UpdateOptions::default().with_deviation_samples(200)).unwrap();
    let fus = surface_id(&db, "fuselage");
    let wing = surface_id(&db, "wing");
    let initial = initial_deviation(&db);
    eprintln!("initial junction deviation from wing, fuselage: {initial:?}");
    let cases: Vec<(&str, Vec<Point3>)> = vec![
        (
            "fuselage radius +5%",
            move_surface_nodes(&db, fus, |p| Point3::new(p.x, p.y * 1.05, p.z * 1.05)),
        ),
        (
            "fuselage radius -5%",
            move_surface_nodes(&db, fus, |p| Point3::new(p.x, p.y * 0.95, p.z * 0.95)),
        ),
        (
            "wing root up 2% chord",
            move_surface_nodes(&db, wing, |p| {
                if p.y.abs() < 1e-12 {
                    Point3::new(p.x, p.y, p.z + 0.02 * 2.0)
                } else {
                    *p
                }
            }),
        ),
    ];
    for (name, nodes) in cases {
        let (new, rep) = base
            .update(&nodes)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let j = rep
            .curves
            .iter()
            .find(|c| c.label.contains("junction"))
            .unwrap();
        let dev = j.deviation.unwrap();
        eprintln!(
            "{name}: junction residual {:.2e}, max move {:.3e}, fallbacks {}, deviation \
             [{:.2e}, {:.2e}] at t = {:?} (= {:.2e} of the model size {scale:.3}), corner \
             residual {:.2e}",
            j.residual,
            j.max_move,
            j.fallbacks,
            dev[0],
            dev[1],
            j.deviation_at.unwrap(),
            dev[0].max(dev[1]) / scale,
            rep.max_corner_residual
        );
        assert!(j.reintersected && j.max_move > 1e-3);
        // the fixture's junction (4 arcs of degree 8) is itself only within ~6e-8 of its
        // surfaces between control points (interpolation error): the update must not be
        // worse than the representation allows
        assert!(
            dev[0] <= 1.5 * initial[0] + 1e-12 && dev[1] <= 1.5 * initial[1] + 1e-12,
            "{name}: deviation {dev:?} vs initial {initial:?}"
        );
        assert!(
            dev[0].max(dev[1]) <= 1e-8 * scale,
            "{name}: deviation {dev:?}"
        );
        // the junction corners are on the updated junction and trailing edge
        for k in &rep.corners {
            if k.updated {
                assert!(k.residual <= 1e-7 * scale, "{k:?}");
            }
        }
        new.validate().unwrap();
    }
}

#[test]
fn shorter_arcs_bring_the_junction_below_1e_8() {
    // the remedy for the interpolation error between control points: the same update with
    // each arc of the junction split in two (8 arcs of degree 8)
    use geom_db::eval::ParamCurve;
    use geom_db::{Arc, SupportCurve};
    use intersect::check::curve_surface_deviation;
    use intersect::project::{ProjectOptions, SurfaceProjector};
    use intersect::ssi::{IntersectionSeeds, SsiOptions, update_curve_points};
    let db = load("wing_body.ron");
    let scale = db.reference_length();
    let fus = surface_id(&db, "fuselage");
    let nodes = move_surface_nodes(&db, fus, |p| Point3::new(p.x, p.y * 1.05, p.z * 1.05));
    let new = db.with_control_points(&nodes).unwrap();
    let c = &db.curves[0];
    let (a, b) = (
        c.defining_surfaces[0].index(),
        c.defining_surfaces[1].index(),
    );
    let po = ProjectOptions::default().with_length_scale(scale);
    let pa = SurfaceProjector::new("wing", &db.surfaces[a], &po).unwrap();
    let pb = SurfaceProjector::new("fuselage", &db.surfaces[b], &po).unwrap();
    let x = geom_db::control::nodes(8);
    let mut pts = Vec::new();
    for k in 0..2 * c.arcs.len() {
        for (i, &xi) in x.iter().enumerate() {
            if k > 0 && i == 0 {
                continue;
            }
            pts.push(c.point(0.5 * (k as f64 + xi)));
        }
    }
    let degrees = vec![8usize; 2 * c.arcs.len()];
    let so = SsiOptions::default().with_length_scale(scale);
    let seeds =
        IntersectionSeeds::new("junction", &pts, None, Some(&degrees), &pa, &pb, &so).unwrap();
    let up = update_curve_points(&seeds, &new.surfaces[a], &new.surfaces[b], &so).unwrap();
    let np = up.new_points();
    let arcs: Vec<Arc> = (0..degrees.len())
        .map(|k| Arc::from_control_points(&np[8 * k..=8 * k + 8]))
        .collect();
    let refined = SupportCurve::new("refined junction", arcs);
    let qa = SurfaceProjector::new("wing", &new.surfaces[a], &po).unwrap();
    let qb = SurfaceProjector::new("fuselage", &new.surfaces[b], &po).unwrap();
    let dev = curve_surface_deviation("refined", &refined, &qa, &qb, 200).unwrap();
    eprintln!(
        "fuselage +5%, junction with 8 arcs of degree 8: deviation {:?} (max residual {:.2e})",
        dev.max_distance, up.max_residual
    );
    assert!(dev.max() < 1e-8, "{dev:?}");
}

#[test]
fn no_projected_point_lands_on_a_wrong_patch_of_the_wing_body() {
    // brute force on a sample: Newton restricted to every patch of every surface from a
    // 4 × 4 grid of starts; the set projector must be as near, and on the same surface and
    // patch unless the point is equidistant (a shared border)
    use geom_db::SupportSurface;
    use geom_db::eval::{ParamSurface, SurfaceDerivs};
    use intersect::project::{ProjectOptions, SurfaceProjector, SurfaceSetProjector};
    struct Restricted<'a> {
        s: &'a SupportSurface,
        u: [f64; 2],
        v: [f64; 2],
    }
    impl ParamSurface for Restricted<'_> {
        fn domain(&self) -> ([f64; 2], [f64; 2]) {
            (self.u, self.v)
        }
        fn derivs(&self, u: f64, v: f64) -> SurfaceDerivs {
            self.s.derivs(u, v)
        }
    }
    let db = load("wing_body.ron");
    let scale = db.reference_length();
    let opts = ProjectOptions::default().with_length_scale(scale);
    let named: Vec<(String, &SupportSurface)> =
        db.surfaces.iter().map(|s| (s.name.clone(), s)).collect();
    let set = SurfaceSetProjector::new(&named, &opts).unwrap();
    let mut subs = Vec::new();
    for (si, s) in db.surfaces.iter().enumerate() {
        for j in 0..s.n_v {
            for i in 0..s.n_u {
                let r = Restricted {
                    s,
                    u: [i as f64, i as f64 + 1.0],
                    v: [j as f64, j as f64 + 1.0],
                };
                subs.push(((si, [i, j]), r));
            }
        }
    }
    let one = opts.clone().with_min_cells(1);
    let subproj: Vec<_> = subs
        .iter()
        .map(|(k, r)| (*k, SurfaceProjector::new("patch", r, &one).unwrap()))
        .collect();
    let pts = points_sample(&db, 40);
    for p in &pts {
        let f = set.project_indexed(p, 0).unwrap();
        let mut best = (f64::INFINITY, (0usize, [0usize; 2]));
        for (k, sp) in &subproj {
            let (du, dv) = sp.surface().domain();
            for a in 0..4 {
                for b in 0..4 {
                    let uv0 = [
                        du[0] + (a as f64 + 0.5) / 4.0 * (du[1] - du[0]),
                        dv[0] + (b as f64 + 0.5) / 4.0 * (dv[1] - dv[0]),
                    ];
                    let g = sp.project_from(p, uv0);
                    if g.distance < best.0 {
                        best = (g.distance, *k);
                    }
                }
            }
        }
        assert!(
            f.foot.distance <= best.0 + 1e-12 * scale,
            "{} > brute {}",
            f.foot.distance,
            best.0
        );
        if (f.surface, f.foot.patch) != best.1 {
            assert!(
                (best.0 - f.foot.distance).abs() <= 1e-9 * scale,
                "surface {} patch {:?} vs brute {:?}",
                f.surface,
                f.foot.patch,
                best.1
            );
        }
    }
}

/// Seeded points near the surfaces (±1 % of the model size along the normal).
fn points_sample(db: &GeomDb, n: usize) -> Vec<Point3> {
    use geom_db::eval::ParamSurface;
    let scale = db.reference_length();
    let mut st = 42u64;
    let mut next = || {
        st = st
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((st >> 11) as f64) / ((1u64 << 53) as f64)
    };
    let mut out = Vec::new();
    while out.len() < n {
        let s = &db.surfaces[(next() * db.surfaces.len() as f64) as usize];
        let (du, dv) = s.domain();
        let u = du[0] + (du[1] - du[0]) * next();
        let v = dv[0] + (dv[1] - dv[0]) * next();
        let d = s.derivs(u, v);
        if let Some(nrm) = d.unit_normal() {
            out.push(d.point + nrm * (0.02 * (next() - 0.5) * scale));
        }
    }
    out
}
