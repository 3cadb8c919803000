//! Poles (degenerate sides of a support surface's parameter rectangle): the whole wing-body
//! (fuselage nose and tail, tip cap ends) and the cylinder with its caps. The checks read the
//! fixtures and test properties (orientation, support, conformity, manifold fans, quality
//! shares, areas and volumes), not node counts.

use geom_db::GeomDb;
use surfgrid::{GenerateOptions, SizeField, generate, grid_stats};

use crate::common::{check_grid, fixture, wing_body_field};

/// Nodes at the image of a degenerate side, per component: (component, node) pairs.
fn pole_nodes(db: &GeomDb, g: &surfgrid::SurfaceGrid) -> Vec<(usize, u32)> {
    let tol = 1e-8 * db.reference_length();
    let mut out = Vec::new();
    for (ci, c) in g.components.iter().enumerate() {
        let s = db.surface(db.surface_component(c.comp).surface);
        for p in surfgrid::pole::degenerate_sides(s, tol) {
            let n = c
                .nodes
                .iter()
                .copied()
                .find(|&v| (g.coords[v as usize] - p.point).norm() <= tol)
                .unwrap_or_else(|| panic!("component {ci}: no node at the pole {:?}", p.point));
            out.push((ci, n));
        }
    }
    out
}

#[test]
fn whole_wing_body_is_meshed_with_its_poles() {
    let db = fixture("wing_body");
    let field = wing_body_field(&db, 0.15);
    let g = generate(&db, &field, &GenerateOptions::default()).unwrap();
    assert_eq!(g.components.len(), db.surface_components.len());
    check_grid(&db, &g, false);
    let poles = pole_nodes(&db, &g);
    // the fixture's fuselage is a body of revolution (nose, tail) and the tip cap is closed at
    // both ends: there are poles to test
    assert!(poles.len() >= 2, "{poles:?}");
    for &(ci, v) in &poles {
        let c = &g.components[ci];
        // a pole is the corner it is, and the corner of a fan of proper triangles
        assert!(
            matches!(g.support[v as usize], surfgrid::NodeSupport::Corner(_)),
            "{:?}",
            g.support[v as usize]
        );
        let fan: Vec<_> = c.global_triangles().filter(|t| t.contains(&v)).collect();
        assert!(!fan.is_empty());
        for t in fan {
            let [a, b, cc] = t.map(|k| g.coords[k as usize]);
            let area = 0.5 * (b - a).cross(&(cc - a)).norm();
            assert!(
                area > 1e-4 * field.size_at(&a).powi(2),
                "degenerate fan triangle {t:?}"
            );
        }
    }
    let st = grid_stats(&g, &field);
    eprintln!("wing-body: {} nodes, {st:?}", g.n_nodes());
    // the targets on the whole wing-body
    assert!(st.frac_min_angle_ge_20 >= 0.99, "{st:?}");
    assert!(st.frac_edges_within_30 >= 0.95, "{st:?}");
}

#[test]
fn cylinder_with_caps_is_closed() {
    let db = fixture("cylinder");
    let field = SizeField::uniform(0.15).unwrap();
    let g = generate(&db, &field, &GenerateOptions::default()).unwrap();
    check_grid(&db, &g, true);
    // caps: one pole each, at the centre, surrounded by a closed fan
    assert_eq!(pole_nodes(&db, &g).len(), 2);
    // radius 1, height 2: area 2π·1·2 + 2·π = 6π and volume 2π (inscribed polyhedron: O(h²)
    // below); the inward normal points into the flow domain (out of the solid), so the
    // signed volume of the positively oriented triangles is the solid's volume
    let (mut area, mut vol) = (0.0, 0.0);
    for c in &g.components {
        for t in c.global_triangles() {
            let [a, b, cc] = t.map(|v| g.coords[v as usize].coords);
            area += 0.5 * (b - a).cross(&(cc - a)).norm();
            vol += a.dot(&b.cross(&cc)) / 6.0;
        }
    }
    let pi = std::f64::consts::PI;
    assert!((area / (6.0 * pi) - 1.0).abs() < 0.01, "area {area}");
    assert!((vol / (2.0 * pi) - 1.0).abs() < 0.01, "volume {vol}");
    let st = grid_stats(&g, &field);
    eprintln!("cylinder: {st:?}");
    assert!(st.frac_min_angle_ge_20 >= 0.99, "{st:?}");
}

/// Coarse and fine sizes: the cap loops start on the radial seam, whose global foot may be on
/// either side (h = 0.6 once made the walk jump across the seam), and few boundary nodes
/// surround the poles.
#[test]
fn poles_at_several_sizes() {
    let db = fixture("cylinder");
    for h in [0.6, 0.4, 0.3, 0.08] {
        let field = SizeField::uniform(h).unwrap();
        let g = generate(&db, &field, &GenerateOptions::default())
            .unwrap_or_else(|e| panic!("cylinder, h = {h}: {e}"));
        check_grid(&db, &g, true);
    }
    let db = fixture("wing_body");
    for h in [0.4, 0.25] {
        let field = wing_body_field(&db, h);
        let g = generate(&db, &field, &GenerateOptions::default())
            .unwrap_or_else(|e| panic!("wing-body, h = {h}: {e}"));
        check_grid(&db, &g, false);
        assert_eq!(pole_nodes(&db, &g).len(), 4);
    }
}
