//! Generation on the sphere fixture: orientation, nodes on their support, conformity,
//! quality.

use geom_db::eval::ParamSurface;
use surfgrid::{GenerateOptions, NodeSupport, SizeField, generate, grid_stats};

use crate::common::fixture;

#[test]
fn sphere_grid_is_valid() {
    let db = fixture("sphere");
    let field = SizeField::uniform(0.15).unwrap();
    let g = generate(&db, &field, &GenerateOptions::default()).unwrap();
    let st = grid_stats(&g, &field);
    eprintln!("{st:?}");
    assert!(st.triangles > 500);
    // orientation w.r.t. the inward normal of the component
    for c in &g.components {
        let sc = db.surface_component(c.comp);
        let s = db.surface(sc.surface);
        for (k, t) in c.global_triangles().enumerate() {
            let [a, b, cc] = t.map(|v| g.coords[v as usize]);
            let n = (b - a).cross(&(cc - a));
            let lt = c.triangles[k];
            let uv = c.uv[lt[0] as usize];
            let nrm = s.normal(uv[0], uv[1]).unwrap() * sc.inward.sign();
            assert!(n.dot(&nrm) > 0.0, "{} triangle {k}", sc.name);
        }
    }
    // every node on its support (evaluated at its parameters) to 1e-12 relative
    let l = db.reference_length();
    for i in 0..g.n_nodes() {
        let p = g.evaluate_node(&db, i);
        assert!((p - g.coords[i]).norm() <= 1e-12 * l, "node {i}");
    }
    // unit sphere: every node at radius 1 within the fixture's approximation
    for p in &g.coords {
        assert!((p.coords.norm() - 1.0).abs() < 1e-6);
    }
    // conformity: every boundary edge of a component is an edge of exactly one other
    let mut count = std::collections::HashMap::new();
    for c in &g.components {
        for t in c.global_triangles() {
            for i in 0..3 {
                let e = (t[i], t[(i + 1) % 3]);
                *count.entry(e).or_insert(0) += 1;
            }
        }
    }
    for (&(a, b), &n) in &count {
        assert_eq!(n, 1, "directed edge {a}-{b} used {n} times");
        assert_eq!(
            count.get(&(b, a)),
            Some(&1),
            "edge {a}-{b} has no twin: the grid is not closed"
        );
    }
    // curve nodes are shared: support of the local boundary nodes
    for c in &g.components {
        for k in 0..c.n_boundary {
            assert!(!matches!(
                g.support[c.nodes[k] as usize],
                NodeSupport::Surface { .. }
            ));
        }
    }
    // total area close to 4π
    let area: f64 = g
        .components
        .iter()
        .flat_map(|c| c.global_triangles())
        .map(|t| {
            let [a, b, c] = t.map(|v| g.coords[v as usize]);
            0.5 * (b - a).cross(&(c - a)).norm()
        })
        .sum();
    // inscribed polyhedron: the deficit is O(h²), well under 1 % at h = 0.15
    assert!(
        (area / (4.0 * std::f64::consts::PI) - 1.0).abs() < 0.01,
        "{area}"
    );
    assert!(st.frac_min_angle_ge_20 > 0.97, "{st:?}");
}

#[test]
fn cylinder_side_across_its_seam() {
    let db = fixture("cylinder");
    let field = SizeField::uniform(0.2).unwrap();
    let side = GenerateOptions::default().with_components(vec![geom_db::SurfCompId(0)]);
    let g = generate(&db, &field, &side).unwrap();
    let st = grid_stats(&g, &field);
    // the side of radius 1 and height 2 across its seam: area 4π minus the chord deficit
    let area: f64 = g.components[0]
        .global_triangles()
        .map(|t| {
            let [a, b, c] = t.map(|v| g.coords[v as usize]);
            0.5 * (b - a).cross(&(c - a)).norm()
        })
        .sum();
    assert!(
        (area / (4.0 * std::f64::consts::PI) - 1.0).abs() < 0.01,
        "{area}"
    );
    assert!(st.frac_min_angle_ge_20 > 0.99, "{st:?}");
}

#[test]
fn generation_does_not_depend_on_the_thread_count() {
    let db = fixture("sphere");
    let field = SizeField::uniform(0.3).unwrap();
    let a = testkit::with_threads(1, || {
        generate(&db, &field, &GenerateOptions::default()).unwrap()
    });
    let b = generate(&db, &field, &GenerateOptions::default()).unwrap();
    assert!(a == b);
}

#[test]
fn msh_keeps_the_parameters_and_vtu_is_written() {
    let db = fixture("sphere");
    let field = SizeField::uniform(0.3).unwrap();
    let g = generate(&db, &field, &GenerateOptions::default()).unwrap();
    let m = g.to_mesh(&db);
    let mut buf = Vec::new();
    mesh::msh::write(&m, mesh::msh::Encoding::Binary, &mut buf).unwrap();
    let r = mesh::msh::read(&buf[..], std::path::Path::new("sphere.msh")).unwrap();
    assert!(r.parametric);
    // the reader may renumber nodes by entity block: match them by position
    let classes = r.classes.as_ref().unwrap();
    let mut by_pos = std::collections::HashMap::new();
    for (i, p) in r.coords.iter().enumerate() {
        by_pos.insert(p.map(f64::to_bits), i);
    }
    let orig = m.classes.as_ref().unwrap();
    for (i, p) in m.coords.iter().enumerate() {
        let j = by_pos[&p.map(f64::to_bits)];
        assert_eq!(classes[j], orig[i], "node {i}");
    }
    let mut vtu = Vec::new();
    mesh::vtu::write(&m, &mesh::vtu::VtuOptions::default(), &mut vtu).unwrap();
    assert!(vtu.len() > 1000);
}
